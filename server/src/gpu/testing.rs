//! Test fixtures of the GPU layer, for the tests of any module that runs
//! WGSL and for the integration suites (the `testing` feature): the test
//! device, and WGSL run from tests. A compute shader reads an array of
//! inputs and writes one result per invocation, read back to the CPU.
//! The shader may `#import` the shader library (`shaders/lib/`), composed
//! exactly as the renderer composes it.
//!
//! The shader's interface, checked against the Rust types before anything
//! runs:
//!
//! ```wgsl
//! @group(0) @binding(0) var<storage, read> input: array<T>;
//! @group(0) @binding(1) var<storage, read_write> output: array<U>;
//! // optional: @group(0) @binding(2), (3), … var t: texture_2d<f32>;
//!
//! @compute @workgroup_size(64)
//! fn main(@builtin(global_invocation_id) id: vec3<u32>) {
//!     if id.x >= arrayLength(&output) { return; }
//!     output[id.x] = f(input[id.x]);
//! }
//! ```
//!
//! One invocation per output element is dispatched; the element types'
//! array strides must equal the Rust types' sizes. Textures are bound as the
//! renderer binds its read-only ones: unfilterable float, read with
//! `textureLoad`. Read-only storage buffers the library's modules declare
//! at group 1 (`loupe::bvh`'s nodes and triangles) are bound from buffers
//! the caller gives `Kernel::run_bound`, in binding order.

use std::path::Path;

use naga::{AddressSpace, StorageAccess, TypeInner};

use super::Gpu;
use super::pipeline;
use crate::diag::Diagnostic;
use crate::shader::{Compose, NagaOil, ShaderDefs, SourceFile, library};

/// Why a kernel could not be built or run. Every misuse is one of these,
/// never a panic.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("the shader does not compose:\n{}", join(.0))]
    Compose(Vec<Diagnostic>),
    #[error("the shader's interface: {0}")]
    Interface(String),
    #[error("the request: {0}")]
    Request(String),
    #[error("wgpu: {0}")]
    Wgpu(String),
}

fn join(ds: &[Diagnostic]) -> String {
    ds.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n")
}

/// The device tests run on, as the renderer opens it. The suite runs on
/// lavapipe where there is no GPU, so having none is a test failure.
pub fn device() -> Gpu {
    super::open()
        .unwrap_or_else(|e| panic!("this test needs a GPU device (lavapipe will do: apt-get install mesa-vulkan-drivers libvulkan1): {e}"))
}

/// A compiled compute shader, ready to run over many inputs.
pub struct Kernel {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    workgroup_width: u32,
    input_stride: u64,
    output_stride: u64,
    textures: usize,
    /// The layout of group 1 and its buffer count, when the shader binds any.
    group1: Option<(wgpu::BindGroupLayout, usize)>,
}

/// Composes `source` (which may import `shaders/lib/`) and runs `entry` over
/// `inputs`, returning `output_len` results.
pub fn run_compute<T: bytemuck::Pod, U: bytemuck::Pod>(
    gpu: &Gpu,
    source: &str,
    entry: &str,
    inputs: &[T],
    output_len: usize,
) -> Result<Vec<U>, Error> {
    Kernel::new(gpu, source, entry)?.run(gpu, inputs, output_len, &[])
}

impl Kernel {
    pub fn new(gpu: &Gpu, source: &str, entry: &str) -> Result<Kernel, Error> {
        Self::with_modules(gpu, source, entry, &[])
    }

