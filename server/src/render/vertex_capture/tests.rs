//! Captures on the device (lavapipe where there is no GPU), of the
//! renderer's own shaders composed as the renderer composes them, against
//! positions worked out here on the CPU.

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3, Vec4};
use wgpu::util::DeviceExt;

use super::*;
use crate::diag::display_path;
use crate::gpu::Gpu;
use crate::gpu::pipeline::{MESH_VERTICES, Stages, TWO_TRIANGLES, VERT, uniform};
use crate::gpu::testing;
use crate::render::passes::{gbuffer::GBUFFER, tonemap::TONEMAP};
use crate::render::pipelines;
use crate::render::resource::PipelineKey;
use crate::shader::{Library, NagaOil, SourceFile, library};

fn shader_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders")
}

/// `key`'s module as the renderer composes it, from `lib`.
fn compose(lib: &Library, key: &PipelineKey) -> naga::Module {
    let display = display_path(&shader_root().join(key.spec.shader));
    pipelines::compose(&NagaOil, lib, key, &display).unwrap_or_else(|e| panic!("{e:?}")).composed.module
}

/// The shader tree, with the material module of the scene file's
/// shorthand (the G-buffer imports it).
fn repository_library() -> Library {
    let mut lib = library::read_tree(&shader_root()).unwrap();
    let program = crate::material::Program {
        definitions: vec![crate::material::shorthand(crate::diag::Location::file_start("test.toml"))],
        ..Default::default()
    };
    crate::render::session::material_module(&mut lib, &shader_root(), &program);
    lib
}

/// The G-buffer pipeline's key and a capture of its vertex stage,
/// composed from `lib`.
fn gbuffer_capture(gpu: &Gpu, lib: &Library) -> (PipelineKey, VertexCapture) {
    let key = PipelineKey::new(&GBUFFER, &[]);
    let vc = VertexCapture::new(&gpu.device, &compose(lib, &key), "vs_main", Some(&MESH_VERTICES)).unwrap();
    (key, vc)
}

/// Records, submits and reads back one capture.
fn capture(
    gpu: &Gpu,
    capture: &VertexCapture,
    layout: &[Option<&[Binding]>],
    bindings: &[(&'static str, wgpu::BindingResource<'_>)],
    draw: &Draw<'_>,
) -> Result<Vec<[f32; 4]>, CaptureError> {
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let pending = capture.record(&gpu.device, &mut encoder, layout, bindings, draw)?;
    gpu.queue.submit([encoder.finish()]);
    pending.map();
    gpu.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    assert!(pending.ready());
    let positions = pending.read();
    assert_eq!(*gpu.uncaptured.lock().unwrap(), Vec::<String>::new(), "no wgpu error went uncaught");
    positions
}

#[test]
fn the_fullscreen_stage_gives_the_triangle_and_the_quad() {
    let gpu = testing::device();
    let lib = repository_library();
    let triangle = vec![[-1.0, -1.0, 0.0, 1.0], [3.0, -1.0, 0.0, 1.0], [-1.0, 3.0, 0.0, 1.0]];
    let quad = [[-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, 1.0], [1.0, -1.0], [1.0, 1.0]].map(|[x, y]| [x, y, 0.0, 1.0]).to_vec();
    for (two, want) in [(false, triangle), (true, quad)] {
        let key = PipelineKey::new(&TONEMAP, &[(TWO_TRIANGLES, two)]);
        let vc = VertexCapture::new(&gpu.device, &compose(&lib, &key), "vs_fullscreen", None).unwrap();
        let draw = Draw { buffer: None, vertices: Vertices::Direct { first: 0 }, count: want.len() as u32, instance: 0 };
        assert_eq!(capture(&gpu, &vc, &key.spec.layout(&key.defs), &[], &draw).unwrap(), want, "TWO_TRIANGLES {two}");
    }
}

/// A scene's GPU data as `scene_gpu` lays it out, with known matrices.
struct Scene {
    view_proj: Mat4,
    models: [Mat4; 2],
    positions: [Vec3; 5],
    view: wgpu::Buffer,
    objects: wgpu::Buffer,
    materials: wgpu::Buffer,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
}

