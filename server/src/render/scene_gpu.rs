//! A scene's data on the GPU: mesh buffers, and the view, object, material,
//! light, media and shadow-view buffers the shaders read. Built once per
//! scene version; passes reach it through their `PassContext`. The byte
//! layouts here mirror the WGSL structs in `shaders/lib/*.wgsl`.

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::{EulerRot, Mat4, Quat, Vec3};
use wgpu::util::DeviceExt;

use super::denoise_weights::DenoiseWeights;
use super::path_geometry::{PathGeometry, Shading};
use crate::denoise::network::Network;
use crate::material::Program;
use crate::mesh::MeshData;
use crate::scene::{Geometry, LightKind, Medium, Renderer, Scene, SdfShape};

pub struct GpuMesh {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
}

pub struct SceneGpu {
    pub view: wgpu::Buffer,
    pub objects: wgpu::Buffer,
    /// `loupe::material`'s parameters and instance table
    /// (`material::Program::buffers`).
    pub material_params: wgpu::Buffer,
    pub material_instances: wgpu::Buffer,
    /// The materials' textures and their sampler.
    pub material_textures: super::material_textures::MaterialTextures,
    pub lights: wgpu::Buffer,
    pub media: wgpu::Buffer,
    pub shadow_views: wgpu::Buffer,
    /// One view-projection per shadow-map layer, in layer order.
    pub shadow_layers: Vec<Mat4>,
    pub meshes: Vec<GpuMesh>,
    /// Per object, in scene order: which mesh it draws.
    pub draws: Vec<usize>,
    /// Per object, in scene order: its name, for per-draw reports.
    pub names: Vec<String>,
    /// The LTC tables, only for scenes with a rect light.
    pub ltc: Option<[wgpu::Texture; 2]>,
    /// The pre-integrated GGX table of the environment's specular light.
    pub dfg: wgpu::TextureView,
    /// The path tracer's geometry, when the scene is path traced.
    pub path: Option<PathGeometry>,
    /// The denoiser's weights, when the path-traced frame is denoised.
    pub denoiser: Option<DenoiseWeights>,
}

/// Where each light's shadow maps sit in the shadow array: the first layer
/// per light (-1 without shadows) and the layer count. Point lights take
/// six layers (a cube), every other type one.
pub fn shadow_layout(scene: &Scene) -> (Vec<i32>, u32) {
    let mut first = vec![-1; scene.lights.len()];
    let mut next = 0u32;
    for (i, l) in scene.shadow_casters() {
        first[i] = next as i32;
        next += if matches!(l.kind, LightKind::Point { .. }) { 6 } else { 1 };
    }
    (first, next)
}

/// The world-space bounding sphere of every object, which directional and
/// spot shadow frusta must cover.
fn bounds(scene: &Scene, meshes: &[Arc<MeshData>], draws: &[usize]) -> (Vec3, f32) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for (o, &m) in scene.objects.iter().zip(draws) {
        let (a, b) = meshes[m].bounds();
        let model = model_matrix(o);
        for i in 0..8 {
            let corner =
                Vec3::new(if i & 1 == 0 { a[0] } else { b[0] }, if i & 2 == 0 { a[1] } else { b[1] }, if i & 4 == 0 { a[2] } else { b[2] });
            let p = model.transform_point3(corner);
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    if lo.x > hi.x {
        return (Vec3::ZERO, 1.0);
    }
    ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3))
}

fn model_matrix(o: &crate::scene::Object) -> Mat4 {
    let r = o.rotation_deg.map(f32::to_radians);
    Mat4::from_scale_rotation_translation(Vec3::from(o.scale), Quat::from_euler(EulerRot::YXZ, r[1], r[0], r[2]), Vec3::from(o.position))
}

fn up_for(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y }
}

