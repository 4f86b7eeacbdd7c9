//! `loupe check`: formats, exit codes, bad input.

use loupe_tests::{Project, loupe, repo};

/// A project whose error sits inside an imported module, at util.wgsl:5:16.
fn import_error_project() -> Project {
    let p = Project::empty("import-error");
    p.write(
        "shaders/lib/util.wgsl",
        "#define_import_path demo::util\n\nfn scale(x: f32) -> f32 {\n    let k = 2u;\n    return x * k;\n}\n",
    );
    p.write(
        "shaders/main.wgsl",
        "#import demo::util::scale\n\n@fragment\nfn fs_main() -> @location(0) vec4<f32> {\n    return vec4(scale(0.5));\n}\n",
    );
    p
}

const UTIL: &str = "shaders/lib/util.wgsl";

#[test]
fn project_shaders_are_clean_with_pipelines_created() {
    let run = loupe(&repo(), &["check", "--no-timings"]);
    run.code(0).stdout_has("0 errors");
    // With a device, the repository's image cases (loupe.toml) render and
    // match their references.
    run.stdout_has("; 5 image cases: 5 passed").stdout_has("image showcase-raster-320x180: passed");
    // With a device (lavapipe here), every pipeline spec is created.
    run.check(run.stdout.contains("pipelines on"), "expected pipelines to be created on an adapter");
    // The default paths hold the scenes too, each one checked.
    let junit = loupe(&repo(), &["check", "--no-device", "--format", "junit"]);
    junit.code(0);
    for scene in ["minimal", "pattern", "showcase", "volume"] {
        junit.check(junit.stdout.contains(&format!("name=\"scenes/{scene}.toml\"")), &format!("scenes/{scene}.toml was checked"));
    }
}

#[test]
fn human_reports_error_in_imported_module_at_its_line() {
    let p = import_error_project();
    let run = p.run(&["check", "--no-device", "--color", "never"]);
    run.code(1).stdout_has(&format!("{UTIL}:5:")).stdout_has("return x * k;").stdout_has("1 error");
}

#[test]
fn json_lines_carry_every_field() {
    let p = import_error_project();
    let run = p.run(&["check", "--no-device", "--format", "json"]);
    run.code(1);
    let diags: Vec<serde_json::Value> = run.stdout.lines().map(|l| serde_json::from_str(l).expect("each line is JSON")).collect();
    let d = diags.iter().find(|d| d["file"] == UTIL).unwrap_or_else(|| panic!("no diagnostic in {UTIL}: {}", run.stdout));
    assert_eq!(d["line"], 5);
    assert!(d["column"].as_u64().unwrap() >= 12);
    for field in ["end_line", "end_column", "severity", "code", "message", "labels", "notes"] {
        assert!(d.get(field).is_some(), "missing {field}: {d}");
    }
    assert_eq!(d["severity"], "error");
    assert_eq!(d["code"], "validation");
}

#[test]
fn github_annotations_point_at_the_module() {
    let p = import_error_project();
    let run = p.run(&["check", "--no-device", "--format", "github"]);
    run.code(1);
    let line = run.stdout.lines().find(|l| l.starts_with("::error ")).unwrap_or_else(|| panic!("{}", run.stdout));
    run.check(line.contains(&format!("file={UTIL},line=5,col=")), "annotation names util.wgsl line 5");
}

#[test]
fn sarif_has_required_fields_and_locations() {
    let p = import_error_project();
    let run = p.run(&["check", "--no-device", "--format", "sarif"]);
    run.code(1);
    let v: serde_json::Value = serde_json::from_str(&run.stdout).expect("SARIF is JSON");
    assert_eq!(v["version"], "2.1.0");
    assert!(v["$schema"].as_str().unwrap().contains("sarif"));
    let run0 = &v["runs"][0];
    assert_eq!(run0["tool"]["driver"]["name"], "loupe");
    let rules = run0["tool"]["driver"]["rules"].as_array().unwrap();
    let result = &run0["results"][0];
    let rule_index = result["ruleIndex"].as_u64().unwrap() as usize;
    assert_eq!(rules[rule_index]["id"], result["ruleId"]);
    assert_eq!(result["level"], "error");
    assert!(result["message"]["text"].as_str().is_some_and(|t| !t.is_empty()));
    let loc = &result["locations"][0]["physicalLocation"];
    assert_eq!(loc["artifactLocation"]["uri"], UTIL);
    assert_eq!(loc["region"]["startLine"], 5);
    assert!(loc["region"]["startColumn"].as_u64().is_some());
}

