//! glTF 2.0 to one `MeshData`: .gltf (buffers in files or data: URIs) and
//! .glb. The default scene's node tree is flattened, node transforms applied.
//! Per vertex it reads POSITION, NORMAL, TEXCOORD_0 and TANGENT; what a
//! primitive leaves out is made (`smooth_normals`, `tangents`).
//!
//! The gltf crate's typed JSON model is used for deserialisation only. Its
//! validation and readers are not: validation rejects legal files (custom
//! `_ATTRIBUTE`s need a feature we do not enable) and names no places, and
//! the readers and importer can panic on out-of-range data. Here every read
//! is bounds-checked, and every error names the glTF element at fault and,
//! in a .gltf, points at where it is written.

use std::borrow::Cow;
use std::path::Path;

use gltf::json::accessor::{ComponentType, GenericComponentType, Type};
use gltf::json::mesh::{Mode, Primitive, Semantic};
use gltf::json::validation::Checked;
use gltf::json::{self, Root};

use super::json_path::JsonPath;
use super::math::{self, IDENTITY, Mat4, NormalTransform, Vec3};
use super::tangents;
use super::uri::{self, Uri, UriError};
use super::{MAX_FILE_BYTES, MAX_TRIANGLES, MAX_VERTICES, MeshData, glb};
use crate::diag::{Code, Diagnostic, LineIndex, Location};
use crate::files::read_capped;

/// Caps on what one load may produce; tests lower them.
pub(super) struct Limits {
    pub triangles: usize,
    pub vertices: usize,
    pub file_bytes: u64,
}

const LIMITS: Limits = Limits { triangles: MAX_TRIANGLES, vertices: MAX_VERTICES, file_bytes: MAX_FILE_BYTES };

/// Geometry-encoding extensions: a file that requires one has no plain float
/// geometry to read. (Required material extensions do not matter here.)
const UNSUPPORTED_EXTENSIONS: [&str; 3] = ["KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_mesh_quantization"];

/// Loads the default scene of a .gltf or .glb as one mesh; `display` names
/// the file in diagnostics.
pub fn load_gltf(path: &Path, display: &str) -> Result<MeshData, Diagnostic> {
    load(path, display, &LIMITS)
}

pub(super) fn load(path: &Path, display: &str, limits: &Limits) -> Result<MeshData, Diagnostic> {
    let parts = read(path, display, limits, false)?.parts;
    Ok(parts.into_iter().next().map(|(_, mesh)| mesh).unwrap_or_default())
}

/// A glTF's default scene split by material: what an object that takes the
/// glTF's own materials draws, one part per material.
#[derive(Debug, Clone)]
pub struct Parts {
    /// Per glTF material (its index; `None`: primitives without one, which
    /// glTF draws with its default material), in the order first drawn, the
    /// triangles that use it.
    pub parts: Vec<(Option<usize>, MeshData)>,
    /// The document's JSON (the .glb's JSON chunk), for its materials.
    pub json: serde_json::Value,
    /// A .gltf's text, to place diagnostics; `None` for a .glb.
    pub text: Option<String>,
}

/// Loads the default scene of a .gltf or .glb split by material.
pub fn load_gltf_parts(path: &Path, display: &str) -> Result<Parts, Diagnostic> {
    read(path, display, &LIMITS, true)
}