/// View-projections of every shadow-map layer.
fn shadow_views(scene: &Scene, center: Vec3, radius: f32) -> Vec<Mat4> {
    let mut views = Vec::new();
    for (_, light) in scene.shadow_casters() {
        match light.kind {
            LightKind::Directional { direction } => {
                let d = Vec3::from(direction);
                let eye = center - d * radius * 2.0;
                let view = Mat4::look_at_rh(eye, center, up_for(d));
                views.push(Mat4::orthographic_rh(-radius, radius, -radius, radius, radius * 0.5, radius * 3.5) * view);
            }
            LightKind::Spot { position, direction, outer_deg, .. } => {
                let (p, d) = (Vec3::from(position), Vec3::from(direction));
                let far = (p.distance(center) + radius).max(0.2);
                let fov = (2.0 * outer_deg + 4.0).min(170.0).to_radians();
                views.push(Mat4::perspective_rh(fov, 1.0, 0.05, far) * Mat4::look_at_rh(p, p + d, up_for(d)));
            }
            LightKind::Rect { position, direction, .. } => {
                // From the centre over the lit hemisphere's useful part.
                let (p, d) = (Vec3::from(position), Vec3::from(direction));
                let far = (p.distance(center) + radius).max(0.2);
                views.push(Mat4::perspective_rh(150f32.to_radians(), 1.0, 0.05, far) * Mat4::look_at_rh(p, p + d, up_for(d)));
            }
            LightKind::Point { position } => {
                let p = Vec3::from(position);
                let far = (p.distance(center) + radius).max(0.2);
                let proj = Mat4::perspective_rh(90f32.to_radians(), 1.0, 0.05, far);
                // Faces in the order `cube_face` in shadows.wgsl picks them.
                for axis in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
                    views.push(proj * Mat4::look_at_rh(p, p + axis, up_for(axis)));
                }
            }
        }
    }
    views
}

fn push_vec4(out: &mut Vec<u8>, v: [f32; 4]) {
    out.extend_from_slice(bytemuck::cast_slice(&v));
}

fn push_mat4(out: &mut Vec<u8>, m: Mat4) {
    out.extend_from_slice(bytemuck::cast_slice(&m.to_cols_array()));
}

/// The `View` uniform: camera matrices, target size and loop counts.
pub fn view_bytes(scene: &Scene) -> Vec<u8> {
    let c = &scene.camera;
    let aspect = scene.width as f32 / scene.height as f32;
    let view = Mat4::look_at_rh(Vec3::from(c.position), Vec3::from(c.target), Vec3::from(c.up));
    let view_proj = Mat4::perspective_rh(c.fov_deg.to_radians(), aspect, c.near, c.far) * view;
    let mut out = Vec::with_capacity(crate::gpu::pipeline::sizes::VIEW as usize);
    push_mat4(&mut out, view_proj);
    push_mat4(&mut out, view_proj.inverse());
    push_vec4(&mut out, [c.position[0], c.position[1], c.position[2], c.near]);
    push_vec4(&mut out, [scene.width as f32, scene.height as f32, c.far, scene.quality.shadow_filter as f32]);
    let counts = [scene.lights.len() as u32, scene.media.len() as u32, scene.quality.volume_steps, scene.quality.volume_shadow_steps];
    out.extend_from_slice(bytemuck::cast_slice(&counts));
    let e = &scene.environment;
    for c in [e.top, e.bottom] {
        push_vec4(&mut out, [c[0] * e.intensity, c[1] * e.intensity, c[2] * e.intensity, 0.0]);
    }
    out
}

/// One `Light` of lights.wgsl: six vec4.
const LIGHT_BYTES: usize = 96;

fn light_bytes(scene: &Scene) -> Vec<u8> {
    let (first_layer, _) = shadow_layout(scene);
    let mut out = Vec::new();
    for (l, layer) in scene.lights.iter().zip(first_layer) {
        let c = l.color.map(|x| x * l.intensity);
        // direction.w holds cos(outer cone) and extra.x cos(inner cone) for
        // spots, as `incident` in lights.wgsl reads them.
        let (kind, position, direction, cos_outer, extra, right, up) = match l.kind {
            LightKind::Directional { direction } => (0.0, [0.0; 3], direction, 0.0, [0.0; 4], [0.0; 3], [0.0; 3]),
            LightKind::Point { position } => (1.0, position, [0.0, -1.0, 0.0], 0.0, [0.0; 4], [0.0; 3], [0.0; 3]),
            LightKind::Spot { position, direction, inner_deg, outer_deg } => {
                (2.0, position, direction, outer_deg.to_radians().cos(), [inner_deg.to_radians().cos(), 0.0, 0.0, 0.0], [0.0; 3], [0.0; 3])
            }
            LightKind::Rect { position, direction, size, two_sided } => {
                let n = Vec3::from(direction);
                let right = up_for(n).cross(n).normalize();
                let up = n.cross(right);
                (
                    3.0,
                    position,
                    direction,
                    0.0,
                    [size[0] * 0.5, size[1] * 0.5, if two_sided { 1.0 } else { 0.0 }, 0.0],
                    right.into(),
                    up.into(),
                )
            }
        };
        push_vec4(&mut out, [c[0], c[1], c[2], kind]);
        push_vec4(&mut out, [position[0], position[1], position[2], layer as f32]);
        push_vec4(&mut out, [direction[0], direction[1], direction[2], cos_outer]);
        push_vec4(&mut out, extra);
        push_vec4(&mut out, [right[0], right[1], right[2], 0.0]);
        push_vec4(&mut out, [up[0], up[1], up[2], 0.0]);
    }
    out
}