#[test]
fn junit_has_one_testcase_per_module_and_a_failure() {
    let p = import_error_project();
    let run = p.run(&["check", "--no-device", "--format", "junit"]);
    run.code(1);
    let xml = &run.stdout;
    run.check(xml.starts_with("<?xml"), "XML declaration first");
    assert_eq!(xml.matches("<testcase ").count(), 2, "{xml}");
    run.check(xml.contains(&format!("name=\"{UTIL}\"")), "a testcase for util.wgsl");
    run.check(xml.contains("<failure "), "a failure element");
    run.check(xml.contains(&format!("{UTIL}:5:")), "failure text names util.wgsl:5");
    // Balanced tags: every opened testcase/testsuite closes.
    for tag in ["testsuites", "testsuite"] {
        assert_eq!(xml.matches(&format!("<{tag} ")).count(), xml.matches(&format!("</{tag}>")).count(), "{tag} balanced");
    }
}

#[test]
fn bad_inputs_become_diagnostics_and_other_files_are_still_checked() {
    let p = Project::empty("bad-inputs");
    p.write("shaders/empty.wgsl", "");
    p.write("shaders/latin1.wgsl", b"fn f() -> f32 { return 1.0; } // caf\xe9\n".as_slice());
    p.write("shaders/huge.wgsl", vec![b' '; 10 << 20].iter().chain(b"fn f() {}\n").copied().collect::<Vec<u8>>());
    p.write("shaders/a.wgsl", "#define_import_path cyc::a\n#import cyc::b\nfn fa() {}\n");
    p.write("shaders/b.wgsl", "#define_import_path cyc::b\n#import cyc::a\nfn fb() {}\n");
    p.write("shaders/missing.wgsl", "#import no::such::module\n@fragment fn fs() -> @location(0) vec4<f32> { return vec4(1.0); }\n");
    let depth = 10_000;
    p.write("shaders/deep.wgsl", format!("fn f() -> f32 {{ return {}1.0{}; }}\n", "(".repeat(depth), ")".repeat(depth)));
    std::os::unix::fs::symlink("/nonexistent/target.wgsl", p.path("shaders/dangling.wgsl")).unwrap();
    p.write("shaders/good.wgsl", "@fragment\nfn fs_main() -> @location(0) vec4<f32> { return vec4(1.0); }\n");
    let run = p.run(&["check", "--no-device", "--format", "json"]);
    run.code(1);
    let diags: Vec<serde_json::Value> = run.stdout.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let code_of = |file: &str| -> Vec<String> {
        diags.iter().filter(|d| d["file"] == format!("shaders/{file}")).map(|d| d["code"].as_str().unwrap().to_owned()).collect()
    };
    assert_eq!(code_of("empty.wgsl"), ["empty-file"], "{}", run.stdout);
    assert_eq!(code_of("latin1.wgsl"), ["encoding"]);
    assert_eq!(code_of("huge.wgsl"), ["file-too-large"]);
    assert_eq!(code_of("dangling.wgsl"), ["io"]);
    assert!(code_of("missing.wgsl").contains(&"import-missing".to_owned()));
    assert!(code_of("a.wgsl").contains(&"import-cycle".to_owned()) || code_of("b.wgsl").contains(&"import-cycle".to_owned()));
    assert!(code_of("good.wgsl").is_empty(), "the valid file is clean");
    // The deep file finished one way or the other without killing the run.
    let junit = p.run(&["check", "--no-device", "--format", "junit"]);
    junit.check(junit.stdout.contains("name=\"shaders/good.wgsl\""), "good.wgsl was checked");
    junit.check(junit.stdout.contains("name=\"shaders/deep.wgsl\""), "deep.wgsl was checked");
}

#[test]
fn latin1_error_is_located_at_the_bad_byte() {
    let p = Project::empty("latin1");
    p.write("shaders/x.wgsl", b"fn f() -> f32 {\n  return 1.0; // caf\xe9\n}\n".as_slice());
    let run = p.run(&["check", "--no-device", "--format", "json"]);
    let d: serde_json::Value = serde_json::from_str(run.stdout.lines().next().unwrap()).unwrap();
    assert_eq!((d["line"].as_u64(), d["column"].as_u64()), (Some(2), Some(21)), "{d}");
}

