//! Pipeline specs and creation. The renderer and `loupe check` build every
//! pipeline through `create`, from the same `PipelineSpec`s (declared by
//! the pass modules, listed in `render::passes::SPECS`), so the check gate
//! creates exactly what the renderer creates.

use std::borrow::Cow;
use std::sync::Arc;

use naga::{AddressSpace, ImageClass, TypeInner};

use crate::diag::{Code, Diagnostic, Location};
use crate::shader::{Composed, Library, ShaderDefs};

/// The HDR format every lit and post pass works in.
pub const HDR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The final displayable output.
pub const LDR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// The def that draws a fullscreen pass as two triangles (six vertices)
/// instead of one (three), to compare their cost.
pub const TWO_TRIANGLES: &str = "TWO_TRIANGLES";

#[derive(Debug, Clone, Copy)]
pub enum Stages {
    /// A fullscreen pass: vertices come from the vertex index, no buffers.
    Fullscreen {
        fragment: &'static str,
        targets: &'static [wgpu::TextureFormat],
    },
    /// Scene geometry: `Vertex` buffers (position, normal), one draw per
    /// object with the object's index as the instance index.
    Mesh {
        vertex: &'static str,
        fragment: Option<&'static str>,
        targets: &'static [wgpu::TextureFormat],
        depth: Depth,
    },
    Compute {
        entry: &'static str,
    },
}

/// The primitive state of every render pipeline: triangle lists,
/// counter-clockwise front faces, and no face culled (planes and open
/// meshes are visible from both sides). Quad statistics model and report
/// each draw's culling from here.
pub fn primitive() -> wgpu::PrimitiveState {
    wgpu::PrimitiveState { cull_mode: None, front_face: wgpu::FrontFace::Ccw, ..Default::default() }
}

/// The slope-scaled bias of `Depth::Biased` (shadow maps).
pub const SHADOW_BIAS: wgpu::DepthBiasState = wgpu::DepthBiasState { constant: 2, slope_scale: 2.0, clamp: 0.0 };

/// How a mesh pipeline uses its depth attachment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// Test and write (the prepass).
    Write,
    /// Test against a filled buffer, write nothing (shading passes after a
    /// prepass shade each pixel once).
    Equal,
    /// Test and write with a slope-scaled bias (shadow maps).
    Biased,
}

/// The depth format of the prepass and shadow maps.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The one vertex buffer of every mesh pipeline, as the pipeline reads it
/// (and as `shader::instrument` reads it for vertex capture): position,
/// normal, UV and tangent, as `MeshData::vertex_bytes` writes them.
pub const MESH_VERTICES: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: crate::mesh::VERTEX_STRIDE as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4],
};

/// When a bind group is part of the pipeline's layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    Always,
    /// Only in permutations with this def: a feature's resources exist only
    /// when the scene uses the feature.
    Def(&'static str),
    /// Only in permutations without this def.
    NotDef(&'static str),
}

/// One resource of a bind group, by the name the pass binds it with: a
/// pass supplies `("shadow_map", view)` pairs and never counts positions.
#[derive(Debug, Clone, Copy)]
pub struct Binding {
    pub name: &'static str,
    pub entry: wgpu::BindGroupLayoutEntry,
}

#[derive(Debug, Clone, Copy)]
pub struct Group {
    /// The `@group(N)` it binds to. Two groups may share an index when
    /// their conditions exclude each other.
    pub index: u32,
    pub when: When,
    pub entries: &'static [Binding],
}

impl Group {
    pub const fn always(index: u32, entries: &'static [Binding]) -> Group {
        Group { index, when: When::Always, entries }
    }

    pub const fn when(index: u32, def: &'static str, entries: &'static [Binding]) -> Group {
        Group { index, when: When::Def(def), entries }
    }

    pub const fn unless(index: u32, def: &'static str, entries: &'static [Binding]) -> Group {
        Group { index, when: When::NotDef(def), entries }
    }

    pub fn active(&self, defs: &ShaderDefs) -> bool {
        match self.when {
            When::Always => true,
            When::Def(d) => defs.contains(d),
            When::NotDef(d) => !defs.contains(d),
        }
    }
}

/// Everything needed to build one pipeline, independent of any scene. Each
/// pass module declares its own; `render::passes::SPECS` lists them all.
#[derive(Debug)]
pub struct PipelineSpec {
    /// Stable id, used in the API and reports: `post.tonemap`.
    pub name: &'static str,
    /// Shader path relative to the shader root, forward slashes.
    pub shader: &'static str,
    pub stages: Stages,
    /// Bind groups: what the renderer binds. A group whose `when` does not
    /// hold for a permutation is left out of its layout.
    pub groups: &'static [Group],
    /// Defs the renderer may switch on; it uses any subset of them.
    pub defs: &'static [&'static str],
}

