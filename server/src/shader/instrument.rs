//! Instrumenting a vertex stage: from a composed module and one of its
//! vertex entry points, a module whose only entry point is a compute
//! kernel that runs that vertex function once per vertex of a draw and
//! stores the clip-space positions it returns. Quad statistics need the
//! positions the pass's own, possibly just edited, shader produces, so the
//! kernel is generated from the module every time, never kept as a copy.
//!
//! The route: in naga's IR the module is cut down to what the vertex entry
//! point uses and the entry point becomes a plain function; naga's WGSL
//! writer prints that, and a generated `@compute` entry point that reads
//! the vertex inputs from storage buffers and calls the function is
//! appended. The writer renames identifiers as it needs to (collisions,
//! keywords, reserved prefixes), so every name the generated code uses
//! (the function, its struct types, the position member) is read from the
//! printed module parsed back, never assumed from the original.
//!
//! The kernel's own bindings, in group [`Instrumented::group`] (one past the
//! highest group the vertex stage uses, so the shader's bindings keep their
//! numbers):
//!
//! ```wgsl
//! @binding(0) var<uniform> draw: Draw;  // DrawParams
//! @binding(1) var<storage, read> indices: array<u32>;
//! @binding(2) var<storage, read_write> positions: array<vec4<f32>>;
//! @binding(3) var<storage, read> vertices: array<u32>;  // only with @location inputs
//! ```

use std::fmt::Write as _;

use naga::common::wgsl::TypeContext as _;
use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use naga::{Binding, BuiltIn, ScalarKind, TypeInner};

/// Invocations per workgroup of the generated kernel.
pub const WORKGROUP_SIZE: u32 = 64;

/// The bindings of the kernel's own group.
pub mod binding {
    pub const DRAW: u32 = 0;
    pub const INDICES: u32 = 1;
    pub const POSITIONS: u32 = 2;
    pub const VERTICES: u32 = 3;
}

/// The uniform at [`binding::DRAW`], byte for byte the generated `Draw`
/// struct. Invocation `i < count` runs vertex `first + i` of a non-indexed
/// draw, or vertex `indices[first + i] + base_vertex` of an indexed one,
/// with `@builtin(instance_index)` = `instance`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DrawParams {
    pub count: u32,
    pub first: u32,
    pub base_vertex: i32,
    pub instance: u32,
    /// 1: read vertex indices from `indices`; 0: vertices are consecutive.
    pub indexed: u32,
}

/// Why a vertex stage cannot be instrumented. Every unusable input is one
/// of these, never a panic.
#[derive(Debug, thiserror::Error)]
pub enum InstrumentError {
    #[error("the module has no entry point `{0}`")]
    NoEntryPoint(String),
    #[error("entry point `{entry}` is a {stage:?} entry point, not a vertex one")]
    NotVertex { entry: String, stage: naga::ShaderStage },
    #[error("the module does not validate: {0}")]
    Invalid(String),
    #[error(
        "vertex input `{input}` of type {ty} cannot be read from a buffer (32-bit scalars and vectors, vertex_index and instance_index can)"
    )]
    UnsupportedInput { input: String, ty: String },
    #[error("vertex input @location({0}) has no attribute in the vertex layout")]
    MissingAttribute(u32),
    #[error("the attribute at @location({location}) is {format:?}; only 32-bit float, uint and sint formats are read")]
    UnsupportedFormat { location: u32, format: wgpu::VertexFormat },
    #[error("the attribute at @location({location}) is {format:?}, which cannot feed an input of type {ty}")]
    FormatMismatch { location: u32, format: wgpu::VertexFormat, ty: String },
    #[error("the vertex layout: {0}")]
    Layout(String),
    /// naga rejected what was generated: a bug in loupe, not in the shader.
    #[error("instrumenting failed inside loupe (please report): {0}")]
    Internal(String),
}

