//! The kernels on the device (lavapipe without a GPU) against a plain CPU
//! convolution written here from the definition: upsample, concatenate,
//! then a 3×3 "same" convolution with zero padding.

use wgpu::util::DeviceExt;

use super::*;
use crate::render::denoise_weights::{BLOCK, blocks, pack_conv};
use crate::gpu::Gpu;
use crate::gpu::pipeline::Pipeline;
use crate::render::resource::PipelineKey;

fn pipeline(gpu: &Gpu, key: &PipelineKey) -> wgpu::ComputePipeline {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let lib = crate::shader::library::read_tree(&root).unwrap();
    let display = crate::diag::display_path(&root.join(key.spec.shader));
    let compiled = crate::render::pipelines::compose(&crate::shader::NagaOil, &lib, key, &display).unwrap_or_else(|d| panic!("{d:?}"));
    match crate::gpu::pipeline::create(&gpu.device, key.spec, &key.defs, &compiled.composed, &lib, &display, None).unwrap_or_else(|d| panic!("{d:?}")) {
        Pipeline::Compute(p) => (*p).clone(),
        Pipeline::Render(_) => unreachable!("a compute spec"),
    }
}

fn buffer(gpu: &Gpu, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: data, usage })
}

/// Runs `pipeline` with `groups` (per group, its (binding, buffer) pairs)
/// and reads back `out` (`len` floats).
fn run(gpu: &Gpu, pipeline: &wgpu::ComputePipeline, groups: &[&[(u32, &wgpu::Buffer)]], out: &wgpu::Buffer, len: usize, workgroups: [u32; 3]) -> Vec<f32> {
    let bind_groups: Vec<wgpu::BindGroup> = groups
        .iter()
        .enumerate()
        .map(|(i, entries)| {
            let entries: Vec<wgpu::BindGroupEntry> = entries.iter().map(|(b, buf)| wgpu::BindGroupEntry { binding: *b, resource: buf.as_entire_binding() }).collect();
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout: &pipeline.get_bind_group_layout(i as u32), entries: &entries })
        })
        .collect();
    let read = gpu.device.create_buffer(&wgpu::BufferDescriptor { label: None, size: (len * 4) as u64, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        for (i, g) in bind_groups.iter().enumerate() {
            pass.set_bind_group(i as u32, g, &[]);
        }
        pass.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
    }
    encoder.copy_buffer_to_buffer(out, 0, &read, 0, (len * 4) as u64);
    gpu.queue.submit([encoder.finish()]);
    read.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("mapped"));
    gpu.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let bytes = read.slice(..).get_mapped_range().expect("mapped").to_vec();
    bytemuck::cast_slice::<u8, f32>(&bytes).to_vec()
}

/// A deterministic value in [-1, 1) for index i of stream `seed`.
fn noise(seed: u32, i: usize) -> f32 {
    let mut x = (i as u32).wrapping_mul(0x9E37_79B9) ^ seed.wrapping_mul(0x85EB_CA6B);
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    (x >> 8) as f32 / (1u32 << 23) as f32 - 1.0
}

/// A planar-free, channels-last tensor: `[y][x][c]` with `c` exact.
struct Tensor {
    w: usize,
    h: usize,
    c: usize,
    data: Vec<f32>,
}

impl Tensor {
    fn random(w: usize, h: usize, c: usize, seed: u32) -> Tensor {
        Tensor { w, h, c, data: (0..w * h * c).map(|i| noise(seed, i)).collect() }
    }

    fn at(&self, x: usize, y: usize, c: usize) -> f32 {
        self.data[(y * self.w + x) * self.c + c]
    }

    /// As the kernels store it: channels padded to whole blocks.
    fn padded(&self) -> Vec<f32> {
        let b = blocks(self.c) * BLOCK;
        let mut out = vec![0.0; self.w * self.h * b];
        for p in 0..self.w * self.h {
            out[p * b..p * b + self.c].copy_from_slice(&self.data[p * self.c..(p + 1) * self.c]);
        }
        out
    }
}