    /// `new`, with `modules` (generated ones, such as a material module)
    /// added to the library `source` imports from.
    pub fn with_modules(gpu: &Gpu, source: &str, entry: &str, modules: &[SourceFile]) -> Result<Kernel, Error> {
        let module = compose(gpu, source, modules)?;
        let ep = module
            .entry_points
            .iter()
            .find(|e| e.name == entry && e.stage == naga::ShaderStage::Compute)
            .ok_or_else(|| Error::Interface(format!("no @compute entry point `{entry}`")))?;
        let [workgroup_width, 1, 1] = ep.workgroup_size else {
            return Err(Error::Interface(format!("workgroup size {:?} is not one-dimensional", ep.workgroup_size)));
        };
        let input_stride = array_stride(&module, 0, StorageAccess::LOAD)?;
        let output_stride = array_stride(&module, 1, StorageAccess::LOAD | StorageAccess::STORE)?;
        let textures = texture_count(&module)?;
        let buffers = group1_count(&module)?;

        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("test kernel"),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(module)),
        });
        let mut entries = vec![pipeline::storage("inputs", 0, wgpu::ShaderStages::COMPUTE).entry, read_write(1)];
        entries.extend((0..textures as u32).map(|k| pipeline::texture("texture", 2 + k).entry));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("test kernel"), entries: &entries });
        let group1 = (buffers > 0).then(|| {
            let entries: Vec<_> = (0..buffers as u32).map(|b| pipeline::storage("group 1", b, wgpu::ShaderStages::COMPUTE).entry).collect();
            (
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("test kernel group 1"), entries: &entries }),
                buffers,
            )
        });
        let mut layouts = vec![Some(&layout)];
        layouts.extend(group1.as_ref().map(|(l, _)| Some(l)));
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("test kernel"),
            bind_group_layouts: &layouts,
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("test kernel"),
            layout: Some(&pipeline_layout),
            module: &shader,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Wgpu(e.to_string()));
        }
        Ok(Kernel { pipeline, layout, workgroup_width, input_stride, output_stride, textures, group1 })
    }

    /// Runs the kernel once per output element with `textures` bound at
    /// bindings 2, 3, …, and reads the results back.
    pub fn run<T: bytemuck::Pod, U: bytemuck::Pod>(
        &self,
        gpu: &Gpu,
        inputs: &[T],
        output_len: usize,
        textures: &[&wgpu::TextureView],
    ) -> Result<Vec<U>, Error> {
        self.run_bound(gpu, inputs, output_len, textures, &[])
    }

    /// `run`, with `buffers` bound at group 1, bindings 0, 1, ….
    pub fn run_bound<T: bytemuck::Pod, U: bytemuck::Pod>(
        &self,
        gpu: &Gpu,
        inputs: &[T],
        output_len: usize,
        textures: &[&wgpu::TextureView],
        buffers: &[&wgpu::Buffer],
    ) -> Result<Vec<U>, Error> {
        let request = |m: String| Err(Error::Request(m));
        let declared = self.group1.as_ref().map_or(0, |(_, n)| *n);
        if buffers.len() != declared {
            return request(format!("{} buffers given for group 1; the shader declares {declared}", buffers.len()));
        }
        if size_of::<T>() as u64 != self.input_stride {
            return request(format!("input elements are {} bytes; the shader's array stride is {}", size_of::<T>(), self.input_stride));
        }
        if size_of::<U>() as u64 != self.output_stride {
            return request(format!("output elements are {} bytes; the shader's array stride is {}", size_of::<U>(), self.output_stride));
        }
        if inputs.is_empty() || output_len == 0 {
            return request(format!("{} inputs and {output_len} outputs: a storage buffer cannot be empty", inputs.len()));
        }
        if textures.len() != self.textures {
            return request(format!("{} textures given; the shader declares {}", textures.len(), self.textures));
        }
        let limits = gpu.device.limits();
        let in_bytes = std::mem::size_of_val(inputs) as u64;
        let out_bytes = (output_len as u64).saturating_mul(self.output_stride);
        let largest = super::largest_binding(&limits);
        if in_bytes.max(out_bytes) > largest {
            return request(format!("{in_bytes} input and {out_bytes} output bytes; the device binds at most {largest}"));
        }
        let groups = (output_len as u64).div_ceil(u64::from(self.workgroup_width));
        if groups > u64::from(limits.max_compute_workgroups_per_dimension) {
            return request(format!("{groups} workgroups; the device dispatches at most {}", limits.max_compute_workgroups_per_dimension));
        }

        let (device, queue) = (&gpu.device, &gpu.queue);
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let input = buffer("test input", in_bytes, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
        queue.write_buffer(&input, 0, bytemuck::cast_slice(inputs));
        let output = buffer("test output", out_bytes, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let readback = buffer("test readback", out_bytes, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
        let mut entries = vec![
            wgpu::BindGroupEntry { binding: 0, resource: input.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: output.as_entire_binding() },
        ];
        entries.extend(
            textures
                .iter()
                .zip(2..)
                .map(|(view, binding)| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) }),
        );
        let bind_group =
            device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("test kernel"), layout: &self.layout, entries: &entries });
        let group1 = self.group1.as_ref().map(|(layout, _)| {
            let entries: Vec<_> =
                buffers.iter().zip(0..).map(|(b, binding)| wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }).collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("test kernel group 1"), layout, entries: &entries })
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            if let Some(g) = &group1 {
                pass.set_bind_group(1, g, &[]);
            }
            pass.dispatch_workgroups(groups as u32, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, out_bytes);
        queue.submit([encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::Wgpu(e.to_string()));
        }
        let (tx, rx) = std::sync::mpsc::channel();
        readback.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Wgpu(e.to_string()))?;
        rx.recv().map_err(|e| Error::Wgpu(e.to_string()))?.map_err(|e| Error::Wgpu(e.to_string()))?;
        let data = readback.slice(..).get_mapped_range().map_err(|e| Error::Wgpu(e.to_string()))?;
        Ok(bytemuck::pod_collect_to_vec(&data))
    }
}