/// The instrumented module, validated, and how to bind it.
#[derive(Debug, Clone)]
pub struct Instrumented {
    pub module: naga::Module,
    /// The compute entry point's name.
    pub entry: String,
    /// The group of the kernel's own bindings ([`binding`]).
    pub group: u32,
    /// Whether the kernel reads [`binding::VERTICES`]: only a vertex stage
    /// with `@location` inputs does.
    pub reads_vertices: bool,
}

/// Instruments vertex entry point `entry` of `module`. `layout` is the
/// vertex buffer the pipeline draws with (`None`: no buffer, as fullscreen
/// passes draw); each `@location` input is read from it as the pipeline
/// reads it, missing components filled with (0, 0, 0, 1) as WebGPU fills
/// them.
pub fn instrument(
    module: &naga::Module,
    entry: &str,
    layout: Option<&wgpu::VertexBufferLayout<'_>>,
) -> Result<Instrumented, InstrumentError> {
    let index = vertex_entry(module, entry)?;
    validate(module).map_err(InstrumentError::Invalid)?;
    if let Some(l) = layout {
        check_layout(l)?;
    }
    let ep = &module.entry_points[index];
    let inputs = ep
        .function
        .arguments
        .iter()
        .map(|a| Input::of(module, layout, a.name.as_deref().unwrap_or("?"), a.ty, a.binding.as_ref()))
        .collect::<Result<Vec<_>, _>>()?;
    let position = position_member(module, &ep.function)?;

    let prefix = free_prefix(module);
    let function = format!("{prefix}vertex");
    let (printed, group) = demote(module, index, &function)?;
    // What the kernel calls, by the names the writer printed.
    let reread = parse(&printed)?;
    let (_, demoted) = reread
        .functions
        .iter()
        .find(|(_, f)| f.name.as_deref() == Some(function.as_str()))
        .ok_or_else(|| InstrumentError::Internal(format!("naga's writer renamed `{function}`")))?;
    let args = inputs
        .iter()
        .zip(&demoted.arguments)
        .map(|(input, arg)| input.expression(&prefix, &reread.types[arg.ty]))
        .collect::<Result<Vec<_>, _>>()?;
    let position = printed_member(&reread, demoted, position)?;
    let reads_vertices = inputs.iter().any(Input::reads_vertices);
    let stride = layout.map_or(0, |l| l.array_stride / 4);
    let source = printed + &kernel(&prefix, group, &function, &args.join(", "), &position, reads_vertices.then_some(stride));
    let module = parse(&source)?;
    validate(&module).map_err(InstrumentError::Internal)?;
    Ok(Instrumented { module, entry: format!("{prefix}vertex_positions"), group, reads_vertices })
}

fn vertex_entry(module: &naga::Module, entry: &str) -> Result<usize, InstrumentError> {
    let named = || module.entry_points.iter().enumerate().filter(|(_, e)| e.name == entry);
    if let Some((i, _)) = named().find(|(_, e)| e.stage == naga::ShaderStage::Vertex) {
        return Ok(i);
    }
    match named().next() {
        Some((_, e)) => Err(InstrumentError::NotVertex { entry: entry.to_owned(), stage: e.stage }),
        None => Err(InstrumentError::NoEntryPoint(entry.to_owned())),
    }
}

/// Every capability: the input was validated against the device already,
/// and what is added needs none.
fn validate(module: &naga::Module) -> Result<ModuleInfo, String> {
    Validator::new(ValidationFlags::all(), Capabilities::all()).validate(module).map_err(|e| e.emit_to_string(""))
}

fn parse(source: &str) -> Result<naga::Module, InstrumentError> {
    naga::front::wgsl::parse_str(source).map_err(|e| InstrumentError::Internal(e.emit_to_string(source)))
}

