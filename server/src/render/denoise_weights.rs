//! The denoiser's weights on the GPU: each convolution's weights and bias
//! packed as both convolution kernels read them (`shaders/lib/conv.wgsl`), uploaded once per
//! network and kept while the network and the way its upsamples and
//! concatenations run (fused into the convolution or not) are the same: a
//! scene edit that moves a light keeps them. Built only for scenes whose
//! path-traced frame is denoised.
//!
//! Tensors are channels-last with channels padded to whole blocks of
//! `BLOCK` (one `vec4` per pixel and block), so every load is a whole
//! vector; `pack_conv` documents the weights' layout.

use std::sync::Arc;

use wgpu::util::DeviceExt;

use crate::denoise::network::{Conv, Network, Op, TensorId};

/// Lanes of a channel block.
pub const BLOCK: usize = 4;
/// Output blocks one invocation of the direct convolution, or one
/// workgroup of the tiled one, computes (`BLOCKS` in `lib/conv.wgsl`): the
/// weights' and bias's output blocks are padded to a multiple.
pub const CONV_BLOCKS: usize = 4;

/// Channel blocks holding `channels`.
pub fn blocks(channels: usize) -> usize {
    channels.div_ceil(BLOCK)
}

/// OIHW weights (`out × (a + b) × 3 × 3`) and a bias, laid out as the
/// shader reads them: per tap, per input block (a's blocks, then b's), per
/// output block, a column-major 4×4 matrix whose column c holds input
/// channel c's weights to the block's four outputs. Padding lanes are 0,
/// so padded channels contribute nothing and padded outputs stay 0.
pub fn pack_conv(weight: &[f32], bias: &[f32], a: usize, b: usize, out: usize) -> (Vec<f32>, Vec<f32>) {
    let inputs = a + b;
    debug_assert_eq!(weight.len(), out * inputs * 9);
    let (a_blocks, in_blocks) = (blocks(a), blocks(a) + blocks(b));
    let out_blocks = blocks(out).next_multiple_of(CONV_BLOCKS);
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

/// A convolution that runs its input's upsample and concatenation itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fusion {
    /// What it reads: the tensor before the upsample, and the skip
    /// connection concatenated after it.
    pub a: TensorId,
    pub skip: TensorId,
    /// The tensors it does not need stored.
    pub upsampled: TensorId,
    pub concatenated: TensorId,
}

/// How `conv` runs fused, or `None` when its input is not the
/// concatenation of an upsample, or either of those is read by another op
/// too (then it is stored anyway).
pub fn fused_inputs(net: &Network, conv: &Conv) -> Option<Fusion> {
    let (upsampled, skip) = net.ops.iter().find_map(|op| match op {
        Op::Concat { first, second, dst } if *dst == conv.src => Some((*first, *second)),
        _ => None,
    })?;
    let a = net.ops.iter().find_map(|op| match op {
        Op::Upsample { src, dst } if *dst == upsampled => Some(*src),
        _ => None,
    })?;
    let read_once = |t: TensorId| !net.tensor(t).skip;
    (read_once(upsampled) && read_once(conv.src)).then_some(Fusion { a, skip, upsampled, concatenated: conv.src })
}

/// One convolution's packed weights and bias.
pub struct ConvWeights {
    pub weights: wgpu::Buffer,
    pub bias: wgpu::Buffer,
}

pub struct DenoiseWeights {
    network: Arc<Network>,
    fused: bool,
    /// Per op of the network: its weights when it is a convolution.
    convs: Arc<Vec<Option<ConvWeights>>>,
}

