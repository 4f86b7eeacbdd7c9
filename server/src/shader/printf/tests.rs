use std::path::PathBuf;

use super::*;
use crate::diag::Diagnostic;
use crate::shader::{Compose, ComposeCache, Library, SourceFile};

const HEAD: &str = "enable wgpu_debug_printf;\n";

fn compose(files: &[(&str, &str)]) -> Result<crate::shader::Composed, Vec<Diagnostic>> {
    let lib = Library::new(files.iter().map(|(n, t)| SourceFile::from_text(n.to_string(), PathBuf::from(n), (*t).into())));
    let entry = lib.get(files.last().unwrap().0).unwrap().clone();
    ComposeCache::default().compose(&lib, &entry, &Default::default(), naga::valid::Capabilities::all())
}

/// (line, column, code) of each diagnostic.
fn at(errs: &[Diagnostic]) -> Vec<(u32, u32, Code)> {
    errs.iter().map(|d| d.location.as_ref().map_or((0, 0, d.code), |l| (l.line, l.column, d.code))).collect()
}

#[test]
fn calls_become_blocks_of_locals_and_comments_are_left_alone() {
    let text = format!(
        "{HEAD}// debugPrintf(\"not a call\", 1);\n/* debugPrintf(\"nor /* nested */ this\"); */\nfn f(x: f32) {{\n    debugPrintf(\"x = %f, %d\", x * (2.0 + 1.0), i32(x));\n}}\n"
    );
    let p = Prints::of(&text, 7);
    assert_eq!(p.problems, []);
    assert_eq!(p.sites.len(), 1);
    let site = &p.sites[0];
    assert_eq!(site.args.iter().map(|a| &text[a.clone()]).collect::<Vec<_>>(), ["x * (2.0 + 1.0)", "i32(x)"]);
    assert_eq!(
        site.format,
        [
            Segment::Text("x = ".into()),
            Segment::Spec(Spec { conversion: Conversion::Fixed, components: 1, precision: None }),
            Segment::Text(", ".into()),
            Segment::Spec(Spec { conversion: Conversion::Signed, components: 1, precision: None })
        ]
    );
    assert!(p.text.starts_with(&" ".repeat(HEAD.len() - 1)), "the directive is blanked: {}", p.text);
    assert!(
        p.text.contains(
            "{ var loupe_printf_00000007_0_0_arg = x * (2.0 + 1.0); var loupe_printf_00000007_0_1_arg = i32(x); var loupe_printf_00000007_0_site: u32; loupe_printf_00000007_0_site = 1u; }"
        ),
        "{}",
        p.text
    );
    assert!(p.text.contains("// debugPrintf(\"not a call\", 1);"));
    assert_eq!(parse_var("loupe_printf_00000007_0_1_arg"), Some((7, 0, Some(1))));
    assert_eq!(parse_var("loupe_printf_00000007_3_site"), Some((7, 3, None)));
    assert_eq!(parse_var("loupe_printf_x"), None);
    // An offset inside a copied argument maps to the same character.
    let arg = p.text.find("i32(x)").unwrap();
    assert_eq!(&text[p.original(arg)..p.original(arg) + 6], "i32(x)");
}

#[test]
fn the_directive_may_share_an_enable_line() {
    let p = Prints::of("enable f16, wgpu_debug_printf;\nfn f() { debugPrintf(\"hi\"); }\n", 1);
    assert_eq!(p.problems, []);
    assert!(p.text.starts_with("enable f16"), "{}", p.text);
    assert!(p.text.lines().next().unwrap().trim_end().ends_with(';') && !p.text.contains(ENABLE), "{}", p.text);
}

#[test]
fn shaders_with_prints_compose_and_errors_point_into_the_file() {
    let ok = format!(
        "{HEAD}@fragment\nfn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {{\n    debugPrintf(\"p = %v2f\", p.xy);\n    return p;\n}}\n"
    );
    let composed = compose(&[("ok.wgsl", &ok)]).unwrap();
    let vars: Vec<_> = composed.module.entry_points[0].function.local_variables.iter().filter_map(|(_, v)| v.name.clone()).collect();
    assert_eq!(vars.len(), 2, "{vars:?}");

    // An error on a line after a print, in a plain file and through the composer.
    let after = format!("{HEAD}fn f(x: f32) -> f32 {{\n    debugPrintf(\"%f\", x);\n    return x + 1u;\n}}\n");
    assert_eq!(at(&compose(&[("after.wgsl", &after)]).unwrap_err()), [(4, 12, Code::Validation)]);
    let imported = format!("#define_import_path util\n{after}");
    let main = "#import util::f\n@fragment\nfn fs() -> @location(0) vec4<f32> { return vec4(f(1.0)); }\n";
    let errs = compose(&[("util.wgsl", &imported), ("main.wgsl", main)]).unwrap_err();
    assert_eq!((at(&errs), errs[0].file()), (vec![(5, 12, Code::Validation)], Some("util.wgsl")), "{errs:?}");

    // An error inside a print's argument.
    let inside = format!("{HEAD}fn f(x: f32) {{\n    debugPrintf(\"%f %f\", x, y + 1.0);\n}}\n");
    assert_eq!(at(&compose(&[("inside.wgsl", &inside)]).unwrap_err()), [(3, 29, Code::Parse)]);
}

