//! The sRGB transfer function, shared by captures (PNG encoding, display)
//! and FLIP (which reads 8-bit sRGB): one formula, on the lowest floor.

/// The sRGB transfer function's inverse, exactly as the spec writes it.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}
