use super::*;

fn f16s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| half::f16::from_f32(*x).to_le_bytes()).collect()
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Two tensors, fp16 weights and fp32 biases.
fn good() -> Vec<u8> {
    let w: Vec<f32> = (0..2 * 3 * 9).map(|i| i as f32 * 0.25 - 4.0).collect();
    write(&[("c.weight", &[2, 3, 3, 3], "oihw", b'h', &f16s(&w)), ("c.bias", &[2], "x", b'f', &f32s(&[1.5, -2.0]))])
}

fn err(bytes: Vec<u8>) -> TzaError {
    Archive::parse(bytes).expect_err("the archive is malformed")
}

/// The byte where the table's first entry's `field` starts in `good()`:
/// offsets into the entry of `c.weight` (name length 8).
fn entry_field(bytes: &[u8], field: &str) -> usize {
    let table = u64::from_le_bytes(bytes[4..12].try_into().unwrap()) as usize;
    let entry = table + 4;
    entry
        + match field {
            "ndims" => 2 + 8,
            "dims" => 2 + 8 + 1,
            "layout" => 2 + 8 + 1 + 16,
            "dtype" => 2 + 8 + 1 + 16 + 4,
            "offset" => 2 + 8 + 1 + 16 + 4 + 1,
            _ => unreachable!(),
        }
}

#[test]
fn reads_tensors_and_values() {
    let a = Archive::parse(good()).unwrap();
    let names: Vec<&str> = a.tensors().iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["c.weight", "c.bias"]);
    let w = a.get("c.weight").unwrap();
    assert_eq!((w.dims.as_slice(), w.layout, w.dtype), (&[2, 3, 3, 3][..], Layout::Oihw, DType::F16));
    let values = a.values(w);
    assert_eq!(values.len(), 54);
    assert_eq!((values[0], values[1], values[53]), (-4.0, -3.75, 9.25));
    let b = a.get("c.bias").unwrap();
    assert_eq!((b.layout, b.dtype, a.values(b)), (Layout::X, DType::F32, vec![1.5, -2.0]));
    assert!(a.get("c.missing").is_none());
}

#[test]
fn every_truncation_is_an_error_at_the_cut() {
    let bytes = good();
    let table = u64::from_le_bytes(bytes[4..12].try_into().unwrap()) as usize;
    // Cutting into the data makes the table offset point past the end;
    // cutting into the table leaves a field unfinished.
    for len in 0..bytes.len() {
        let e = err(bytes[..len].to_vec());
        match e.kind {
            TzaErrorKind::Truncated { len: l, .. } => {
                assert_eq!(l, len as u64);
                assert!(e.at as usize <= len, "{e}");
            }
            TzaErrorKind::TableOffset { .. } => assert!(len < table, "{e}"),
            _ => panic!("cut at {len}: {e}"),
        }
    }
    let e = err(bytes[..7].to_vec());
    assert_eq!(e.to_string(), "at byte 4: expected the tensor table offset (8 bytes), but the file ends at byte 7");
}

#[test]
fn refuses_wrong_magic_and_version() {
    let mut bytes = good();
    bytes[0] = 0x42;
    let e = err(bytes);
    assert_eq!((e.at, e.kind), (0, TzaErrorKind::Magic(0x4142)));
    let mut bytes = good();
    bytes[2] = 1;
    bytes[3] = 7;
    let e = err(bytes);
    assert_eq!(e.at, 2);
    assert_eq!(e.to_string(), "at byte 2: format version 1.7 is not supported: only major version 2 is");
}