/// Shapes that are unbounded (half-spaces) are clipped to this box around
/// the origin for marching.
const PLANE_EXTENT: f32 = 50.0;

/// The box medium `m`'s marches are clipped to (`bounds_min`/`bounds_max`
/// of media.wgsl): its shapes' bounds grown by the smooth-union radius.
pub fn medium_bounds(m: &Medium) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for s in &m.shapes {
        let (slo, shi) = match *s {
            SdfShape::Sphere { center, radius } => (Vec3::from(center) - radius, Vec3::from(center) + radius),
            SdfShape::Box { center, half_extents } => {
                (Vec3::from(center) - Vec3::from(half_extents), Vec3::from(center) + Vec3::from(half_extents))
            }
            SdfShape::Plane { normal, offset } => {
                let (mut plo, mut phi) = (Vec3::splat(-PLANE_EXTENT), Vec3::splat(PLANE_EXTENT));
                // An axis-aligned half-space bounds one side exactly.
                for axis in 0..3 {
                    if normal[axis] > 0.999 {
                        phi[axis] = offset;
                    } else if normal[axis] < -0.999 {
                        plo[axis] = -offset;
                    }
                }
                (plo, phi)
            }
        };
        lo = lo.min(slo);
        hi = hi.max(shi);
    }
    (lo - m.blend, hi + m.blend)
}

fn medium_bytes(scene: &Scene) -> Vec<u8> {
    let mut out = Vec::new();
    for m in &scene.media {
        let (lo, hi) = medium_bounds(m);
        let mut shapes = Vec::new();
        for s in &m.shapes {
            let (a, b) = match *s {
                SdfShape::Sphere { center, radius } => ([0.0, center[0], center[1], center[2]], [0.0, 0.0, 0.0, radius]),
                SdfShape::Box { center, half_extents } => {
                    ([1.0, center[0], center[1], center[2]], [half_extents[0], half_extents[1], half_extents[2], 0.0])
                }
                SdfShape::Plane { normal, offset } => ([2.0, normal[0], normal[1], normal[2]], [0.0, 0.0, 0.0, offset]),
            };
            shapes.push(a);
            shapes.push(b);
        }
        push_vec4(&mut out, [m.absorption[0], m.absorption[1], m.absorption[2], m.blend]);
        push_vec4(&mut out, [m.scattering[0], m.scattering[1], m.scattering[2], m.edge]);
        push_vec4(&mut out, [m.emission[0], m.emission[1], m.emission[2], m.shapes.len() as f32]);
        let noise = m.noise.as_ref().map_or([0.0; 4], |n| [n.octaves as f32, n.frequency, n.amplitude, 0.0]);
        push_vec4(&mut out, noise);
        push_vec4(&mut out, [lo.x, lo.y, lo.z, 0.0]);
        push_vec4(&mut out, [hi.x, hi.y, hi.z, 0.0]);
        shapes.resize(2 * crate::scene::MAX_SHAPES, [0.0; 4]);
        for s in shapes {
            push_vec4(&mut out, s);
        }
    }
    out
}