/// What the draw reads: indices 1..5, each plus a base vertex of -1
/// (wrapping, as the hardware adds it).
const INDICES: [u32; 5] = [7, 4, 2, 1, 3];
const BASE_VERTEX: i32 = -1;

impl Scene {
    fn new(gpu: &Gpu) -> Scene {
        let view_proj = Mat4::perspective_rh(1.1, 1.5, 0.1, 100.0) * Mat4::look_at_rh(Vec3::new(2.0, 3.0, 5.0), Vec3::ZERO, Vec3::Y);
        let models = [
            Mat4::IDENTITY,
            Mat4::from_scale_rotation_translation(
                Vec3::new(1.5, 0.5, 2.0),
                Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7),
                Vec3::new(0.3, -1.0, 2.0),
            ),
        ];
        let positions = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, -0.5, 0.25),
            Vec3::new(-2.0, 1.0, 0.5),
            Vec3::new(0.5, 2.0, -1.0),
            Vec3::new(-0.75, -1.25, 3.0),
        ];
        let mut view: Vec<f32> = [view_proj, view_proj.inverse()].iter().flat_map(|m| m.to_cols_array()).collect();
        view.extend([0.0; 8]); // position, params
        view.extend([0.0f32; 4]); // counts: bit patterns of zero
        view.extend([0.0; 8]); // environment
        let objects: Vec<u8> = models
            .iter()
            .flat_map(|m| {
                [
                    bytemuck::cast_slice(&m.to_cols_array()).to_vec(),
                    bytemuck::cast_slice(&m.inverse().transpose().to_cols_array()).to_vec(),
                    vec![0u8; 16],
                ]
                .concat()
            })
            .collect();
        // Position, normal, UV, tangent: `MESH_VERTICES`.
        let vertices: Vec<f32> = positions.iter().flat_map(|p| [p.x, p.y, p.z, 0.0, 1.0, 0.0, 0.5, 0.5, 1.0, 0.0, 0.0, 1.0]).collect();
        let init = |label, contents: &[u8], usage| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        use wgpu::BufferUsages as U;
        Scene {
            view_proj,
            models,
            positions,
            view: init("view", bytemuck::cast_slice(&view), U::UNIFORM),
            objects: init("objects", &objects, U::STORAGE),
            materials: init("materials", &[0; 32], U::STORAGE),
            vertices: init("vertices", bytemuck::cast_slice(&vertices), U::VERTEX | U::STORAGE),
            indices: init("indices", bytemuck::cast_slice(&INDICES), U::INDEX | U::STORAGE),
        }
    }

    /// The bindings as the G-buffer pass names them.
    fn bindings(&self) -> [(&'static str, wgpu::BindingResource<'_>); 3] {
        [
            ("view", self.view.as_entire_binding()),
            ("objects", self.objects.as_entire_binding()),
            ("materials", self.materials.as_entire_binding()),
        ]
    }

    /// Indices 1..5 of object 1.
    fn draw(&self) -> Draw<'_> {
        Draw {
            buffer: Some(&self.vertices),
            vertices: Vertices::Indexed { indices: &self.indices, first: 1, base_vertex: BASE_VERTEX },
            count: 4,
            instance: 1,
        }
    }

    /// view_proj · model · position of the vertices `draw` runs.
    fn expected(&self) -> Vec<Vec4> {
        INDICES[1..]
            .iter()
            .map(|&i| self.view_proj * self.models[1] * self.positions[(i as i32 + BASE_VERTEX) as usize].extend(1.0))
            .collect()
    }
}

fn assert_close(got: &[[f32; 4]], want: &[Vec4]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        let scale = w.abs().max_element().max(1.0);
        assert!((Vec4::from_array(*g) - *w).abs().max_element() <= 1e-5 * scale, "got {g:?}, want {w:?}");
    }
}

#[test]
fn the_gbuffer_stage_gives_view_proj_model_position() {
    let gpu = testing::device();
    let (key, vc) = gbuffer_capture(&gpu, &repository_library());
    let scene = Scene::new(&gpu);
    let got = capture(&gpu, &vc, &key.spec.layout(&key.defs), &scene.bindings(), &scene.draw()).unwrap();
    assert_close(&got, &scene.expected());
}

