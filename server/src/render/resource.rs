//! What the graph is made of: handles to resources (textures and buffers,
//! per frame or kept across frames), how a pass accesses each, and which
//! pipeline a pass uses. A leaf module: the graph, the pass context and
//! the pool all build on it, and it imports none of them.

use serde::Serialize;

use crate::gpu::pipeline::PipelineSpec;
use crate::shader::ShaderDefs;

/// A resource of the graph: a texture or a buffer, made by one pass and
/// read by others.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Handle(pub(crate) usize);

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TextureKind {
    D2,
    /// An array of 2D layers (shadow maps: one or six per light).
    D2Array,
    D3,
}

#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct TextureDesc {
    pub format: wgpu::TextureFormat,
    pub width: u32,
    pub height: u32,
    /// Array layers, or depth for a 3D texture.
    pub layers: u32,
    pub kind: TextureKind,
}

impl TextureDesc {
    pub fn d2(format: wgpu::TextureFormat, width: u32, height: u32) -> Self {
        TextureDesc { format, width, height, layers: 1, kind: TextureKind::D2 }
    }

    /// An array texture of `layers` layers.
    pub fn array(format: wgpu::TextureFormat, width: u32, height: u32, layers: u32) -> Self {
        TextureDesc { format, width, height, layers, kind: TextureKind::D2Array }
    }
}

/// The element type a buffer holds, as the shader writes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Element {
    F32,
    F16,
    U32,
}

impl Element {
    pub fn bytes(self) -> u64 {
        match self {
            Element::F16 => 2,
            Element::F32 | Element::U32 => 4,
        }
    }
}

/// How a buffer's bytes read as a tensor: its dimensions, outermost first,
/// channels last. A histogram is `[bins]`; an image tensor `[h, w, c]`.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize)]
pub struct TensorLayout {
    /// `(name, size)` per dimension, e.g. `[("y", 360), ("x", 640), ("c", 32)]`.
    pub dims: Vec<(&'static str, u32)>,
    pub element: Element,
}

impl TensorLayout {
    pub fn new(dims: &[(&'static str, u32)], element: Element) -> Self {
        TensorLayout { dims: dims.to_vec(), element }
    }

    pub fn len(&self) -> u64 {
        self.dims.iter().map(|(_, n)| u64::from(*n)).product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// What statistics are split by: the innermost dimension's size when
    /// there are several dimensions (channels last); one for a 1-D tensor.
    pub fn channels(&self) -> usize {
        match self.dims.as_slice() {
            [_, .., (_, n)] => *n as usize,
            _ => 1,
        }
    }

    pub fn bytes(&self) -> u64 {
        self.len() * self.element.bytes()
    }
}

/// The GPU memory behind a handle.
pub enum Physical {
    Texture { texture: wgpu::Texture, view: wgpu::TextureView },
    Buffer(wgpu::Buffer),
}

#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum ResourceDesc {
    Texture(TextureDesc),
    /// A buffer described as a tensor, so a capture can show its values.
    Buffer(TensorLayout),
}

impl From<TextureDesc> for ResourceDesc {
    fn from(d: TextureDesc) -> Self {
        ResourceDesc::Texture(d)
    }
}

impl From<TensorLayout> for ResourceDesc {
    fn from(t: TensorLayout) -> Self {
        ResourceDesc::Buffer(t)
    }
}

/// What a resource's values mean, declared by the pass that creates it, so
/// that a viewer shows them by what they are rather than by a guess from
/// the format: colour with sRGB encoding, normals remapped from [-1, 1],
/// depth as one grey channel, data and ids as plain numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Meaning {
    /// Linear radiance or reflectance, shown sRGB-encoded.
    Color,
    /// Unit vectors with components in [-1, 1].
    Normal,
    /// Depth as the depth test sees it, through `Projection`.
    Depth(Projection),
    /// Numbers that are not a colour (coverage, counts, parameters).
    Data,
    /// Identifiers (object, primitive): integers with no order.
    Id,
}

impl Meaning {
    /// Its protocol spelling.
    pub fn name(self) -> &'static str {
        match self {
            Meaning::Color => "color",
            Meaning::Normal => "normal",
            Meaning::Depth(_) => "depth",
            Meaning::Data => "data",
            Meaning::Id => "id",
        }
    }
}

/// Which projection a depth resource was rendered through: the scene's
/// camera (whose near and far linearise it) or another one (a light's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Projection {
    Camera,
    Light,
}

