//! Materials: a layered material language compiled to WGSL for the raster
//! and the path tracer. Laid out as naga is: `front` (the `*.mat` parser and
//! the scene's shorthand) → `tree` (the IR) → analysis → `back` (WGSL).
//! [docs/materials.md](../../../docs/materials.md) is the language.

pub mod analysis;
#[cfg(test)]
mod build;
pub mod operators;
pub mod report;
pub mod tree;