/// The default scene's triangles: one part, or (`split`) one per material.
fn read(path: &Path, display: &str, limits: &Limits, split: bool) -> Result<Parts, Diagnostic> {
    let bytes =
        read_capped(path, limits.file_bytes).map_err(|e| e.diagnostic("file", limits.file_bytes).at(Location::file_start(display)))?;
    let is_glb = bytes.starts_with(glb::MAGIC);
    if !is_glb && path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) {
        return Err(
            Diagnostic::error(Code::Scene, "not a binary glTF file: it does not start with `glTF`").at(Location::file_start(display))
        );
    }
    let (doc, json, bin) = if is_glb {
        let glb = glb::parse(&bytes).map_err(|e| Diagnostic::error(Code::Scene, e).at(Location::file_start(display)))?;
        (Doc { display, text: None }, glb.json, glb.bin)
    } else {
        let text = std::str::from_utf8(&bytes).map_err(|e| not_utf8(display, &bytes, e))?;
        (Doc { display, text: Some((text, LineIndex::new(text))) }, &bytes[..], None)
    };
    let root: Root = serde_json::from_slice(json).map_err(|e| doc.json_error(&e))?;
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if UNSUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(doc.error(
                &JsonPath::top("extensionsRequired").index(i),
                format!("the file requires {ext}, which loupe does not support: export uncompressed float geometry"),
            ));
        }
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = load_buffers(&doc, &root, base, bin, limits)?;
    let parts = Flattener { doc: &doc, root: &root, buffers: &buffers, limits, split, meshes: vec![None; root.meshes.len()] }.run()?;
    let (json, text) = if split {
        (serde_json::from_slice(json).map_err(|e| doc.json_error(&e))?, doc.text.as_ref().map(|(t, _)| (*t).to_owned()))
    } else {
        (serde_json::Value::Null, None)
    };
    Ok(Parts { parts, json, text })
}

fn not_utf8(display: &str, bytes: &[u8], e: std::str::Utf8Error) -> Diagnostic {
    let valid = e.valid_up_to();
    let prefix = std::str::from_utf8(&bytes[..valid]).unwrap_or_default();
    let (line, column) = LineIndex::new(prefix).line_col(prefix, valid);
    let at = Location { file: display.to_owned(), line, column, end_line: line, end_column: column + 1 };
    Diagnostic::error(Code::Encoding, "a .gltf file must be UTF-8 JSON").at(at)
}

/// The file being loaded, to place diagnostics.
pub struct Doc<'a> {
    pub display: &'a str,
    /// A .gltf's text. `None` for a .glb: its JSON sits in a binary file no
    /// editor shows by line, so its diagnostics name elements, at the file.
    pub text: Option<(&'a str, LineIndex)>,
}

impl Doc<'_> {
    /// Where the element at `path` is written, clipped to its first line: a
    /// whole primitive underlined would hide which one is meant.
    pub fn at(&self, path: &JsonPath) -> Location {
        let Some((text, lines)) = &self.text else {
            return Location::file_start(self.display);
        };
        let range = path.locate(text);
        let end = text.get(range.clone()).and_then(|s| s.find('\n')).map_or(range.end, |n| range.start + n);
        lines.location(self.display, text, range.start..end)
    }

    fn error(&self, path: &JsonPath, message: impl Into<String>) -> Diagnostic {
        Diagnostic::error(Code::Scene, message).at(self.at(path))
    }

    /// serde_json counts lines from 1 and columns in bytes, the column being
    /// that of the last byte it read (0 before the first of a line).
    fn json_error(&self, e: &serde_json::Error) -> Diagnostic {
        let (line, column) = (e.line(), e.column());
        let full = e.to_string();
        let Some((text, lines)) = &self.text else {
            return Diagnostic::error(Code::Scene, format!("invalid glTF JSON in the binary file's JSON chunk: {full}"))
                .at(Location::file_start(self.display));
        };
        let message = full.strip_suffix(&format!(" at line {line} column {column}")).unwrap_or(&full);
        let message = format!("invalid glTF JSON: {message}");
        if line == 0 {
            return Diagnostic::error(Code::Scene, message).at(Location::file_start(self.display));
        }
        let line_start: usize = text.split_inclusive('\n').take(line - 1).map(str::len).sum();
        let mut at = (line_start + column.saturating_sub(1)).min(text.len());
        while !text.is_char_boundary(at) {
            at -= 1;
        }
        let end = at + text[at..].chars().next().map_or(0, char::len_utf8);
        Diagnostic::error(Code::Scene, message).at(lines.location(self.display, text, at..end))
    }

    /// At the offending character of the URI when the JSON string is written
    /// without escapes (so string offsets are text offsets), else at the URI.
    fn uri_error(&self, path: &JsonPath, uri: &str, e: UriError) -> Diagnostic {
        let d = self.error(path, format!("{path}: {}", e.message));
        let (Some((text, lines)), Some(offset)) = (&self.text, e.offset) else {
            return d;
        };
        let range = path.locate(text);
        if range.end > range.start + 1 && text.get(range.start + 1..range.end - 1) == Some(uri) {
            let at = range.start + 1 + offset;
            return d.at(lines.location(self.display, text, at..at + 1));
        }
        d
    }
}

