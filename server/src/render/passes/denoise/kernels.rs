//! The denoiser's GPU kernels (`shaders/denoise/`): their pipeline specs,
//! the uniforms they read, and the host-side layouts of weights and
//! tensors. Tensors are channels-last, channels padded to a multiple of 4
//! (one `vec4` per pixel and block), so every load is a whole vector.

use crate::gpu::pipeline::{COMPUTE, Group, PipelineSpec, Stages, sizes, storage, storage_rw, uniform};

/// Lanes of a channel block.
pub const BLOCK: usize = 4;
/// Output blocks one convolution invocation computes (the shader's BLOCKS).
pub const CONV_BLOCKS: u32 = 4;
/// Both kernels' workgroup side in pixels.
pub const TILE: u32 = 8;

/// Reads the first input 2× nearest-upsampled.
pub const UPSAMPLE: &str = "UPSAMPLE";
/// Takes a second input, concatenated after the first along channels.
pub const CONCAT: &str = "CONCAT";

pub static CONV: PipelineSpec = PipelineSpec {
    name: "denoise.conv",
    shader: "denoise/conv.wgsl",
    stages: Stages::Compute { entry: "conv" },
    groups: &[
        Group::always(0, &[uniform("layer", 0, COMPUTE, 2 * sizes::VEC4), storage("a", 1, COMPUTE), storage("weights", 3, COMPUTE), storage("bias", 4, COMPUTE), storage_rw("out", 5)]),
        Group::when(1, CONCAT, &[storage("b", 0, COMPUTE)]),
    ],
    defs: &[UPSAMPLE, CONCAT],
};

pub static POOL: PipelineSpec = PipelineSpec {
    name: "denoise.pool",
    shader: "denoise/pool.wgsl",
    stages: Stages::Compute { entry: "max_pool" },
    groups: &[Group::always(0, &[uniform("pool", 0, COMPUTE, sizes::VEC4), storage("input", 1, COMPUTE), storage_rw("out", 2)])],
    defs: &[],
};

/// Channel blocks holding `channels`.
pub fn blocks(channels: usize) -> usize {
    channels.div_ceil(BLOCK)
}

/// A convolution's uniform, as `Layer` in `conv.wgsl` declares it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct LayerUniform {
    pub width: u32,
    pub height: u32,
    pub a_width: u32,
    pub a_height: u32,
    pub a_blocks: u32,
    pub b_blocks: u32,
    pub out_blocks: u32,
    pub relu: u32,
}

/// The max-pool's uniform, as `Pool` in `pool.wgsl` declares it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct PoolUniform {
    pub width: u32,
    pub height: u32,
    pub blocks: u32,
    pub pad: u32,
}

/// OIHW weights (`out × (a + b) × 3 × 3`) and a bias, laid out as the
/// shader reads them: per tap, per input block (a's blocks, then b's), per
/// output block, a column-major 4×4 matrix whose column c holds input
/// channel c's weights to the block's four outputs. Padding lanes are 0,
/// so padded channels contribute nothing and padded outputs stay 0.
pub fn pack_conv(weight: &[f32], bias: &[f32], a: usize, b: usize, out: usize) -> (Vec<f32>, Vec<f32>) {
    let inputs = a + b;
    debug_assert_eq!(weight.len(), out * inputs * 9);
    let (a_blocks, in_blocks, out_blocks) = (blocks(a), blocks(a) + blocks(b), blocks(out));
    let mut w = vec![0.0; 9 * in_blocks * out_blocks * 16];
    for o in 0..out {
        for i in 0..inputs {
            // The input channel's block and lane: b's channels start on a
            // block of their own.
            let (block, lane) = if i < a { (i / BLOCK, i % BLOCK) } else { (a_blocks + (i - a) / BLOCK, (i - a) % BLOCK) };
            for tap in 0..9 {
                let m = (tap * in_blocks + block) * out_blocks + o / BLOCK;
                w[m * 16 + lane * 4 + o % BLOCK] = weight[(o * inputs + i) * 9 + tap];
            }
        }
    }
    let mut padded_bias = vec![0.0; out_blocks * BLOCK];
    padded_bias[..out].copy_from_slice(bias);
    (w, padded_bias)
}

#[cfg(test)]
#[path = "tests.rs"]
mod tests;