/// The capture is made from the module it is given: an edit to the vertex
/// shader shows in the positions.
#[test]
fn an_edited_vertex_shader_is_followed() {
    let gpu = testing::device();
    let mut lib = repository_library();
    let path = shader_root().join(GBUFFER.shader);
    let original = lib.get(&display_path(&path)).unwrap().text.to_string();
    let edited = original.replace("Varyings(view.view_proj * world,", "Varyings(view.view_proj * world + vec4(0.25, -0.5, 0.0, 0.125),");
    assert_ne!(edited, original, "the edit applies");
    lib.upsert(SourceFile::from_text(display_path(&path), path, edited.into()));
    let (key, vc) = gbuffer_capture(&gpu, &lib);
    let scene = Scene::new(&gpu);
    let got = capture(&gpu, &vc, &key.spec.layout(&key.defs), &scene.bindings(), &scene.draw()).unwrap();
    let moved: Vec<Vec4> = scene.expected().iter().map(|p| p + Vec4::new(0.25, -0.5, 0.0, 0.125)).collect();
    assert_close(&got, &moved);
}

/// Integer and narrower or wider formats, builtins as struct members, a
/// stride with padding, a direct draw from a first vertex, a binding in a
/// group past an unused one; names the WGSL writer renames (`clip0`).
const MIXED: &str = "
@group(1) @binding(0) var<uniform> scale: vec4<f32>;
struct In1 {
    @location(0) a: vec2<f32>,
    @builtin(vertex_index) index0: u32,
    @location(2) c: vec4<i32>,
}
struct Out1 {
    @location(0) color: vec4<f32>,
    @builtin(position) clip0: vec4<f32>,
}
@vertex
fn vs(v: In1, @location(1) b: u32, @builtin(instance_index) instance: u32) -> Out1 {
    let p = vec4(v.a.x + f32(b), v.a.y * f32(v.c.x + v.c.y), f32(v.c.z * 10 + v.c.w), f32(v.index0 * 100u + instance));
    return Out1(vec4(1.0), p * scale);
}
";

#[test]
fn formats_builtins_and_groups_are_read_as_the_pipeline_reads_them() {
    use wgpu::VertexFormat as F;
    let gpu = testing::device();
    let attributes = [
        wgpu::VertexAttribute { format: F::Float32x3, offset: 0, shader_location: 0 },
        wgpu::VertexAttribute { format: F::Uint32, offset: 12, shader_location: 1 },
        wgpu::VertexAttribute { format: F::Sint32x2, offset: 16, shader_location: 2 },
    ];
    let layout = wgpu::VertexBufferLayout { array_stride: 28, step_mode: wgpu::VertexStepMode::Vertex, attributes: &attributes };
    let module = naga::front::wgsl::parse_str(MIXED).unwrap();
    let vc = VertexCapture::new(&gpu.device, &module, "vs", Some(&layout)).unwrap();
    // Seven words a vertex: a (3 × f32), b (u32), c (2 × i32), padding.
    let words: Vec<u32> = (0..4u32)
        .flat_map(|v| [(v as f32 + 0.5).to_bits(), (2.0 - v as f32).to_bits(), 99f32.to_bits(), 10 * v, (v as i32 - 3) as u32, 4, 0xdead])
        .collect();
    let init = |contents: &[u8], usage| gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage });
    let vertices = init(bytemuck::cast_slice(&words), wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE);
    let scale = init(bytemuck::cast_slice(&[1.0f32, 2.0, 3.0, 1.0]), wgpu::BufferUsages::UNIFORM);
    static SCALE: &[Binding] = &[uniform("scale", 0, VERT, 16)];
    let draw = Draw { buffer: Some(&vertices), vertices: Vertices::Direct { first: 1 }, count: 3, instance: 7 };
    let got = capture(&gpu, &vc, &[None, Some(SCALE)], &[("scale", scale.as_entire_binding())], &draw).unwrap();
    let want: Vec<[f32; 4]> = (1..4u32)
        .map(|v| {
            let (a, b, c) = ([v as f32 + 0.5, 2.0 - v as f32], 10 * v, [v as i32 - 3, 4, 0, 1]);
            [a[0] + b as f32, 2.0 * a[1] * (c[0] + c[1]) as f32, 3.0 * (c[2] * 10 + c[3]) as f32, (v * 100 + 7) as f32]
        })
        .collect();
    assert_eq!(got, want);
}