/// The reference: `a` upsampled 2× (nearest) when asked, `b`'s channels
/// after it, a 3×3 zero-padded convolution, bias, optional ReLU.
fn reference(a: &Tensor, b: Option<&Tensor>, upsample: bool, weight: &[f32], bias: &[f32], out: usize, relu: bool) -> Tensor {
    let (w, h) = if upsample { (a.w * 2, a.h * 2) } else { (a.w, a.h) };
    let inputs = a.c + b.map_or(0, |b| b.c);
    let input = |x: usize, y: usize, i: usize| if i < a.c { if upsample { a.at(x / 2, y / 2, i) } else { a.at(x, y, i) } } else { b.unwrap().at(x, y, i - a.c) };
    let mut data = vec![0.0; w * h * out];
    for y in 0..h {
        for x in 0..w {
            for o in 0..out {
                let mut sum = f64::from(bias[o]);
                for i in 0..inputs {
                    for tap in 0..9 {
                        let (sx, sy) = (x as i64 + (tap % 3) as i64 - 1, y as i64 + (tap / 3) as i64 - 1);
                        if sx >= 0 && sy >= 0 && (sx as usize) < w && (sy as usize) < h {
                            sum += f64::from(weight[(o * inputs + i) * 9 + tap]) * f64::from(input(sx as usize, sy as usize, i));
                        }
                    }
                }
                data[(y * w + x) * out + o] = if relu { sum.max(0.0) as f32 } else { sum as f32 };
            }
        }
    }
    Tensor { w, h, c: out, data }
}

/// Both convolution kernels.
const KERNELS: [DenoiserKernel; 2] = [DenoiserKernel::Direct, DenoiserKernel::Tiled];

#[allow(clippy::too_many_arguments)]
fn conv_on_gpu(gpu: &Gpu, kernel: DenoiserKernel, a: &Tensor, b: Option<&Tensor>, upsample: bool, weight: &[f32], bias: &[f32], out: usize, relu: bool) -> Vec<f32> {
    let key = PipelineKey::new(conv_spec(kernel), &[(UPSAMPLE, upsample), (CONCAT, b.is_some())]);
    let p = pipeline(gpu, &key);
    let (w, h) = if upsample { (a.w * 2, a.h * 2) } else { (a.w, a.h) };
    let b_channels = b.map_or(0, |b| b.c);
    let (packed, packed_bias) = pack_conv(weight, bias, a.c, b_channels, out);
    let u = LayerUniform {
        width: w as u32,
        height: h as u32,
        a_width: a.w as u32,
        a_height: a.h as u32,
        a_blocks: blocks(a.c) as u32,
        b_blocks: blocks(b_channels) as u32,
        out_blocks: blocks(out) as u32,
        relu: relu.into(),
    };
    use wgpu::BufferUsages as U;
    let uniform = buffer(gpu, bytemuck::bytes_of(&u), U::UNIFORM);
    let a_buf = buffer(gpu, bytemuck::cast_slice(&a.padded()), U::STORAGE);
    let weights = buffer(gpu, bytemuck::cast_slice(&packed), U::STORAGE);
    let bias_buf = buffer(gpu, bytemuck::cast_slice(&packed_bias), U::STORAGE);
    let len = w * h * blocks(out) * BLOCK;
    let out_buf = buffer(gpu, &vec![0xffu8; len * 4], U::STORAGE | U::COPY_SRC);
    let b_buf = b.map(|b| buffer(gpu, bytemuck::cast_slice(&b.padded()), U::STORAGE));
    let group0: &[(u32, &wgpu::Buffer)] = &[(0, &uniform), (1, &a_buf), (3, &weights), (4, &bias_buf), (5, &out_buf)];
    let group1 = b_buf.as_ref().map(|b| [(0u32, b)]);
    let mut groups = vec![group0];
    if let Some(g) = &group1 {
        groups.push(g);
    }
    run(gpu, &p, &groups, &out_buf, len, conv_workgroups(kernel, w as u32, h as u32, blocks(out) as u32))
}