/// The meshes of a scene, one per distinct geometry (shared by every object
/// using it), and per object which one it draws.
fn object_meshes(scene: &Scene, loaded: &BTreeMap<String, Arc<MeshData>>) -> (Vec<Arc<MeshData>>, Vec<usize>) {
    let mut keys: Vec<&Geometry> = Vec::new();
    let mut draws = Vec::new();
    for o in &scene.objects {
        let i = keys.iter().position(|k| same_geometry(k, &o.geometry)).unwrap_or_else(|| {
            keys.push(&o.geometry);
            keys.len() - 1
        });
        draws.push(i);
    }
    let data = keys
        .iter()
        .map(|g| match g {
            Geometry::Shape(s) => Arc::new(crate::mesh::shape(s).expect("validated shape")),
            Geometry::Mesh { file, .. } => loaded.get(file).cloned().unwrap_or_else(|| Arc::new(crate::mesh::cube())),
        })
        .collect();
    (data, draws)
}

/// Every triangle the raster draws, in world space, with its `[object,
/// primitive]`: what the path tracer's hierarchy is built over.
pub fn world_triangles(scene: &Scene, loaded: &BTreeMap<String, Arc<MeshData>>) -> Vec<([glam::Vec3; 3], [u32; 2])> {
    let (data, draws) = object_meshes(scene, loaded);
    triangles_of(scene, &data, &draws)
}

fn triangles_of(scene: &Scene, data: &[Arc<MeshData>], draws: &[usize]) -> Vec<([glam::Vec3; 3], [u32; 2])> {
    let mut out = Vec::new();
    for (object, (o, &mesh)) in scene.objects.iter().zip(draws).enumerate() {
        let (model, m) = (model_matrix(o), &data[mesh]);
        for (primitive, t) in m.indices.as_chunks::<3>().0.iter().enumerate() {
            let v = t.map(|i| model.transform_point3(glam::Vec3::from(m.positions[i as usize])));
            out.push((v, [object as u32, primitive as u32]));
        }
    }
    out
}

/// Per triangle of `ids` (`[object, primitive]`), its vertices' world-space
/// normals and tangents and their UVs (`Shading`): what a path-traced hit
/// shades with, interpolated as the raster interpolates them. Tangents move
/// as geometry.wgsl's `world_tangent` moves them.
fn world_shading(scene: &Scene, data: &[Arc<MeshData>], draws: &[usize], ids: &[[u32; 2]]) -> Vec<Shading> {
    let models: Vec<Mat4> = scene.objects.iter().map(model_matrix).collect();
    let normal_matrices: Vec<Mat4> = models.iter().map(|m| m.inverse().transpose()).collect();
    ids.iter()
        .map(|&[object, primitive]| {
            let (o, m) = (object as usize, &data[draws[object as usize]]);
            let material = scene.objects[o].material as f32;
            let vertex = |k: usize| m.indices[3 * primitive as usize + k] as usize;
            let normal = |k: usize| {
                let n = normal_matrices[o].transform_vector3(Vec3::from(m.normals[vertex(k)])).normalize_or_zero();
                [n.x, n.y, n.z, if k == 0 { material } else { 0.0 }]
            };
            let mirrored = models[o].determinant() < 0.0;
            let tangent = |k: usize| {
                let [x, y, z, w] = m.tangents[vertex(k)];
                let t = models[o].transform_vector3(Vec3::new(x, y, z)).normalize_or_zero();
                [t.x, t.y, t.z, if mirrored { -w } else { w }]
            };
            let uv = |k: usize| m.uvs[vertex(k)];
            let [a, b, c] = [uv(0), uv(1), uv(2)];
            [normal(0), normal(1), normal(2), tangent(0), tangent(1), tangent(2), [a[0], a[1], b[0], b[1]], [c[0], c[1], 0.0, 0.0]]
        })
        .collect()
}