#[test]
fn a_draw_the_capture_cannot_read_is_an_error() {
    let gpu = testing::device();
    let (key, vc) = gbuffer_capture(&gpu, &repository_library());
    let layout = key.spec.layout(&key.defs);
    let scene = Scene::new(&gpu);
    let err = |bindings: &[(&'static str, wgpu::BindingResource<'_>)], draw: &Draw<'_>| {
        capture(&gpu, &vc, &layout, bindings, draw).unwrap_err().to_string()
    };
    let b = scene.bindings();
    assert!(err(&b[..1], &scene.draw()).contains("`objects`, which the pass did not bind"));
    assert!(err(&b, &Draw { count: 0, ..scene.draw() }).contains("no vertices"));
    assert!(err(&b, &Draw { count: 5, ..scene.draw() }).contains("indices 1..6 run past the index buffer's 5"));
    assert!(err(&b, &Draw { buffer: None, ..scene.draw() }).contains("the draw has none"));
    let buffer = |size, usage| gpu.device.create_buffer(&wgpu::BufferDescriptor { label: None, size, usage, mapped_at_creation: false });
    let vertex_only = buffer(120, wgpu::BufferUsages::VERTEX);
    assert!(err(&b, &Draw { buffer: Some(&vertex_only), ..scene.draw() }).contains("the vertex buffer lacks STORAGE usage"));
    let ragged = buffer(122, wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE);
    assert!(err(&b, &Draw { buffer: Some(&ragged), ..scene.draw() }).contains("122 bytes are not whole words"));
    let index_only = buffer(20, wgpu::BufferUsages::INDEX);
    let draw = Draw { vertices: Vertices::Indexed { indices: &index_only, first: 0, base_vertex: 0 }, ..scene.draw() };
    assert!(err(&b, &draw).contains("the index buffer lacks STORAGE usage"));
    // A spec layout that does not name what the shader binds.
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let e = vc.record(&gpu.device, &mut encoder, &[], &b, &scene.draw()).err().expect("unnamed bindings");
    assert!(matches!(e, CaptureError::Unnamed { group: 0, binding: 0 }), "{e}");
    // Read before mapping.
    let pending = vc.record(&gpu.device, &mut encoder, &layout, &b, &scene.draw()).unwrap();
    assert!(!pending.ready());
    assert!(matches!(pending.read(), Err(CaptureError::Readback(_))));
    // Instrumenting errors come through.
    let e = VertexCapture::new(&gpu.device, &compose(&repository_library(), &key), "fs_main", Some(&MESH_VERTICES))
        .err()
        .expect("a fragment stage");
    assert!(matches!(e, CaptureError::Instrument(InstrumentError::NotVertex { .. })), "{e}");
}

/// Every vertex stage the renderer draws with, under every permutation,
/// instruments and builds: the WGSL writer and parser round-trip what
/// naga_oil composes.
#[test]
fn every_vertex_stage_of_the_renderer_builds_a_capture() {
    let gpu = testing::device();
    let lib = repository_library();
    let mut built = 0;
    for spec in crate::render::passes::specs() {
        let (entry, layout) = match spec.stages {
            Stages::Fullscreen { .. } => ("vs_fullscreen", None),
            Stages::Mesh { vertex, .. } => (vertex, Some(&MESH_VERTICES)),
            Stages::Compute { .. } => continue,
        };
        for defs in spec.permutations() {
            let key = PipelineKey { spec, defs };
            VertexCapture::new(&gpu.device, &compose(&lib, &key), entry, layout).unwrap_or_else(|e| panic!("{}: {e}", key.label()));
            built += 1;
        }
    }
    assert!(built >= 30, "only {built} vertex stages");
    assert_eq!(*gpu.uncaptured.lock().unwrap(), Vec::<String>::new());
}
