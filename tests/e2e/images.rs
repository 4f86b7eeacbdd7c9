//! `loupe check`'s image gate (docs/images.md) on copies of the repository
//! with tiny cases: a shader change that alters the frame fails and names
//! its case, one within noise passes, blessing makes it pass, and bad
//! references and outputs are diagnostics at the case's line.

use loupe_tests::{Project, Run};
use serde_json::Value;

const TONEMAP: &str = "shaders/post/tonemap.wgsl";
/// The tonemapper's input, to scale in the shader.
const INPUT: &str = "let c = max(texel.rgb, vec3(0.0));";

/// A copy of the repository's shaders and scenes with `cases` as its
/// loupe.toml. The source gate checks one scene only, so that each run
/// costs little more than its images.
fn project(name: &str, cases: &str) -> Project {
    let p = Project::copy_of_repo(name);
    p.write("loupe.toml", format!("[check]\npaths = [\"scenes/pattern.toml\"]\n\n{cases}"));
    p
}

/// The test pattern, small: an HDR ramp, colour bars and a 1-pixel checker
/// through exposure and the tonemapper.
const PATTERN: &str = "[[images]]\nname = \"pattern\"\nscene = \"scenes/pattern.toml\"\nsize = \"64x36\"\n";

/// The JSON lines of a run: diagnostics, and image cases (with `image`).
fn json(run: &Run) -> (Vec<Value>, Vec<Value>) {
    let lines: Vec<Value> = run.stdout.lines().map(|l| serde_json::from_str(l).expect("each line is JSON")).collect();
    lines.into_iter().partition(|v| v.get("image").is_none())
}

/// The repository's tonemapper with its input scaled by `factor`.
fn scale_tonemap_input(p: &Project, factor: &str) {
    let shader = std::fs::read_to_string(loupe_tests::repo().join(TONEMAP)).unwrap();
    assert!(shader.contains(INPUT), "{TONEMAP} changed: the test edits `{INPUT}`");
    p.write(TONEMAP, shader.replace(INPUT, &format!("let c = max(texel.rgb * {factor}, vec3(0.0));")));
}

#[test]
fn a_changed_tonemapper_fails_the_case_a_change_within_noise_passes_and_blessing_accepts_it() {
    let p = project("images-tonemap", PATTERN);
    let reference = p.path("tests/images/pattern/tonemap.color.png");
    let bless = p.run(&["check", "--bless", "--no-timings"]);
    bless.code(0).stdout_has("image pattern: blessed; tonemap/color new");
    bless.check(reference.exists(), "the reference was written");
    p.run(&["check", "--no-timings"]).code(0).stdout_has("image pattern: passed");

    // A constant in the tonemapper: the frame darkens.
    scale_tonemap_input(&p, "0.6");
    let run = p.run(&["check", "--no-timings", "--color", "never"]);
    run.code(1).stdout_has("image pattern: failed").stdout_has("error[image-mismatch]: `tonemap/color` differs from its reference");
    run.stdout_has("loupe.toml:4:1").stdout_has("loupe check --bless pattern");
    // An excerpt of the case in loupe.toml, as every other diagnostic has.
    run.stdout_has("[[images]]\n  │ ^^^^^^^^^^ in this image case");
    let report = std::fs::read_to_string(p.path("target/loupe-images/report.html")).expect("report.html is written on a failure");
    for image in ["reference", "actual", "flip", "side-by-side"] {
        let rel = format!("pattern/tonemap.color.{image}.png");
        run.check(report.contains(&format!("src=\"{rel}\"")), &format!("report.html shows {rel}"));
        let png = image::open(p.path(&format!("target/loupe-images/{rel}"))).expect("a PNG");
        let width = if image == "side-by-side" { 3 * 64 + 2 * 4 } else { 64 };
        assert_eq!((png.width(), png.height()), (width, 36), "{rel}");
    }
    run.check(report.contains("FLIP mean"), "report.html has the figures");
    let (_, cases) = json(&p.run(&["check", "--format", "json"]));
    let mean = cases[0]["outputs"][0]["flip"]["mean"].as_f64().expect("the figures");
    assert!(mean > 0.01, "the mean exceeds the default threshold: {mean}");

    // Within noise: a change no one can see passes, and the report goes.
    scale_tonemap_input(&p, "0.999");
    p.run(&["check", "--no-timings"]).code(0).stdout_has("image pattern: passed");
    assert!(!p.path("target/loupe-images/report.html").exists(), "a passing run leaves no stale report");

    // The intended change, blessed, passes; blessing again changes nothing.
    scale_tonemap_input(&p, "0.6");
    p.run(&["check", "--bless", "pattern"]).code(0).stdout_has("tonemap/color changed: FLIP mean");
    let blessed = std::fs::read(&reference).unwrap();
    p.run(&["check", "--bless"]).code(0).stdout_has("tonemap/color unchanged");
    assert_eq!(std::fs::read(&reference).unwrap(), blessed, "an unchanged reference is not rewritten");
    p.run(&["check"]).code(0).stdout_has("image pattern: passed");
    // A plain check never writes a reference.
    std::fs::remove_file(&reference).unwrap();
    p.run(&["check"]).code(1);
    assert!(!reference.exists());
}

