use super::*;

fn sample() -> Image {
    Image { width: 3, height: 2, data: (0..18).map(|i| i as f32 * 0.05 - 0.1).collect() }
}

fn pfm_err(bytes: &[u8]) -> pfm::PfmError {
    pfm::parse(bytes).expect_err("the file is malformed")
}

#[test]
fn pfm_round_trips_bottom_row_first() {
    let img = sample();
    let bytes = pfm::encode(&img);
    assert!(bytes.starts_with(b"PF\n3 2\n-1.0\n"));
    // The first pixel stored is the bottom row's first.
    assert_eq!(&bytes[12..16], &img.pixel(0, 1)[0].to_le_bytes());
    assert_eq!(pfm::parse(&bytes).unwrap(), img);
}

#[test]
fn pfm_reads_grey_big_endian_and_scaled() {
    let mut grey = b"Pf 2 1\n2.0\n".to_vec();
    for v in [1.5f32, -3.0] {
        grey.extend(v.to_be_bytes());
    }
    let img = pfm::parse(&grey).unwrap();
    assert_eq!(img.data, [3.0, 3.0, 3.0, -6.0, -6.0, -6.0]);
}

#[test]
fn pfm_errors_say_where() {
    let good = pfm::encode(&sample());
    let e = pfm_err(b"P6\n3 2\n255\n");
    assert_eq!((e.at, e.message.as_str()), (0, "expected `PF` (RGB) or `Pf` (grey), found `P6`: not a PFM file"));
    let e = pfm_err(b"PF\n3 x\n-1\n");
    assert_eq!((e.at, e.message.as_str()), (5, "expected the height, a whole number, found `x`"));
    let e = pfm_err(b"PF\n0 2\n-1\n");
    assert_eq!((e.at, e.message.as_str()), (3, "the width is 0: expected 1..=8192"));
    let e = pfm_err(b"PF\n99999 2\n-1\n");
    assert_eq!(e.at, 3);
    let e = pfm_err(b"PF\n3 2\n0\n");
    assert_eq!(e.at, 7);
    assert!(e.message.starts_with("expected the scale"), "{}", e.message);
    let e = pfm_err(b"PF\n3 2");
    assert_eq!((e.at, e.message.as_str()), (6, "expected the scale in the PFM header, found the end of the file"));
    let e = pfm_err(&good[..good.len() - 1]);
    assert_eq!((e.at, e.message.as_str()), (12, "3×2 pixels of 3 f32 take 72 bytes, but the file ends after 71"));
    let mut long = good.clone();
    long.push(0);
    assert_eq!(pfm_err(&long).message, "3×2 pixels of 3 f32 take 72 bytes, but bytes follow after 73");
    let e = pfm_err(b"PF\n3 2\n-1.0");
    assert_eq!((e.at, e.message.as_str()), (11, "expected one whitespace character after the scale, then the pixels"));
}

#[test]
fn files_round_trip_by_extension() {
    let dir = tempfile::tempdir().unwrap();
    let img = Image { width: 3, height: 2, data: (0..18).map(|i| i as f32 / 17.0).collect() };
    for ext in ["pfm", "exr", "PNG"] {
        let path = dir.path().join(format!("a.{ext}"));
        write(&path, &img).unwrap();
        let back = read(&path, "a").unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        // PNG stores 8 bits.
        let tol = if ext == "PNG" { 0.5 / 255.0 + 1e-6 } else { 0.0 };
        for (a, b) in back.data.iter().zip(&img.data) {
            assert!((a - b).abs() <= tol, "{ext}: {a} {b}");
        }
    }
}

#[test]
fn unreadable_images_are_diagnostics() {
    let dir = tempfile::tempdir().unwrap();
    let d = read(&dir.path().join("a.jpg"), "a.jpg").unwrap_err();
    assert_eq!((d.code, d.file()), (Code::Image, Some("a.jpg")));
    let d = read(&dir.path().join("none.pfm"), "none.pfm").unwrap_err();
    assert_eq!(d.code, Code::Io);
    for (name, bytes) in [("bad.pfm", &b"PF\n1 1\n-1\n\0\0"[..]), ("bad.exr", b"not an exr"), ("bad.png", b"\x89PNG\r\n\x1a\n")] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let d = read(&path, name).unwrap_err();
        assert_eq!((d.code, d.location.clone()), (Code::Image, Some(Location::file_start(name))), "{}", d.message);
    }
    let d = read(&dir.path().join("bad.pfm"), "bad.pfm").unwrap_err();
    assert!(d.message.starts_with("at byte 10: "), "{}", d.message);
}