#[test]
fn exit_codes() {
    let p = Project::empty("exit-codes");
    p.run(&["check", "does/not/exist"]).code(2).stderr_has("does/not/exist");
    p.run(&["check", "--no-such-flag"]).code(2);
    p.write("shaders/orphan.wgsl", "fn helper() -> f32 { return 1.0; }\n");
    p.run(&["check", "--no-device"]).code(0).stdout_has("1 warning");
    p.run(&["check", "--no-device", "--deny-warnings"]).code(1);
    // Every format agrees with the exit code: a denied warning is a failure.
    p.run(&["check", "--no-device", "--deny-warnings", "--format", "junit"]).code(1).stdout_has("failures=\"1\"");
    p.run(&["check", "--no-device", "--deny-warnings", "--format", "sarif"]).code(1).stdout_has("\"level\": \"error\"");
    loupe(&repo(), &["--version"]).code(0).stdout_has("loupe ");
    for sub in ["check", "serve"] {
        loupe(&repo(), &[sub, "--help"]).code(0).stdout_has("Usage:");
    }
}

#[test]
fn binding_that_the_renderer_does_not_bind_is_located() {
    let p = Project::copy_of_repo("binding");
    let path = "shaders/post/exposure.wgsl";
    let src = p.read(path).replace("@group(0) @binding(1) var hdr", "@group(0) @binding(5) var hdr");
    p.write(path, src);
    let run = p.run(&["check", "--format", "json"]);
    run.code(1);
    let d = binding_mismatch(&run.stdout);
    assert_eq!(d["file"], path);
    let line = p.read(path).lines().position(|l| l.contains("@binding(5)")).unwrap() + 1;
    assert_eq!(d["line"].as_u64(), Some(line as u64));
}

#[test]
fn uniform_struct_of_the_wrong_size_is_located() {
    // The bug that once blanked every frame: a vec3 pad aligns to 16 and
    // makes a 16-byte uniform struct 32 bytes.
    let p = Project::copy_of_repo("uniform-size");
    let path = "shaders/post/exposure.wgsl";
    let src = p.read(path).replace("    _pad0: f32,\n    _pad1: vec2<f32>,", "    _pad: vec3<f32>,");
    assert!(src.contains("_pad: vec3<f32>"), "the edit applies");
    p.write(path, src);
    let run = p.run(&["check", "--format", "json"]);
    run.code(1);
    let d = binding_mismatch(&run.stdout);
    assert_eq!(d["file"], path);
    let line = p.read(path).lines().position(|l| l.contains("var<uniform> exposure")).unwrap() + 1;
    assert_eq!(d["line"].as_u64(), Some(line as u64));
    let text = d.to_string();
    assert!(text.contains("32 bytes") && text.contains("16 bytes"), "{text}");
}

/// The first `binding-mismatch` of a JSON-lines report.
fn binding_mismatch(stdout: &str) -> serde_json::Value {
    stdout
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .find(|d| d["code"] == "binding-mismatch")
        .unwrap_or_else(|| panic!("no binding-mismatch: {stdout}"))
}

#[test]
fn clean_runs_print_no_error_lines() {
    // Without XDG_RUNTIME_DIR, creating a Vulkan instance on Mesa once made
    // libwayland print `error: XDG_RUNTIME_DIR is invalid or not set` for
    // every clean run: removed here so the test holds on a desktop too.
    let p = Project::copy_of_repo("quiet");
    for args in [&["check", "--no-timings"][..], &["render", "--scene", "scenes/minimal.toml", "--out", "out", "--size", "64x36"][..]] {
        let out = std::process::Command::new(loupe_tests::loupe_bin())
            .args(args)
            .current_dir(&p.root)
            .env_remove("XDG_RUNTIME_DIR")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "loupe {}: {stderr}", args.join(" "));
        let errors: Vec<&str> = stderr.lines().filter(|l| l.to_lowercase().contains("error")).collect();
        assert!(errors.is_empty(), "loupe {} printed error lines: {errors:?}", args.join(" "));
    }
}

/// A project with a clean shader and a scene whose fourth line holds an
/// unknown field.
fn broken_scene_project() -> Project {
    let p = Project::empty("bad-scene");
    p.write("shaders/ok.wgsl", "@fragment\nfn fs_main() -> @location(0) vec4<f32> { return vec4(1.0); }\n");
    p.write("scenes/bad.toml", "[output]\nwidth = 64\nheight = 64\ncolour = 1\n");
    p
}