/// The generated kernel reads 32-bit words: offsets and the stride must
/// be whole words, and attributes step per vertex.
fn check_layout(layout: &wgpu::VertexBufferLayout<'_>) -> Result<(), InstrumentError> {
    if layout.step_mode != wgpu::VertexStepMode::Vertex {
        return Err(InstrumentError::Layout("only per-vertex attributes are read".into()));
    }
    if !layout.array_stride.is_multiple_of(4) {
        return Err(InstrumentError::Layout(format!("a stride of {} bytes is not a multiple of 4", layout.array_stride)));
    }
    match layout.attributes.iter().find(|a| !a.offset.is_multiple_of(4)) {
        Some(a) => Err(InstrumentError::Layout(format!("@location({}) sits at byte {}, not a multiple of 4", a.shader_location, a.offset))),
        None => Ok(()),
    }
}

/// The scalar kinds a vertex attribute can hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    F32,
    U32,
    I32,
}

impl Kind {
    fn of(scalar: naga::Scalar) -> Option<Kind> {
        match (scalar.kind, scalar.width) {
            (ScalarKind::Float, 4) => Some(Kind::F32),
            (ScalarKind::Uint, 4) => Some(Kind::U32),
            (ScalarKind::Sint, 4) => Some(Kind::I32),
            _ => None,
        }
    }

    /// The kind and component count a format delivers, for the formats
    /// whose components are whole 32-bit words.
    fn of_format(format: wgpu::VertexFormat) -> Option<(Kind, u32)> {
        use wgpu::VertexFormat as F;
        let kind = match format {
            F::Float32 | F::Float32x2 | F::Float32x3 | F::Float32x4 => Kind::F32,
            F::Uint32 | F::Uint32x2 | F::Uint32x3 | F::Uint32x4 => Kind::U32,
            F::Sint32 | F::Sint32x2 | F::Sint32x3 | F::Sint32x4 => Kind::I32,
            _ => return None,
        };
        Some((kind, (format.size() / 4) as u32))
    }

    fn wgsl(self) -> &'static str {
        match self {
            Kind::F32 => "f32",
            Kind::U32 => "u32",
            Kind::I32 => "i32",
        }
    }

    /// `word`, a `u32` expression, as this kind.
    fn read(self, word: String) -> String {
        match self {
            Kind::U32 => word,
            _ => format!("bitcast<{}>({word})", self.wgsl()),
        }
    }

    /// WebGPU's value for a component the format lacks: 1 for w, else 0.
    fn missing(self, component: u32) -> String {
        format!(
            "{}{}",
            u32::from(component == 3),
            match self {
                Kind::F32 => ".0",
                Kind::U32 => "u",
                Kind::I32 => "i",
            }
        )
    }
}

/// One argument of the vertex function, or one member of a struct
/// argument, and where its value comes from.
#[derive(Debug)]
enum Input {
    VertexIndex,
    InstanceIndex,
    /// Components read from the vertex buffer: the input has `components`
    /// of `kind`; the format supplies `supplied`, from `word` on.
    Attribute {
        kind: Kind,
        components: u32,
        supplied: u32,
        word: u32,
    },
    Struct(Vec<Input>),
}

