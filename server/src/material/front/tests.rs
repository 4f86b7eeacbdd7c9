//! The front end on small sources: what parses, what lowers to which tree,
//! and where each error points.

use std::path::{Path, PathBuf};

use super::{Loaded, load, load_text};
use crate::diag::{Code, Diagnostic, display_path};
use crate::material::tree::*;

fn ok(text: &str) -> Loaded {
    load_text(Path::new("t.mat"), text).unwrap_or_else(|e| panic!("{}", lines(&e)))
}

fn errors(text: &str) -> Vec<Diagnostic> {
    load_text(Path::new("t.mat"), text).expect_err("errors")
}

fn lines(ds: &[Diagnostic]) -> String {
    ds.iter().map(|d| format!("{d} {:?}\n", d.notes)).collect()
}

/// The one error `text` gives: its line:col and message.
fn one_error(text: &str) -> (u32, u32, String) {
    let e = errors(text);
    assert_eq!(e.len(), 1, "{}", lines(&e));
    let l = e[0].location.clone().expect("located");
    (l.line, l.column, e[0].message.clone())
}

fn dir_with(files: &[(&str, &[u8])]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, text) in files {
        let path = dir.path().join(name);
        std::fs::create_dir_all(path.parent().expect("parent")).expect("mkdir");
        std::fs::write(path, text).expect("write");
    }
    dir
}

#[test]
fn a_slab_lowers_to_one_node_with_its_fields_and_the_params_it_uses() {
    let l = ok(
        "// Its colour.\nparam tint: color = rgb(0.5, 0.25, 1) in [0, 1]\nparam unused: float = 2\nparam rough: float = 0.3 in [0, 1] mm\nmaterial m = slab { base_color: tint * 0.5, specular_roughness: rough }\n",
    );
    let d = &l.definitions[0];
    assert_eq!((d.name.as_str(), d.location.line, d.location.column, d.energy_compensation), ("m", 5, 10, true));
    let names: Vec<&str> = d.params.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["tint", "rough"]);
    assert_eq!(d.params[0].doc.as_deref(), Some("Its colour."));
    assert_eq!(
        (d.params[0].default, d.params[1].unit.as_deref(), d.params[1].range),
        (Value::Vec3([0.5, 0.25, 1.0]), Some("mm"), Some((0.0, 1.0)))
    );
    assert_eq!(d.nodes.len(), 1);
    let NodeKind::Slab(slab) = &d.node(d.root).kind else { panic!("a slab") };
    let color = slab.get(Field::BaseColor).expect("set");
    let ExprKind::Binary(BinOp::Mul, a, _) = d.expr(color).kind else { panic!("{:?}", d.expr(color)) };
    assert_eq!((d.expr(a).kind.clone(), d.expr(color).ty), (ExprKind::Param(0), Type::Color));
    assert_eq!(d.expr(slab.get(Field::SpecularRoughness).unwrap()).kind, ExprKind::Param(1));
    assert_eq!(l.warnings.len(), 1, "`unused` is used by no material");
    assert_eq!(l.warnings[0].location.as_ref().map(|l| l.line), Some(3));
}

#[test]
fn operators_fns_and_lets_inline_children_before_parents() {
    let l = ok(
        "fn coat(r: float) -> slab { let s = slab { specular_roughness: r }; s }\nparam w: float = 0.5\nmaterial m {\n  let unused = slab {}\n  let base = mix(slab {}, slab { base_metalness: 1 }, w)\n  coverage(layer(coat(0.1), add(base, base)), 0.9)\n}\n",
    );
    let d = &l.definitions[0];
    assert_eq!(d.nodes.len(), 7, "the unused let leaves nothing: {:?}", d.nodes);
    for (i, n) in d.nodes.iter().enumerate() {
        let kids: Vec<u32> = match &n.kind {
            NodeKind::Mix { a, b, .. } | NodeKind::Add { a, b } | NodeKind::Layer { top: a, base: b } => vec![a.0, b.0],
            NodeKind::Coverage { a, .. } => vec![a.0],
            NodeKind::Slab(_) => vec![],
        };
        assert!(kids.iter().all(|&k| (k as usize) < i), "node {i} has a later child");
    }
    assert!(matches!(d.node(d.root).kind, NodeKind::Coverage { .. }));
    assert_eq!(d.params.len(), 1, "the weight's param");
}