#[test]
fn refuses_offsets_past_the_end() {
    let mut bytes = good();
    let len = bytes.len() as u64;
    bytes[4..12].copy_from_slice(&(len + 1).to_le_bytes());
    assert_eq!(err(bytes).kind, TzaErrorKind::TableOffset { offset: len + 1, len });

    let mut bytes = good();
    let at = entry_field(&bytes, "offset");
    bytes[at..at + 8].copy_from_slice(&(len - 10).to_le_bytes());
    let e = err(bytes);
    assert_eq!(e.at, at as u64);
    assert_eq!(e.kind, TzaErrorKind::DataPastEnd { name: "c.weight".into(), offset: len - 10, size: 108, len });

    // An offset so large that offset + size wraps.
    let mut bytes = good();
    bytes[at..at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(matches!(err(bytes).kind, TzaErrorKind::DataPastEnd { .. }));
}

#[test]
fn refuses_sizes_that_overflow_or_exceed_the_file() {
    // 10 GB claimed by a small file: refused by its size, nothing allocated.
    let mut bytes = good();
    let at = entry_field(&bytes, "dims");
    for (i, d) in [100_000u32, 50_000, 1, 1].iter().enumerate() {
        bytes[at + 4 * i..at + 4 * i + 4].copy_from_slice(&d.to_le_bytes());
    }
    let e = err(bytes);
    assert!(matches!(e.kind, TzaErrorKind::DataPastEnd { size: 10_000_000_000, .. }), "{e}");
    assert!(e.to_string().contains("claims 10000000000 bytes"), "{e}");
    // Dimensions whose product overflows 64 bits.
    let mut bytes = good();
    bytes[at..at + 16].fill(0xFF);
    let e = err(bytes);
    assert_eq!(e.at as usize, entry_field(&good(), "ndims") - 10);
    assert!(matches!(e.kind, TzaErrorKind::Overflow { .. }), "{e}");
}

#[test]
fn refuses_unknown_dtype_layout_and_names() {
    let mut bytes = good();
    let at = entry_field(&bytes, "dtype");
    bytes[at] = b'd';
    let e = err(bytes);
    assert_eq!(e.at, at as u64);
    assert_eq!(e.kind, TzaErrorKind::DType { name: "c.weight".into(), found: "d".into() });

    let mut bytes = good();
    let at = entry_field(&bytes, "layout");
    bytes[at..at + 4].copy_from_slice(b"ohwi");
    let e = err(bytes);
    assert_eq!(e.at, at as u64);
    assert_eq!(e.kind, TzaErrorKind::Layout { name: "c.weight".into(), layout: "ohwi".into() });

    let mut bytes = good();
    let at = entry_field(&bytes, "ndims") - 8;
    bytes[at] = 0xFF;
    let e = err(bytes);
    assert_eq!((e.at, e.kind), (at as u64, TzaErrorKind::NameEncoding));
}

#[test]
fn refuses_duplicate_names() {
    let b = f32s(&[1.0]);
    let bytes = write(&[("x.bias", &[1], "x", b'f', &b), ("y.bias", &[1], "x", b'f', &b), ("x.bias", &[1], "x", b'f', &b)]);
    let e = err(bytes);
    let TzaErrorKind::Duplicate { name, first } = &e.kind else { panic!("{e}") };
    assert_eq!(name, "x.bias");
    assert!(*first < e.at);
}

#[test]
fn errors_are_located_diagnostics() {
    let mut bytes = good();
    bytes[2] = 3;
    let d = err(bytes).diagnostic("weights/bad.tza");
    assert_eq!(d.code, crate::diag::Code::Weights);
    assert_eq!(d.location, Some(crate::diag::Location::file_start("weights/bad.tza")));
    assert!(d.message.starts_with("at byte 2: format version 3.0"), "{}", d.message);

    let dir = tempfile::tempdir().unwrap();
    let d = read(&dir.path().join("none.tza"), "none.tza").unwrap_err();
    assert_eq!((d.code, d.file()), (crate::diag::Code::Io, Some("none.tza")));
}

/// OIDN's own weights (v2.2-era `rt_ldr_alb_nrm`), as the project keeps
/// them beside the repository.
#[test]
fn reads_oidn_weights() {
    let path = crate::denoise::testing::weights("rt_ldr_alb_nrm.tza");
    let a = read(&path, "rt_ldr_alb_nrm.tza").unwrap();
    assert_eq!(a.tensors().len(), 32);
    let w = a.get("enc_conv0.weight").unwrap();
    assert_eq!((w.dims.as_slice(), w.layout, w.dtype), (&[32, 9, 3, 3][..], Layout::Oihw, DType::F16));
    let b = a.get("dec_conv0.bias").unwrap();
    assert_eq!((b.dims.as_slice(), b.layout), (&[3][..], Layout::X));
    assert!(a.values(w).iter().all(|v| v.is_finite()));
}