impl Input {
    fn of(
        module: &naga::Module,
        layout: Option<&wgpu::VertexBufferLayout<'_>>,
        name: &str,
        ty: naga::Handle<naga::Type>,
        binding: Option<&Binding>,
    ) -> Result<Input, InstrumentError> {
        let unsupported = || InstrumentError::UnsupportedInput { input: name.to_owned(), ty: module.to_ctx().type_to_string(ty) };
        let inner = &module.types[ty].inner;
        match binding {
            Some(Binding::BuiltIn(BuiltIn::VertexIndex)) => Ok(Input::VertexIndex),
            Some(Binding::BuiltIn(BuiltIn::InstanceIndex)) => Ok(Input::InstanceIndex),
            Some(Binding::BuiltIn(_)) => Err(unsupported()),
            Some(Binding::Location { location, .. }) => {
                let (kind, components) = match *inner {
                    TypeInner::Scalar(s) => (Kind::of(s).ok_or_else(unsupported)?, 1),
                    TypeInner::Vector { size, scalar } => (Kind::of(scalar).ok_or_else(unsupported)?, size as u32),
                    _ => return Err(unsupported()),
                };
                let attribute = layout
                    .and_then(|l| l.attributes.iter().find(|a| a.shader_location == *location))
                    .ok_or(InstrumentError::MissingAttribute(*location))?;
                let format = attribute.format;
                let (supplied_kind, supplied) =
                    Kind::of_format(format).ok_or(InstrumentError::UnsupportedFormat { location: *location, format })?;
                if supplied_kind != kind {
                    return Err(InstrumentError::FormatMismatch { location: *location, format, ty: module.to_ctx().type_to_string(ty) });
                }
                Ok(Input::Attribute { kind, components, supplied, word: (attribute.offset / 4) as u32 })
            }
            None => match inner {
                TypeInner::Struct { members, .. } => members
                    .iter()
                    .map(|m| Input::of(module, layout, m.name.as_deref().unwrap_or("?"), m.ty, m.binding.as_ref()))
                    .collect::<Result<Vec<_>, _>>()
                    .map(Input::Struct),
                _ => Err(unsupported()),
            },
        }
    }

    fn reads_vertices(&self) -> bool {
        match self {
            Input::Attribute { .. } => true,
            Input::Struct(members) => members.iter().any(Input::reads_vertices),
            Input::VertexIndex | Input::InstanceIndex => false,
        }
    }

    /// The WGSL expression of this input in the kernel; `ty` is its type in
    /// the printed module (a struct is built by that type's printed name).
    fn expression(&self, p: &str, ty: &naga::Type) -> Result<String, InstrumentError> {
        Ok(match self {
            Input::VertexIndex => format!("{p}vertex_index"),
            Input::InstanceIndex => format!("{p}draw.instance"),
            Input::Attribute { kind, components, supplied, word } => {
                let parts: Vec<String> = (0..*components)
                    .map(|c| if c < *supplied { kind.read(format!("{p}vertices[{p}at + {}u]", word + c)) } else { kind.missing(c) })
                    .collect();
                match components {
                    1 => parts.join(""),
                    n => format!("vec{n}<{}>({})", kind.wgsl(), parts.join(", ")),
                }
            }
            Input::Struct(members) => {
                let name = ty.name.as_deref().ok_or_else(|| InstrumentError::Internal("a printed input struct has no name".into()))?;
                // Vertex input structs do not nest: members need no type.
                let values = members.iter().map(|m| m.expression(p, ty)).collect::<Result<Vec<_>, _>>()?;
                format!("{name}({})", values.join(", "))
            }
        })
    }
}

/// Which member of the vertex function's result struct is
/// `@builtin(position)`; `None` when the result itself is.
fn position_member(module: &naga::Module, function: &naga::Function) -> Result<Option<usize>, InstrumentError> {
    let is_position = |b: Option<&Binding>| matches!(b, Some(Binding::BuiltIn(BuiltIn::Position { .. })));
    let missing = || InstrumentError::Invalid("the vertex entry point has no @builtin(position) output".into());
    let result = function.result.as_ref().ok_or_else(missing)?;
    if is_position(result.binding.as_ref()) {
        return Ok(None);
    }
    match &module.types[result.ty].inner {
        TypeInner::Struct { members, .. } => members.iter().position(|m| is_position(m.binding.as_ref())).map(Some).ok_or_else(missing),
        _ => Err(missing()),
    }
}