impl PipelineSpec {
    /// Every def set the renderer can request: the power set of `defs`.
    pub fn permutations(&self) -> Vec<ShaderDefs> {
        let n = self.defs.len();
        (0u32..1 << n).map(|mask| (0..n).filter(|i| mask & (1 << i) != 0).map(|i| self.defs[i].to_owned()).collect()).collect()
    }

    /// The bindings of each group index for `defs`; `None` where the
    /// permutation binds nothing.
    pub fn layout(&self, defs: &ShaderDefs) -> Vec<Option<&'static [Binding]>> {
        let active: Vec<&Group> = self.groups.iter().filter(|g| g.active(defs)).collect();
        let count = active.iter().map(|g| g.index + 1).max().unwrap_or(0);
        (0..count).map(|i| active.iter().find(|g| g.index == i).map(|g| g.entries)).collect()
    }

    /// The entry points the pipeline runs.
    pub fn entry_points(&self) -> Vec<&'static str> {
        match self.stages {
            Stages::Fullscreen { fragment, .. } => vec!["vs_fullscreen", fragment],
            Stages::Mesh { vertex, fragment, .. } => [Some(vertex), fragment].into_iter().flatten().collect(),
            Stages::Compute { entry } => vec![entry],
        }
    }

    /// The entry point wgpu errors are reported at.
    fn main_entry(&self) -> &'static str {
        match self.stages {
            Stages::Fullscreen { fragment, .. } => fragment,
            Stages::Mesh { fragment, vertex, .. } => fragment.unwrap_or(vertex),
            Stages::Compute { entry } => entry,
        }
    }
}

pub const FRAG: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;
pub const VERT: wgpu::ShaderStages = wgpu::ShaderStages::VERTEX;
pub const COMPUTE: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;
pub const ALL: wgpu::ShaderStages = wgpu::ShaderStages::VERTEX_FRAGMENT.union(wgpu::ShaderStages::COMPUTE);

const fn buffer(name: &'static str, binding: u32, visibility: wgpu::ShaderStages, ty: wgpu::BufferBindingType, size: u64) -> Binding {
    Binding {
        name,
        entry: wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: std::num::NonZeroU64::new(size) },
            count: None,
        },
    }
}

/// A uniform buffer of exactly `size` bytes. The size is part of the
/// layout, so a shader struct of another size is an error naming the
/// binding (wgpu would otherwise only fail the frame that binds it).
pub const fn uniform(name: &'static str, binding: u32, visibility: wgpu::ShaderStages, size: u64) -> Binding {
    buffer(name, binding, visibility, wgpu::BufferBindingType::Uniform, size)
}

/// A read-only storage buffer (arrays of objects, lights, media).
pub const fn storage(name: &'static str, binding: u32, visibility: wgpu::ShaderStages) -> Binding {
    buffer(name, binding, visibility, wgpu::BufferBindingType::Storage { read_only: true }, 0)
}

/// A read-write storage buffer, for compute passes.
pub const fn storage_rw(name: &'static str, binding: u32) -> Binding {
    buffer(name, binding, COMPUTE, wgpu::BufferBindingType::Storage { read_only: false }, 0)
}

/// A read-write storage buffer a fragment shader writes (the G-buffer's
/// material words).
pub const fn storage_rw_fragment(name: &'static str, binding: u32) -> Binding {
    buffer(name, binding, FRAG, wgpu::BufferBindingType::Storage { read_only: false }, 0)
}

/// A 2D texture a compute pass writes with `textureStore`.
pub const fn storage_texture(name: &'static str, binding: u32, format: wgpu::TextureFormat) -> Binding {
    Binding {
        name,
        entry: wgpu::BindGroupLayoutEntry {
            binding,
            visibility: COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        },
    }
}