/// Compares the padded GPU result with the exact-channel reference; the
/// padding lanes must be exactly 0.
fn assert_matches(gpu: &[f32], want: &Tensor, what: &str) {
    let b = blocks(want.c) * BLOCK;
    let mut worst = 0.0f32;
    for p in 0..want.w * want.h {
        for c in 0..b {
            let got = gpu[p * b + c];
            if c >= want.c {
                assert_eq!(got, 0.0, "{what}: padding lane {c} of pixel {p}");
                continue;
            }
            let expect = want.data[p * want.c + c];
            worst = worst.max((got - expect).abs() / (1.0 + expect.abs()));
        }
    }
    // f32 sums of a few hundred terms in another order than the f64 reference.
    assert!(worst < 1e-5, "{what}: worst relative error {worst}");
}

/// Both kernels, at a size that is no multiple of either's tile (edge
/// tiles on the right and bottom, the tiled kernel's halo crossing tiles)
/// with 3 input blocks (the tiled kernel's last chunk half full).
#[test]
fn a_plain_convolution_matches_the_definition() {
    let gpu = crate::gpu::testing::device();
    let (cin, out) = (9, 7);
    let a = Tensor::random(37, 19, cin, 1);
    let weight: Vec<f32> = (0..out * cin * 9).map(|i| noise(2, i) * 0.3).collect();
    let bias: Vec<f32> = (0..out).map(|i| noise(3, i)).collect();
    for kernel in KERNELS {
        for relu in [false, true] {
            let got = conv_on_gpu(&gpu, kernel, &a, None, false, &weight, &bias, out, relu);
            assert_matches(&got, &reference(&a, None, false, &weight, &bias, out, relu), &format!("{kernel:?}, relu {relu}"));
        }
    }
}

#[test]
fn upsample_concat_and_convolution_fused_match_the_three_done_apart() {
    let gpu = crate::gpu::testing::device();
    // Channel counts off the block size, a's blocks odd (a chunk of the
    // tiled kernel holds a's last block and b's first), and more outputs
    // than one invocation's blocks, so every lane and block boundary is
    // crossed; the output, 22×18, is no multiple of either kernel's tile.
    let (ca, cb, out) = (10, 5, 21);
    let a = Tensor::random(11, 9, ca, 4);
    let b = Tensor::random(22, 18, cb, 5);
    let weight: Vec<f32> = (0..out * (ca + cb) * 9).map(|i| noise(6, i) * 0.3).collect();
    let bias: Vec<f32> = (0..out).map(|i| noise(7, i)).collect();
    for kernel in KERNELS {
        let got = conv_on_gpu(&gpu, kernel, &a, Some(&b), true, &weight, &bias, out, true);
        assert_matches(&got, &reference(&a, Some(&b), true, &weight, &bias, out, true), &format!("{kernel:?}, fused"));
    }
}

#[test]
fn max_pool_takes_the_largest_of_each_two_by_two() {
    let gpu = crate::gpu::testing::device();
    let p = pipeline(&gpu, &PipelineKey::new(&POOL, &[]));
    // An odd size: the last column and row pool what they have.
    let t = Tensor::random(7, 5, 6, 8);
    let (ow, oh, b) = (4, 3, blocks(6));
    use wgpu::BufferUsages as U;
    let uniform = buffer(&gpu, bytemuck::bytes_of(&PoolUniform { width: 7, height: 5, blocks: b as u32, pad: 0 }), U::UNIFORM);
    let input = buffer(&gpu, bytemuck::cast_slice(&t.padded()), U::STORAGE);
    let len = ow * oh * b * BLOCK;
    let out = buffer(&gpu, &vec![0u8; len * 4], U::STORAGE | U::COPY_SRC);
    let got = run(&gpu, &p, &[&[(0, &uniform), (1, &input), (2, &out)]], &out, len, [1, 1, b as u32]);
    let mut want = Tensor { w: ow, h: oh, c: 6, data: vec![0.0; ow * oh * 6] };
    for y in 0..oh {
        for x in 0..ow {
            for c in 0..6 {
                let mut m = f32::NEG_INFINITY;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = ((2 * x + dx).min(6), (2 * y + dy).min(4));
                    m = m.max(t.at(sx, sy, c));
                }
                want.data[(y * ow + x) * 6 + c] = m;
            }
        }
    }
    assert_matches(&got, &want, "pool");
}