impl SceneGpu {
    /// `network`: what the scene's `[denoiser]` names. `previous`: the
    /// scene's last GPU data, whose path-tracing hierarchy is kept when the
    /// triangles are the same, and whose denoiser weights when the network
    /// and its fusion are.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        loaded: &BTreeMap<String, Arc<MeshData>>,
        materials: &Program,
        network: Option<&Arc<Network>>,
        previous: Option<&SceneGpu>,
    ) -> Self {
        let (data, draws) = object_meshes(scene, loaded);
        let path = (scene.quality.renderer == Renderer::Path).then(|| {
            let source = triangles_of(scene, &data, &draws);
            PathGeometry::new(device, source, previous.and_then(|p| p.path.as_ref()), |ids| world_shading(scene, &data, &draws, ids))
        });
        let denoised = scene.quality.renderer == Renderer::Path && scene.denoiser.is_some() && scene.quality.denoise;
        let denoiser = network
            .filter(|_| denoised)
            .map(|n| DenoiseWeights::new(device, n, scene.quality.denoiser_fused, previous.and_then(|p| p.denoiser.as_ref())));
        let meshes = data
            .iter()
            .map(|m| GpuMesh {
                vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("mesh vertices"),
                    contents: &m.vertex_bytes(),
                    // Storage too: quad statistics read them in compute.
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
                }),
                indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("mesh indices"),
                    contents: bytemuck::cast_slice(&m.indices),
                    usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE,
                }),
                index_count: m.indices.len() as u32,
            })
            .collect();

        let mut objects = Vec::new();
        for o in &scene.objects {
            let model = model_matrix(o);
            push_mat4(&mut objects, model);
            push_mat4(&mut objects, model.inverse().transpose());
            objects.extend_from_slice(bytemuck::cast_slice(&[o.material as u32, 0, 0, 0]));
        }
        let (material_params, material_instances) = materials.buffers();
        let (center, radius) = bounds(scene, &data, &draws);
        let shadow_layers = shadow_views(scene, center, radius);
        let mut shadow_bytes = Vec::new();
        for m in &shadow_layers {
            push_mat4(&mut shadow_bytes, *m);
        }
        let storage = |label: &str, mut bytes: Vec<u8>| {
            // Bindings may not be empty: an unused slot stands in.
            if bytes.is_empty() {
                bytes.resize(16, 0);
            }
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        SceneGpu {
            view: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("view"),
                contents: &view_bytes(scene),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            objects: storage("objects", objects),
            // Never empty (`buffers` pads): the path tracer binds them in a
            // compute pass, where a binding is checked against the shader's
            // element size even when no triangle reads one.
            material_params: storage("material params", bytemuck::cast_slice(&material_params).to_vec()),
            material_instances: storage("material instances", bytemuck::cast_slice(&material_instances).to_vec()),
            material_textures: super::material_textures::MaterialTextures::new(device, queue, &materials.layers),
            // A scene without lights still binds one (zeroed) light: the
            // shader's array needs room for one element.
            lights: storage("lights", if scene.lights.is_empty() { vec![0; LIGHT_BYTES] } else { light_bytes(scene) }),
            media: storage("media", medium_bytes(scene)),
            shadow_views: storage("shadow views", shadow_bytes),
            shadow_layers,
            meshes,
            draws,
            names: scene.objects.iter().map(|o| o.name.clone()).collect(),
            ltc: scene.has_rect_lights().then(|| super::ltc::create_textures(device, queue)),
            dfg: super::dfg::create_texture(device, queue).create_view(&Default::default()),
            path,
            denoiser,
        }
    }
}

