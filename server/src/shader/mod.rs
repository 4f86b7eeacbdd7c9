//! WGSL sources → composed, validated naga modules.

pub mod compose;
pub mod guard;
pub mod instrument;
pub mod instrument_printf;
pub mod library;
pub mod printf;

pub use compose::{Compose, ComposeCache, Composed, NagaOil, ShaderDefs, defs_key};
pub use library::{Library, SourceFile};
