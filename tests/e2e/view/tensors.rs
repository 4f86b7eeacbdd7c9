//! The Tensors tab of `loupe view`'s window against a real daemon running
//! the denoiser: a tensor picked from the list, every channel of it in the
//! grid, the exact values under the cursor, and the daemon capturing it
//! only while the tab asks.

use std::sync::Arc;
use std::time::{Duration, Instant};

use egui_kittest::kittest::{By, NodeT, Queryable, by};
use loupe::render::capture::CapturedTensor;
use loupe::serve::shared::read;
use loupe_view::egui::{self, accesskit::Role};

use super::{Window, small_minimal};

const TENSOR: &str = "denoise.enc_conv0/tensor";

/// The readout under the images: `((x, y), every channel's value, frame)`.
fn readout(w: &Window) -> Option<([usize; 2], Vec<f32>, u64)> {
    let by = By::new().predicate(|n| n.value().is_some_and(|v| v.starts_with('(') && v.contains("· frame")));
    let text = w.harness.query_all(by).next()?.accesskit_node().value()?;
    let (place, rest) = text.strip_prefix('(')?.split_once(") ")?;
    let (x, y) = place.split_once(", ")?;
    let (values, frame) = rest.rsplit_once("· frame ")?;
    let values = values.split("  ").filter(|v| !v.is_empty()).map(|v| v.split_once('=')?.1.parse().ok()).collect::<Option<_>>()?;
    Some(([x.parse().ok()?, y.parse().ok()?], values, frame.trim().parse().ok()?))
}

/// The labels of channel `ch`'s images: `c3`, or `c3 constant = 0` when
/// every value of it is the same.
fn channel_images(w: &Window, ch: usize) -> Vec<(String, egui::Rect)> {
    let name = format!("c{ch}");
    let by = by().role(Role::Image).predicate(move |n| n.label().is_some_and(|l| l == name || l.starts_with(&format!("{name} "))));
    w.harness.query_all(by).map(|n| (n.accesskit_node().label().unwrap_or_default(), n.rect())).collect()
}

/// The grid cell of channel `ch`: where its image lies in the window.
fn cell(w: &Window, ch: usize) -> egui::Rect {
    channel_images(w, ch).first().unwrap_or_else(|| panic!("no image of c{ch}")).1
}