#[test]
fn an_imported_material_called_with_named_arguments_replaces_those_params() {
    let dir = dir_with(&[
        ("lib/base.mat", b"param color: color = grey(0.5)\nparam rough: float = 0.25 in [0, 1]\nmaterial plastic = slab { base_color: color, specular_roughness: rough }\n"),
        ("top.mat", b"import \"lib/base.mat\" as lib\nparam paint: color = rgb(1, 0, 0)\nmaterial m = lib.plastic(color: paint * 0.5)\n"),
    ]);
    let l = load(&dir.path().join("top.mat")).unwrap_or_else(|e| panic!("{}", lines(&e)));
    assert_eq!(l.files.len(), 2);
    assert!(l.files[1].ends_with("lib/base.mat"));
    let d = &l.definitions[0];
    assert_eq!(d.params.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), ["paint"]);
    let NodeKind::Slab(slab) = &d.node(d.root).kind else { panic!() };
    let rough = d.expr(slab.get(Field::SpecularRoughness).unwrap());
    assert_eq!(rough.kind, ExprKind::Const(Value::Float(0.25)), "the other param's default, as a constant");
    assert!(rough.location.file.ends_with("base.mat"), "spans point into the imported file");
    assert!(matches!(d.expr(slab.get(Field::BaseColor).unwrap()).kind, ExprKind::Binary(BinOp::Mul, ..)));
}

#[test]
fn syntax_errors_are_located_and_each_declaration_reports_its_own() {
    let e = errors("param a: float = \nmaterial m = slab { base_color: }\nmaterial n = slab {} )\n");
    let at: Vec<(u32, u32)> = e.iter().map(|d| d.location.as_ref().map(|l| (l.line, l.column)).unwrap()).collect();
    assert_eq!(at, [(2, 1), (2, 33), (3, 22)], "{}", lines(&e));
    assert!(e.iter().all(|d| d.code == Code::Material));
}

#[test]
fn semantic_errors_name_what_is_known() {
    let (line, col, msg) = one_error("material m = slab { base_colour: grey(0.5) }");
    assert_eq!((line, col), (1, 21));
    assert!(msg.contains("unknown field `base_colour`"), "{msg}");
    let e = errors("material m = slab { base_colour: grey(0.5) }");
    assert_eq!(e[0].notes, ["did you mean `base_color`?"]);
    let (_, col, msg) = one_error("material m = slab { base_color: 0.5 }");
    assert_eq!((col, msg.contains("must be a color, not a float") && msg.contains("grey(x)")), (33, true), "{msg}");
    let (_, col, msg) = one_error("material m = slab { specular_ior: 0.5 }");
    assert_eq!((col, msg.as_str()), (35, "`specular_ior` must lie in [1, 5], not 0.5"));
    let (_, _, msg) = one_error("material m = slab { thickness: 0 / 0 }");
    assert_eq!(msg, "`thickness` evaluates to NaN");
    let (_, col, msg) = one_error("material m = slab { specular_roughness: nan }");
    assert_eq!((col, msg.contains("finite")), (41, true), "{msg}");
    let (_, col, msg) = one_error("material m = slab { specular_roughness: 1e40 }");
    assert_eq!((col, msg.contains("finite")), (41, true), "{msg}");
    let (_, col, msg) = one_error("material m = mix(slab {}, slab {})");
    assert_eq!((col, msg.as_str()), (14, "`mix` takes 3 arguments, not 2"));
    let (_, _, msg) = one_error("material m = lerp(slab {}, slab {}, 0.5)");
    assert!(msg.contains("must be a value, not a slab"), "{msg}");
    let (_, _, msg) = one_error("material m = layr(slab {}, slab {})");
    assert!(msg.contains("unknown function `layr`"), "{msg}");
}

#[test]
fn declarations_and_defaults_are_checked() {
    let (line, _, msg) = one_error("param a: float = 2 in [0, 1]\nmaterial m = slab { specular_roughness: a }");
    assert_eq!((line, msg.as_str()), (1, "the default of `a` is outside its range"));
    let (line, col, msg) = one_error("material m = slab {}\nmaterial m = slab {}");
    assert_eq!((line, col, msg.as_str()), (2, 10, "`m` is declared twice"));
    let (_, _, msg) = one_error("material m = slab { base_metalness: 1, base_metalness: 0 }");
    assert_eq!(msg, "field `base_metalness` is set twice");
    let (_, _, msg) = one_error("param a: float = 0.5 in [0, 2]\nmaterial m = slab { specular_roughness: a }");
    assert_eq!(msg, "param `a` may leave the range of `specular_roughness`");
    let (_, _, msg) = one_error("fn f(x: float) -> slab { f(x) }\nmaterial m = f(1)");
    assert_eq!(msg, "recursion: f -> f");
    let (_, _, msg) = one_error("fn f(x: color) -> slab { slab { base_color: x } }\nmaterial m = f(1)");
    assert!(msg.contains("argument `x` must be a color"), "{msg}");
}