#[test]
fn a_broken_scene_fails_the_run_at_its_line_and_column() {
    let p = broken_scene_project();
    p.run(&["check", "--no-device", "--color", "never"])
        .code(1)
        .stdout_has("error[scene]: unknown field `colour`")
        .stdout_has("scenes/bad.toml:4:1")
        .stdout_has("colour = 1")
        .stdout_has("1 error");
    let run = p.run(&["check", "--no-device", "--format", "json"]);
    run.code(1);
    let d: serde_json::Value = serde_json::from_str(run.stdout.lines().next().expect("one diagnostic")).unwrap();
    assert_eq!((d["file"].as_str(), d["line"].as_u64(), d["column"].as_u64()), (Some("scenes/bad.toml"), Some(4), Some(1)), "{d}");
    assert_eq!(d["code"], "scene");
    // Every other format carries it too.
    let github = p.run(&["check", "--no-device", "--format", "github"]);
    github.code(1).stdout_has("file=scenes/bad.toml,line=4,col=1");
    let sarif = p.run(&["check", "--no-device", "--format", "sarif"]);
    sarif.code(1).stdout_has("\"uri\": \"scenes/bad.toml\"");
    let junit = p.run(&["check", "--no-device", "--format", "junit"]);
    junit.code(1).stdout_has("name=\"scenes/bad.toml\"").stdout_has("<failure ");
}

#[test]
fn a_scene_named_on_the_command_line_is_checked_as_a_scene() {
    let p = broken_scene_project();
    let run = p.run(&["check", "--no-device", "--format", "json", "scenes/bad.toml"]);
    run.code(1);
    let codes: Vec<String> =
        run.stdout.lines().map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["code"].as_str().unwrap().to_owned()).collect();
    assert_eq!(codes, ["scene"], "the scene's error, not a WGSL parse error: {}", run.stdout);
}

#[test]
fn a_missing_gltf_is_located_at_the_mesh_value() {
    let p = Project::empty("missing-gltf");
    let scene = "[output]\nwidth = 64\nheight = 64\n\n[[materials]]\nname = \"m\"\n\n[[objects]]\nname = \"o\"\nmesh = \"meshes/nope.gltf\"\nmaterial = \"m\"\n";
    p.write("scenes/gone.toml", scene);
    let run = p.run(&["check", "--no-device", "--format", "json"]);
    run.code(1);
    let d: serde_json::Value = serde_json::from_str(run.stdout.lines().next().unwrap()).unwrap();
    assert_eq!((d["file"].as_str(), d["line"].as_u64(), d["column"].as_u64()), (Some("scenes/gone.toml"), Some(10), Some(8)), "{d}");
    assert!(d["message"].as_str().unwrap().contains("meshes/nope.gltf"), "{d}");
}

#[test]
fn toml_files_that_are_not_scenes_are_left_alone() {
    let p = Project::empty("not-scenes");
    p.write("shaders/ok.wgsl", "@fragment\nfn fs_main() -> @location(0) vec4<f32> { return vec4(1.0); }\n");
    p.write("loupe.toml", "[check]\ndeny_warnings = true\n");
    p.write("Cargo.toml", "[package]\nname = \"x\"\n");
    p.write("scenes/loupe.toml", "[check]\n");
    // Searching the whole project finds the shader, not the TOML files
    // outside scenes/, and never the project file.
    let run = p.run(&["check", "--no-device", "--format", "junit", "."]);
    run.code(0);
    assert_eq!(run.stdout.matches("<testcase ").count(), 1, "{}", run.stdout);
    run.check(!run.stdout.contains(".toml"), "no TOML file was checked");
}

/// A compute shader using f64 in a function's signature.
const F64_SHADER: &str =
    "fn twice(x: f64) -> f64 {\n    return x * 2.0;\n}\n\n@compute @workgroup_size(1)\nfn main() {\n    _ = twice(1.0);\n}\n";