/// Hovers the centre of pixel `[x, y]` of channel 0's image until the
/// readout names a frame whose capture the daemon still holds; returns
/// the pixel and values the readout names, and that capture.
fn values_under(w: &mut Window, [x, y]: [usize; 2], [height, width]: [usize; 2]) -> ([usize; 2], Vec<f32>, Arc<CapturedTensor>) {
    let start = Instant::now();
    loop {
        let r = cell(w, 0);
        let at = r.min + egui::vec2((x as f32 + 0.5) * r.width() / width as f32, (y as f32 + 0.5) * r.height() / height as f32);
        w.harness.hover_at(at);
        w.harness.step();
        if let Some((pixel, values, frame)) = readout(w) {
            let t = read(&w.shared.tensors).get(TENSOR).expect("captured while the panel shows it").clone();
            if t.frame == frame {
                return (pixel, values, t);
            }
        }
        assert!(start.elapsed() < Duration::from_secs(120), "no readout matched a capture of its frame");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_denoiser_tensor_shows_every_channel_and_the_exact_values_under_the_cursor() {
    // Path traced with 2 samples and denoised: lavapipe runs the network
    // on the 64×36 frame (padded to 64×48) in well under a second.
    let p = small_minimal("view-tensors", "\n[quality]\nrenderer = \"path\"\npath_spp = 2\n\n[denoiser]\nmode = \"ldr\"\n");
    let mut w = Window::open(&p, "scenes/minimal.toml", 10.0, None, egui::vec2(900.0, 700.0));
    w.step_until("the denoiser's first layer", |h| h.state().model().image_tensors().any(|(n, _)| n == TENSOR));
    let [height, width, channels] =
        w.harness.state().model().image_tensors().find(|(n, _)| n == TENSOR).expect("listed").1.map(|n| n as usize);
    assert_eq!([height, width], [48, 64], "the padded frame");
    assert!(channels > 3, "{channels} channels");
    assert!(!read(&w.shared.tensors).contains_key(TENSOR), "nothing asked for it yet, so nothing captured it");

    // Picked from the list in the Tensors tab: a grey image per channel.
    w.harness.get_by_label("Tensors").click();
    w.harness.run_steps(2);
    w.harness.get_by_label("tensor").click();
    w.harness.run_steps(3);
    w.harness.get_by_label(TENSOR).click();
    w.step_until("the grid", |h| h.query_all(by().role(Role::Image)).count() == channels);

    // Under the cursor: the pixel it is over, every channel's value there
    // exactly as the daemon captured it in the frame the readout names.
    let at = |t: &CapturedTensor, [x, y]: [usize; 2]| t.data[(y * width + x) * channels..][..channels].to_vec();
    let (a, va, captured) = values_under(&mut w, [41, 17], [height, width]);
    assert_eq!(captured.data.len(), height * width * channels, "the capture's shape is the one listed");
    assert_eq!(a, [41, 17], "the pixel under the cursor");
    assert_eq!(va, at(&captured, a), "the readout at {a:?}");

    // The grid, made from that same capture: one image per channel.
    let mut constant = 0;
    for ch in 0..channels {
        let images = channel_images(&w, ch);
        assert_eq!(images.len(), 1, "one image of channel {ch}: {images:?}");
        // A channel labelled constant holds that one value (a dead ReLU's).
        if let Some(v) = images[0].0.strip_prefix(&format!("c{ch} constant = ")) {
            let v: f32 = v.parse().expect("a value");
            assert!(captured.data.iter().skip(ch).step_by(channels).all(|x| *x == v), "c{ch} is all {v}");
            constant += 1;
        }
    }
    assert!(constant < channels, "some channels vary");
    let (b, vb, captured) = values_under(&mut w, [3, 40], [height, width]);
    assert_eq!(b, [3, 40]);
    assert_eq!(vb, at(&captured, b), "the readout at {b:?}");
    assert_ne!(va, vb, "two pixels of the lit frame differ, or this test could not tell them apart");

    // Three channels as RGB: one image, and the readout still exact.
    w.harness.get_by_label("RGB").click();
    w.step_until("the RGB image", |h| h.query_all(by().role(Role::Image)).count() == 1);
    let r = w.harness.query_all(by().role(Role::Image)).next().expect("the image").rect();
    let at = r.min + egui::vec2(41.5 * r.width() / width as f32, 17.5 * r.height() / height as f32);
    let start = Instant::now();
    loop {
        w.harness.hover_at(at);
        w.harness.step();
        if let Some((pixel, values, frame)) = readout(&w)
            && read(&w.shared.tensors).get(TENSOR).is_some_and(|t| t.frame == frame)
        {
            assert_eq!((pixel, values.len()), ([41, 17], channels), "the RGB image maps the cursor as the grid does");
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "no readout over the RGB image");
        std::thread::sleep(Duration::from_millis(20));
    }

    // Another tab: the daemon stops capturing the tensor (a frame or two
    // already on its way may still carry it).
    w.harness.get_by_label("Frame").click();
    w.harness.step();
    let asked_until = w.harness.state().model().frame.expect("frames").0;
    w.step_until("frames after the tab closed", |h| h.state().model().frame.is_some_and(|(f, _)| f >= asked_until + 4));
    let last = read(&w.shared.tensors)[TENSOR].frame;
    w.step_until("more frames", |h| h.state().model().frame.is_some_and(|(f, _)| f >= asked_until + 8));
    assert_eq!(read(&w.shared.tensors)[TENSOR].frame, last, "captured after the window stopped asking");
    w.close();
}
