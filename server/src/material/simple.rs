//! The simple storage class's own module, `loupe::material_simple`: the
//! module `back` writes for the shorthand's one slab alone (one closure,
//! no optional field), so the lighting of tiles holding only simple pixels
//! runs no closure loop over the program's features. It unpacks the simple
//! words exactly as `loupe::material` does (`pack.rs`), and compensates
//! as the program's materials may ask (the header's bit 6).

use super::back;
use super::tree::Definition;
use crate::diag::Location;

/// The module's import path.
pub const IMPORT_PATH: &str = "loupe::material_simple";
/// Where it sits among the shader files: generated, never on disk.
pub const DISPLAY: &str = "generated/material_simple.wgsl";

/// The module for a program of `definitions`.
pub fn wgsl(definitions: &[Definition]) -> String {
    let mut slab = super::shorthand(Location::file_start(DISPLAY));
    slab.energy_compensation = definitions.iter().any(|d| d.energy_compensation);
    back::module(&[slab], back::Bindings::RENDERER, IMPORT_PATH, &[false])
}
