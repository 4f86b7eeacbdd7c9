use std::path::PathBuf;

use super::*;
use crate::shader::{Compose, Library, NagaOil, SourceFile, library};

fn shader_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shaders")
}

fn compose(lib: &Library, display: &str, defs: &crate::shader::ShaderDefs) -> Module {
    let file = lib.get(display).unwrap_or_else(|| panic!("{display} is in the library"));
    NagaOil.compose(lib, file, defs, naga::valid::Capabilities::all()).unwrap_or_else(|e| panic!("{display} {defs:?}: {e:?}")).module
}

/// `text` with each `(after, print)`'s print after the first line that
/// starts with `after`, and the directive on top.
fn with_prints(text: &str, prints: &[(&str, &str)]) -> String {
    let mut out = String::from("enable wgpu_debug_printf;\n");
    let mut done = vec![false; prints.len()];
    for line in text.lines() {
        out.push_str(line);
        out.push('\n');
        for ((after, print), done) in prints.iter().zip(&mut done) {
            if !*done && line.starts_with(after) {
                out.push_str(print);
                out.push('\n');
                *done = true;
            }
        }
    }
    assert!(done.iter().all(|d| *d), "a line starts with each of {prints:?}");
    out
}

/// The repository's shaders with prints added to the lighting pass (a
/// compute stage over a material module and many imports, whose functions
/// that take their pixel get a flag of their own) and to the fullscreen
/// test pattern (a fragment stage), and every shader that already holds a
/// print (the path tracer): each composes, and validates instrumented,
/// under every def set the renderer can ask for.
#[test]
fn every_shader_with_a_print_validates_instrumented() {
    let mut lib = library::read_tree(&shader_root()).unwrap();
    let program = crate::material::Program {
        definitions: vec![crate::material::shorthand(crate::diag::Location::file_start("test.toml"))],
        ..Default::default()
    };
    crate::render::session::material_module(&mut lib, &shader_root(), &program);
    let edits: [(&str, &[(&str, &str)]); 2] = [
        (
            "passes/lighting.wgsl",
            &[
                ("fn shade(", "    debugPrintf(\"texel %v2u at %v3f, lit %d\", texel, vec3(1.0), true);"),
                ("fn shade_at(", "    debugPrintf(\"pixel %v2u\", pixel);"),
                ("fn load_words(", "    debugPrintf(\"pixel %v2d\", pixel);"),
                ("fn visibility(", "    debugPrintf(\"distance %f\", distance);"),
            ],
        ),
        ("passes/test_pattern.wgsl", &[("fn fs", "    debugPrintf(\"%f %x\", 1.5, 7u);")]),
    ];
    for (shader, prints) in edits {
        let file = lib.files().find(|f| f.display.ends_with(shader)).unwrap_or_else(|| panic!("{shader}")).clone();
        let text = with_prints(&file.text, prints);
        lib.upsert(SourceFile::from_text(file.display.clone(), file.path.clone(), text.into()));
    }
    let mut checked = BTreeMap::<&str, usize>::new();
    for spec in crate::render::passes::specs() {
        let Some(file) = lib.files().find(|f| f.display.ends_with(spec.shader)).cloned() else { continue };
        let printing = lib.reachable_under(&file, &Default::default(), &spec.defs.iter().map(|d| d.to_string()).collect());
        if !printing.iter().any(|d| lib.get(d).is_some_and(|f| !f.prints.sites.is_empty())) {
            continue;
        }
        for defs in spec.permutations() {
            let module = compose(&lib, &file.display, &defs);
            assert!(has_prints(&module), "{} {defs:?}", spec.name);
            let out = instrument(&module, [3, 5], 0, 0).unwrap_or_else(|e| panic!("{} {defs:?}: {e}", spec.name));
            assert!(!out.sites.is_empty());
            if spec.name == "lighting.deferred" {
                let flagged = out
                    .module
                    .functions
                    .iter()
                    .filter(|(_, f)| f.local_variables.iter().any(|(_, v)| v.name.as_deref() == Some("loupe_printf_here")));
                let mut names: Vec<&str> = flagged.filter_map(|(_, f)| f.name.as_deref()).collect();
                names.sort_unstable();
                assert_eq!(names, ["load_words", "shade", "shade_at"], "{defs:?}");
            }
            *checked.entry(spec.name).or_default() += 1;
        }
    }
    let checked: Vec<&str> = checked.into_keys().collect();
    assert_eq!(checked, ["debug.test_pattern", "lighting.deferred", "path_trace"], "the pipelines instrumented");
}