/// `.name` of member `member` of `function`'s result struct as printed;
/// empty when the result itself is the position.
fn printed_member(module: &naga::Module, function: &naga::Function, member: Option<usize>) -> Result<String, InstrumentError> {
    let Some(k) = member else { return Ok(String::new()) };
    let name = function.result.as_ref().and_then(|r| match &module.types[r.ty].inner {
        TypeInner::Struct { members, .. } => members.get(k)?.name.as_deref(),
        _ => None,
    });
    name.map(|n| format!(".{n}"))
        .ok_or_else(|| InstrumentError::Internal(format!("the printed vertex function's result has no member {k}")))
}

/// `loupe_`, or `loupe_1_`, `loupe_2_`, …: a prefix no name in the module
/// starts with, so nothing the kernel declares collides with the shader's
/// names, nor makes naga's writer rename the demoted function.
fn free_prefix(module: &naga::Module) -> String {
    let mut names: Vec<&str> = Vec::new();
    names.extend(module.types.iter().filter_map(|(_, t)| t.name.as_deref()));
    names.extend(module.constants.iter().filter_map(|(_, c)| c.name.as_deref()));
    names.extend(module.overrides.iter().filter_map(|(_, o)| o.name.as_deref()));
    names.extend(module.global_variables.iter().filter_map(|(_, g)| g.name.as_deref()));
    let functions = module.functions.iter().map(|(_, f)| f).chain(module.entry_points.iter().map(|e| &e.function));
    for f in functions {
        names.extend(f.name.as_deref());
        names.extend(f.arguments.iter().filter_map(|a| a.name.as_deref()));
        names.extend(f.local_variables.iter().filter_map(|(_, l)| l.name.as_deref()));
        names.extend(f.named_expressions.values().map(String::as_str));
    }
    let mut k = 0u64;
    loop {
        let prefix = if k == 0 { "loupe_".to_owned() } else { format!("loupe_{k}_") };
        if !names.iter().any(|n| n.starts_with(&prefix)) {
            return prefix;
        }
        k += 1;
    }
}

/// The module cut down to entry point `index`, that entry point turned
/// into the plain function `function`, printed as WGSL; and the group one
/// past the highest the vertex stage binds.
fn demote(module: &naga::Module, index: usize, function: &str) -> Result<(String, u32), InstrumentError> {
    let mut cut = module.clone();
    let vertex = cut.entry_points.swap_remove(index);
    // With the vertex stage the only entry point, compacting leaves exactly
    // what it uses: other stages' bindings would otherwise stay in the
    // module, and in the way of the kernel's group.
    cut.entry_points = vec![vertex];
    naga::compact::compact(&mut cut, naga::compact::KeepUnused::No);
    let mut demoted =
        cut.entry_points.pop().map(|e| e.function).ok_or_else(|| InstrumentError::Internal("compaction dropped the entry point".into()))?;
    demoted.name = Some(function.to_owned());
    // Argument and result bindings are only allowed on entry points.
    for a in &mut demoted.arguments {
        a.binding = None;
    }
    if let Some(r) = &mut demoted.result {
        r.binding = None;
    }
    cut.functions.append(demoted, naga::Span::UNDEFINED);
    let group = cut.global_variables.iter().filter_map(|(_, g)| g.binding.as_ref()).map(|b| b.group + 1).max().unwrap_or(0);
    let info = validate(&cut).map_err(InstrumentError::Internal)?;
    let printed = naga::back::wgsl::write_string(&cut, &info, naga::back::wgsl::WriterFlags::empty())
        .map_err(|e| InstrumentError::Internal(e.to_string()))?;
    Ok((printed, group))
}

