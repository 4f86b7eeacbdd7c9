use super::*;
use crate::denoise::testing::weights;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/denoise/fixtures").join(name)
}

fn job(weights_file: &str, aux: bool, mode: Mode, output: PathBuf) -> Job {
    Job {
        weights: weights(weights_file),
        color: fixture("color.pfm"),
        albedo: aux.then(|| fixture("albedo.pfm")),
        normal: aux.then(|| fixture("normal.pfm")),
        mode,
        input_scale: None,
        precision: Precision::F32,
        output,
        dump_tensors: None,
    }
}

/// Peak signal-to-noise ratio of `a` against `reference`, the peak the
/// larger of 1 and the reference's maximum.
fn psnr(a: &Image, reference: &Image) -> f64 {
    let mse = a.data.iter().zip(&reference.data).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>() / a.data.len() as f64;
    let peak = reference.data.iter().fold(1.0f32, |m, v| m.max(*v)) as f64;
    10.0 * (peak * peak / mse).log10()
}

/// OIDN 2.5.1's own output on the same 32×24 image (fixtures/README.md):
/// the same up to float rounding (about 140 dB measured; 100 dB asked).
#[test]
fn matches_oidn_ldr() {
    let dir = tempfile::tempdir().unwrap();
    for (weights_file, aux, reference) in
        [("rt_ldr_alb_nrm.tza", true, "oidn_ldr_alb_nrm.pfm"), ("rt_ldr.tza", false, "oidn_ldr.pfm")]
    {
        let out = dir.path().join("out.pfm");
        let report = run(&job(weights_file, aux, Mode::Ldr, out.clone())).unwrap();
        assert_eq!((report.width, report.height, report.input_scale), (32, 24, 1.0));
        let ours = image::read(&out, "out").unwrap();
        let theirs = image::read(&fixture(reference), reference).unwrap();
        let db = psnr(&ours, &theirs);
        assert!(db > 100.0, "{weights_file}: {db:.1} dB against OIDN");
        // ... and the denoiser did something: the noisy input is far off.
        let noisy = image::read(&fixture("color.pfm"), "color").unwrap();
        let clamped = Image { data: noisy.data.iter().map(|v| v.clamp(0.0, 1.0)).collect(), ..noisy };
        assert!(psnr(&clamped, &theirs) < 40.0);
    }
}

/// HDR (PU transfer, autoexposure) with the LDR weights, against pixels of
/// `oidnDenoise -d cpu --hdr color.pfm --alb albedo.pfm --nrm normal.pfm
/// -w rt_ldr_alb_nrm.tza` (OIDN 2.5.1): its brightest and darkest pixels
/// and a corner.
#[test]
fn matches_oidn_hdr() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let report = run(&job("rt_ldr_alb_nrm.tza", true, Mode::Hdr, out.clone())).unwrap();
    assert!(report.input_scale != 1.0, "autoexposure chose {}", report.input_scale);
    let ours = image::read(&out, "out").unwrap();
    let oidn = [
        ((31, 1), [5.982_078, 5.351_539_6, 5.136_591_4]),
        ((0, 10), [0.057_281_05, 0.056_842_916, 0.128_387_75]),
        ((31, 23), [0.129_826_35, 0.102_893_8, 0.133_941_66]),
    ];
    for ((x, y), want) in oidn {
        for (got, want) in ours.pixel(x, y).iter().zip(want) {
            assert!((got - want).abs() < 1e-4 * want.max(1.0), "({x}, {y}): {got} != {want}");
        }
    }
}

#[test]
fn dumps_every_tensor_as_npy() {
    let dir = tempfile::tempdir().unwrap();
    let mut j = job("rt_ldr.tza", false, Mode::Ldr, dir.path().join("out.pfm"));
    j.dump_tensors = Some(dir.path().join("tensors"));
    j.precision = Precision::F16;
    let report = run(&j).unwrap();
    assert_eq!(report.tensors_dumped, 29);
    let npy = std::fs::read(dir.path().join("tensors/concat4.npy")).unwrap();
    let header = String::from_utf8_lossy(&npy[10..128]);
    // The padded 32×32 image at level 3: 4×4, 96 + 64 channels.
    assert!(header.contains("'shape': (4, 4, 160)"), "{header}");
    assert!(dir.path().join("tensors/input.npy").is_file() && dir.path().join("tensors/dec_conv0.npy").is_file());
}

