//! The whole material compiler on arbitrary bytes: front end → tree →
//! analysis (folding, pruning, the compile report) → the WGSL back end →
//! the generated `loupe::material` module composed with the shader library
//! it imports (`shaders/lib`) and validated by naga, as `loupe check`
//! checks a library module. A file the front end and the analysis accept
//! must generate a module that validates: a rejected module is a compiler
//! bug, reported as a panic with naga's diagnostics.

#![no_main]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use loupe::material::{Program, analysed, back, front, report::Report};
use loupe::shader::compose::{ShaderDefs, check_library};
use loupe::shader::library::{Library, read_tree};

fuzz_target!(|data: &[u8]| {
    let root = loupe_fuzz::project(data);
    let Ok(loaded) = front::load(&root) else { return };
    let mut definitions = Vec::new();
    for d in &loaded.definitions {
        let Ok(analysis) = analysed(d) else { return };
        serde_json::to_string(&Report::new(&analysis)).expect("a report serialises");
        definitions.push(analysis.def);
    }
    validate(Program { definitions, ..Program::default() });
});

/// The repository's shaders, read once.
fn shaders() -> &'static (PathBuf, Library) {
    static SHADERS: OnceLock<(PathBuf, Library)> = OnceLock::new();
    SHADERS.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
        let lib = read_tree(&root).expect("the repository's shaders");
        (root, lib)
    })
}

/// Composes and validates `program`'s module under each def the module
/// itself reads (`#ifdef LIGHT_RECT`); panics with the diagnostics.
fn validate(program: Program) {
    let (root, lib) = shaders();
    let mut lib = lib.clone();
    loupe::render::session::material_module(&mut lib, root, &program);
    let module = lib.get(back::DISPLAY).expect("the generated module").clone();
    for defs in [ShaderDefs::new(), ShaderDefs::from(["LIGHT_RECT".to_owned()])] {
        if let Err(ds) = check_library(&lib, &module, &defs, naga::valid::Capabilities::default()) {
            let shown: Vec<String> = ds.iter().map(ToString::to_string).collect();
            panic!("the generated module does not validate under {defs:?}:\n{}\n{}", shown.join("\n"), module.text);
        }
    }
}