fn parse(source: &str) -> Module {
    let prints = printf::Prints::of(source, 1);
    assert_eq!(prints.problems, []);
    naga::front::wgsl::parse_str(&prints.text).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&prints.text)))
}

/// The builtin the selection needs is added when missing, and read from
/// where it is (an argument, or a member of an input struct) otherwise;
/// vertex stages never print.
#[test]
fn the_selection_reads_the_builtin_where_the_entry_point_has_it() {
    let m = parse(
        "enable wgpu_debug_printf;
struct In { @location(0) uv: vec2<f32>, @builtin(position) at: vec4<f32> }
fn helper(x: f32) { debugPrintf(\"%f\", x); }
@fragment fn a(v: In) -> @location(0) vec4<f32> { helper(v.uv.x); return v.at; }
@fragment fn b() -> @location(0) vec4<f32> { helper(2.0); return vec4(1.0); }
@compute @workgroup_size(1) fn c(@builtin(global_invocation_id) id: vec3<u32>) { debugPrintf(\"%u\", id.x); }
@compute @workgroup_size(1) fn e(@builtin(local_invocation_id) l: vec3<u32>) { debugPrintf(\"%u\", l.x); }
@vertex fn d() -> @builtin(position) vec4<f32> { helper(1.0); return vec4(1.0); }
",
    );
    let out = instrument(&m, [1, 2], 0, 0).unwrap();
    let args = |name: &str| out.module.entry_points.iter().find(|e| e.name == name).unwrap().function.arguments.len();
    assert_eq!((args("a"), args("b"), args("c"), args("d"), args("e")), (1, 1, 1, 0, 1));
    assert_eq!(out.sites.len(), 3);
    assert_eq!(out.group, 0);
    let bound: Vec<_> = out.module.global_variables.iter().filter_map(|(_, g)| g.binding).collect();
    assert_eq!(bound, [ResourceBinding { group: 0, binding: 0 }]);
    assert!(!has_prints(&naga::front::wgsl::parse_str("fn f() { var loupe: u32; }").unwrap()));
    // Past a group the caller keeps, numbered after sites of other modules.
    let later = instrument(&m, [1, 2], 3, 10).unwrap();
    assert_eq!(later.group, 3);
    let words =
        |out: &InstrumentedPrints| naga::back::wgsl::write_string(&out.module, &out.info, naga::back::wgsl::WriterFlags::empty()).unwrap();
    let text = words(&later);
    assert!(text.contains("] = 10u;") && text.contains("] = 12u;") && !text.contains("] = 0u;"), "{text}");
}

/// In a compute stage that does not read its global id, the functions
/// that take their pixel (`pixel` or `texel`, a `vec2` of `u32` or `i32`)
/// and print get a flag of their own, set at their start; a function
/// whose argument is named or typed otherwise, or that does not print,
/// gets none.
#[test]
fn functions_that_take_their_pixel_and_print_get_a_flag_of_their_own() {
    let m = parse(
        "enable wgpu_debug_printf;
fn a(pixel: vec2<u32>) { debugPrintf(\"%v2u\", pixel); }
fn b(x: f32, texel: vec2<i32>) { debugPrintf(\"%f\", x); }
fn c(p: vec2<u32>) { debugPrintf(\"%v2u\", p); }
fn d(pixel: vec3<u32>) { debugPrintf(\"%v3u\", pixel); }
fn e(texel: vec2<f32>) { debugPrintf(\"%v2f\", texel); }
fn f(pixel: vec2<u32>) -> u32 { return pixel.x; }
@compute @workgroup_size(1) fn tiles(@builtin(local_invocation_id) l: vec3<u32>) {
    a(l.xy); b(1.0, vec2<i32>(l.xy)); c(l.xy); d(l); e(vec2<f32>(l.xy)); debugPrintf(\"%u\", f(l.xy));
}
",
    );
    let out = instrument(&m, [1, 2], 0, 0).unwrap();
    let flagged: Vec<&str> = out
        .module
        .functions
        .iter()
        .filter(|(_, f)| f.local_variables.iter().any(|(_, v)| v.name.as_deref() == Some("loupe_printf_here")))
        .filter_map(|(_, f)| f.name.as_deref())
        .collect();
    assert_eq!(flagged, ["a", "b"]);
    let text = naga::back::wgsl::write_string(&out.module, &out.info, naga::back::wgsl::WriterFlags::empty()).unwrap();
    assert!(text.contains("loupe_printf_by_argument = true;"), "{text}");
}