fn same_geometry(a: &Geometry, b: &Geometry) -> bool {
    match (a, b) {
        (Geometry::Shape(x), Geometry::Shape(y)) => x == y,
        (Geometry::Mesh { file: x, .. }, Geometry::Mesh { file: y, .. }) => x == y,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_layouts_match_the_shader_structs() {
        let scene = crate::scene::parse("s.toml", "").unwrap();
        assert_eq!(view_bytes(&scene).len() as u64, crate::gpu::pipeline::sizes::VIEW);
        let s = crate::scene::parse(
            "s.toml",
            "[[lights]]\ntype = \"rect\"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\nsize = [1, 2]\n\
             [[media]]\nabsorption = [0, 0, 0]\nscattering = [1, 1, 1]\nshapes = [{ type = \"plane\", normal = [0, 1, 0], offset = 0.5 }]\n",
        )
        .unwrap();
        assert_eq!(light_bytes(&s).len(), LIGHT_BYTES, "six vec4 per light");
        let media = medium_bytes(&s);
        assert_eq!(media.len(), 6 * 16 + 32 * 16);
        let floats: &[f32] = bytemuck::cast_slice(&media);
        assert_eq!(floats[4 * 4 + 1], -PLANE_EXTENT, "bounds below the plane");
        assert_eq!(floats[5 * 4 + 1], 0.5, "the plane's offset caps the box at y = 0.5");
    }

    /// The path tracer's triangles are the raster's: every object's mesh
    /// in world space, and a ray from the camera to its target finds the
    /// object there.
    #[test]
    fn world_triangles_are_what_the_raster_draws() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/showcase.toml");
        let loaded = crate::scene::load(&path).unwrap();
        let tris = world_triangles(&loaded.scene, &loaded.meshes);
        let (data, draws) = object_meshes(&loaded.scene, &loaded.meshes);
        let drawn: usize = draws.iter().map(|&m| data[m].indices.len() / 3).sum();
        assert_eq!(tris.len(), drawn);
        assert!(loaded.scene.objects.len() > 1, "a scene of several objects");
        for (object, o) in loaded.scene.objects.iter().enumerate() {
            let (min, max) = data[draws[object]].bounds();
            let model = model_matrix(o);
            let centre = model.transform_point3((glam::Vec3::from(min) + glam::Vec3::from(max)) * 0.5);
            let mine: Vec<_> = tris.iter().filter(|(_, id)| id[0] == object as u32).collect();
            assert_eq!(mine.len(), data[draws[object]].indices.len() / 3, "object {object}");
            // Its triangles sit around its transformed bounds' centre.
            let mean = mine.iter().map(|(t, _)| (t[0] + t[1] + t[2]) / 3.0).sum::<glam::Vec3>() / mine.len() as f32;
            let size = (model.transform_vector3(glam::Vec3::from(max) - glam::Vec3::from(min))).length();
            assert!((mean - centre).length() <= size, "object {object}: {mean} vs {centre}");
        }
        let bvh = crate::bvh::Bvh::build(&tris);
        let cam = &loaded.scene.camera;
        let (eye, target) = (glam::Vec3::from(cam.position), glam::Vec3::from(cam.target));
        let hit = bvh.intersect(eye, (target - eye).normalize(), 1e-4, f32::INFINITY).expect("the camera looks at something");
        assert!(hit.t < (target - eye).length() * 2.0);
    }

    /// The path tracer's per-triangle data carries the raster's vertex
    /// attributes: the UVs as they are, the tangents moved by the model
    /// matrix and their handedness flipped by a mirroring scale, as
    /// `world_tangent` in geometry.wgsl moves them.
    #[test]
    fn shading_carries_uvs_and_world_tangents() {
        let s = crate::scene::parse(
            "s.toml",
            "[[materials]]\nname = \"m\"\n\
             [[objects]]\nshape = \"plane\"\nmaterial = \"m\"\nrotation_deg = [0, 90, 0]\n\
             [[objects]]\nshape = \"plane\"\nmaterial = \"m\"\nscale = [-1, 1, 1]\n",
        )
        .unwrap();
        let (data, draws) = object_meshes(&s, &BTreeMap::new());
        // The second triangle of each plane: vertices 0, 2, 3.
        let shading = world_shading(&s, &data, &draws, &[[0, 1], [1, 1]]);
        let plane = crate::mesh::plane();
        // Turned a quarter about +Y, +X goes to −Z; mirrored in X, to −X.
        for (sh, tangent, w) in [(&shading[0], Vec3::NEG_Z, 1.0), (&shading[1], Vec3::NEG_X, -1.0)] {
            let uvs = [[sh[6][0], sh[6][1]], [sh[6][2], sh[6][3]], [sh[7][0], sh[7][1]]];
            for k in 0..3 {
                assert_eq!(uvs[k], plane.uvs[plane.indices[3 + k] as usize], "vertex {k}");
                let (n, t) = (Vec3::from_slice(&sh[k][..3]), Vec3::from_slice(&sh[3 + k][..3]));
                assert!(n.dot(t).abs() < 1e-6 && t.abs_diff_eq(tangent, 1e-6) && sh[3 + k][3] == w, "vertex {k}: {:?}", sh[3 + k]);
            }
        }
    }

    #[test]
    fn point_lights_take_six_shadow_layers() {
        let s = crate::scene::parse(
            "s.toml",
            "[[materials]]\nname = \"m\"\n[[objects]]\nshape = \"cube\"\nmaterial = \"m\"\n\
             [[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nshadows = false\n\
             [[lights]]\ntype = \"spot\"\nposition = [0, 3, 0]\ndirection = [0, -1, 0]\n",
        )
        .unwrap();
        assert_eq!(shadow_layout(&s), (vec![0, -1, 6], 7));
    }
}
