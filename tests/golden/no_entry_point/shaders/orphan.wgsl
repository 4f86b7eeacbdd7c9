// Neither an entry point nor an importable module: nothing can use this.
fn helper() -> f32 { return 1.0; }
