//! The one guard around compiler calls: a panic inside naga, naga_oil or
//! wgpu becomes a `compiler-panic` diagnostic at the file being compiled,
//! so `loupe check` goes on with the other files and the daemon keeps
//! rendering.

use std::panic::AssertUnwindSafe;

use crate::diag::{Code, Diagnostic, Location};

/// Runs `f`; a panic in it is a diagnostic naming `who` crashed on `display`.
pub fn guarded<T>(display: &str, who: &str, f: impl FnOnce() -> Result<T, Vec<Diagnostic>>) -> Result<T, Vec<Diagnostic>> {
    std::panic::catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| {
        let msg = panic_message(&*payload);
        Err(vec![
            Diagnostic::error(Code::CompilerPanic, format!("{who} crashed on this file"))
                .at(Location::file_start(display))
                .with_note(format!("panic: {msg}"))
                .with_note("this is a bug in the compiler, not necessarily in your shader"),
        ])
    })
}

/// What a caught panic said.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| (*s).to_owned()))
        .unwrap_or_else(|| "unknown panic".to_owned())
}
