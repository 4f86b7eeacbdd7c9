//! The denoiser: OIDN's U-Net (Open Image Denoise, Intel, Apache-2.0) run
//! on OIDN's own weights files.
//!
//! `tza` reads a weights file; `network` builds the U-Net it describes from
//! its tensor names and shapes, as an ordered list of ops over named tensors
//! that a backend walks; `cpu` is the plain f32 reference of that walk;
//! `process` is OIDN's pre- and post-processing around it (transfer
//! functions, autoexposure, padding); `image` reads and writes the files
//! `loupe denoise` takes; `tiles` cuts an image too large for the device
//! into overlapping windows. This is the CPU model: it imports nothing from
//! the renderer. `loupe denoise` itself, on the GPU or on `cpu`, is
//! `crate::offline::denoise`.

pub mod bundled;
pub mod cpu;
pub mod image;
pub mod network;
pub mod process;
pub mod tiles;
pub mod tza;

pub use crate::denoise_options::Precision;
use crate::diag::{Code, Diagnostic, Location};

/// A problem in a weights file: a binary file has no lines, so the location
/// is the file and the message says the byte.
fn weights_error(display: &str, at: u64, message: String) -> Diagnostic {
    Diagnostic::error(Code::Weights, format!("at byte {at}: {message}")).at(Location::file_start(display))
}

#[cfg(test)]
pub mod testing;