#[test]
fn bad_prints_are_reported_at_the_call() {
    let case = |body: &str| {
        let text = format!("{HEAD}fn f(x: f32, v: vec3<f32>, s: S) {{\n    {body}\n}}\nstruct S {{ a: f32 }}\n");
        at(&compose(&[("bad.wgsl", &text)]).err().unwrap_or_default())
    };
    assert_eq!(case("debugPrintf(\"%f %f\", x);"), [(3, 5, Code::PrintfArguments)]);
    assert_eq!(case("debugPrintf(\"%f\", x, x);"), [(3, 26, Code::PrintfArguments)]);
    assert_eq!(case("debugPrintf(\"a %q\", x);"), [(3, 20, Code::PrintfFormat)]);
    assert_eq!(case("debugPrintf(\"%v5f\", v);"), [(3, 18, Code::PrintfFormat)]);
    assert_eq!(case("debugPrintf(\"%f\", v);"), [(3, 23, Code::PrintfType)]);
    assert_eq!(case("debugPrintf(\"%v3d\", v);"), [(3, 25, Code::PrintfType)]);
    assert_eq!(case("debugPrintf(\"%f\", s);"), [(3, 23, Code::PrintfType)]);
    assert_eq!(case("debugPrintf(\"%f\", x * 2);"), [], "the premise: this one composes");
}

#[test]
fn prints_that_are_not_statements_or_strings_are_refused() {
    let problems = |body: &str| {
        let p = Prints::of(&format!("{HEAD}fn f(x: f32) {{\n    {body}\n}}\n"), 0);
        p.problems.iter().map(|p| p.code).collect::<Vec<_>>()
    };
    assert_eq!(problems("let y = debugPrintf(\"%f\", x);"), [Code::PrintfSyntax]);
    assert_eq!(problems("debugPrintf(\"%f\", x)"), [Code::PrintfSyntax]);
    assert_eq!(problems("debugPrintf(\"%f, x);"), [Code::PrintfSyntax]);
    assert_eq!(problems("debugPrintf(x);"), [Code::PrintfSyntax]);
    let p = Prints::of("fn f() { debugPrintf(\"hi\"); }\n", 0);
    assert_eq!(p.problems.iter().map(|p| (p.code, p.range.clone())).collect::<Vec<_>>(), [(Code::PrintfSyntax, 9..20)]);
}

#[test]
fn format_strings() {
    let spec = |s: &str| match parse_format(s).unwrap().as_slice() {
        [Segment::Spec(spec)] => *spec,
        other => panic!("{other:?}"),
    };
    assert_eq!(spec("%.3v4e"), Spec { conversion: Conversion::Exponent, components: 4, precision: Some(3) });
    assert_eq!(spec("%v2x").to_string(), "%v2x");
    assert_eq!(parse_format("100%% %i").unwrap()[0], Segment::Text("100% ".into()));
    assert!(parse_format("%").is_err());
    assert!(parse_format("%.2d").is_err());
    assert_eq!(parse_format("ab %v1f").unwrap_err().0, 3);
}

#[test]
fn values_are_shown_as_c_shows_them() {
    let site = |format: &str| Site { call: 0..0, format: parse_format(format).unwrap(), args: Vec::new() };
    let f = |x: f32| x.to_bits();
    let (text, values) = site("%d %u %x %f|%.2f %e %g %g %g %v2f").render(&[
        (-3i32) as u32,
        7,
        255,
        f(1.5),
        f(2.0 / 3.0),
        f(1234.5),
        f(0.0001),
        f(1e-5),
        f(100000.0),
        f(0.25),
        f(f32::NAN),
    ]);
    assert_eq!(text, "-3 7 ff 1.500000|0.67 1.234500e+03 0.0001 1e-05 100000 0.250000, nan");
    assert_eq!(values[0], serde_json::json!(-3));
    assert_eq!(values[9], serde_json::json!([0.25, "nan"]));
    assert_eq!(site("%v3u").words(), 3);
}
