//! Value checks after serde: ranges, NaN, references between tables, fields
//! that do not apply to a light's type. Each problem names a path in the
//! document (`lights[2].intensity`) and is located there through the spans
//! toml_edit keeps, so the user sees the exact value at fault.

use std::collections::BTreeSet;

use super::file::{self, LightType, Scale, Vec3};
use super::settings::Value;
use super::settings::{self, SETTINGS};
use super::*;

/// One step of a path into the TOML document.
#[derive(Debug, Clone)]
pub enum Seg {
    Key(&'static str),
    Index(usize),
}

struct Checker<'a> {
    display: &'a str,
    text: &'a str,
    doc: toml_edit::Document<&'a str>,
}

type Checked<T> = Result<T, Diagnostic>;

impl Checker<'_> {
    /// Where the value at `path` is written, when the document has a span
    /// for it.
    fn location(&self, path: &[Seg]) -> Option<Location> {
        self.located(span_of(self.doc.as_item(), path))
    }

    fn located(&self, span: Option<std::ops::Range<usize>>) -> Option<Location> {
        Some(LineIndex::new(self.text).location(self.display, self.text, span?))
    }

    fn error(&self, path: &[Seg], message: impl Into<String>) -> Diagnostic {
        self.error_at(&path_string(path), span_of(self.doc.as_item(), path), message)
    }

    /// An error about `path` at `span` (a key, where the key is the
    /// problem), or at the file's start when there is no span.
    fn error_at(&self, path: &str, span: Option<std::ops::Range<usize>>, message: impl Into<String>) -> Diagnostic {
        let d = Diagnostic::error(Code::Scene, format!("{path}: {}", message.into()));
        match self.located(span) {
            Some(at) => d.with_label(at, "here", true),
            None => d.at(Location::file_start(self.display)),
        }
    }

    /// Where `materials[i].params.NAME` is written (keys are the user's,
    /// so not a `Seg` path).
    fn param_location(&self, i: usize, name: &str) -> Option<Location> {
        let table = self.doc.get("materials")?.as_array_of_tables()?.get(i)?.get("params")?;
        let item = table.as_inline_table().and_then(|t| t.get(name)).or_else(|| table.as_table().and_then(|t| t.get(name)?.as_value()))?;
        self.located(item.span())
    }

    fn finite(&self, path: &[Seg], v: f32) -> Checked<f32> {
        if v.is_finite() {
            return Ok(v);
        }
        Err(match self.overflowed(path, v) {
            Some(written) => self.out_of_range(path, written, f32::MIN, f32::MAX),
            None => self.error(path, format!("must be a finite number, not {v}")),
        })
    }

    /// The number written at `path` when it is finite but `v`, the `f32`
    /// serde made of it, is not (`1e308`): too large, not infinite.
    fn overflowed(&self, path: &[Seg], v: f32) -> Option<f64> {
        if !v.is_infinite() {
            return None;
        }
        let written: f64 = self.text.get(span_of(self.doc.as_item(), path)?)?.trim().replace('_', "").parse().ok()?;
        written.is_finite().then_some(written)
    }

    fn out_of_range(&self, path: &[Seg], written: f64, lo: f32, hi: f32) -> Diagnostic {
        // The shortest decimal of each bound: 3.4028235e38, not the f64
        // nearest f32::MAX.
        let bound = |f: f32| settings::shown(f.to_string().parse().unwrap_or(f64::from(f)));
        let (lo, hi, written) = (bound(lo), bound(hi), settings::shown(written));
        self.error(path, format!("out of range: must be between {lo} and {hi}, not {written}"))
    }

    fn range(&self, path: &[Seg], v: f32, lo: f32, hi: f32) -> Checked<f32> {
        if let Some(written) = self.overflowed(path, v) {
            return Err(self.out_of_range(path, written, lo, hi));
        }
        self.finite(path, v)?;
        if (lo..=hi).contains(&v) { Ok(v) } else { Err(self.error(path, format!("must be between {lo} and {hi}, not {v}"))) }
    }

    fn positive(&self, path: &[Seg], v: f32) -> Checked<f32> {
        self.finite(path, v)?;
        if v > 0.0 { Ok(v) } else { Err(self.error(path, format!("must be greater than 0, not {v}"))) }
    }

    fn int(&self, path: &[Seg], v: i64, lo: i64, hi: i64) -> Checked<u32> {
        if (lo..=hi).contains(&v) { Ok(v as u32) } else { Err(self.error(path, format!("must be between {lo} and {hi}, not {v}"))) }
    }

    fn vec3(&self, path: &[Seg], v: Vec3) -> Checked<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.finite(&with(path, Seg::Index(i)), *c)?;
        }
        Ok(v)
    }

    fn non_negative(&self, path: &[Seg], v: f32) -> Checked<f32> {
        self.finite(path, v)?;
        if v < 0.0 { Err(self.error(path, format!("must not be negative, not {v}"))) } else { Ok(v) }
    }

    fn non_negative3(&self, path: &[Seg], v: Vec3) -> Checked<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.non_negative(&with(path, Seg::Index(i)), *c)?;
        }
        Ok(v)
    }

    fn unit01(&self, path: &[Seg], v: Vec3) -> Checked<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.range(&with(path, Seg::Index(i)), *c, 0.0, 1.0)?;
        }
        Ok(v)
    }

    fn direction(&self, path: &[Seg], v: Vec3) -> Checked<Vec3> {
        self.vec3(path, v)?;
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if len > 1e-6 { Ok(v.map(|c| c / len)) } else { Err(self.error(path, "must not be the zero vector")) }
    }

    /// Whether the file itself sets `s`.
    fn written(&self, s: &settings::Setting) -> bool {
        let (table, key) = s.split();
        self.doc.as_item().get(table).and_then(|t| t.get(key)).is_some()
    }

    fn required<T>(&self, path: &[Seg], v: Option<T>, why: &str) -> Checked<T> {
        v.ok_or_else(|| self.error(path, format!("is required {why}")))
    }
}