/// An unfilterable f32 texture read with `textureLoad`: exact values, any
/// float format, no sampler.
pub const fn texture(name: &'static str, binding: u32) -> Binding {
    image(name, binding, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2)
}

/// A depth texture read with `textureLoad`.
pub const fn depth_texture(name: &'static str, binding: u32) -> Binding {
    image(name, binding, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2)
}

/// A depth array texture (shadow maps) read with `textureLoad`.
pub const fn depth_array(name: &'static str, binding: u32) -> Binding {
    image(name, binding, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2Array)
}

const fn image(
    name: &'static str,
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    view_dimension: wgpu::TextureViewDimension,
) -> Binding {
    Binding {
        name,
        entry: wgpu::BindGroupLayoutEntry {
            binding,
            visibility: FRAG.union(COMPUTE),
            ty: wgpu::BindingType::Texture { sample_type, view_dimension, multisampled: false },
            count: None,
        },
    }
}

/// Uniform sizes, in bytes, as the renderer writes them.
pub mod sizes {
    pub const VIEW: u64 = 208;
    pub const MAT4: u64 = 64;
    pub const VEC4: u64 = 16;
}

/// The error for a pipeline whose shader file is not there.
pub fn missing_shader(spec: &str, display: &str) -> Diagnostic {
    Diagnostic::error(Code::Io, format!("pipeline `{spec}` needs `{display}`, which does not exist"))
}

/// A created pipeline, shared so a frame in flight keeps its pipeline alive
/// while a reload replaces it.
#[derive(Debug, Clone)]
pub enum Pipeline {
    Render(Arc<wgpu::RenderPipeline>),
    Compute(Arc<wgpu::ComputePipeline>),
}

/// Creates the pipeline for `spec` from an already composed module. Driver
/// and wgpu validation errors are caught with an error scope and become
/// diagnostics at the shader's entry point; nothing here panics. `prints`:
/// the module is instrumented for prints (`shader::instrument_printf`) and
/// binds the print buffer at `@group(prints) @binding(0)`, past the
/// spec's groups.
pub fn create(
    device: &wgpu::Device,
    spec: &PipelineSpec,
    defs: &ShaderDefs,
    composed: &Composed,
    lib: &Library,
    shader_display: &str,
    prints: Option<u32>,
) -> Result<Pipeline, Vec<Diagnostic>> {
    let mismatches = check_bindings(spec, defs, composed, lib, prints);
    if !mismatches.is_empty() {
        return Err(mismatches);
    }
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(spec.name),
        source: wgpu::ShaderSource::Naga(Cow::Owned(composed.module.clone())),
    });
    let mut layouts: Vec<Option<wgpu::BindGroupLayout>> = spec
        .layout(defs)
        .into_iter()
        .map(|bindings| {
            bindings.map(|bindings| {
                let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings.iter().map(|b| b.entry).collect();
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(spec.name), entries: &entries })
            })
        })
        .collect();
    if let Some(group) = prints {
        layouts.resize_with(layouts.len().max(group as usize + 1), || None);
        layouts[group as usize] = Some(print_layout(device));
    }
    let layout_refs: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(Option::as_ref).collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(spec.name),
        bind_group_layouts: &layout_refs,
        immediate_size: 0,
    });
    let color_targets = |targets: &[wgpu::TextureFormat]| -> Vec<Option<wgpu::ColorTargetState>> {
        targets.iter().map(|&format| Some(format.into())).collect()
    };
    let pipeline = match spec.stages {
        Stages::Fullscreen { fragment, targets } => {
            Pipeline::Render(Arc::new(device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(spec.name),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_fullscreen"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &color_targets(targets),
                }),
                primitive: primitive(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                multiview_mask: None,
                cache: None,
            })))
        }
        Stages::Mesh { vertex, fragment, targets, depth } => {
            let targets = color_targets(targets);
            Pipeline::Render(Arc::new(device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(spec.name),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vertex),
                    compilation_options: Default::default(),
                    buffers: &[Some(MESH_VERTICES)],
                },
                fragment: fragment.map(|entry| wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                primitive: primitive(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(depth != Depth::Equal),
                    depth_compare: Some(if depth == Depth::Equal { wgpu::CompareFunction::LessEqual } else { wgpu::CompareFunction::Less }),
                    stencil: Default::default(),
                    bias: if depth == Depth::Biased { SHADOW_BIAS } else { Default::default() },
                }),
                multisample: wgpu::MultisampleState::default(),
                multiview_mask: None,
                cache: None,
            })))
        }
        Stages::Compute { entry } => Pipeline::Compute(Arc::new(device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(spec.name),
            layout: Some(&layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        }))),
    };
    let errors: Vec<String> =
        [pollster::block_on(oom.pop()), pollster::block_on(scope.pop())].into_iter().flatten().map(|e| e.to_string()).collect();
    if errors.is_empty() {
        return Ok(pipeline);
    }
    let at = entry_location(composed, lib, shader_display, spec.main_entry());
    Err(errors
        .into_iter()
        .map(|e| {
            Diagnostic::error(Code::Pipeline, format!("pipeline `{}` was rejected", spec.name))
                .with_label(at.clone(), "for this entry point", true)
                .with_note(e)
        })
        .collect())
}