/// The shader composed with the repository's shader library.
fn compose(gpu: &Gpu, source: &str, modules: &[SourceFile]) -> Result<naga::Module, Error> {
    let shaders = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let mut lib = library::read_tree(&shaders.join("lib")).map_err(Error::Interface)?;
    for m in modules {
        lib.upsert(m.clone());
    }
    let entry = SourceFile::from_text("test_kernel.wgsl".into(), shaders.join("test_kernel.wgsl"), source.into());
    lib.upsert(entry.clone());
    NagaOil.compose(&lib, &entry, &ShaderDefs::new(), gpu.capabilities()).map(|c| c.module).map_err(Error::Compose)
}

/// A storage buffer the shader writes.
fn read_write(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: false },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The element stride of the runtime-sized storage array at `@group(0)
/// @binding(binding)`, which must have exactly the access `access`.
fn array_stride(module: &naga::Module, binding: u32, access: StorageAccess) -> Result<u64, Error> {
    let what = if access.contains(StorageAccess::STORE) { "var<storage, read_write>" } else { "var<storage, read>" };
    let wrong = || Error::Interface(format!("@group(0) @binding({binding}) must be a {what} runtime-sized array"));
    let (_, global) = module
        .global_variables
        .iter()
        .find(|(_, g)| g.binding.as_ref().is_some_and(|b| b.group == 0 && b.binding == binding))
        .ok_or_else(wrong)?;
    match (global.space, &module.types[global.ty].inner) {
        (AddressSpace::Storage { access: a }, TypeInner::Array { size: naga::ArraySize::Dynamic, stride, .. }) if a == access => {
            Ok(u64::from(*stride))
        }
        _ => Err(wrong()),
    }
}

/// How many textures the shader binds after the two buffers; they must be
/// `texture_2d<f32>` at consecutive bindings from 2.
fn texture_count(module: &naga::Module) -> Result<usize, Error> {
    let mut bindings: Vec<u32> = Vec::new();
    for (_, g) in module.global_variables.iter() {
        let Some(b) = &g.binding else { continue };
        if b.group == 1 {
            continue;
        }
        if b.group != 0 {
            return Err(Error::Interface(format!("@group({}): only groups 0 and 1 are bound", b.group)));
        }
        if b.binding < 2 {
            continue;
        }
        let sampled_2d = matches!(
            module.types[g.ty].inner,
            TypeInner::Image {
                dim: naga::ImageDimension::D2,
                arrayed: false,
                class: naga::ImageClass::Sampled { kind: naga::ScalarKind::Float, multi: false }
            }
        );
        if !sampled_2d {
            return Err(Error::Interface(format!("@binding({}) must be a texture_2d<f32>", b.binding)));
        }
        bindings.push(b.binding);
    }
    bindings.sort_unstable();
    if bindings.iter().zip(2..).any(|(b, want)| *b != want) {
        return Err(Error::Interface(format!("textures must sit at consecutive bindings from 2, not {bindings:?}")));
    }
    Ok(bindings.len())
}