fn with(path: &[Seg], seg: Seg) -> Vec<Seg> {
    let mut p = path.to_vec();
    p.push(seg);
    p
}

fn path_string(path: &[Seg]) -> String {
    let mut s = String::new();
    for seg in path {
        match seg {
            Seg::Key(k) if s.is_empty() => s.push_str(k),
            Seg::Key(k) => {
                s.push('.');
                s.push_str(k);
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// The byte range of the value at `path`; for a missing key, the table it
/// belongs in (its first key), so "is required" points somewhere useful.
fn span_of(item: &toml_edit::Item, path: &[Seg]) -> Option<std::ops::Range<usize>> {
    use toml_edit::{Item, Value};
    let Some((first, rest)) = path.split_first() else {
        return match item {
            Item::Value(v) => v.span(),
            Item::ArrayOfTables(a) => a.span(),
            Item::Table(t) => t.iter().next().and_then(|(k, _)| t.key(k)).and_then(|k| k.span()),
            Item::None => None,
        };
    };
    let next: Option<Item> = match (item, first) {
        (Item::Table(t), Seg::Key(k)) => match t.get(k) {
            Some(v) => Some(v.clone()),
            None => return span_of(item, &[]),
        },
        (Item::ArrayOfTables(a), Seg::Index(i)) => a.get(*i).map(|t| Item::Table(t.clone())),
        (Item::Value(Value::Array(a)), Seg::Index(i)) => a.get(*i).map(|v| Item::Value(v.clone())),
        (Item::Value(Value::InlineTable(t)), Seg::Key(k)) => match t.get(k) {
            Some(v) => Some(Item::Value(v.clone())),
            None => return t.span(),
        },
        _ => None,
    };
    match next {
        Some(n) => span_of(&n, rest).or_else(|| span_of(item, &[])),
        None => span_of(item, &[]),
    }
}

pub fn scene(display: &str, text: &str, f: file::File) -> Result<Scene, Diagnostic> {
    let doc = toml_edit::Document::parse(text).map_err(|e| syntax_error(display, text, e.message(), e.span()))?;
    let c = Checker { display, text, doc };
    use Seg::{Index as I, Key as K};

    let width = c.int(&[K("output"), K("width")], f.output.width, 1, i64::from(MAX_SIDE))?;
    let height = c.int(&[K("output"), K("height")], f.output.height, 1, i64::from(MAX_SIDE))?;

    let cam = &f.camera;
    let cp = |k| [K("camera"), K(k)];
    c.vec3(&cp("position"), cam.position)?;
    c.vec3(&cp("target"), cam.target)?;
    c.direction(&cp("up"), cam.up)?;
    c.range(&cp("fov_deg"), cam.fov_deg, 1.0, 179.0)?;
    c.positive(&cp("near"), cam.near)?;
    c.positive(&cp("far"), cam.far)?;
    if cam.far <= cam.near {
        return Err(c.error(&cp("far"), format!("must be greater than camera.near ({})", cam.near)));
    }
    if cam.position == cam.target {
        return Err(c.error(&cp("target"), "must differ from camera.position"));
    }

    let mut names = BTreeSet::new();
    let mut materials = Vec::new();
    for (i, m) in f.materials.iter().enumerate() {
        let p = |k| [K("materials"), I(i), K(k)];
        if !names.insert(m.name.as_str()) {
            return Err(c.error(&p("name"), format!("a material named `{}` is already defined", m.name)));
        }
        let source = match &m.file {
            None => {
                if m.material.is_some() {
                    return Err(c.error(&p("material"), "applies to a material `file` only"));
                }
                if !m.params.is_empty() {
                    return Err(c.error(&p("params"), "applies to a material `file` only"));
                }
                MaterialSource::Shorthand {
                    base_color: c.unit01(&p("base_color"), m.base_color.unwrap_or([0.8; 3]))?,
                    metallic: c.range(&p("metallic"), m.metallic.unwrap_or(0.0), 0.0, 1.0)?,
                    roughness: c.range(&p("roughness"), m.roughness.unwrap_or(0.5), 0.0, 1.0)?,
                }
            }
            Some(file) => {
                for (key, set) in
                    [("base_color", m.base_color.is_some()), ("metallic", m.metallic.is_some()), ("roughness", m.roughness.is_some())]
                {
                    if set {
                        return Err(c.error(&p(key), "a material from a `file` takes its values from the file: set them in `params`"));
                    }
                }
                if file.trim().is_empty() {
                    return Err(c.error(&p("file"), "must name a material file (.mat)"));
                }
                let at = c.location(&p("file")).unwrap_or_else(|| Location::file_start(display));
                let params = m
                    .params
                    .iter()
                    .map(|(name, v)| {
                        let at = c.param_location(i, name).unwrap_or_else(|| at.clone());
                        (name.clone(), *v, at)
                    })
                    .collect();
                MaterialSource::File { file: file.clone(), material: m.material.clone(), params, at }
            }
        };
        materials.push(Material { name: m.name.clone(), source });
    }

    if f.objects.len() > MAX_OBJECTS {
        return Err(c.error(&[K("objects"), I(MAX_OBJECTS)], format!("at most {MAX_OBJECTS} objects")));
    }
    let mut objects = Vec::new();
    for (i, o) in f.objects.iter().enumerate() {
        let p = |k| [K("objects"), I(i), K(k)];
        let geometry = match (&o.shape, &o.mesh) {
            (Some(s), None) => {
                if crate::mesh::shape(s).is_none() {
                    return Err(c.error(&p("shape"), format!("unknown shape `{s}`; expected one of: {}", crate::mesh::SHAPES.join(", "))));
                }
                Geometry::Shape(s.clone())
            }
            (None, Some(m)) => {
                let at = c.location(&p("mesh")).unwrap_or_else(|| Location::file_start(display));
                Geometry::Mesh { file: m.clone(), at }
            }
            (Some(_), Some(_)) => return Err(c.error(&p("mesh"), "give either `shape` or `mesh`, not both")),
            (None, None) => return Err(c.error(&[K("objects"), I(i)], "needs a `shape` (sphere, cube, plane) or a `mesh` (a glTF file)")),
        };
        let (material, gltf_materials) = match (&o.material, &geometry) {
            (Some(name), _) => {
                let Some(material) = f.materials.iter().position(|m| &m.name == name) else {
                    let known: Vec<&str> = f.materials.iter().map(|m| m.name.as_str()).collect();
                    return Err(c.error(
                        &p("material"),
                        format!(
                            "no material named `{name}` (defined: {})",
                            if known.is_empty() { "none".into() } else { known.join(", ") }
                        ),
                    ));
                };
                (material, false)
            }
            // Its index is the instance `loaded` appends per glTF material.
            (None, Geometry::Mesh { .. }) => (0, true),
            (None, Geometry::Shape(_)) => {
                return Err(c.error(&[K("objects"), I(i)], "needs a `material`: only a glTF mesh brings materials of its own"));
            }
        };
        let scale = match o.scale {
            Scale::Uniform(s) => [s; 3],
            Scale::Axes(a) => a,
        };
        for (k, s) in scale.iter().enumerate() {
            let sp = if matches!(o.scale, Scale::Axes(_)) { with(&p("scale"), I(k)) } else { p("scale").to_vec() };
            c.finite(&sp, *s)?;
            if *s == 0.0 {
                return Err(c.error(&sp, "must not be zero"));
            }
        }
        objects.push(Object {
            name: o.name.clone().unwrap_or_else(|| format!("object{i}")),
            geometry,
            material,
            gltf_materials,
            position: c.vec3(&p("position"), o.position)?,
            rotation_deg: c.vec3(&p("rotation_deg"), o.rotation_deg)?,
            scale,
        });
    }

    if f.lights.len() > MAX_LIGHTS {
        return Err(c.error(&[K("lights"), I(MAX_LIGHTS)], format!("at most {MAX_LIGHTS} lights")));
    }
    let mut lights = Vec::new();
    for (i, l) in f.lights.iter().enumerate() {
        let p = |k| [K("lights"), I(i), K(k)];
        let kind_name = format!("for a {} light", format!("{:?}", l.kind).to_lowercase());
        let not_for = |k: &'static str, present: bool| -> Checked<()> {
            if present { Err(c.error(&p(k), format!("does not apply {kind_name}"))) } else { Ok(()) }
        };
        c.non_negative3(&p("color"), l.color)?;
        c.non_negative(&p("intensity"), l.intensity)?;
        let position = |c: &Checker| -> Checked<Vec3> { c.vec3(&p("position"), c.required(&p("position"), l.position, &kind_name)?) };
        let direction =
            |c: &Checker| -> Checked<Vec3> { c.direction(&p("direction"), c.required(&p("direction"), l.direction, &kind_name)?) };
        if l.kind != LightType::Spot {
            not_for("inner_deg", l.inner_deg.is_some())?;
            not_for("outer_deg", l.outer_deg.is_some())?;
        }
        if l.kind != LightType::Rect {
            not_for("size", l.size.is_some())?;
            not_for("two_sided", l.two_sided)?;
        }
        let kind = match l.kind {
            LightType::Directional => {
                not_for("position", l.position.is_some())?;
                LightKind::Directional { direction: direction(&c)? }
            }
            LightType::Point => {
                not_for("direction", l.direction.is_some())?;
                LightKind::Point { position: position(&c)? }
            }
            LightType::Spot => {
                let outer = c.range(&p("outer_deg"), l.outer_deg.unwrap_or(30.0), 0.1, 89.0)?;
                let inner = c.range(&p("inner_deg"), l.inner_deg.unwrap_or(outer * 0.8), 0.0, 89.0)?;
                if inner > outer {
                    return Err(c.error(&p("inner_deg"), format!("must not exceed outer_deg ({outer})")));
                }
                LightKind::Spot { position: position(&c)?, direction: direction(&c)?, inner_deg: inner, outer_deg: outer }
            }
            LightType::Rect => {
                let size = c.required(&p("size"), l.size, &kind_name)?;
                for (k, s) in size.iter().enumerate() {
                    c.positive(&with(&p("size"), I(k)), *s)?;
                }
                LightKind::Rect { position: position(&c)?, direction: direction(&c)?, size, two_sided: l.two_sided }
            }
        };
        lights.push(Light { kind, color: l.color, intensity: l.intensity, shadows: l.shadows });
    }

    if f.media.len() > MAX_MEDIA {
        return Err(c.error(&[K("media"), I(MAX_MEDIA)], format!("at most {MAX_MEDIA} media")));
    }
    let mut media = Vec::new();
    for (i, m) in f.media.iter().enumerate() {
        let p = |k| [K("media"), I(i), K(k)];
        if m.shapes.is_empty() {
            return Err(c.error(&p("shapes"), "needs at least one shape"));
        }
        if m.shapes.len() > MAX_SHAPES {
            return Err(c.error(&with(&p("shapes"), I(MAX_SHAPES)), format!("at most {MAX_SHAPES} shapes per medium")));
        }
        for (k, s) in m.shapes.iter().enumerate() {
            let sp = |key| [K("media"), I(i), K("shapes"), I(k), K(key)];
            match s {
                SdfShape::Sphere { center, radius } => {
                    c.vec3(&sp("center"), *center)?;
                    c.positive(&sp("radius"), *radius)?;
                }
                SdfShape::Box { center, half_extents } => {
                    c.vec3(&sp("center"), *center)?;
                    for (j, h) in half_extents.iter().enumerate() {
                        c.positive(&with(&sp("half_extents"), I(j)), *h)?;
                    }
                }
                SdfShape::Plane { normal, offset } => {
                    c.direction(&sp("normal"), *normal)?;
                    c.finite(&sp("offset"), *offset)?;
                }
            }
        }
        c.non_negative(&p("blend"), m.blend)?;
        c.positive(&p("edge"), m.edge)?;
        c.non_negative3(&p("absorption"), m.absorption)?;
        c.non_negative3(&p("scattering"), m.scattering)?;
        c.non_negative3(&p("emission"), m.emission)?;
        if let Some(n) = &m.noise {
            let np = |k| [K("media"), I(i), K("noise"), K(k)];
            c.int(&np("octaves"), n.octaves, 1, 8)?;
            c.positive(&np("frequency"), n.frequency)?;
            c.range(&np("amplitude"), n.amplitude, 0.0, 1.0)?;
        }
        let shapes = m
            .shapes
            .iter()
            .map(|s| match *s {
                SdfShape::Plane { normal, offset } => {
                    let len = (normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]).sqrt();
                    SdfShape::Plane { normal: normal.map(|x| x / len), offset }
                }
                ref other => other.clone(),
            })
            .collect();
        media.push(Medium {
            name: m.name.clone().unwrap_or_else(|| format!("medium{i}")),
            shapes,
            blend: m.blend,
            edge: m.edge,
            absorption: m.absorption,
            scattering: m.scattering,
            emission: m.emission,
            noise: m.noise.clone(),
        });
    }

    let env = &f.environment;
    let ep = |k| [K("environment"), K(k)];
    c.non_negative3(&ep("top"), env.top)?;
    c.non_negative3(&ep("bottom"), env.bottom)?;
    c.non_negative(&ep("intensity"), env.intensity)?;

    let denoiser = match &f.denoiser {
        Some(d) => {
            let path = [K("denoiser"), K("weights")];
            if d.weights.as_ref().is_some_and(|w| w.trim().is_empty()) {
                return Err(c.error(&path, "must name a weights file (.tza), or be left out for the bundled network"));
            }
            let at = c.location(&path).or_else(|| c.location(&path[..1])).unwrap_or_else(|| Location::file_start(display));
            let input_scale = d.input_scale.map(|s| c.positive(&[K("denoiser"), K("input_scale")], s)).transpose()?;
            Some(Denoiser { weights: d.weights.clone(), at, precision: d.precision, mode: d.mode, input_scale })
        }
        None => None,
    };

    let mut scene = Scene {
        width,
        height,
        camera: f.camera,
        materials,
        objects,
        lights,
        media,
        environment: f.environment,
        denoiser,
        post: Post::default(),
        quality: Quality::default(),
    };
    settings(&c, &mut scene)?;
    Ok(scene)
}

/// Reads `[post]` and `[quality]` through the settings table: an unknown key
/// is an error at the key, a value of the wrong type or out of range an
/// error at the value; then the ordered pairs are checked.
fn settings(c: &Checker, scene: &mut Scene) -> Checked<()> {
    // SETTINGS lists each table's entries together.
    let mut tables: Vec<&str> = SETTINGS.iter().map(|s| s.split().0).collect();
    tables.dedup();
    let root = c.doc.as_table();
    for name in tables {
        let Some((key, item)) = root.get_key_value(name) else { continue };
        let Some(table) = item.as_table_like() else {
            return Err(c.error_at(name, item.span().or_else(|| key.span()), "must be a table"));
        };
        for (k, item) in table.iter() {
            let path = format!("{name}.{k}");
            let Some(setting) = settings::find(&path) else {
                let known: Vec<&str> = SETTINGS.iter().filter(|s| s.split().0 == name).map(|s| s.split().1).collect();
                let span = table.get_key_value(k).and_then(|(key, _)| key.span());
                return Err(c.error_at(&path, span, format!("unknown key; expected one of: {}", known.join(", "))));
            };
            let value = match item.as_value() {
                Some(v) => plain(v).map_err(|found| setting.expected(found)),
                None => Err(setting.expected("a table")),
            };
            value.and_then(|v| setting.set(scene, &v)).map_err(|e| c.error_at(&path, item.span(), e))?;
        }
    }
    for (low, high) in settings::ORDERED {
        let (Some(lo), Some(hi)) = (settings::find(low), settings::find(high)) else { continue };
        let (Some(a), Some(b)) = (settings::number(&(lo.get)(scene)), settings::number(&(hi.get)(scene))) else { continue };
        if a < b {
            continue;
        }
        // At the upper value where the file has one, else at the lower.
        return Err(if c.written(hi) || !c.written(lo) {
            c.error(&segs(hi), format!("must be greater than {low} ({a})"))
        } else {
            c.error(&segs(lo), format!("must be less than {high} ({b})"))
        });
    }
    Ok(())
}

fn segs(s: &settings::Setting) -> [Seg; 2] {
    let (table, key) = s.split();
    [Seg::Key(table), Seg::Key(key)]
}

/// A TOML value as an override carries it; other kinds of value are
/// described for the error.
fn plain(v: &toml_edit::Value) -> Result<Value, &'static str> {
    use toml_edit::Value as T;
    match v {
        T::Boolean(b) => Ok(Value::Bool(*b.value())),
        T::Integer(i) => Ok(Value::Int(*i.value())),
        T::Float(f) => Ok(Value::Float(*f.value())),
        T::String(s) => Ok(Value::Text(s.value().clone())),
        T::Datetime(_) => Err("a date"),
        T::Array(_) => Err("an array"),
        T::InlineTable(_) => Err("a table"),
    }
}