#[test]
fn named_arguments_of_a_material_are_checked() {
    let lib = "param color: color = grey(0.5)\nparam rough: float = 0.5 in [0, 1]\nmaterial p = slab { base_color: color, specular_roughness: rough }\n";
    let dir = dir_with(&[("lib.mat", lib.as_bytes()), ("a.mat", b"import \"lib.mat\"\nmaterial m = lib.p(colour: grey(1), rough: 2)\n")]);
    let e = load(&dir.path().join("a.mat")).expect_err("errors");
    let msgs: Vec<&str> = e.iter().map(|d| d.message.as_str()).collect();
    assert_eq!(msgs, ["unknown param `colour` of `p`", "param `rough` must lie in [0, 1], not 2"], "{}", lines(&e));
    assert_eq!(e[0].notes, ["did you mean `color`?"]);
}

#[test]
fn bad_files_are_diagnostics_at_their_import() {
    let dir = dir_with(&[
        ("a.mat", b"import \"b.mat\"\nmaterial m = slab {}\n"),
        ("b.mat", b"import \"a.mat\"\nmaterial n = slab {}\n"),
        ("bin.mat", b"material m = slab {}\xff\n"),
        ("uses_bin.mat", b"import \"bin.mat\"\nimport \"gone.mat\"\nmaterial m = slab {}\n"),
        ("empty.mat", b"  \n"),
    ]);
    let e = load(&dir.path().join("a.mat")).expect_err("a cycle");
    assert_eq!((e.len(), e[0].code), (1, Code::ImportCycle));
    let (a, b) = (display_path(&dir.path().join("a.mat")), display_path(&dir.path().join("b.mat")));
    assert_eq!(e[0].notes, [format!("cycle: {a} -> {b} -> {a}")]);
    assert_eq!(e[0].file(), Some(b.as_str()), "at the import that closes the cycle");
    let e = load(&dir.path().join("uses_bin.mat")).expect_err("bad imports");
    let codes: Vec<Code> = e.iter().map(|d| d.code).collect();
    assert_eq!(codes, [Code::Encoding, Code::ImportMissing], "{}", lines(&e));
    assert_eq!(e[1].location.as_ref().map(|l| (l.line, l.column)), Some((2, 8)));
    assert_eq!(load(&dir.path().join("empty.mat")).expect_err("empty")[0].code, Code::EmptyFile);
}

#[test]
fn a_file_over_the_cap_is_refused_before_it_is_read() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("huge.mat");
    let f = std::fs::File::create(&path).expect("create");
    f.set_len(crate::shader::library::MAX_FILE_BYTES + 1).expect("a sparse file");
    assert_eq!(load(&path).expect_err("too large")[0].code, Code::FileTooLarge);
}

#[test]
fn deep_nesting_and_deep_imports_are_errors_not_overflows() {
    for (open, close) in [("(", ")"), ("-", ""), ("1 + ", "1"), ("saturate(", ")")] {
        let text = format!("material m = slab {{ thickness: {}1{} }}", open.repeat(100_000), close.repeat(100_000));
        let e = errors(&text);
        assert!(e[0].message.contains("nested too deeply"), "{open}: {}", lines(&e));
    }
    let mut files: Vec<(String, Vec<u8>)> =
        (0..40).map(|i| (format!("f{i}.mat"), format!("import \"f{}.mat\"\nmaterial m{i} = slab {{}}\n", i + 1).into_bytes())).collect();
    files.push(("f40.mat".into(), b"material m = slab {}\n".to_vec()));
    let named: Vec<(&str, &[u8])> = files.iter().map(|(n, t)| (n.as_str(), t.as_slice())).collect();
    let dir = dir_with(&named);
    let e = load(&dir.path().join("f0.mat")).expect_err("too deep");
    assert!(e[0].message.contains("imports nest more than"), "{}", lines(&e));
    // Calls that double at each level: a size limit, not a hang.
    let mut text = String::from("fn f0(x: float) -> float { x }\n");
    for i in 1..40 {
        text += &format!("fn f{i}(x: float) -> float {{ f{}(x) + f{}(x) }}\n", i - 1, i - 1);
    }
    text += "material m = slab { thickness: f39(1) }\n";
    assert!(errors(&text)[0].message.starts_with("material too large"));
}

#[test]
fn the_starter_library_loads() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/materials");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("scenes/materials") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "mat") {
            let l = load(&path).unwrap_or_else(|e| panic!("{}: {}", path.display(), lines(&e)));
            assert!(!l.definitions.is_empty() && l.warnings.is_empty(), "{}: {:?}", path.display(), l.warnings);
            count += 1;
        }
    }
    assert!(count >= 7, "the library's files");
}
