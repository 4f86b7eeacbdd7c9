//! `loupe denoise`: OIDN's weights and the denoiser's test images through
//! the binary, every output format, and the exit codes of bad input.

use loupe_tests::{Project, repo};

pub(crate) fn fixture(name: &str) -> String {
    repo().join("server/src/denoise/fixtures").join(name).display().to_string()
}

/// OIDN's weights as the repository ships them.
pub(crate) fn weights(name: &str) -> String {
    loupe_tests::oidn_weights(name).display().to_string()
}

#[test]
fn denoises_into_every_format() {
    let p = Project::empty("denoise");
    let (w, color, albedo, normal) = (weights("rt_ldr_alb_nrm.tza"), fixture("color.pfm"), fixture("albedo.pfm"), fixture("normal.pfm"));
    let root = repo().display().to_string();
    for out in ["out.pfm", "out.exr", "out.png"] {
        let args =
            ["denoise", "--root", &root, "--weights", &w, "--color", &color, "--albedo", &albedo, "--normal", &normal, "--ldr", "-o", out];
        let run = p.run(&args);
        run.code(0)
            .stdout_has("32x24, colour, albedo and normal, input scale 1")
            .check(!run.stdout.contains("CPU reference"), "the GPU by default");
    }
    let cpu =
        ["denoise", "-d", "cpu", "--weights", &w, "--color", &color, "--albedo", &albedo, "--normal", &normal, "--ldr", "-o", "cpu.pfm"];
    p.run(&cpu).code(0).stdout_has("on the CPU reference");
    assert!(std::fs::read(p.path("out.pfm")).unwrap().starts_with(b"PF\n32 24\n"));
    assert_eq!(image::open(p.path("out.png")).unwrap().to_rgb8().dimensions(), (32, 24));
    assert!(std::fs::metadata(p.path("out.exr")).unwrap().len() > 32 * 24 * 12);

    let ldr = weights("rt_ldr.tza");
    p.run(&[
        "denoise",
        "--root",
        &root,
        "--weights",
        &ldr,
        "--color",
        &color,
        "--hdr",
        "--precision",
        "f16",
        "-o",
        "hdr.exr",
        "--dump-tensors",
        "t",
    ])
    .code(0)
    .stdout_has("29 tensors in t");
    let dumped = std::fs::read_dir(p.path("t")).unwrap().count();
    assert_eq!(dumped, 29);
    assert!(p.path("t/upsample4.npy").is_file());
}

#[test]
fn bad_input_has_exit_codes() {
    let p = Project::empty("denoise-bad");
    let (w, color) = (weights("rt_ldr.tza"), fixture("color.pfm"));
    p.write("cut.tza", &std::fs::read(&w).unwrap()[..1000]);
    p.run(&["denoise", "--weights", "cut.tza", "--color", &color, "--ldr", "-o", "o.pfm"]).code(1).stderr_has(
        "cut.tza:1:1: error[weights]: at byte 4: the tensor table is said to start at byte 1829504, past the end of the file (1000 bytes)",
    );
    p.write("bad.pfm", "PF\n2 2\n-1\n");
    p.run(&["denoise", "--weights", &w, "--color", "bad.pfm", "--ldr", "-o", "o.pfm"])
        .code(1)
        .stderr_has("error[image]: at byte 10: 2×2 pixels of 3 f32 take 48 bytes, but the file ends after 0")
        .stderr_has("bad.pfm:1:1");
    p.run(&["denoise", "--weights", &w, "--color", &color, "--albedo", &fixture("albedo.pfm"), "--ldr", "-o", "o.pfm"])
        .code(1)
        .stderr_has("error[weights]: these weights take colour, but colour and albedo were given");
    p.run(&["denoise", "--weights", &w, "--color", "missing.pfm", "--ldr", "-o", "o.pfm"]).code(2).stderr_has("error[io]");
    // The GPU's shaders are under --root (here the empty project).
    p.run(&["denoise", "--weights", &w, "--color", &color, "--ldr", "-o", "o.pfm"])
        .code(2)
        .stderr_has("error[io]: cannot read the shaders");
    p.run(&["denoise", "--weights", &w, "--color", &color, "--ldr", "--tile", "100", "-o", "o.pfm"]).code(2).stderr_has("not a tile side");
    p.run(&["denoise", "--weights", &w, "--color", &color, "--ldr", "-o", "no/such/dir/o.pfm"]).code(2).stderr_has("error[io]");
    for usage in [
        &["--color", &color, "-o", "o.pfm"][..],
        &["--color", &color, "--hdr", "--srgb", "-o", "o.pfm"],
        &["--color", &color, "--ldr", "--normal", &color, "-o", "o.pfm"],
        &["--color", &color, "--ldr", "--input-scale", "-1", "-o", "o.pfm"],
    ] {
        let mut args = vec!["denoise", "--weights", &w];
        args.extend_from_slice(usage);
        p.run(&args).code(2);
    }
    assert!(!p.path("o.pfm").exists());
}