/// The generated compute entry point and its bindings (see the module
/// docs), calling `function(args)` and storing `.position` of its result
/// (`position` is empty when the result is the position). `stride` is the
/// vertex stride in words, when vertices are read.
fn kernel(p: &str, group: u32, function: &str, args: &str, position: &str, stride: Option<u64>) -> String {
    use binding::*;
    let mut k = String::new();
    let _ = write!(
        k,
        "
struct {p}Draw {{ count: u32, first: u32, base_vertex: i32, instance: u32, indexed: u32 }}
@group({group}) @binding({DRAW}) var<uniform> {p}draw: {p}Draw;
@group({group}) @binding({INDICES}) var<storage, read> {p}indices: array<u32>;
@group({group}) @binding({POSITIONS}) var<storage, read_write> {p}positions: array<vec4<f32>>;
"
    );
    if stride.is_some() {
        let _ = writeln!(k, "@group({group}) @binding({VERTICES}) var<storage, read> {p}vertices: array<u32>;");
    }
    let _ = write!(
        k,
        "
@compute @workgroup_size({WORKGROUP_SIZE})
fn {p}vertex_positions(@builtin(global_invocation_id) {p}id: vec3<u32>) {{
    let {p}i = {p}id.x;
    if {p}i >= {p}draw.count {{
        return;
    }}
    var {p}vertex_index = {p}draw.first + {p}i;
    if {p}draw.indexed != 0u {{
        {p}vertex_index = {p}indices[{p}vertex_index] + bitcast<u32>({p}draw.base_vertex);
    }}
"
    );
    if let Some(stride) = stride {
        let _ = writeln!(k, "    let {p}at = {p}vertex_index * {stride}u;");
    }
    let _ = write!(
        k,
        "    let {p}out = {function}({args});
    {p}positions[{p}i] = {p}out{position};
}}
"
    );
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(source: &str) -> naga::Module {
        naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)))
    }

    /// A vertex stage with one input per `@location`, typed as given.
    fn stage(inputs: &str) -> naga::Module {
        parse(&format!(
            "{}
@vertex
fn vs({inputs}) -> @builtin(position) vec4<f32> {{
    return vec4(1.0);
}}
@fragment
fn fs() -> @location(0) vec4<f32> {{
    return vec4(1.0);
}}
",
            if inputs.contains("f16") { "enable f16;" } else { "" }
        ))
    }

    fn layout(stride: u64, attributes: &[wgpu::VertexAttribute]) -> wgpu::VertexBufferLayout<'_> {
        wgpu::VertexBufferLayout { array_stride: stride, step_mode: wgpu::VertexStepMode::Vertex, attributes }
    }

    fn attribute(location: u32, format: wgpu::VertexFormat, offset: u64) -> wgpu::VertexAttribute {
        wgpu::VertexAttribute { format, offset, shader_location: location }
    }

    #[test]
    fn the_entry_point_must_exist_and_be_a_vertex_one() {
        let m = stage("");
        assert!(matches!(instrument(&m, "nope", None), Err(InstrumentError::NoEntryPoint(e)) if e == "nope"));
        let e = instrument(&m, "fs", None).unwrap_err();
        assert!(matches!(e, InstrumentError::NotVertex { stage: naga::ShaderStage::Fragment, .. }), "{e}");
        assert!(instrument(&m, "vs", None).is_ok());
    }

    #[test]
    fn a_module_naga_rejects_is_not_instrumented() {
        // Parses, but a position is a vec4<f32>.
        let m = parse("@vertex fn vs() -> @builtin(position) vec3<f32> { return vec3(1.0); }");
        let e = instrument(&m, "vs", None).unwrap_err();
        assert!(matches!(e, InstrumentError::Invalid(_)), "{e}");
    }

    #[test]
    fn inputs_the_buffer_cannot_feed_are_refused() {
        let f32x3 = [attribute(0, wgpu::VertexFormat::Float32x3, 0)];
        let l = layout(12, &f32x3);
        let e = instrument(&stage("@location(0) h: vec3<f16>"), "vs", Some(&l)).unwrap_err();
        assert!(matches!(&e, InstrumentError::UnsupportedInput { input, ty } if input == "h" && ty == "vec3<f16>"), "{e}");
        let e = instrument(&stage("@location(0) p: vec3<f32>, @location(1) q: f32"), "vs", Some(&l)).unwrap_err();
        assert!(matches!(e, InstrumentError::MissingAttribute(1)), "{e}");
        let e = instrument(&stage("@location(0) p: vec3<f32>"), "vs", None).unwrap_err();
        assert!(matches!(e, InstrumentError::MissingAttribute(0)), "{e}");
        let e = instrument(&stage("@location(0) p: vec3<u32>"), "vs", Some(&l)).unwrap_err();
        assert!(matches!(&e, InstrumentError::FormatMismatch { location: 0, ty, .. } if ty == "vec3<u32>"), "{e}");
        let unorm = [attribute(0, wgpu::VertexFormat::Unorm8x4, 0)];
        let e = instrument(&stage("@location(0) c: vec4<f32>"), "vs", Some(&layout(4, &unorm))).unwrap_err();
        assert!(matches!(e, InstrumentError::UnsupportedFormat { location: 0, format: wgpu::VertexFormat::Unorm8x4 }), "{e}");
        let e = instrument(&stage("@location(0) p: vec3<f32>"), "vs", Some(&layout(14, &f32x3))).unwrap_err();
        assert!(matches!(&e, InstrumentError::Layout(m) if m.contains("14 bytes")), "{e}");
    }

    /// naga's writer renames what it must (here: names ending in a digit
    /// get a `_`); the kernel uses the printed names, so it still builds.
    #[test]
    fn names_the_writer_changes_are_looked_up() {
        let m = parse(
            "
struct In1 { @location(0) p: vec3<f32>, @builtin(vertex_index) index0: u32 }
struct Out1 { @location(0) uv: vec2<f32>, @builtin(position) clip0: vec4<f32> }
fn loupe_vertex(p: vec3<f32>) -> vec4<f32> { return vec4(p, 1.0); }
@vertex
fn vs(v: In1) -> Out1 {
    return Out1(v.p.xy, loupe_vertex(v.p) + f32(v.index0));
}
",
        );
        let f32x3 = [attribute(0, wgpu::VertexFormat::Float32x3, 0)];
        let out = instrument(&m, "vs", Some(&layout(12, &f32x3))).unwrap();
        let names: Vec<&str> = out.module.types.iter().filter_map(|(_, t)| t.name.as_deref()).collect();
        assert!(names.contains(&"Out1_") && names.contains(&"In1_"), "the premise: the writer renamed the structs: {names:?}");
        // `loupe_` is taken by the shader, so the kernel's names move over.
        assert_eq!(out.entry, "loupe_1_vertex_positions");
        let ep = &out.module.entry_points;
        assert_eq!((ep.len(), ep[0].stage, ep[0].workgroup_size), (1, naga::ShaderStage::Compute, [WORKGROUP_SIZE, 1, 1]));
    }

    /// The kernel's group follows the groups the vertex stage binds; other
    /// stages' bindings are cut away with them.
    #[test]
    fn the_kernel_binds_past_the_vertex_stages_groups() {
        let m = parse(
            "
@group(0) @binding(3) var<uniform> offset: vec4<f32>;
@group(3) @binding(0) var<uniform> tint: vec4<f32>;
@vertex
fn vs() -> @builtin(position) vec4<f32> { return offset; }
@fragment
fn fs() -> @location(0) vec4<f32> { return tint; }
",
        );
        let out = instrument(&m, "vs", None).unwrap();
        assert_eq!((out.group, out.reads_vertices), (1, false));
        let mut bound: Vec<(u32, u32)> =
            out.module.global_variables.iter().filter_map(|(_, g)| g.binding.as_ref()).map(|b| (b.group, b.binding)).collect();
        bound.sort_unstable();
        let own = [binding::DRAW, binding::INDICES, binding::POSITIONS].map(|b| (1, b));
        assert_eq!(bound, [&[(0, 3)], &own[..]].concat());
        assert_eq!(instrument(&stage(""), "vs", None).unwrap().group, 0, "no bindings: group 0");
    }
}