#[test]
fn a_missing_reference_fails_naming_the_bless_command() {
    let p = project("images-missing", PATTERN);
    let run = p.run(&["check", "--no-timings", "--color", "never"]);
    run.code(1).stdout_has("error[reference-missing]").stdout_has("tests/images/pattern/tonemap.color.png does not exist");
    run.stdout_has("`loupe check --bless pattern`").stdout_has("image pattern: failed");
    // What a bless would write is there to look at.
    assert!(p.path("target/loupe-images/pattern/tonemap.color.actual.png").exists());
    p.run(&["check", "--bless", "nosuch"]).code(2).stderr_has("no image case named nosuch").stderr_has("pattern");
    p.run(&["check", "--no-images"]).code(0);
}

#[test]
fn bad_references_outputs_and_scenes_are_diagnostics_at_their_case() {
    let cases = "[[images]]\nname = \"small\"\nscene = \"scenes/pattern.toml\"\nsize = \"64x36\"\n\n\
                 [[images]]\nname = \"corrupt\"\nscene = \"scenes/pattern.toml\"\nsize = \"64x36\"\n\n\
                 [[images]]\nname = \"hdr\"\nscene = \"scenes/pattern.toml\"\nsize = \"64x36\"\noutputs = [\"test_pattern/color\"]\n\n\
                 [[images]]\nname = \"output\"\nscene = \"scenes/pattern.toml\"\nsize = \"64x36\"\noutputs = [\"tonemap/nope\"]\n\n\
                 [[images]]\nname = \"scene\"\nscene = \"scenes/nope.toml\"\nsize = \"64x36\"\n";
    let p = project("images-bad", cases);
    p.run(&["check", "--bless", "small", "corrupt", "hdr"]).code(0);
    // A reference of another size, a PNG cut short, an EXR of garbage.
    let small = p.path("tests/images/small/tonemap.color.png");
    let (w, h) = (32, 18);
    image::RgbImage::new(w, h).save(&small).unwrap();
    let corrupt = p.path("tests/images/corrupt/tonemap.color.png");
    let bytes = std::fs::read(&corrupt).unwrap();
    std::fs::write(&corrupt, &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(p.path("tests/images/hdr/test_pattern.color.exr"), b"not an exr").unwrap();

    let run = p.run(&["check", "--format", "json"]);
    run.code(1);
    let (diagnostics, cases) = json(&run);
    // Each case's line, three lines on for loupe.toml's [check].
    let at = |line: u64, needle: &str| {
        let found =
            diagnostics.iter().any(|d| d["file"] == "loupe.toml" && d["line"] == line && d["message"].as_str().unwrap().contains(needle));
        run.check(found, &format!("a diagnostic at loupe.toml:{line} saying {needle:?}"));
    };
    at(4, "is 32x18, but the case renders `tonemap/color` at 64x36");
    at(9, "cannot read the PNG file");
    at(14, "cannot read the OpenEXR file");
    at(24, "has no image output `tonemap/nope`");
    at(26, "scenes/nope.toml");
    assert_eq!(cases.len(), 5);
    for case in &cases {
        assert_eq!(case["verdict"], "failed", "never a pass: {case}");
    }
}

#[test]
fn shards_cover_every_case_once_and_each_format_parses() {
    let cases: String =
        (0..5).map(|i| format!("[[images]]\nname = \"c{i}\"\nscene = \"scenes/pattern.toml\"\nsize = \"{}x8\"\n\n", 8 + i)).collect();
    let p = project("images-shards", &cases);
    let names = |run: &Run| -> Vec<String> { json(run).1.iter().map(|c| c["image"].as_str().unwrap().to_owned()).collect() };
    let first = p.run(&["check", "--format", "json", "--shard", "1/2"]);
    let second = p.run(&["check", "--format", "json", "--shard", "2/2"]);
    let (mut a, b) = (names(&first), names(&second));
    assert_eq!((a.clone(), b.clone()), (vec!["c0".to_owned(), "c2".into(), "c4".into()], vec!["c1".to_owned(), "c3".into()]));
    a.extend(b);
    a.sort();
    assert_eq!(a, ["c0", "c1", "c2", "c3", "c4"]);
    p.run(&["check", "--shard", "3/2"]).code(2);

    // Every case fails for want of a reference; every format says so.
    let sarif: Value = serde_json::from_str(&p.run(&["check", "--format", "sarif", "--shard", "1/2"]).stdout).expect("SARIF is JSON");
    let results = sarif["runs"][0]["results"].as_array().unwrap();
    let missing: Vec<&Value> = results.iter().filter(|r| r["ruleId"] == "reference-missing").collect();
    assert_eq!(missing.len(), 3, "{results:?}");
    let location = &missing[0]["locations"][0]["physicalLocation"];
    assert_eq!(location["artifactLocation"]["uri"], "loupe.toml");
    assert_eq!(location["region"]["startLine"], 4, "the first case's line, after [check]");
    let junit = p.run(&["check", "--format", "junit", "--jobs", "2"]);
    junit.code(1);
    assert_eq!(junit.stdout.matches("<testcase classname=\"loupe.images\"").count(), 5, "{}", junit.stdout);
    assert_eq!(junit.stdout.matches("type=\"reference-missing\"").count(), 5, "{}", junit.stdout);
    let github = p.run(&["check", "--format", "github", "--shard", "2/2"]);
    assert_eq!(github.stdout.lines().filter(|l| l.starts_with("::error file=loupe.toml") && l.contains("reference-missing")).count(), 2);
}

#[test]
fn without_a_device_every_case_is_skipped_never_passed() {
    let p = project("images-no-device", PATTERN);
    let run = super::no_adapter::without_adapter(&p.root, &["check", "--no-timings", "--format", "junit"]);
    run.code(0);
    run.check(run.stdout.contains(r#"<testcase classname="loupe.images" name="pattern""#), "a test case for the image case");
    run.check(run.stdout.contains(r#"<skipped message="no device: the image cases need one"/>"#), "skipped, with the reason");
    run.check(run.stdout.contains(r#"skipped="1""#), "counted as skipped");
    let human = super::no_adapter::without_adapter(&p.root, &["check", "--no-timings"]);
    human.stdout_has("image pattern: skipped (no device: the image cases need one)").stdout_has("1 image case: 1 skipped");
    super::no_adapter::without_adapter(&p.root, &["check", "--images"]).code(3).stderr_has("mesa-vulkan-drivers");
    // With --no-device they are skipped as well; with --no-images, not run.
    p.run(&["check", "--no-device", "--no-timings"]).code(0).stdout_has("image pattern: skipped (--no-device)");
    let none = p.run(&["check", "--no-images", "--no-timings"]);
    none.check(!none.stdout.contains("image pattern"), "--no-images runs no case");
}