#[test]
fn a_missing_capability_is_named_with_the_flag_that_allows_it() {
    let p = Project::empty("capabilities");
    p.write("shaders/wide.wgsl", F64_SHADER);
    let run = p.run(&["check", "--no-device", "--format", "json"]);
    run.code(1);
    let d: serde_json::Value = serde_json::from_str(run.stdout.lines().next().unwrap()).unwrap();
    let message = d["message"].as_str().unwrap();
    assert!(message.contains("`f64`") && message.contains("`float64` capability"), "{d}");
    assert!(d["notes"].to_string().contains("--capabilities float64"), "{d}");
    // At the type as written: line 1, `x: f64`.
    assert_eq!((d["file"].as_str(), d["line"].as_u64(), d["column"].as_u64()), (Some("shaders/wide.wgsl"), Some(1), Some(13)), "{d}");
    p.run(&["check", "--no-device", "--capabilities", "float64"]).code(0).stdout_has("0 errors");
    p.run(&["check", "--no-device", "--capabilities", "all"]).code(0);
    // A list replaces the default: f64 alone does not allow i64.
    p.write("shaders/wide.wgsl", F64_SHADER.replace("_ = twice(1.0);", "_ = twice(1.0);\n    let n: i64 = 1li;"));
    p.run(&["check", "--no-device", "--capabilities", "float64", "--color", "never"]).code(1).stdout_has("`shader-int64` capability");
    p.run(&["check", "--no-device", "--capabilities", "float64,shader-int64"]).code(0);
    let bad = p.run(&["check", "--no-device", "--capabilities", "float64,doubles"]);
    bad.code(2).stderr_has("unknown capability `doubles`").stderr_has("shader-int64").stderr_has("shader-float16");
}

#[test]
fn loupe_toml_sets_the_defaults_and_flags_override_them() {
    let p = Project::empty("project-file");
    p.write("src/wide.wgsl", F64_SHADER);
    p.write("src/orphan.wgsl", "fn helper() -> f32 { return 1.0; }\n");
    // No shaders/ or scenes/: only loupe.toml's paths lead to src/.
    p.write("loupe.toml", "[check]\npaths = [\"src\"]\ncapabilities = [\"float64\"]\nformat = \"json\"\n");
    let run = p.run(&["check", "--no-device"]);
    run.code(0);
    let d: serde_json::Value = serde_json::from_str(run.stdout.lines().next().expect("the orphan's warning, as JSON")).unwrap();
    assert_eq!((d["file"].as_str(), d["code"].as_str()), (Some("src/orphan.wgsl"), Some("unused-module")), "{d}");
    // Flags win: the format, the capabilities, the paths.
    p.run(&["check", "--no-device", "--format", "human"]).code(0).stdout_has("1 warning");
    p.run(&["check", "--no-device", "--capabilities", "shader-int64", "--format", "human"]).code(1).stdout_has("`float64` capability");
    p.run(&["check", "--no-device", "src/orphan.wgsl"]).code(0).stdout_has("\"src/orphan.wgsl\"");
    // deny_warnings, and the flag's way back.
    p.write("loupe.toml", "[check]\npaths = [\"src\"]\ncapabilities = \"all\"\ndeny_warnings = true\n");
    // A denied warning is an error in the output as in the exit code.
    p.run(&["check", "--no-device"]).code(1).stdout_has("error[unused-module]").stdout_has("1 error");
    p.run(&["check", "--no-device", "--deny-warnings=false"]).code(0).stdout_has("1 warning");
    p.write("loupe.toml", "[check]\npaths = [\"src\"]\ncapabilities = \"all\"\n");
    p.run(&["check", "--no-device", "--deny-warnings"]).code(1);
}

#[test]
fn a_bad_project_file_is_a_located_usage_error() {
    let p = Project::empty("bad-project-file");
    p.write("shaders/ok.wgsl", "@fragment\nfn fs_main() -> @location(0) vec4<f32> { return vec4(1.0); }\n");
    for (text, at, says) in [
        ("[check]\nformat = \"json\"\nfromat = \"json\"\n", "loupe.toml:3:1", "unknown key `fromat`"),
        ("[check]\ndeny_warnings = \"yes\"\n", "loupe.toml:2:17", "true or false"),
        ("[check]\nformat = \"xml\"\n", "loupe.toml:2:10", "not \"xml\""),
        ("[check]\ncapabilities = [\"f64\"]\n", "loupe.toml:2:17", "unknown capability `f64`"),
        ("[check]\npaths = \"shaders\"\n", "loupe.toml:2:9", "an array of paths"),
        ("[serve]\nport = 1\n", "loupe.toml:1:2", "unknown table `serve`"),
        ("[check\n", "loupe.toml:1:", "error[project-file]"),
    ] {
        p.write("loupe.toml", text);
        p.run(&["check", "--no-device"]).code(2).stderr_has(at).stderr_has(says).stderr_has("error[project-file]");
    }
}