/// How long a resource's contents live.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Lifetime {
    /// Made and used within one frame.
    Frame,
    /// Kept from frame to frame (adaptation state, accumulation), zeroed
    /// when created or reset. Keyed by name, so the next frame's graph
    /// finds the same one.
    History,
}

/// How a pass uses a resource. The graph derives each resource's usage
/// flags from these, and its reads and writes for culling.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// A texture read in a shader.
    Sampled,
    /// A storage buffer read in a shader.
    StorageRead,
    /// A storage buffer read and written in a shader.
    StorageWrite,
    /// A colour attachment, cleared and written.
    ColorTarget,
    /// A depth attachment, cleared and written.
    DepthTarget,
    /// A depth attachment tested against, not written.
    DepthTest,
    CopySrc,
    CopyDst,
    /// A buffer of indirect dispatch arguments.
    Indirect,
}

impl Access {
    pub fn writes(self) -> bool {
        matches!(self, Access::StorageWrite | Access::ColorTarget | Access::DepthTarget | Access::CopyDst)
    }

    pub fn texture_usage(self) -> wgpu::TextureUsages {
        use wgpu::TextureUsages as U;
        match self {
            Access::Sampled => U::TEXTURE_BINDING,
            Access::StorageRead | Access::StorageWrite => U::STORAGE_BINDING,
            Access::ColorTarget | Access::DepthTarget | Access::DepthTest => U::RENDER_ATTACHMENT,
            Access::CopySrc => U::COPY_SRC,
            Access::CopyDst => U::COPY_DST,
            Access::Indirect => U::empty(),
        }
    }

    pub fn buffer_usage(self) -> wgpu::BufferUsages {
        use wgpu::BufferUsages as U;
        match self {
            Access::StorageRead | Access::StorageWrite | Access::Sampled => U::STORAGE,
            Access::CopySrc => U::COPY_SRC,
            Access::CopyDst => U::COPY_DST,
            Access::Indirect => U::INDIRECT,
            Access::ColorTarget | Access::DepthTarget | Access::DepthTest => U::empty(),
        }
    }
}

/// Which pipeline a pass uses, with the defs this frame needs.
#[derive(Debug, Clone)]
pub struct PipelineKey {
    pub spec: &'static PipelineSpec,
    pub defs: ShaderDefs,
}

impl PipelineKey {
    /// The key for `spec` with the defs whose flag is true. Every def must
    /// be one the spec declares: that list is what `loupe check` builds.
    pub fn new(spec: &'static PipelineSpec, defs: &[(&'static str, bool)]) -> Self {
        for (d, _) in defs {
            debug_assert!(spec.defs.contains(d), "pipeline `{}` does not declare def `{d}`", spec.name);
        }
        PipelineKey { spec, defs: defs.iter().filter(|(_, on)| *on).map(|(d, _)| (*d).to_owned()).collect() }
    }

    pub fn label(&self) -> String {
        if self.defs.is_empty() {
            self.spec.name.to_owned()
        } else {
            format!("{}[{}]", self.spec.name, crate::shader::defs_key(&self.defs))
        }
    }

    fn id(&self) -> (&'static str, &ShaderDefs) {
        (self.spec.name, &self.defs)
    }
}

impl PartialEq for PipelineKey {
    fn eq(&self, other: &Self) -> bool {
        self.id() == other.id()
    }
}

impl Eq for PipelineKey {}

impl PartialOrd for PipelineKey {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for PipelineKey {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.id().cmp(&other.id())
    }
}

impl std::hash::Hash for PipelineKey {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.id().hash(state);
    }
}