/// The print buffer's group: one read-write storage buffer, written by
/// fragment and compute stages.
fn print_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("debug prints"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    })
}

/// Where `fn <entry>` is written, or the file start.
fn entry_location(composed: &Composed, lib: &Library, shader_display: &str, entry: &str) -> Location {
    find_in_files(composed, lib, |line| line.contains(&format!("fn {entry}"))).unwrap_or_else(|| Location::file_start(shader_display))
}

fn find_in_files(composed: &Composed, lib: &Library, pred: impl Fn(&str) -> bool) -> Option<Location> {
    composed.files.iter().rev().filter_map(|d| lib.get(d)).find_map(|f| {
        let mut offset = 0;
        for line in f.text.split_inclusive('\n') {
            if pred(line) {
                let lead = line.len() - line.trim_start().len();
                let end = offset + line.trim_end().len();
                return Some(f.location(offset + lead..end));
            }
            offset += line.len();
        }
        None
    })
}

/// Every resource the shader declares must exist in the layout the renderer
/// binds, with a compatible type. wgpu would reject a mismatch too, but only
/// with the composed module's names; this names the declaration's line.
fn check_bindings(spec: &PipelineSpec, defs: &ShaderDefs, composed: &Composed, lib: &Library, prints: Option<u32>) -> Vec<Diagnostic> {
    let module = &composed.module;
    let layout = spec.layout(defs);
    let mut out = Vec::new();
    for (handle, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        if Some(rb.group) == prints {
            continue;
        }
        let entries = spec.entry_points();
        let used = module
            .entry_points
            .iter()
            .enumerate()
            .any(|(i, ep)| entries.contains(&ep.name.as_str()) && !composed.info.get_entry_point(i)[handle].is_empty());
        if !used {
            continue; // unused by this pipeline's entry points: wgpu ignores it too
        }
        let name = var.name.clone().unwrap_or_default();
        let expected = layout.get(rb.group as usize).copied().flatten().and_then(|g| g.iter().find(|b| b.entry.binding == rb.binding));
        let problem = match expected {
            None => Some(format!("the renderer binds nothing at @group({}) @binding({})", rb.group, rb.binding)),
            Some(b) => incompatibility(module, var, &b.entry.ty),
        };
        if let Some(problem) = problem {
            let g = format!("@group({})", rb.group);
            let b = format!("@binding({})", rb.binding);
            let at = find_in_files(composed, lib, |l| l.contains(&g) && l.contains(&b))
                .unwrap_or_else(|| Location::file_start(composed.files.last().map_or("", String::as_str)));
            out.push(
                Diagnostic::error(
                    Code::BindingMismatch,
                    format!("binding `{}` does not match pipeline `{}`", crate::shader::compose::undecorate(&name), spec.name),
                )
                .with_label(at, problem, true)
                .with_note(format!("pipeline `{}` binds: {}", spec.name, describe_layout(&layout))),
            );
        }
    }
    out
}

