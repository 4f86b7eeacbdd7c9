//! The single storage class's own module, `loupe::material_single`: the
//! raster's definitions with one closure as they are, and each of the
//! others replaced by the shorthand's slab. The replacement keeps every
//! definition at its index (a pixel's header names it, and its words'
//! layout follows it) while `MATERIAL_CLOSURES` drops to 1 and the module
//! carries only the one-closure materials' features: the lighting of
//! tiles whose dearest pixel has one closure runs one closure's code, not
//! the program's closure loop. A tile of this class holds only simple and
//! single pixels, and both unpack here as in `loupe::material`.

use super::back;
use super::tree::Definition;

/// The module's import path.
pub const IMPORT_PATH: &str = "loupe::material_single";
/// Where it sits among the shader files: generated, never on disk.
pub const DISPLAY: &str = "generated/material_single.wgsl";

/// The module for the raster's (simplified) `definitions`.
pub fn wgsl(definitions: &[Definition]) -> String {
    let single: Vec<Definition> =
        definitions.iter().map(|d| if back::closures(d, d.root) == 1 { d.clone() } else { super::shorthand(d.location.clone()) }).collect();
    back::module(&single, back::Bindings::RENDERER, IMPORT_PATH, &vec![false; single.len()])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::features::Features;

    /// The library's materials: the module keeps the one-closure ones'
    /// features and drops what only the layered ones bring.
    #[test]
    fn one_closure_the_one_closure_materials_features_and_every_index() {
        let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/materials.toml");
        let loaded = crate::loaded::load(&scene).unwrap_or_else(|d| panic!("{d}"));
        let raster = loaded.materials.raster_definitions();
        let text = wgsl(&raster);
        assert!(text.contains("const MATERIAL_CLOSURES: u32 = 1u;"), "{text}");
        assert!(!text.contains("s.closures[1]"), "no second closure is written");
        let multi: Vec<&Definition> = raster.iter().filter(|d| back::closures(d, d.root) > 1).collect();
        let single: Vec<Definition> = raster.iter().filter(|d| back::closures(d, d.root) == 1).cloned().collect();
        assert!(!multi.is_empty() && !single.is_empty(), "the library has both kinds");
        let (all, one) = (Features::of(&raster), Features::of(&single));
        assert_ne!(all.names(), one.names(), "the library's multi-closure materials bring features of their own");
        assert!(
            text.contains(&format!("// Features: core{}.", one.names().iter().map(|n| format!(", {n}")).collect::<String>())),
            "{text}"
        );
        // Every definition keeps its index: a one-closure one is itself.
        for (i, d) in raster.iter().enumerate() {
            let name = if back::closures(d, d.root) == 1 { d.name.as_str() } else { "shorthand" };
            assert!(text.contains(&format!("//   {i}: {name} (")), "definition {i} ({}) in {text}", d.name);
        }
    }
}
