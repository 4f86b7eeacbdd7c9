//! The material front end on arbitrary bytes: reading (encoding, size),
//! lexing, parsing, imports (missing, cyclic, deep) and lowering to the
//! tree. Any input must give definitions or located diagnostics, never a
//! panic.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let root = loupe_fuzz::project(data);
    let _ = loupe::material::front::load(&root);
});
