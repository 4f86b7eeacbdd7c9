//! Pipeline specs and creation. The renderer and `loupe check` build every
//! pipeline through `create`, from the same `PipelineSpec`, so the check
//! gate creates exactly what the renderer creates.

use std::borrow::Cow;
use std::sync::Arc;

use naga::{AddressSpace, ImageClass, TypeInner};

use crate::diag::{Code, Diagnostic, Location};
use crate::shader::{Composed, Library, ShaderDefs};

/// The HDR format every lit and post pass works in.
pub const HDR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The final displayable output.
pub const LDR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

#[derive(Debug, Clone, Copy)]
pub enum Stages {
    /// A fullscreen pass: vertices come from the vertex index, no buffers.
    Fullscreen { fragment: &'static str, targets: &'static [wgpu::TextureFormat] },
    Compute { entry: &'static str },
}

/// Everything needed to build one pipeline, independent of any scene.
#[derive(Debug, Clone, Copy)]
pub struct PipelineSpec {
    /// Stable id, used in the API and reports: `post.tonemap`.
    pub name: &'static str,
    /// Shader path relative to the shader root, forward slashes.
    pub shader: &'static str,
    pub stages: Stages,
    /// Bind group layouts, group by group: what the renderer binds.
    pub groups: &'static [&'static [wgpu::BindGroupLayoutEntry]],
    /// Defs the renderer may switch on; it uses any subset of them.
    pub defs: &'static [&'static str],
}

impl PipelineSpec {
    /// Every def set the renderer can request: the power set of `defs`.
    pub fn permutations(&self) -> Vec<ShaderDefs> {
        let n = self.defs.len();
        (0u32..1 << n)
            .map(|mask| (0..n).filter(|i| mask & (1 << i) != 0).map(|i| self.defs[i].to_owned()).collect())
            .collect()
    }
}

const FRAG: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;

pub const fn uniform(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// An unfilterable f32 texture read with `textureLoad`: exact values, any
/// float format, no sampler.
pub const fn texture(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: FRAG.union(wgpu::ShaderStages::COMPUTE),
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Every pipeline the renderer can build.
pub const SPECS: &[PipelineSpec] = &[
    PipelineSpec {
        name: "debug.test_pattern",
        shader: "passes/test_pattern.wgsl",
        stages: Stages::Fullscreen { fragment: "fs_main", targets: &[HDR] },
        groups: &[&[uniform(0, FRAG)]],
        defs: &["TWO_TRIANGLES"],
    },
    PipelineSpec {
        name: "post.tonemap",
        shader: "post/tonemap.wgsl",
        stages: Stages::Fullscreen { fragment: "fs_main", targets: &[LDR] },
        groups: &[&[uniform(0, FRAG), texture(1)]],
        defs: &["TWO_TRIANGLES", "TONEMAP_REINHARD"],
    },
];

pub fn spec(name: &str) -> Option<&'static PipelineSpec> {
    SPECS.iter().find(|s| s.name == name)
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
/// diagnostics at the shader's entry point; nothing here panics.
pub fn create(
    device: &wgpu::Device,
    spec: &PipelineSpec,
    composed: &Composed,
    lib: &Library,
    shader_display: &str,
) -> Result<(Pipeline, Vec<wgpu::BindGroupLayout>), Vec<Diagnostic>> {
    let mismatches = check_bindings(spec, composed, lib);
    if !mismatches.is_empty() {
        return Err(mismatches);
    }
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(spec.name),
        source: wgpu::ShaderSource::Naga(Cow::Owned(composed.module.clone())),
    });
    let layouts: Vec<wgpu::BindGroupLayout> = spec
        .groups
        .iter()
        .map(|entries| device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(spec.name), entries }))
        .collect();
    let layout_refs: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(Some).collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(spec.name),
        bind_group_layouts: &layout_refs,
        immediate_size: 0,
    });
    let pipeline = match spec.stages {
        Stages::Fullscreen { fragment, targets } => {
            let targets: Vec<Option<wgpu::ColorTargetState>> =
                targets.iter().map(|&format| Some(format.into())).collect();
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
                    targets: &targets,
                }),
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                multiview_mask: None,
                cache: None,
            })))
        }
        Stages::Compute { entry } => Pipeline::Compute(Arc::new(device.create_compute_pipeline(
            &wgpu::ComputePipelineDescriptor {
                label: Some(spec.name),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            },
        ))),
    };
    let errors: Vec<String> = [pollster::block_on(oom.pop()), pollster::block_on(scope.pop())]
        .into_iter()
        .flatten()
        .map(|e| e.to_string())
        .collect();
    if errors.is_empty() {
        return Ok((pipeline, layouts));
    }
    let entry = match spec.stages {
        Stages::Fullscreen { fragment, .. } => fragment,
        Stages::Compute { entry } => entry,
    };
    let at = entry_location(composed, lib, shader_display, entry);
    Err(errors
        .into_iter()
        .map(|e| {
            Diagnostic::error(Code::Pipeline, format!("pipeline `{}` was rejected", spec.name))
                .with_label(at.clone(), "for this entry point", true)
                .with_note(e)
        })
        .collect())
}