/// The largest difference between two images' values.
fn max_difference(a: &std::path::Path, b: &std::path::Path) -> f32 {
    let read = |p: &std::path::Path| loupe::denoise::image::read(p, &p.display().to_string()).unwrap_or_else(|d| panic!("{d}"));
    let (a, b) = (read(a), read(b));
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.data.iter().zip(&b.data).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
}

/// Without --weights, the network loupe bundles for the range and the
/// inputs: in LDR, OIDN 2.5.1's own output for `rt_ldr.tza` and
/// `rt_ldr_alb_nrm.tza` (fixtures/README.md); in HDR, what `rt_hdr.tza`
/// named gives, not what `rt_ldr.tza` does; colour and albedo alone, which
/// no bundled network takes, an error at the albedo.
#[test]
fn without_weights_the_bundled_network_fits_the_range_and_inputs() {
    let p = Project::empty("denoise-bundled");
    let (color, albedo, normal) = (fixture("color.pfm"), fixture("albedo.pfm"), fixture("normal.pfm"));
    let root = repo().display().to_string();
    p.run(&["denoise", "--root", &root, "--color", &color, "--ldr", "-o", "ldr.exr"]).code(0).stdout_has("32x24, colour, input scale 1");
    p.run(&["denoise", "--root", &root, "--color", &color, "--albedo", &albedo, "--normal", &normal, "--ldr", "-o", "aux.exr"]).code(0);
    let oidn = |name: &str| std::path::PathBuf::from(fixture(name));
    for (ours, theirs) in [("ldr.exr", "oidn_ldr.pfm"), ("aux.exr", "oidn_ldr_alb_nrm.pfm")] {
        let d = max_difference(&p.path(ours), &oidn(theirs));
        assert!(d < 1e-3, "{ours} is {d} from OIDN's {theirs}");
    }
    assert!(max_difference(&p.path("ldr.exr"), &oidn("oidn_ldr_alb_nrm.pfm")) > 1e-2, "the two networks differ: the check can tell");

    let hdr = |weights: Option<String>, out: &str| {
        let mut args = vec!["denoise", "-d", "cpu", "--color", &color, "--hdr", "-o", out];
        if let Some(w) = &weights {
            args.extend(["--weights", w.as_str()]);
        }
        p.run(&args).code(0);
        p.path(out)
    };
    let (bundled, named, ldr) =
        (hdr(None, "hdr.pfm"), hdr(Some(weights("rt_hdr.tza")), "named.pfm"), hdr(Some(weights("rt_ldr.tza")), "l.pfm"));
    assert_eq!(std::fs::read(&bundled).unwrap(), std::fs::read(&named).unwrap(), "--hdr: rt_hdr.tza");
    assert!(max_difference(&bundled, &ldr) > 1e-2, "not rt_ldr.tza");

    p.run(&["denoise", "-d", "cpu", "--color", &color, "--albedo", &albedo, "--ldr", "-o", "o.pfm"])
        .code(1)
        .stderr_has("albedo.pfm:1:1: error[weights]: loupe bundles OIDN's networks for colour alone and for colour, albedo and normal; none takes colour and albedo");
    assert!(!p.path("o.pfm").exists());
}
