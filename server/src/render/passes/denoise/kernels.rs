//! The denoiser's network kernels (`shaders/denoise/`): their pipeline
//! specs and the uniforms they read. Tensors are channels-last, channels
//! padded to a multiple of 4 (one `vec4` per pixel and block, f32 or with
//! F16 four halves: `shaders/lib/tensor.wgsl`), so every load is a whole
//! vector; the weights' layout is `render::denoise_weights::pack_conv`'s.

use crate::gpu::pipeline::{COMPUTE, Group, PipelineSpec, Stages, sizes, storage, storage_rw, uniform};
use crate::render::denoise_weights::CONV_BLOCKS;
use crate::scene::DenoiserKernel;

/// Every kernel's workgroup side in invocations.
pub const TILE: u32 = 8;

/// The tiled convolution's output tile per workgroup in pixels
/// (`TILE_W` × `TILE_H` in `conv_tiled.wgsl`).
const TILED: (u32, u32) = (2 * TILE, TILE);

/// Reads the first input 2× nearest-upsampled.
pub const UPSAMPLE: &str = "UPSAMPLE";
/// Takes a second input, concatenated after the first along channels.
pub const CONCAT: &str = "CONCAT";
/// Tensors stored as f16 (accumulation stays f32); the convolution counts
/// the values too large for an f16.
pub const F16: &str = "F16";

/// Both convolution kernels bind the same (`shaders/lib/conv.wgsl`).
const CONV_GROUPS: &[Group] = &[
    Group::always(
        0,
        &[
            uniform("layer", 0, COMPUTE, 2 * sizes::VEC4),
            storage("a", 1, COMPUTE),
            storage("weights", 3, COMPUTE),
            storage("bias", 4, COMPUTE),
            storage_rw("out", 5),
        ],
    ),
    Group::when(1, CONCAT, &[storage("b", 0, COMPUTE)]),
    Group::when(2, F16, &[storage_rw("overflow", 0)]),
];

pub static CONV: PipelineSpec = PipelineSpec {
    name: "denoise.conv",
    shader: "denoise/conv.wgsl",
    stages: Stages::Compute { entry: "conv" },
    groups: CONV_GROUPS,
    defs: &[UPSAMPLE, CONCAT, F16],
};

pub static CONV_TILED: PipelineSpec = PipelineSpec {
    name: "denoise.conv_tiled",
    shader: "denoise/conv_tiled.wgsl",
    stages: Stages::Compute { entry: "conv" },
    groups: CONV_GROUPS,
    defs: &[UPSAMPLE, CONCAT, F16],
};

/// The pipeline of `kernel`'s convolution.
pub fn conv_spec(kernel: DenoiserKernel) -> &'static PipelineSpec {
    match kernel {
        DenoiserKernel::Direct => &CONV,
        DenoiserKernel::Tiled => &CONV_TILED,
    }
}

/// The workgroups of `kernel`'s convolution making a `width` × `height`
/// tensor of `out_blocks` channel blocks: each covers `CONV_BLOCKS` output
/// blocks and, direct, a `TILE` × `TILE` square of pixels (one per
/// invocation), tiled, its `TILED` tile.
pub fn conv_workgroups(kernel: DenoiserKernel, width: u32, height: u32, out_blocks: u32) -> [u32; 3] {
    let (tw, th) = match kernel {
        DenoiserKernel::Direct => (TILE, TILE),
        DenoiserKernel::Tiled => TILED,
    };
    [width.div_ceil(tw), height.div_ceil(th), out_blocks.div_ceil(CONV_BLOCKS as u32)]
}

pub static POOL: PipelineSpec = PipelineSpec {
    name: "denoise.pool",
    shader: "denoise/pool.wgsl",
    stages: Stages::Compute { entry: "max_pool" },
    groups: &[Group::always(0, &[uniform("pool", 0, COMPUTE, sizes::VEC4), storage("input", 1, COMPUTE), storage_rw("out", 2)])],
    defs: &[F16],
};

/// 2× nearest upsample, stored (when not fused into the convolution).
pub static UPSAMPLE_NEAREST: PipelineSpec = PipelineSpec {
    name: "denoise.upsample",
    shader: "denoise/upsample.wgsl",
    stages: Stages::Compute { entry: "upsample_nearest" },
    groups: &[Group::always(0, &[uniform("upsample", 0, COMPUTE, sizes::VEC4), storage("input", 1, COMPUTE), storage_rw("out", 2)])],
    defs: &[F16],
};

/// Concatenation along channels, stored (when not fused into the convolution).
pub static CONCAT_CHANNELS: PipelineSpec = PipelineSpec {
    name: "denoise.concat",
    shader: "denoise/concat.wgsl",
    stages: Stages::Compute { entry: "concat_channels" },
    groups: &[Group::always(0, &[uniform("concat", 0, COMPUTE, sizes::VEC4), storage("a", 1, COMPUTE), storage("b", 2, COMPUTE), storage_rw("out", 3)])],
    defs: &[F16],
};

/// A convolution's uniform, as `Layer` in `lib/conv.wgsl` declares it.
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

/// The max-pool's uniform, as `Pool` in `pool.wgsl` declares it (the
/// input's size), and the upsample's, as `Upsample` in `upsample.wgsl`
/// declares it (the output's size).
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct PoolUniform {
    pub width: u32,
    pub height: u32,
    pub blocks: u32,
    pub pad: u32,
}

/// The concatenation's uniform, as `Concat` in `concat.wgsl` declares it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct ConcatUniform {
    pub width: u32,
    pub height: u32,
    pub a_channels: u32,
    pub b_channels: u32,
}

#[cfg(test)]
mod tests;