fn load_buffers<'a>(doc: &Doc, root: &Root, base: &Path, bin: Option<&'a [u8]>, limits: &Limits) -> Result<Vec<Cow<'a, [u8]>>, Diagnostic> {
    let mut budget = limits.file_bytes;
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let path = JsonPath::element("buffers", i);
        let data = match (&buffer.uri, bin) {
            (None, Some(bin)) if i == 0 => Cow::Borrowed(bin),
            (None, _) if doc.text.is_none() && i == 0 => {
                return Err(doc.error(&path, format!("{path} has no uri and the binary file has no BIN chunk")));
            }
            (None, _) => {
                return Err(doc.error(&path, format!("{path} has no uri: give a file name or a data: URI")));
            }
            (Some(u), _) => match uri::parse(u) {
                Ok(Uri::Data(bytes)) => Cow::Owned(bytes),
                Ok(Uri::Relative(file)) => Cow::Owned(read_capped(&base.join(&file), budget).map_err(|e| {
                    let what = format!("`{file}`, the data of {path}");
                    e.diagnostic(&what, budget).at(doc.at(&path.field("uri")))
                })?),
                Err(e) => return Err(doc.uri_error(&path.field("uri"), u, e)),
            },
        };
        let declared = buffer.byte_length.0;
        if (data.len() as u64) < declared {
            return Err(doc
                .error(&path.field("byteLength"), format!("{path} declares byteLength {declared}, but its data is {} bytes", data.len())));
        }
        budget = budget.checked_sub(data.len() as u64).ok_or_else(|| {
            Diagnostic::error(
                Code::FileTooLarge,
                format!("{path} takes the buffers over {} bytes, the limit for one file", limits.file_bytes),
            )
            .at(doc.at(&path))
        })?;
        out.push(data);
    }
    Ok(out)
}

/// An accessor's elements, bounds-checked: element `i` is
/// `bytes[i * stride..][..size]`.
struct Elements<'b> {
    bytes: &'b [u8],
    stride: usize,
    size: usize,
    count: usize,
    component: ComponentType,
}

impl<'b> Elements<'b> {
    fn iter(&self) -> impl Iterator<Item = &'b [u8]> + '_ {
        (0..self.count).map(|i| &self.bytes[i * self.stride..][..self.size])
    }
}

/// What an accessor must hold for one use: its type and allowed component types.
struct Want {
    type_: Type,
    components: &'static [ComponentType],
}

const VEC3_F32: Want = Want { type_: Type::Vec3, components: &[ComponentType::F32] };
const VEC4_F32: Want = Want { type_: Type::Vec4, components: &[ComponentType::F32] };
/// glTF allows TEXCOORD_n as floats or as normalized unsigned integers.
const TEXCOORDS: Want = Want { type_: Type::Vec2, components: &[ComponentType::F32, ComponentType::U8, ComponentType::U16] };
const INDICES: Want = Want { type_: Type::Scalar, components: &[ComponentType::U8, ComponentType::U16, ComponentType::U32] };

struct Flattener<'a> {
    doc: &'a Doc<'a>,
    root: &'a Root,
    buffers: &'a [Cow<'a, [u8]>],
    limits: &'a Limits,
    /// Keep primitives of different materials apart.
    split: bool,
    /// Each mesh decoded once, however many nodes place it: its primitives
    /// joined, per material when `split`.
    meshes: Vec<Option<Vec<Group>>>,
}

/// Triangles of one material (`None`: no material, or not split).
type Group = (Option<usize>, MeshData);

/// The group of `out` for `key`, added if new.
fn group(out: &mut Vec<Group>, key: Option<usize>) -> &mut MeshData {
    let i = out.iter().position(|(k, _)| *k == key).unwrap_or_else(|| {
        out.push((key, MeshData::default()));
        out.len() - 1
    });
    &mut out[i].1
}