impl DenoiseWeights {
    /// Packs and uploads `network`'s weights for the fused kernels (`fused`)
    /// or the separate ones, or keeps `previous`'s when they are the same.
    pub fn new(device: &wgpu::Device, network: &Arc<Network>, fused: bool, previous: Option<&DenoiseWeights>) -> Self {
        if let Some(p) = previous.filter(|p| p.fused == fused && (Arc::ptr_eq(&p.network, network) || p.network == *network)) {
            return DenoiseWeights { network: network.clone(), fused, convs: p.convs.clone() };
        }
        let convs = network
            .ops
            .iter()
            .map(|op| {
                let Op::Conv(c) = op else { return None };
                let (a, b) = match fused.then(|| fused_inputs(network, c)).flatten() {
                    Some(f) => (network.tensor(f.a).channels, network.tensor(f.skip).channels),
                    None => (c.in_channels, 0),
                };
                let (w, bias) = pack_conv(&c.weight, &c.bias, a, b, c.out_channels);
                let storage = |label: String, data: &[f32]| {
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(&label),
                        contents: bytemuck::cast_slice(data),
                        usage: wgpu::BufferUsages::STORAGE,
                    })
                };
                Some(ConvWeights { weights: storage(format!("{} weights", c.name), &w), bias: storage(format!("{} bias", c.name), &bias) })
            })
            .collect();
        log::info!("denoiser: uploaded the weights of {} convolutions", network.ops.iter().filter(|op| matches!(op, Op::Conv(_))).count());
        DenoiseWeights { network: network.clone(), fused, convs: Arc::new(convs) }
    }

    /// The weights of op `op`, when it is a convolution.
    pub fn conv(&self, op: usize) -> Option<&ConvWeights> {
        self.convs.get(op)?.as_ref()
    }

    /// Whether `other` shares this one's buffers (they were not uploaded again).
    pub fn same_buffers(&self, other: &DenoiseWeights) -> bool {
        Arc::ptr_eq(&self.convs, &other.convs)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use crate::denoise::testing::{network, small_unet};
    use crate::render::scene_gpu::SceneGpu;

    const SCENE: &str = "[quality]\nrenderer = \"path\"\n[denoiser]\nweights = \"w.tza\"\n\
        [[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\n";

    /// A scene edit keeps the uploaded weights, as does the same network
    /// read again; another network or the other fusion uploads; a frame
    /// that is not denoised has none.
    #[test]
    fn the_weights_are_uploaded_once_per_network_and_fusion() {
        let gpu = crate::gpu::testing::device();
        let net = Arc::new(network(&small_unet(9), 1));
        let gpu_of = |text: &str, n: &Arc<crate::denoise::network::Network>, previous: Option<&SceneGpu>| {
            let scene = crate::scene::parse("s.toml", text).unwrap_or_else(|d| panic!("{d}"));
            SceneGpu::new(&gpu.device, &gpu.queue, &scene, &Default::default(), &Default::default(), Some(n), previous)
        };
        let first = gpu_of(SCENE, &net, None);
        let weights = first.denoiser.as_ref().expect("a denoised frame has weights");
        assert!(weights.conv(0).is_some() && weights.conv(net.ops.len()).is_none());
        let kept = |g: &SceneGpu| g.denoiser.as_ref().is_some_and(|w| w.same_buffers(weights));
        assert!(kept(&gpu_of(&SCENE.replace("[0, 2, 0]", "[1, 2, 0]"), &net, Some(&first))), "a light moved");
        assert!(kept(&gpu_of(SCENE, &Arc::new(network(&small_unet(9), 1)), Some(&first))), "the same weights read again");
        assert!(!kept(&gpu_of(SCENE, &Arc::new(network(&small_unet(9), 2)), Some(&first))), "other weights");
        let separate = SCENE.replace("renderer = \"path\"", "renderer = \"path\"\ndenoiser_fused = false");
        assert!(!kept(&gpu_of(&separate, &net, Some(&first))), "the other fusion packs the concatenations' weights otherwise");
        assert!(gpu_of(&SCENE.replace("\"path\"", "\"raster\""), &net, Some(&first)).denoiser.is_none(), "the raster is not denoised");
    }
}
