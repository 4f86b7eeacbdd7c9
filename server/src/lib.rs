//! loupe: a shader hot-reload server and frame debugger for WGSL on wgpu.
//!
//! Data flow: sources (`shader::library`) → compose + validate
//! (`shader::compose`) → pipelines (`gpu::pipeline`, `render::pipelines`) →
//! render graph (`render::graph`) → captures (`render::capture`) → stream
//! (`serve::http`) → UI (`client/`). `check` is the same chain stopped after
//! pipeline creation, printed for CI. See ARCHITECTURE.md.

pub mod bvh;
pub mod check;
pub mod color;
pub mod denoise;
pub mod denoise_options;
pub mod diag;
pub mod files;
pub mod flip;
pub mod gpu;
pub mod loaded;
pub mod material;
pub mod mesh;
pub mod npy;
pub mod offline;
pub mod protocol;
pub mod quads;
pub mod render;
#[cfg(test)]
mod repo_docs;
pub mod scene;
pub mod serve;
pub mod shader;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
#[cfg(test)]
mod tests;
pub mod tradeoffs;