fn incompatibility(module: &naga::Module, var: &naga::GlobalVariable, ty: &wgpu::BindingType) -> Option<String> {
    let inner = &module.types[var.ty].inner;
    if let (wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, min_binding_size: Some(bound), .. }, AddressSpace::Uniform) =
        (ty, var.space)
    {
        let size = u64::from(inner.size(module.to_ctx()));
        if size != bound.get() {
            return Some(format!("a uniform struct of {size} bytes, but the renderer binds {bound} bytes"));
        }
    }
    let ok = match (ty, var.space, inner) {
        (wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, .. }, AddressSpace::Uniform, _) => true,
        (wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only }, .. }, AddressSpace::Storage { access }, _) => {
            !*read_only || !access.contains(naga::StorageAccess::STORE)
        }
        (wgpu::BindingType::Sampler(_), AddressSpace::Handle, TypeInner::Sampler { .. }) => true,
        (
            wgpu::BindingType::Texture { sample_type, multisampled, view_dimension },
            AddressSpace::Handle,
            TypeInner::Image { class, dim, arrayed },
        ) => {
            let dims_match = match view_dimension {
                wgpu::TextureViewDimension::D2 => *dim == naga::ImageDimension::D2 && !arrayed,
                wgpu::TextureViewDimension::D2Array => *dim == naga::ImageDimension::D2 && *arrayed,
                _ => true,
            };
            dims_match
                && match (sample_type, class) {
                    (wgpu::TextureSampleType::Float { .. }, ImageClass::Sampled { kind: naga::ScalarKind::Float, multi }) => {
                        multi == multisampled
                    }
                    (wgpu::TextureSampleType::Depth, ImageClass::Depth { multi }) => multi == multisampled,
                    (wgpu::TextureSampleType::Uint, ImageClass::Sampled { kind: naga::ScalarKind::Uint, multi }) => multi == multisampled,
                    (wgpu::TextureSampleType::Sint, ImageClass::Sampled { kind: naga::ScalarKind::Sint, multi }) => multi == multisampled,
                    _ => false,
                }
        }
        (wgpu::BindingType::StorageTexture { .. }, AddressSpace::Handle, TypeInner::Image { class: ImageClass::Storage { .. }, .. }) => {
            true
        }
        _ => false,
    };
    (!ok).then(|| format!("declared as {}, but the renderer binds {}", describe_var(var, inner), describe_binding(ty)))
}

fn describe_var(var: &naga::GlobalVariable, inner: &TypeInner) -> String {
    match (var.space, inner) {
        (AddressSpace::Uniform, _) => "a uniform buffer".into(),
        (AddressSpace::Storage { .. }, _) => "a storage buffer".into(),
        (_, TypeInner::Sampler { .. }) => "a sampler".into(),
        (_, TypeInner::Image { class: ImageClass::Storage { .. }, .. }) => "a storage texture".into(),
        (_, TypeInner::Image { class: ImageClass::Depth { .. }, arrayed: true, .. }) => "a depth texture array".into(),
        (_, TypeInner::Image { class: ImageClass::Depth { .. }, .. }) => "a depth texture".into(),
        (_, TypeInner::Image { class: ImageClass::Sampled { kind, .. }, .. }) => format!("a {kind:?} texture").to_lowercase(),
        _ => "a resource".into(),
    }
}

fn describe_binding(ty: &wgpu::BindingType) -> String {
    match ty {
        wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, .. } => "a uniform buffer".into(),
        wgpu::BindingType::Buffer { .. } => "a storage buffer".into(),
        wgpu::BindingType::Sampler(_) => "a sampler".into(),
        wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Depth,
            view_dimension: wgpu::TextureViewDimension::D2Array,
            ..
        } => "a depth texture array".into(),
        wgpu::BindingType::Texture { sample_type: wgpu::TextureSampleType::Depth, .. } => "a depth texture".into(),
        wgpu::BindingType::Texture { sample_type, .. } => match sample_type {
            wgpu::TextureSampleType::Uint => "a uint texture".into(),
            wgpu::TextureSampleType::Sint => "a sint texture".into(),
            _ => "a float texture".into(),
        },
        wgpu::BindingType::StorageTexture { .. } => "a storage texture".into(),
        _ => "another binding type".into(),
    }
}

fn describe_layout(layout: &[Option<&[Binding]>]) -> String {
    let mut parts = Vec::new();
    for (g, entries) in layout.iter().enumerate() {
        for b in entries.iter().copied().flatten() {
            parts.push(format!("@group({g}) @binding({}) {} `{}`", b.entry.binding, describe_binding(&b.entry.ty), b.name));
        }
    }
    parts.join("; ")
}
