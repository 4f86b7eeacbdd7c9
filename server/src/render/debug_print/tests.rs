//! Prints on a real device (lavapipe): a fragment and a compute stage
//! print their position, a uniform and an expression at three pixels; a
//! compute stage that maps invocations to pixels its own way prints from
//! the function that takes the pixel for the pixel only.

use std::path::PathBuf;
use std::sync::Arc;

use super::*;
use crate::gpu::{Gpu, testing};
use crate::shader::instrument_printf::{self, InstrumentedPrints};
use crate::shader::{Compose, Library, NagaOil};

const SIZE: u32 = 16;

const SHADER: &str = "enable wgpu_debug_printf;
@group(0) @binding(0) var<uniform> u: vec4<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    debugPrintf(\"at %v2f u %f sum %d\", p.xy, u.x, i32(p.x) * 100 + i32(p.y));
    return vec4(u.x);
}

@compute @workgroup_size(4, 4)
fn cs(@builtin(global_invocation_id) id: vec3<u32>) {
    debugPrintf(\"id %v2u u %.2f odd %u\", id.xy, u.y, (id.x + id.y) % 2u == 1u);
}

@compute @workgroup_size(4, 4)
fn everyone(@builtin(local_invocation_id) l: vec3<u32>) {
    debugPrintf(\"l %u\", l.x + 4u * l.y);
}

@compute @workgroup_size(1)
fn loops(@builtin(global_invocation_id) id: vec3<u32>) {
    for (var i = 0u; i < 100u; i++) {
        debugPrintf(\"i %u\", i);
    }
}

fn shade(texel: vec2<u32>, k: u32) {
    debugPrintf(\"texel %v2u k %u\", texel, k);
}

// Like the tiled lighting: each invocation of the first row of
// workgroups shades a column of four pixels, one per call.
@compute @workgroup_size(4, 4)
fn tiled(@builtin(workgroup_id) w: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>) {
    if w.y == 0u {
        for (var k = 0u; k < 4u; k++) {
            shade(vec2(l.x + 4u * w.x, l.y + 4u * k), k);
        }
    }
    debugPrintf(\"everyone\");
}

// A stage that selects by its global id follows the invocation, whatever
// the argument says.
@compute @workgroup_size(4, 4)
fn by_id(@builtin(global_invocation_id) id: vec3<u32>) {
    shade(id.yx, 9u);
}
";

fn source() -> (Arc<SourceFile>, naga::Module) {
    let lib = Library::new([SourceFile::from_text("print.wgsl".into(), PathBuf::from("print.wgsl"), SHADER.into())]);
    let file = lib.get("print.wgsl").unwrap().clone();
    let composed = NagaOil.compose(&lib, &file, &Default::default(), naga::valid::Capabilities::all()).unwrap();
    (file, composed.module)
}

fn shader(gpu: &Gpu, module: naga::Module) -> wgpu::ShaderModule {
    gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("print test"),
        source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(module)),
    })
}

fn uniform(gpu: &Gpu) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&[0.25f32, 0.75, 0.0, 0.0]),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

fn bind(gpu: &Gpu, layout: &wgpu::BindGroupLayout, resource: wgpu::BindingResource<'_>) -> wgpu::BindGroup {
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &[wgpu::BindGroupEntry { binding: 0, resource }],
    })
}

/// Runs `record` between the buffer's clear and copy, and decodes.
fn run(
    gpu: &Gpu,
    out: &InstrumentedPrints,
    file: &Arc<SourceFile>,
    words: u64,
    record: impl FnOnce(&mut wgpu::CommandEncoder, &PrintBuffer),
) -> Printed {
    let prints = PrintBuffer::new(&gpu.device, words);
    let table = Arc::new(table("test", &out.sites, std::slice::from_ref(file)));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    prints.clear(&mut encoder);
    record(&mut encoder, &prints);
    let groups = Default::default();
    let binding = PrintBinding { buffer: &prints, groups: &groups, table: &table, pixel: [0, 0] };
    let pending = prints.copy_out(&gpu.device, &mut encoder, &binding);
    gpu.queue.submit([encoder.finish()]);
    pending.map();
    gpu.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    pending.read().expect("mapped")
}

fn fragment(gpu: &Gpu, pixel: [u32; 2]) -> Printed {
    let (file, module) = source();
    let out = instrument_printf::instrument(&module, pixel, 0, 0).unwrap();
    let module = shader(gpu, out.module.clone());
    let pipeline = gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: None,
        layout: None,
        vertex: wgpu::VertexState { module: &module, entry_point: Some("vs"), compilation_options: Default::default(), buffers: &[] },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::TextureFormat::Rgba8Unorm.into())],
        }),
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    });
    let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: SIZE, height: SIZE, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());
    let u = uniform(gpu);
    run(gpu, &out, &file, DEFAULT_WORDS, |encoder, prints| {
        let own = bind(gpu, &pipeline.get_bind_group_layout(0), u.as_entire_binding());
        let printing = bind(gpu, &pipeline.get_bind_group_layout(out.group), prints.binding());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &own, &[]);
        pass.set_bind_group(out.group, &printing, &[]);
        pass.draw(0..3, 0..1);
    })
}