/// A file name that is not UTF-8 (Latin-1 `café`): human output shows the
/// byte escaped, never U+FFFD; SARIF's URI holds the real byte, so it
/// names the file that exists.
#[cfg(unix)]
#[test]
fn a_file_name_that_is_not_utf8_is_shown_escaped_and_its_uri_is_real() {
    use std::os::unix::ffi::OsStrExt;
    let p = Project::empty("latin1-name");
    std::fs::create_dir_all(p.path("shaders")).expect("mkdir");
    let name = std::ffi::OsStr::from_bytes(b"caf\xe9.wgsl");
    std::fs::write(p.path("shaders").join(name), "fn f() -> f32 { return 1u; }\n").expect("write");
    let human = p.run(&["check", "--no-device", "--color", "never", "shaders"]);
    human.code(1).stdout_has("shaders/caf\\xE9.wgsl:1:").check(!human.stdout.contains('\u{fffd}'), "no U+FFFD in the output");
    let sarif = p.run(&["check", "--no-device", "--format", "sarif", "shaders"]);
    let log: serde_json::Value = serde_json::from_str(&sarif.stdout).expect("SARIF is JSON");
    let uri = log["runs"][0]["results"][0]["locations"][0]["physicalLocation"]["artifactLocation"]["uri"].as_str().expect("a URI");
    assert_eq!(uri, "shaders/caf%E9.wgsl", "{}", sarif.stdout);
    // Percent-decoded, the URI names the file on disk.
    let (mut bytes, mut rest) = (Vec::new(), uri.as_bytes());
    while let Some((&b, tail)) = rest.split_first() {
        match (b, tail.get(..2).and_then(|h| u8::from_str_radix(std::str::from_utf8(h).ok()?, 16).ok())) {
            (b'%', Some(byte)) => (bytes.push(byte), rest = &tail[2..]),
            _ => (bytes.push(b), rest = tail),
        };
    }
    assert!(p.root.join(std::ffi::OsStr::from_bytes(&bytes)).is_file(), "{uri}, decoded, is the file");
}

#[test]
fn material_files_are_checked_in_every_format() {
    let p = Project::empty("bad-material");
    p.write("scenes/materials/lib.mat", "param tint: color = grey(0.5)\nmaterial base = slab { base_color: tint }\n");
    p.write(
        "scenes/materials/bad.mat",
        "import \"lib.mat\"\n\nmaterial m = layer(\n    slab { specular_ior: 0.5 },\n    lib.base(tint: grey(0.2)),\n)\n",
    );
    let run = p.run(&["check", "--no-device", "--format", "json"]);
    run.code(1);
    let diags: Vec<serde_json::Value> = run.stdout.lines().map(|l| serde_json::from_str(l).expect("each line is JSON")).collect();
    let d = diags.iter().find(|d| d["code"] == "material").unwrap_or_else(|| panic!("no material diagnostic: {}", run.stdout));
    assert_eq!(
        (d["file"].as_str(), d["line"].as_u64(), d["column"].as_u64()),
        (Some("scenes/materials/bad.mat"), Some(4), Some(26)),
        "{d}"
    );
    assert_eq!(diags.len(), 1, "lib.mat is clean: {}", run.stdout);
    let at = "scenes/materials/bad.mat:4:26";
    p.run(&["check", "--no-device", "--color", "never"]).code(1).stdout_has("error[material]").stdout_has("scenes/materials/bad.mat:4:26");
    p.run(&["check", "--no-device", "--format", "github"]).code(1).stdout_has("file=scenes/materials/bad.mat,line=4,col=26");
    p.run(&["check", "--no-device", "--format", "sarif"]).code(1).stdout_has("\"ruleId\": \"material\"").stdout_has("\"startLine\": 4");
    p.run(&["check", "--no-device", "--format", "junit"]).code(1).stdout_has("name=\"scenes/materials/lib.mat\"").stdout_has(at);
    // The file named on the command line, alone.
    p.run(&["check", "--no-device", "--format", "json", "scenes/materials/bad.mat"]).code(1).stdout_has("\"code\":\"material\"");
}