impl Flattener<'_> {
    fn run(mut self) -> Result<Vec<Group>, Diagnostic> {
        let (doc, root) = (self.doc, self.root);
        if root.meshes.is_empty() {
            return Err(doc.error(&JsonPath::top("meshes"), "the file has no meshes"));
        }
        let mut out = Vec::new();
        let scene = match root.scene {
            Some(s) => Some((s.value(), JsonPath::top("scene"))),
            None if !root.scenes.is_empty() => Some((0, JsonPath::element("scenes", 0))),
            None => None,
        };
        // Where the drawn nodes are listed, for "no triangles" errors.
        let (listed_at, roots) = match scene {
            Some((s, referenced_at)) => {
                let scene = root.scenes.get(s).ok_or_else(|| {
                    doc.error(&referenced_at, format!("scene {s} does not exist: the file has {} scenes", root.scenes.len()))
                })?;
                let path = JsonPath::element("scenes", s);
                let roots = scene.nodes.iter().enumerate().map(|(k, n)| (n.value(), path.field("nodes").index(k)));
                (path.clone(), roots.collect())
            }
            // No scene: a library of meshes, drawn where they stand.
            None if root.nodes.is_empty() => {
                for m in 0..root.meshes.len() {
                    self.place(&mut out, m, &IDENTITY, &JsonPath::element("meshes", m))?;
                }
                (JsonPath::top("meshes"), Vec::new())
            }
            // No scene but nodes: every tree of them.
            None => {
                let mut has_parent = vec![false; root.nodes.len()];
                for child in root.nodes.iter().flat_map(|n| n.children.iter().flatten()) {
                    if let Some(flag) = has_parent.get_mut(child.value()) {
                        *flag = true;
                    }
                }
                let roots = (0..root.nodes.len()).filter(|&n| !has_parent[n]).map(|n| (n, JsonPath::element("nodes", n)));
                (JsonPath::top("nodes"), roots.collect())
            }
        };
        self.walk(&mut out, roots)?;
        if out.iter().all(|(_, m)| m.indices.is_empty()) {
            return Err(doc.error(&listed_at, format!("{listed_at} has no triangles to draw")));
        }
        Ok(out)
    }

    /// Depth-first over node trees with an explicit stack: a deep or cyclic
    /// hierarchy can neither overflow the stack nor loop.
    fn walk(&mut self, out: &mut Vec<Group>, roots: Vec<(usize, JsonPath)>) -> Result<(), Diagnostic> {
        let (doc, root) = (self.doc, self.root);
        let mut seen = vec![false; root.nodes.len()];
        let mut stack: Vec<(usize, Mat4, JsonPath)> = roots.into_iter().rev().map(|(n, at)| (n, IDENTITY, at)).collect();
        while let Some((n, parent, referenced_at)) = stack.pop() {
            let node = root.nodes.get(n).ok_or_else(|| {
                let count = root.nodes.len();
                doc.error(&referenced_at, format!("{referenced_at} refers to nodes[{n}], but the file has {count} nodes"))
            })?;
            if std::mem::replace(&mut seen[n], true) {
                return Err(doc.error(
                    &referenced_at,
                    format!("{referenced_at} reaches nodes[{n}] a second time: nodes must form trees, one parent each, no cycles"),
                ));
            }
            let path = JsonPath::element("nodes", n);
            let world = math::mul(&parent, &self.local_transform(node, &path)?);
            if let Some(mesh) = node.mesh {
                self.place(out, mesh.value(), &world, &path.field("mesh"))?;
            }
            for (k, child) in node.children.as_deref().unwrap_or_default().iter().enumerate().rev() {
                stack.push((child.value(), world, path.field("children").index(k)));
            }
        }
        Ok(())
    }

    fn local_transform(&self, node: &json::Node, path: &JsonPath) -> Result<Mat4, Diagnostic> {
        let finite = |values: &[f32], field: &'static str| {
            if values.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(self.doc.error(&path.field(field), format!("{path}.{field} holds a number too large for f32")))
            }
        };
        if let Some(matrix) = node.matrix {
            finite(&matrix, "matrix")?;
            return Ok(matrix);
        }
        let t = node.translation.unwrap_or([0.0; 3]);
        let q = node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r.0);
        let s = node.scale.unwrap_or([1.0; 3]);
        finite(&t, "translation")?;
        finite(&q, "rotation")?;
        finite(&s, "scale")?;
        // Exporters write quaternions rounded to a few digits: renormalise
        // rather than skew the mesh.
        let len = q.iter().map(|v| v * v).sum::<f32>().sqrt();
        if !(len > 0.0 && len.is_finite()) {
            return Err(self.doc.error(&path.field("rotation"), format!("{path}.rotation is not a unit quaternion")));
        }
        Ok(math::from_trs(t, q.map(|v| v / len), s))
    }

    /// Appends mesh `m`, transformed by `world`, to `out`.
    fn place(&mut self, out: &mut Vec<Group>, m: usize, world: &Mat4, referenced_at: &JsonPath) -> Result<(), Diagnostic> {
        if self.meshes.get(m).is_none() {
            let count = self.root.meshes.len();
            return Err(self.doc.error(referenced_at, format!("{referenced_at} refers to meshes[{m}], but the file has {count} meshes")));
        }
        let part = match self.meshes[m].take() {
            Some(part) => part,
            None => self.decode_mesh(m)?,
        };
        // Split by material, the parts together stay within the limits.
        let count = |groups: &[Group]| groups.iter().fold((0, 0), |(v, t), (_, m)| (v + m.positions.len(), t + m.triangle_count()));
        let ((v, t), (pv, pt)) = (count(out), count(&part));
        let placed = within_limits(v + pv, t + pt, self.doc, referenced_at, self.limits)
            .and_then(|()| part.iter().try_for_each(|(key, p)| extend(group(out, *key), p, world, self.doc, referenced_at, self.limits)));
        self.meshes[m] = Some(part);
        placed
    }

    fn decode_mesh(&self, m: usize) -> Result<Vec<Group>, Diagnostic> {
        let path = JsonPath::element("meshes", m);
        let mut out = Vec::new();
        for (p, primitive) in self.root.meshes[m].primitives.iter().enumerate() {
            let at = path.field("primitives").index(p);
            let part = self.decode_primitive(primitive, &at)?;
            let key = if self.split { primitive.material.map(|i| i.value()) } else { None };
            extend(group(&mut out, key), &part, &IDENTITY, self.doc, &at, self.limits)?;
        }
        Ok(out)
    }

    fn decode_primitive(&self, primitive: &Primitive, path: &JsonPath) -> Result<MeshData, Diagnostic> {
        let doc = self.doc;
        match primitive.mode {
            Checked::Valid(Mode::Triangles) => {}
            Checked::Valid(mode) => {
                return Err(doc.error(
                    &path.field("mode"),
                    format!("{path} has mode {} ({}); loupe draws only TRIANGLES (4)", mode.as_gl_enum(), mode_name(mode)),
                ));
            }
            Checked::Invalid => {
                return Err(doc.error(&path.field("mode"), format!("{path}.mode is not a glTF primitive mode (0 to 6)")));
            }
        }
        let attributes = path.field("attributes");
        let Some(&position) = primitive.attributes.get(&Checked::Valid(Semantic::Positions)) else {
            return Err(doc.error(&attributes, format!("{path} has no POSITION attribute")));
        };
        let position_at = attributes.key("POSITION");
        let positions = self.read_floats(position, &position_at, &VEC3_F32)?;
        let n = positions.len();
        // An optional per-vertex attribute, one element per position.
        let attribute =
            |semantic: Semantic, name: &'static str, what: &str| -> Result<Option<(JsonPath, json::Index<json::Accessor>)>, Diagnostic> {
                let Some(&accessor) = primitive.attributes.get(&Checked::Valid(semantic)) else {
                    return Ok(None);
                };
                let at = attributes.key(name);
                let count = self.root.accessors.get(accessor.value()).map_or(n, |a| a.count.0 as usize);
                if count != n {
                    return Err(doc.error(&at, format!("{path} has {count} {what} for {n} positions")));
                }
                Ok(Some((at, accessor)))
            };
        let normals = attribute(Semantic::Normals, "NORMAL", "normals")?.map(|(at, a)| self.read_floats(a, &at, &VEC3_F32)).transpose()?;
        let uvs = attribute(Semantic::TexCoords(0), "TEXCOORD_0", "texture coordinates")?
            .map(|(at, a)| self.read_texcoords(a, &at))
            .transpose()?;
        let tangents =
            attribute(Semantic::Tangents, "TANGENT", "tangents")?.map(|(at, a)| self.read_floats(a, &at, &VEC4_F32)).transpose()?;
        let indices = match primitive.indices {
            Some(accessor) => {
                let indices_at = path.field("indices");
                let (accessor_path, elements) = self.accessor(accessor, &indices_at, &INDICES)?;
                if elements.count > self.limits.triangles * 3 {
                    let (count, limit) = (elements.count, self.limits.triangles);
                    return Err(doc.error(&accessor_path, format!("{accessor_path} has {count} indices; the limit is {limit} triangles")));
                }
                let indices: Vec<u32> = elements
                    .iter()
                    .map(|e| match elements.component {
                        ComponentType::U8 => u32::from(e[0]),
                        ComponentType::U16 => u32::from(u16::from_le_bytes([e[0], e[1]])),
                        _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
                    })
                    .collect();
                if let Some((k, &bad)) = indices.iter().enumerate().find(|&(_, &i)| i as usize >= n) {
                    return Err(doc.error(
                        &indices_at,
                        format!("{path}: index {bad} (element {k} of its indices) is out of range: the primitive has {n} vertices"),
                    ));
                }
                indices
            }
            None => (0..n as u32).collect(),
        };
        if indices.len() % 3 != 0 {
            let what = if primitive.indices.is_some() { "indices" } else { "vertices and no indices" };
            return Err(doc.error(path, format!("{path} has {} {what}: TRIANGLES needs a multiple of 3", indices.len())));
        }
        let normals = normals.unwrap_or_else(|| smooth_normals(&positions, &indices));
        // Given tangents are kept (made unit and perpendicular to the
        // normal, as exporters round them); missing ones are generated.
        let (uvs, tangents) = match (uvs, tangents) {
            (uvs, Some(given)) => {
                let tangents = given.iter().zip(&normals).map(|(&t, &n)| tangents::given(t, n)).collect();
                (uvs.unwrap_or_else(|| vec![[0.0; 2]; n]), tangents)
            }
            (Some(uvs), None) => {
                let tangents = tangents::mikktspace(&positions, &normals, &uvs, &indices);
                (uvs, tangents)
            }
            (None, None) => (vec![[0.0; 2]; n], tangents::without_uvs(&normals)),
        };
        Ok(MeshData { positions, normals, uvs, tangents, indices })
    }

    /// The vertex-count cap on an attribute's accessor.
    fn check_vertex_count(&self, path: &JsonPath, count: usize) -> Result<(), Diagnostic> {
        if count > self.limits.vertices {
            let limit = self.limits.vertices;
            return Err(self.doc.error(path, format!("{path} has {count} vertices; the limit is {limit}")));
        }
        Ok(())
    }

    /// An accessor of `N` finite floats per element.
    fn read_floats<const N: usize>(
        &self,
        accessor: json::Index<json::Accessor>,
        used_at: &JsonPath,
        want: &Want,
    ) -> Result<Vec<[f32; N]>, Diagnostic> {
        let (path, elements) = self.accessor(accessor, used_at, want)?;
        self.check_vertex_count(&path, elements.count)?;
        self.floats_of(&path, &elements, used_at)
    }

    fn floats_of<const N: usize>(&self, path: &JsonPath, elements: &Elements, used_at: &JsonPath) -> Result<Vec<[f32; N]>, Diagnostic> {
        let mut out = Vec::with_capacity(elements.count);
        for (k, e) in elements.iter().enumerate() {
            let v: [f32; N] = std::array::from_fn(|c| f32::from_le_bytes([e[4 * c], e[4 * c + 1], e[4 * c + 2], e[4 * c + 3]]));
            if let Some(bad) = v.iter().find(|c| !c.is_finite()) {
                return Err(self
                    .doc
                    .error(path, format!("{path} (used as {used_at}) holds {bad} in element {k}: vertex data must be finite")));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// TEXCOORD_0: floats, or unsigned bytes or shorts that the accessor
    /// declares normalized (to 0..1), as glTF allows.
    fn read_texcoords(&self, accessor: json::Index<json::Accessor>, used_at: &JsonPath) -> Result<Vec<[f32; 2]>, Diagnostic> {
        let (path, elements) = self.accessor(accessor, used_at, &TEXCOORDS)?;
        self.check_vertex_count(&path, elements.count)?;
        let component = elements.component;
        if component == ComponentType::F32 {
            return self.floats_of(&path, &elements, used_at);
        }
        let unorm = |bytes: usize, max: f32| -> Vec<[f32; 2]> {
            let word = |e: &[u8], c: usize| e[c * bytes..][..bytes].iter().rev().fold(0u32, |w, &b| w << 8 | u32::from(b));
            elements.iter().map(|e| [0, 1].map(|c| word(e, c) as f32 / max)).collect()
        };
        if !self.root.accessors[accessor.value()].normalized {
            let name = component_name(component);
            return Err(self.doc.error(
                &path,
                format!("{path}, used as {used_at}, holds {name} that are not normalized: set \"normalized\": true, or store FLOAT"),
            ));
        }
        Ok(match component {
            ComponentType::U8 => unorm(1, 255.0),
            _ => unorm(2, 65535.0),
        })
    }

    /// The elements of an accessor used at `used_at`, checked against
    /// `want` and against the bytes really there.
    fn accessor(
        &self,
        index: json::Index<json::Accessor>,
        used_at: &JsonPath,
        want: &Want,
    ) -> Result<(JsonPath, Elements<'_>), Diagnostic> {
        let (doc, root) = (self.doc, self.root);
        let a = index.value();
        let Some(accessor) = root.accessors.get(a) else {
            let count = root.accessors.len();
            return Err(doc.error(used_at, format!("{used_at} refers to accessors[{a}], but the file has {count} accessors")));
        };
        let path = JsonPath::element("accessors", a);
        let component = match (accessor.type_, accessor.component_type) {
            (Checked::Valid(t), Checked::Valid(GenericComponentType(c))) if t == want.type_ && want.components.contains(&c) => c,
            (t, c) => {
                let found = match (t, c) {
                    (Checked::Valid(t), Checked::Valid(GenericComponentType(c))) => {
                        format!("{} of {}", type_name(t), component_name(c))
                    }
                    _ => "of an invalid type or componentType".to_owned(),
                };
                let wanted: Vec<&str> = want.components.iter().map(|&c| component_name(c)).collect();
                return Err(doc.error(
                    &path,
                    format!("{path}, used as {used_at}, is {found}; it must be {} of {}", type_name(want.type_), wanted.join(" or ")),
                ));
            }
        };
        if accessor.sparse.is_some() {
            return Err(doc.error(&path.field("sparse"), format!("{path} is sparse; loupe does not read sparse accessors")));
        }
        let Some(view_index) = accessor.buffer_view else {
            return Err(doc.error(&path, format!("{path} has no bufferView")));
        };
        let v = view_index.value();
        let Some(view) = root.buffer_views.get(v) else {
            let count = root.buffer_views.len();
            return Err(doc.error(&path.field("bufferView"), format!("{path} refers to bufferViews[{v}], but the file has {count}")));
        };
        let view_path = JsonPath::element("bufferViews", v);
        let b = view.buffer.value();
        let Some(buffer) = self.buffers.get(b) else {
            let count = self.buffers.len();
            return Err(doc.error(&view_path.field("buffer"), format!("{view_path} refers to buffers[{b}], but the file has {count}")));
        };
        let view_start = view.byte_offset.map_or(0, |o| o.0);
        let view_len = view.byte_length.0;
        if view_start.checked_add(view_len).is_none_or(|end| end > buffer.len() as u64) {
            return Err(doc.error(
                &view_path,
                format!(
                    "{view_path} covers bytes {view_start}..{} of buffers[{b}], which has {} bytes",
                    u128::from(view_start) + u128::from(view_len),
                    buffer.len()
                ),
            ));
        }
        let size = component.size() * want.type_.multiplicity();
        let stride = view.byte_stride.map_or(size, |s| s.0);
        if stride < size {
            return Err(doc.error(
                &view_path.field("byteStride"),
                format!("{view_path} has byteStride {stride}, less than the {size}-byte elements of {path}"),
            ));
        }
        let count = accessor.count.0;
        let start = accessor.byte_offset.map_or(0, |o| o.0);
        // The last element ends (count - 1) strides and one element in.
        let span = match count {
            0 => Some(0),
            _ => (count - 1).checked_mul(stride as u64).and_then(|s| s.checked_add(size as u64)),
        };
        let end = span.and_then(|span| span.checked_add(start));
        let Some(end) = end.filter(|&end| end <= view_len) else {
            return Err(doc.error(
                &path,
                format!(
                    "{path} reads {count} elements of {size} bytes every {stride} from byte {start} of {view_path}, past its byteLength {view_len}"
                ),
            ));
        };
        let bytes = &buffer[(view_start + start) as usize..(view_start + end) as usize];
        Ok((path, Elements { bytes, stride, size, count: count as usize, component }))
    }
}

/// Appends `part` transformed by `m` to `out`, within the limits.
fn extend(out: &mut MeshData, part: &MeshData, m: &Mat4, doc: &Doc, at: &JsonPath, limits: &Limits) -> Result<(), Diagnostic> {
    within_limits(out.positions.len() + part.positions.len(), out.triangle_count() + part.triangle_count(), doc, at, limits)?;
    let base = out.positions.len() as u32;
    let normal = NormalTransform::of(m);
    for &p in &part.positions {
        let q = math::transform_point(m, p);
        if !q.iter().all(|c| c.is_finite()) {
            return Err(doc.error(at, format!("{at}: the node transforms put vertices beyond the range of f32")));
        }
        out.positions.push(q);
    }
    let first_normal = out.normals.len();
    out.normals.extend(part.normals.iter().map(|&n| normal.apply(n)));
    out.uvs.extend_from_slice(&part.uvs);
    let columns = math::linear_columns(m);
    let normals = &out.normals[first_normal..];
    out.tangents.extend(part.tangents.iter().zip(normals).map(|(&t, &n)| tangents::transform(t, &columns, normal.mirrors, n)));
    for t in part.indices.chunks_exact(3) {
        // A mirroring transform turns counter-clockwise into clockwise.
        let [a, b, c] = if normal.mirrors { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] };
        out.indices.extend([a + base, b + base, c + base]);
    }
    Ok(())
}

/// An error unless a mesh of `vertices` and `triangles` is within the limits.
fn within_limits(vertices: usize, triangles: usize, doc: &Doc, at: &JsonPath, limits: &Limits) -> Result<(), Diagnostic> {
    if vertices > limits.vertices || triangles > limits.triangles {
        let (max_v, max_t) = (limits.vertices, limits.triangles);
        return Err(doc.error(
            at,
            format!("with {at} the mesh has {vertices} vertices and {triangles} triangles; the limits are {max_v} and {max_t}"),
        ));
    }
    Ok(())
}

/// Area-weighted vertex normals: each triangle adds its unnormalised
/// geometric normal (length = twice its area) to its three vertices.
fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut sums = vec![[0.0f32; 3]; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
        let n = math::cross(math::sub(b, a), math::sub(c, a));
        for &i in t {
            sums[i as usize] = math::add(sums[i as usize], n);
        }
    }
    sums.into_iter().map(math::normalize_or_up).collect()
}

fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

fn type_name(t: Type) -> &'static str {
    match t {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

fn component_name(c: ComponentType) -> &'static str {
    match c {
        ComponentType::I8 => "BYTE",
        ComponentType::U8 => "UNSIGNED_BYTE",
        ComponentType::I16 => "SHORT",
        ComponentType::U16 => "UNSIGNED_SHORT",
        ComponentType::U32 => "UNSIGNED_INT",
        ComponentType::F32 => "FLOAT",
    }
}
