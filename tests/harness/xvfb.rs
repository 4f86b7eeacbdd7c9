//! A virtual X display (Xvfb) for `loupe view`'s real window, and
//! screenshots of it (xwd), for the window's smoke test, its benchmark
//! and the README's screenshot. `tests/run` installs xvfb and x11-apps.

use std::process::{Child, Command};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// A running Xvfb, stopped when dropped.
pub struct Xvfb {
    child: Child,
    /// `:N`, for `DISPLAY`.
    pub display: String,
}

impl Xvfb {
    /// Starts a screen of `width`×`height` at 24 bits on a display number
    /// of its own (neither parallel processes nor tests in one process
    /// meet), and waits for its socket.
    pub fn start(width: u32, height: u32) -> Xvfb {
        static STARTED: AtomicU32 = AtomicU32::new(0);
        let display = format!(":{}", 100 + (std::process::id() % 200) * 4 + STARTED.fetch_add(1, Ordering::Relaxed) % 4);
        let screen = format!("{width}x{height}x24");
        let child = Command::new("Xvfb")
            .args([display.as_str(), "-screen", "0", &screen, "-nolisten", "tcp"])
            .spawn()
            .expect("Xvfb (tests/run installs xvfb)");
        let x = Xvfb { child, display };
        let socket = std::path::PathBuf::from(format!("/tmp/.X11-unix/X{}", &x.display[1..]));
        let start = Instant::now();
        while !socket.exists() {
            assert!(start.elapsed() < Duration::from_secs(30), "Xvfb did not start");
            std::thread::sleep(Duration::from_millis(50));
        }
        x
    }

    /// The whole screen, as RGBA.
    pub fn screenshot(&self) -> image::RgbaImage {
        let shot = Command::new("xwd").args(["-root", "-silent", "-display", &self.display]).output().expect("xwd (x11-apps)");
        assert!(shot.status.success(), "xwd failed: {}", String::from_utf8_lossy(&shot.stderr));
        xwd_image(&shot.stdout)
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A 32-bit ZPixmap XWD dump (what `xwd` writes of a 24-bit screen) as
/// RGBA: the header's fields are big-endian words; each pixel is a word in
/// the dump's byte order, its channels where the colour masks say.
pub fn xwd_image(xwd: &[u8]) -> image::RgbaImage {
    let word = |i: usize| u32::from_be_bytes(xwd[i * 4..i * 4 + 4].try_into().expect("four bytes"));
    let (header, width, height, byte_order, bits) = (word(0) as usize, word(4), word(5), word(7), word(11));
    let (masks, ncolors) = ([word(14), word(15), word(16)], word(19) as usize);
    assert_eq!(bits, 32, "32 bits per pixel");
    let pixels = &xwd[header + ncolors * 12..];
    let channel = |p: u32, mask: u32| ((p & mask) >> mask.trailing_zeros()) as u8;
    image::RgbaImage::from_fn(width, height, |x, y| {
        let i = ((y * width + x) * 4) as usize;
        let b: [u8; 4] = pixels[i..i + 4].try_into().expect("four bytes");
        let p = if byte_order == 0 { u32::from_le_bytes(b) } else { u32::from_be_bytes(b) };
        image::Rgba([channel(p, masks[0]), channel(p, masks[1]), channel(p, masks[2]), 255])
    })
}
