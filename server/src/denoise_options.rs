//! The choices a denoise is made with: the colour's range (`Mode`) and how
//! tensors are stored (`Precision`). They are what a scene's `[denoiser]`
//! and `loupe denoise` name, so they live apart from `denoise`: the scene
//! file's reader names them without depending on the denoiser.

/// How the colour is encoded, as OIDN's `hdr` and `srgb` flags say: the
/// range the weights were trained for (OIDN ships `rt_hdr_*` and
/// `rt_ldr_*` variants of each network). The scene's `[denoiser] mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Linear values in [0, 1]; the network sees them sRGB-encoded.
    Ldr,
    /// Values already sRGB-encoded, in [0, 1] (OIDN's `srgb`): used as they are.
    LdrSrgb,
    /// Linear values of any magnitude; the network sees them through the
    /// perceptual (PU) curve, after the input scale.
    #[default]
    Hdr,
}

/// How tensors are stored between ops. Accumulation is f32 either way;
/// `F16` rounds every tensor to half precision when it is stored, as the
/// GPU's f16 storage does. The scene's `[denoiser] precision`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    F16,
    #[default]
    F32,
}