/// Where `fn <entry>` is written, or the file start.
fn entry_location(composed: &Composed, lib: &Library, shader_display: &str, entry: &str) -> Location {
    find_in_files(composed, lib, |line| line.contains(&format!("fn {entry}")))
        .unwrap_or_else(|| Location::file_start(shader_display))
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
fn check_bindings(spec: &PipelineSpec, composed: &Composed, lib: &Library) -> Vec<Diagnostic> {
    let module = &composed.module;
    let mut out = Vec::new();
    for (handle, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let used = (0..module.entry_points.len()).any(|i| !composed.info.get_entry_point(i)[handle].is_empty());
        if !used {
            continue; // declared but unused by every entry point: wgpu ignores it too
        }
        let name = var.name.clone().unwrap_or_default();
        let expected = spec
            .groups
            .get(rb.group as usize)
            .and_then(|g| g.iter().find(|e| e.binding == rb.binding));
        let problem = match expected {
            None => Some(format!("the renderer binds nothing at @group({}) @binding({})", rb.group, rb.binding)),
            Some(entry) => incompatibility(module, var, &entry.ty),
        };
        if let Some(problem) = problem {
            let g = format!("@group({})", rb.group);
            let b = format!("@binding({})", rb.binding);
            let at = find_in_files(composed, lib, |l| l.contains(&g) && l.contains(&b))
                .unwrap_or_else(|| Location::file_start(composed.files.last().map_or("", String::as_str)));
            out.push(
                Diagnostic::error(Code::BindingMismatch, format!("binding `{}` does not match pipeline `{}`", crate::shader::compose::undecorate(&name), spec.name))
                    .with_label(at, problem, true)
                    .with_note(format!("pipeline `{}` binds: {}", spec.name, describe_layout(spec))),
            );
        }
    }
    out
}

fn incompatibility(module: &naga::Module, var: &naga::GlobalVariable, ty: &wgpu::BindingType) -> Option<String> {
    let inner = &module.types[var.ty].inner;
    let ok = match (ty, var.space, inner) {
        (wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, .. }, AddressSpace::Uniform, _) => true,
        (wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only }, .. }, AddressSpace::Storage { access }, _) => {
            !*read_only || !access.contains(naga::StorageAccess::STORE)
        }
        (wgpu::BindingType::Sampler(_), AddressSpace::Handle, TypeInner::Sampler { .. }) => true,
        (wgpu::BindingType::Texture { sample_type, multisampled, .. }, AddressSpace::Handle, TypeInner::Image { class, .. }) => {
            match (sample_type, class) {
                (wgpu::TextureSampleType::Float { .. }, ImageClass::Sampled { kind: naga::ScalarKind::Float, multi }) => multi == multisampled,
                (wgpu::TextureSampleType::Depth, ImageClass::Depth { multi }) => multi == multisampled,
                (wgpu::TextureSampleType::Uint, ImageClass::Sampled { kind: naga::ScalarKind::Uint, multi }) => multi == multisampled,
                (wgpu::TextureSampleType::Sint, ImageClass::Sampled { kind: naga::ScalarKind::Sint, multi }) => multi == multisampled,
                _ => false,
            }
        }
        (wgpu::BindingType::StorageTexture { .. }, AddressSpace::Handle, TypeInner::Image { class: ImageClass::Storage { .. }, .. }) => true,
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

fn describe_layout(spec: &PipelineSpec) -> String {
    let mut parts = Vec::new();
    for (g, entries) in spec.groups.iter().enumerate() {
        for e in entries.iter() {
            parts.push(format!("@group({g}) @binding({}) {}", e.binding, describe_binding(&e.ty)));
        }
    }
    parts.join("; ")
}