/// How many buffers the shader binds at group 1; they must be
/// `var<storage, read>` at consecutive bindings from 0.
fn group1_count(module: &naga::Module) -> Result<usize, Error> {
    let mut bindings: Vec<u32> = Vec::new();
    for (_, g) in module.global_variables.iter() {
        let Some(b) = g.binding.as_ref().filter(|b| b.group == 1) else { continue };
        if g.space != (AddressSpace::Storage { access: StorageAccess::LOAD }) {
            return Err(Error::Interface(format!("@group(1) @binding({}) must be a var<storage, read>", b.binding)));
        }
        bindings.push(b.binding);
    }
    bindings.sort_unstable();
    if bindings.iter().zip(0..).any(|(b, want)| *b != want) {
        return Err(Error::Interface(format!("group 1's buffers must sit at consecutive bindings from 0, not {bindings:?}")));
    }
    Ok(bindings.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOUBLE: &str = "
@group(0) @binding(0) var<storage, read> input: array<f32>;
@group(0) @binding(1) var<storage, read_write> output: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&output) {
        return;
    }
    output[id.x] = 2.0 * input[id.x];
}
";

    #[test]
    fn a_kernel_doubles_its_inputs() {
        let gpu = device();
        // More than one workgroup, not a multiple of its width.
        let inputs: Vec<f32> = (0..100).map(|i| i as f32 - 30.5).collect();
        let out: Vec<f32> = run_compute(&gpu, DOUBLE, "main", &inputs, inputs.len()).unwrap();
        assert_eq!(out, inputs.iter().map(|x| 2.0 * x).collect::<Vec<_>>());
    }

    #[test]
    fn imports_from_the_shader_library_resolve() {
        let gpu = device();
        let src = "
#import loupe::color::luminance

@group(0) @binding(0) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> output: array<f32>;

@compute @workgroup_size(8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&output) {
        output[id.x] = luminance(input[id.x].rgb);
    }
}
";
        let out: Vec<f32> = run_compute(&gpu, src, "main", &[[1.0f32, 1.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0]], 2).unwrap();
        assert!((out[0] - 1.0).abs() < 1e-6 && out[1] == 0.0, "{out:?}");
    }

    #[test]
    fn misuse_is_an_error_not_a_panic() {
        let gpu = device();
        let kernel = Kernel::new(&gpu, DOUBLE, "main").unwrap();
        let err = |r: Result<Vec<f32>, Error>| r.expect_err("must be refused").to_string();
        // Inputs of the wrong size for the shader's array.
        let pairs = [[1.0f32, 2.0]; 4];
        let e = kernel.run::<[f32; 2], f32>(&gpu, &pairs, 4, &[]).expect_err("wrong input size");
        assert!(e.to_string().contains("8 bytes") && e.to_string().contains("stride is 4"), "{e}");
        let e = kernel.run::<f32, [f32; 4]>(&gpu, &[1.0], 1, &[]).expect_err("wrong output size");
        assert!(e.to_string().contains("16 bytes"), "{e}");
        assert!(err(kernel.run(&gpu, &[] as &[f32], 1, &[])).contains("cannot be empty"));
        assert!(err(kernel.run(&gpu, &[1.0f32], 0, &[])).contains("cannot be empty"));
        // More output than the device can bind.
        assert!(err(kernel.run(&gpu, &[1.0f32], usize::MAX / 8, &[])).contains("at most"));
        let tex = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = tex.create_view(&Default::default());
        assert!(err(kernel.run(&gpu, &[1.0f32], 1, &[&view])).contains("1 textures given; the shader declares 0"));
        // A shader that does not compose, or lacks the entry point.
        let e = Kernel::new(&gpu, "fn broken( {", "main").err().expect("a parse error");
        assert!(matches!(e, Error::Compose(_)), "{e}");
        let e = Kernel::new(&gpu, DOUBLE, "nope").err().expect("no such entry point");
        assert!(e.to_string().contains("no @compute entry point `nope`"), "{e}");
        let e = Kernel::new(&gpu, &DOUBLE.replace("storage, read>", "storage, read_write>"), "main").err().expect("input written");
        assert!(e.to_string().contains("@binding(0) must be a var<storage, read>"), "{e}");
        // A module that binds buffers at group 1 (the BVH's) needs them.
        let traced = "#import loupe::bvh::occluded
@group(0) @binding(0) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&output) {
        output[id.x] = select(0u, 1u, occluded(input[id.x].xyz, vec3(0.0, 0.0, 1.0), 0.0, 1.0));
    }
}";
        let bvh = Kernel::new(&gpu, traced, "main").unwrap();
        let e = bvh.run::<[f32; 4], u32>(&gpu, &[[0.0; 4]], 1, &[]).expect_err("no buffers for group 1");
        assert!(e.to_string().contains("0 buffers given for group 1; the shader declares 2"), "{e}");
        // The kernel still works after all that.
        assert_eq!(kernel.run::<f32, f32>(&gpu, &[1.5], 1, &[]).unwrap(), [3.0]);
    }
}