#[test]
fn png_colour_is_srgb_decoded_unless_srgb() {
    let dir = tempfile::tempdir().unwrap();
    let color = image::read(&fixture("color.pfm"), "color").unwrap();
    let encoded = Image { data: color.data.iter().map(|v| Transfer::Srgb.forward(v.clamp(0.0, 1.0))).collect(), ..color };
    let png = dir.path().join("color.png");
    image::write(&png, &encoded).unwrap();
    // LDR from the PNG and from the PFM agree up to the PNG's 8 bits.
    let (from_png, from_pfm) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let mut j = job("rt_ldr.tza", false, Mode::Ldr, from_png.clone());
    j.color = png.clone();
    run(&j).unwrap();
    run(&job("rt_ldr.tza", false, Mode::Ldr, from_pfm.clone())).unwrap();
    let (a, b) = (image::read(&from_png, "a").unwrap(), image::read(&from_pfm, "b").unwrap());
    assert!(psnr(&a, &b) > 35.0, "{}", psnr(&a, &b));
    // --srgb: the network sees the PNG's values as they are and they are
    // written back as they come, which is what decoding, the sRGB transfer
    // into the network and back, and encoding did: the same 8 bits.
    j.mode = Mode::LdrSrgb;
    run(&j).unwrap();
    assert_eq!(image::read(&from_png, "a").unwrap(), a);

    // In float files --srgb means the values are encoded: encoded values
    // with it denoise to the encoding of what linear ones without it do.
    let encoded_pfm = dir.path().join("encoded.pfm");
    image::write(&encoded_pfm, &encoded).unwrap();
    let (srgb_out, linear_out) = (dir.path().join("s.pfm"), dir.path().join("l.pfm"));
    let mut j = job("rt_ldr.tza", false, Mode::LdrSrgb, srgb_out.clone());
    j.color = encoded_pfm;
    run(&j).unwrap();
    run(&job("rt_ldr.tza", false, Mode::Ldr, linear_out.clone())).unwrap();
    let s = image::read(&srgb_out, "s").unwrap();
    let l = image::read(&linear_out, "l").unwrap();
    let l_encoded = Image { data: l.data.iter().map(|v| Transfer::Srgb.forward(*v)).collect(), ..l.clone() };
    assert!(psnr(&s, &l_encoded) > 90.0, "{}", psnr(&s, &l_encoded));
    assert!(psnr(&s, &l) < 30.0);
}

#[test]
fn inputs_must_fit_the_weights_and_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.pfm");
    let d = run(&job("rt_ldr.tza", true, Mode::Ldr, out.clone())).unwrap_err();
    assert_eq!(d.code, Code::Weights);
    assert_eq!(d.message, "these weights take colour, but colour, albedo and normal were given");
    let mut j = job("rt_ldr_alb_nrm.tza", true, Mode::Ldr, out.clone());
    j.normal = None;
    assert_eq!(run(&j).unwrap_err().message, "these weights take colour, albedo and normal, but colour and albedo were given");
    j.albedo = None;
    j.normal = Some(fixture("normal.pfm"));
    let d = run(&j).unwrap_err();
    assert_eq!((d.code, d.file().map(|f| f.ends_with("normal.pfm"))), (Code::Image, Some(true)));

    let small = dir.path().join("small.pfm");
    image::write(&small, &Image { width: 2, height: 2, data: vec![0.5; 12] }).unwrap();
    let mut j = job("rt_ldr_alb_nrm.tza", true, Mode::Ldr, out.clone());
    j.albedo = Some(small.clone());
    let d = run(&j).unwrap_err();
    assert_eq!(d.message, "the image is 2×2, but the colour is 32×24");
    assert_eq!(d.file(), Some(small.display().to_string().as_str()));

    let bad = dir.path().join("bad.tza");
    std::fs::write(&bad, b"\xD7\x41\x02\x00").unwrap();
    let mut j = job("rt_ldr.tza", false, Mode::Ldr, out);
    j.weights = bad;
    let d = run(&j).unwrap_err();
    assert_eq!((d.code, d.message.as_str()), (Code::Weights, "at byte 4: expected the tensor table offset (8 bytes), but the file ends at byte 4"));
}