fn compute(gpu: &Gpu, entry: &str, pixel: [u32; 2], words: u64) -> Printed {
    let (file, module) = source();
    let out = instrument_printf::instrument(&module, pixel, 0, 0).unwrap();
    let module = shader(gpu, out.module.clone());
    let pipeline = gpu.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let u = uniform(gpu);
    let uses_uniform = entry == "cs";
    run(gpu, &out, &file, words, |encoder, prints| {
        let printing = bind(gpu, &pipeline.get_bind_group_layout(out.group), prints.binding());
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        if uses_uniform {
            pass.set_bind_group(0, &bind(gpu, &pipeline.get_bind_group_layout(0), u.as_entire_binding()), &[]);
        }
        pass.set_bind_group(out.group, &printing, &[]);
        pass.dispatch_workgroups(SIZE / 4, SIZE / 4, 1);
    })
}

fn texts(p: &Printed) -> Vec<(String, u32, u32, &str)> {
    p.lines.iter().map(|l| (l.file.clone(), l.line, l.column, l.text.as_str())).collect()
}

#[test]
fn a_fragment_stage_prints_at_the_selected_pixel_only() {
    let gpu = testing::device();
    for (pixel, text) in [
        ([0, 0], "at 0.500000, 0.500000 u 0.250000 sum 0"),
        ([3, 5], "at 3.500000, 5.500000 u 0.250000 sum 305"),
        ([15, 9], "at 15.500000, 9.500000 u 0.250000 sum 1509"),
    ] {
        let printed = fragment(&gpu, pixel);
        assert_eq!(texts(&printed), [("print.wgsl".to_owned(), 12, 5, text)], "{pixel:?}");
        assert_eq!(printed.dropped, 0);
    }
    let values = &fragment(&gpu, [3, 5]).lines[0].values;
    assert_eq!(*values, [serde_json::json!([3.5, 5.5]), serde_json::json!(0.25), serde_json::json!(305)]);
}

#[test]
fn a_compute_stage_prints_at_the_invocation_whose_id_is_the_pixel() {
    let gpu = testing::device();
    for (pixel, text) in [([0, 0], "id 0, 0 u 0.75 odd 0"), ([3, 2], "id 3, 2 u 0.75 odd 1"), ([15, 15], "id 15, 15 u 0.75 odd 0")] {
        let printed = compute(&gpu, "cs", pixel, DEFAULT_WORDS);
        assert_eq!(texts(&printed), [("print.wgsl".to_owned(), 18, 5, text)], "{pixel:?}");
    }
    assert_eq!(compute(&gpu, "cs", [SIZE, 0], DEFAULT_WORDS).lines, [], "no invocation is outside the grid");
}

/// A compute stage that does not read its global id prints from every
/// invocation: 16 workgroups of 16.
#[test]
fn a_compute_stage_without_a_global_id_prints_from_every_invocation() {
    let gpu = testing::device();
    let printed = compute(&gpu, "everyone", [0, 0], DEFAULT_WORDS);
    assert_eq!((printed.lines.len(), printed.dropped), (256, 0));
    for l in 0..16 {
        assert_eq!(printed.lines.iter().filter(|p| p.text == format!("l {l}")).count(), 16, "{l}");
    }
    let capped = compute(&gpu, "everyone", [0, 0], 100);
    assert_eq!((capped.lines.len(), capped.dropped), (50, 206));
}

/// 100 prints of 2 words each into 51 words: 25 fit, 75 are counted.
#[test]
fn prints_in_a_loop_overflow_with_the_right_count() {
    let gpu = testing::device();
    let printed = compute(&gpu, "loops", [0, 0], 51);
    let texts: Vec<&str> = printed.lines.iter().map(|l| l.text.as_str()).collect();
    assert_eq!(texts, (0..25).map(|i| format!("i {i}")).collect::<Vec<_>>());
    assert_eq!(printed.dropped, 75);
    let all = compute(&gpu, "loops", [0, 0], DEFAULT_WORDS);
    assert_eq!((all.lines.len(), all.dropped), (100, 0));
}

/// A compute stage without a global id: the calls of the function that
/// takes its pixel print for the selected pixel only, each call of the
/// loop answering for itself; a print elsewhere prints from every
/// invocation. A stage with a global id selects by it, not by the
/// argument.
#[test]
fn a_function_taking_its_pixel_prints_for_that_pixel_only() {
    let gpu = testing::device();
    for (pixel, k) in [([0, 0], 0), ([5, 9], 2), ([15, 14], 3)] {
        let printed = compute(&gpu, "tiled", pixel, DEFAULT_WORDS);
        let shaded: Vec<&str> = printed.lines.iter().map(|l| l.text.as_str()).filter(|t| t.starts_with("texel")).collect();
        assert_eq!(shaded, [format!("texel {}, {} k {k}", pixel[0], pixel[1])], "{pixel:?}");
        assert_eq!(printed.lines.iter().filter(|l| l.text == "everyone").count(), 256, "{pixel:?}");
    }
    let by_id: Vec<String> = compute(&gpu, "by_id", [5, 9], DEFAULT_WORDS).lines.into_iter().map(|l| l.text).collect();
    assert_eq!(by_id, ["texel 9, 5 k 9"]);
}
