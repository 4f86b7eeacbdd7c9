//! The WGSL back end: a program's definitions → the `loupe::material`
//! module that the G-buffer, the lighting pass and the path tracer import.
//!
//! The module is built around one shape, the `Surface`: what `init` makes
//! of a material at a shading point, a short array of closures (the tree's
//! leaf slabs after its operators have weighted them, MDL's "init" step),
//! so `eval`, `pdf`, `sample`, `emission` and the raster's environment and
//! rect-light terms are loops over closures, the same for every material.
//! Only `init` differs per definition; it is dispatched by a `switch` over
//! the definitions the scene uses.
//!
//! A closure's core is `brdf.wgsl`'s slab (Lambert through Fresnel plus
//! GGX, `slab_cos`); a feature no definition uses (edge tint, haze, fuzz,
//! emission, absorption through a layer's top, transmission, a thin film)
//! leaves its fields and its code out of the module. The scene file's shorthand makes closures whose
//! F0 is `specular_f0` and F90 white, with weight 1, so its evaluation is
//! `brdf_cos` to the bit and the old scenes render what they did.

use std::fmt::Write;

pub use super::features::Features;
use super::tree::{BinOp, Builtin, Definition, ExprId, ExprKind, Field, NodeId, NodeKind, Type, Value};

/// The module's import path.
pub const IMPORT_PATH: &str = "loupe::material";
/// Where the module sits among the shader files, as diagnostics show it: it
/// is generated, never on disk.
pub const DISPLAY: &str = "generated/material.wgsl";
/// The path tracer's module: the same code for the full definitions (or the
/// simplified ones, `quality.path_simplified_materials`), under its own
/// name, so the raster's and the path tracer's pipelines each depend on
/// their own.
pub const PATH_IMPORT_PATH: &str = "loupe::material_path";
pub const PATH_DISPLAY: &str = "generated/material_path.wgsl";
/// The def the path tracer's solid-glass code compiles under, which a
/// module with that code implies for its importers
/// (`shader::compose::IMPLIES`).
pub const TRANSMISSION_DEF: &str = "MATERIAL_TRANSMISSION";
/// Where the module's two buffers, and its textures and their sampler, are
/// bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bindings {
    pub group: u32,
    pub params: u32,
    pub instances: u32,
    /// A `texture_2d_array<f32>`: one layer per texture of the scene.
    pub textures: u32,
    /// A filtering sampler (trilinear, repeating).
    pub sampler: u32,
}

impl Bindings {
    /// The renderer's: group 0, at bindings free in every pass that
    /// imports the module.
    pub const RENDERER: Bindings = Bindings { group: 0, params: 10, instances: 11, textures: 12, sampler: 13 };
}

/// The leaf slabs under `root`: the closures its `init` makes.
pub fn closures(d: &Definition, root: NodeId) -> usize {
    match &d.node(root).kind {
        NodeKind::Slab(_) => 1,
        NodeKind::Mix { a, b, .. } | NodeKind::Layer { top: a, base: b } | NodeKind::Add { a, b } => closures(d, *a) + closures(d, *b),
        NodeKind::Coverage { a, .. } => closures(d, *a),
    }
}

/// The `loupe::material` module for `definitions` (index = the definition
/// id instances name), its buffers bound at `bindings`.
pub fn wgsl(definitions: &[Definition], bindings: Bindings) -> String {
    module(definitions, bindings, IMPORT_PATH, &vec![false; definitions.len()])
}

/// `wgsl` under `import_path`, with `simplified[i]` the "simplified here"
/// flag of definition `i` (`material_simplified`, for the packer's header
/// bit).
pub fn module(definitions: &[Definition], bindings: Bindings, import_path: &str, simplified: &[bool]) -> String {
    let features = Features::of(definitions);
    let max = definitions.iter().map(|d| closures(d, d.root)).max().unwrap_or(1).max(1);
    let mut w = String::new();
    header(&mut w, definitions, features, max, bindings, import_path);
    simplified_flags(&mut w, simplified);
    closure_struct(&mut w, features);
    for (i, d) in definitions.iter().enumerate() {
        Init { d, w: &mut w, next: 0, temps: 0 }.function(i);
    }
    dispatch(&mut w, definitions.len(), features);
    if features.textures {
        w.push_str(TEXTURES);
    }
    if features.anisotropy {
        w.push_str(TANGENT);
    }
    w.push_str(&common(features));
    super::pack::write(&mut w, definitions, features);
    w
}

/// Per definition, whether the simplification changed it.
fn simplified_flags(w: &mut String, simplified: &[bool]) {
    let cases: Vec<String> = simplified.iter().enumerate().filter(|(_, s)| **s).map(|(i, _)| format!("{i}u")).collect();
    w.push_str("// Whether the simplification to the budget changed definition `d`.\nfn material_simplified(d: u32) -> bool {\n");
    if cases.is_empty() {
        w.push_str("    return false;\n}\n\n");
    } else {
        let _ = write!(
            w,
            "    switch d {{\n        case {}: {{\n            return true;\n        }}\n        default: {{\n            return false;\n        }}\n    }}\n}}\n\n",
            cases.join(", ")
        );
    }
}

fn header(w: &mut String, definitions: &[Definition], f: Features, max: usize, b: Bindings, import_path: &str) {
    w.push_str("// Generated by loupe's material compiler (server/src/material/back.rs)\n// from the scene's materials; never on disk. Definitions:\n");
    for (i, d) in definitions.iter().enumerate() {
        let _ = writeln!(w, "//   {i}: {} ({})", d.name, d.location);
    }
    let names = f.names();
    let _ = writeln!(w, "// Features: core{}.", names.iter().map(|n| format!(", {n}")).collect::<String>());
    let _ = writeln!(w, "#define_import_path {import_path}\n");
    w.push_str("#import loupe::brdf::{BrdfSample, PI, slab_cos, slab_pdf, slab_direction, specular_f0, f_schlick_edge, luminance_of}\n");
    w.push_str("#import loupe::pack::{pack_unorm3, unpack_unorm3, pack_sqrt3, unpack_sqrt3, unorm_encode, unorm_decode, pack_octahedral, unpack_octahedral, pack_rgb9e5, unpack_rgb9e5, pack_dither}\n");
    let radiance = if f.transmission { ", gradient_radiance" } else { "" };
    let _ = writeln!(w, "#import loupe::ambient::{{ambient_light, gradient_irradiance{radiance}}}");
    if f.fuzz {
        w.push_str("#import loupe::fuzz::fuzz_cos\n");
    }
    if f.anisotropy {
        w.push_str("#import loupe::brdf::{slab_cos_aniso, slab_pdf_aniso, slab_direction_aniso}\n");
    }
    if f.compensated {
        w.push_str("#import loupe::multiscatter::energy_compensation\n");
    }
    if f.transmission {
        w.push_str("#import loupe::btdf::{dielectric_cos, dielectric_pdf, dielectric_direction, fresnel_dielectric}\n");
        let _ = writeln!(w, "{}{TRANSMISSION_DEF}", crate::shader::compose::IMPLIES);
    }
    if f.thin_film {
        w.push_str("#import loupe::iridescence::{thin_film_fresnel, f0_to_ior, schlick_f0_of}\n");
    }
    w.push_str("#ifdef LIGHT_RECT\n#import loupe::ltc::ltc_rect\n#endif\n\n");
    let _ = writeln!(w, "// A float parameter in .x, a colour or vector in .xyz; each instance's block starts at its slot.");
    let _ = writeln!(w, "@group({}) @binding({}) var<storage, read> material_params: array<vec4<f32>>;", b.group, b.params);
    let _ = writeln!(w, "// Per instance: x = definition, y = first parameter slot, z = 1: energy compensation on.");
    let _ = writeln!(w, "@group({}) @binding({}) var<storage, read> material_instances: array<vec4<u32>>;\n", b.group, b.instances);
    if f.textures {
        let _ = writeln!(w, "// The scene's textures, one layer each (a texture param's value is its layer).");
        let _ = writeln!(w, "@group({}) @binding({}) var material_textures: texture_2d_array<f32>;", b.group, b.textures);
        let _ = writeln!(w, "@group({}) @binding({}) var material_sampler: sampler;\n", b.group, b.sampler);
    }
    let _ = writeln!(w, "const MATERIAL_CLOSURES: u32 = {max}u;\n");
}

fn closure_struct(w: &mut String, f: Features) {
    w.push_str("// A leaf slab at a shading point, weighted by the operators above it.\nstruct Closure {\n");
    w.push_str(
        "    weight: vec3<f32>,\n    base_color: vec3<f32>,\n    metallic: f32,\n    reflectance: vec3<f32>,\n    roughness: f32,\n",
    );
    if f.edge {
        w.push_str("    // F90, the grazing reflectance.\n    edge: vec3<f32>,\n");
    }
    if f.haze {
        w.push_str("    // x: the second lobe's share, y: its roughness.\n    haze: vec2<f32>,\n");
    }
    if f.haze && f.compensated {
        w.push_str("    // The second lobe's energy compensation over the first's (1: none).\n    haze_compensation: vec3<f32>,\n");
    }
    if f.fuzz {
        w.push_str("    // Colour times weight.\n    fuzz_color: vec3<f32>,\n    fuzz_roughness: f32,\n");
    }
    if f.emission {
        w.push_str("    emission: vec3<f32>,\n");
    }
    if f.absorption {
        w.push_str("    // What crosses the slab toward the viewer and back.\n    transmittance: vec3<f32>,\n");
    }
    if f.normal {
        w.push_str("    // The slab's shading normal; zero: the geometry's.\n    normal: vec3<f32>,\n");
    }
    if f.anisotropy {
        w.push_str("    // The GGX lobe's anisotropy (0: isotropic) and the direction of its\n    // longer roughness, world space.\n    anisotropy: f32,\n    tangent: vec3<f32>,\n");
    }
    if f.transmission {
        w.push_str("    // The share of the closure that is a transmitting dielectric, the\n    // relative IOR across its interface from v's side, 1: a thin wall,\n    // and the colour kept per unit of distance inside (once through a\n    // thin wall).\n    transmission: f32,\n    eta: f32,\n    thin: f32,\n    tint: vec3<f32>,\n");
    }
    if f.thin_film {
        w.push_str("    // The film's weight, and its Fresnel at the shading point's n·v,\n    // scaled as F0 is (specular weight and tint, energy compensation).\n    film: f32,\n    film_fresnel: vec3<f32>,\n");
    }
    w.push_str("}\n\nstruct Surface {\n    closures: array<Closure, MATERIAL_CLOSURES>,\n    count: u32,\n}\n\n");
    w.push_str("// A closure with every optional part neutral and weight 1.\nfn make_closure(base_color: vec3<f32>, metallic: f32, reflectance: vec3<f32>, roughness: f32) -> Closure {\n    var c: Closure;\n");
    w.push_str("    c.weight = vec3(1.0);\n    c.base_color = base_color;\n    c.metallic = metallic;\n    c.reflectance = reflectance;\n    c.roughness = roughness;\n");
    if f.edge {
        w.push_str("    c.edge = vec3(1.0);\n");
    }
    if f.absorption {
        w.push_str("    c.transmittance = vec3(1.0);\n");
    }
    if f.transmission {
        w.push_str("    c.transmission = 0.0;\n    c.eta = 1.5;\n    c.thin = 0.0;\n    c.tint = vec3(1.0);\n");
    }
    if f.haze && f.compensated {
        w.push_str("    c.haze_compensation = vec3(1.0);\n");
    }
    if f.thin_film {
        w.push_str("    c.film = 0.0;\n    c.film_fresnel = vec3(0.0);\n");
    }
    if f.anisotropy {
        w.push_str("    c.anisotropy = 0.0;\n    c.tangent = vec3(0.0);\n");
    }
    w.push_str("    return c;\n}\n\n");
}

/// One definition's `init`: straight-line code over its tree.
struct Init<'a> {
    d: &'a Definition,
    w: &'a mut String,
    /// The next closure slot.
    next: usize,
    /// Temporaries made so far (their names are numbered).
    temps: usize,
}

impl Init<'_> {
    fn function(mut self, index: usize) {
        let d = self.d;
        let _ = writeln!(self.w, "// {} ({})", d.name, d.location);
        let _ = writeln!(self.w, "fn material_{index}_init(slot: u32, n: vec3<f32>, v: vec3<f32>, p: MaterialPoint) -> Surface {{");
        self.w.push_str("    let n_v = max(dot(n, v), 1e-4);\n    var s: Surface;\n");
        let count = closures(d, d.root);
        let _ = writeln!(self.w, "    s.count = {count}u;");
        self.node(d.root);
        self.w.push_str("    return s;\n}\n\n");
    }

    fn temp(&mut self, prefix: &str) -> String {
        self.temps += 1;
        format!("{prefix}{}", self.temps)
    }

    /// Emits the closures of `id`; returns their slots.
    fn node(&mut self, id: NodeId) -> std::ops::Range<usize> {
        let d = self.d;
        match &d.node(id).kind {
            NodeKind::Slab(slab) => {
                let k = self.next;
                self.next += 1;
                self.slab(k, slab);
                k..k + 1
            }
            NodeKind::Mix { a, b, weight } => {
                let (ra, rb) = (self.node(*a), self.node(*b));
                let t = self.temp("mix");
                let _ = writeln!(self.w, "    let {t} = saturate({});", self.expr(*weight));
                self.scale(ra.clone(), &format!("(1.0 - {t})"));
                self.scale(rb.clone(), &t);
                ra.start..rb.end
            }
            NodeKind::Coverage { a, weight } => {
                let ra = self.node(*a);
                let t = self.temp("coverage");
                let _ = writeln!(self.w, "    let {t} = saturate({});", self.expr(*weight));
                self.scale(ra.clone(), &t);
                ra
            }
            NodeKind::Add { a, b } => {
                let ra = self.node(*a);
                let rb = self.node(*b);
                ra.start..rb.end
            }
            NodeKind::Layer { top, base } => {
                let (rt, rb) = (self.node(*top), self.node(*base));
                let (e, t, r, c) = (self.temp("e_top"), self.temp("t_top"), self.temp("r_top"), self.temp("c_top"));
                // What the top reflects, what crosses it (the uncovered part
                // crosses whole) and its mean roughness, by its weights.
                let _ = writeln!(self.w, "    var {e} = vec3(0.0);\n    var {t} = vec3(0.0);\n    var {r} = 0.0;\n    var {c} = 0.0;");
                for k in rt.clone() {
                    let _ = writeln!(
                        self.w,
                        "    {e} += s.closures[{k}].weight * closure_albedo(s.closures[{k}], n_v);\n    {t} += s.closures[{k}].weight * closure_transmittance(s.closures[{k}]);\n    {r} += luminance_of(s.closures[{k}].weight) * s.closures[{k}].roughness;\n    {c} += luminance_of(s.closures[{k}].weight);"
                    );
                }
                let _ = writeln!(self.w, "    {t} += vec3(max(1.0 - {c}, 0.0));\n    {r} /= max({c}, 1e-6);");
                for k in rb.clone() {
                    // f = f_top + (1 - E_top) T f_base; the base's lobes
                    // widen by the top's roughness (α² add).
                    let _ = writeln!(
                        self.w,
                        "    s.closures[{k}].weight *= saturate(vec3(1.0) - {e}) * {t};\n    s.closures[{k}].roughness = min(pow(pow(s.closures[{k}].roughness, 4.0) + pow({r}, 4.0), 0.25), 1.0);"
                    );
                }
                rt.start..rb.end
            }
        }
    }

    fn scale(&mut self, slots: std::ops::Range<usize>, by: &str) {
        for k in slots {
            let _ = writeln!(self.w, "    s.closures[{k}].weight *= {by};");
        }
    }

    fn field(&self, slab: &super::tree::Slab, f: Field) -> String {
        let text = match slab.get(f) {
            Some(e) => self.expr(e),
            None => value(f.default()),
        };
        match (f.ty(), slab.get(f).map(|e| self.d.expr(e).ty)) {
            (Type::Color, Some(Type::Float)) => format!("vec3<f32>({text})"),
            _ => text,
        }
    }

    fn slab(&mut self, k: usize, slab: &super::tree::Slab) {
        let base = self.field(slab, Field::BaseColor);
        let metallic = self.field(slab, Field::BaseMetalness);
        let roughness = self.field(slab, Field::SpecularRoughness);
        let _ = writeln!(self.w, "    {{\n        let base_color = saturate({base});\n        let metallic = saturate({metallic});");
        // Without an IOR or tint of its own, F0 is the shorthand's, to the bit.
        let f0 = if slab.get(Field::SpecularIor).is_none() && slab.get(Field::SpecularColor).is_none() {
            "specular_f0(base_color, metallic)".to_owned()
        } else {
            let ior = self.field(slab, Field::SpecularIor);
            let tint = self.field(slab, Field::SpecularColor);
            format!("mix(ior_reflectance(max({ior}, 1.0)) * saturate({tint}), base_color, metallic)")
        };
        let _ = writeln!(self.w, "        var c = make_closure(base_color, metallic, {f0}, saturate({roughness}));");
        let set = |f: Field| slab.get(f).is_some();
        if set(Field::SpecularEdgeColor) || set(Field::SpecularWeight) {
            let edge = self.field(slab, Field::SpecularEdgeColor);
            let weight = self.field(slab, Field::SpecularWeight);
            let _ = writeln!(
                self.w,
                "        let specular_weight = saturate({weight});\n        c.edge = saturate({edge}) * specular_weight;\n        c.reflectance *= specular_weight;"
            );
        }
        if set(Field::HazeWeight) {
            let (hw, hr) = (self.field(slab, Field::HazeWeight), self.field(slab, Field::HazeRoughness));
            let _ = writeln!(self.w, "        c.haze = vec2(saturate({hw}), saturate({hr}));");
        }
        if set(Field::FuzzWeight) {
            let (fw, fc, fr) =
                (self.field(slab, Field::FuzzWeight), self.field(slab, Field::FuzzColor), self.field(slab, Field::FuzzRoughness));
            let _ = writeln!(self.w, "        c.fuzz_color = saturate({fw}) * saturate({fc});\n        c.fuzz_roughness = saturate({fr});");
        }
        if set(Field::EmissionLuminance) {
            let (ec, el) = (self.field(slab, Field::EmissionColor), self.field(slab, Field::EmissionLuminance));
            let _ = writeln!(self.w, "        c.emission = max({ec}, vec3(0.0)) * max({el}, 0.0);");
        }
        if set(Field::Thickness) && (set(Field::TransmissionColor) || set(Field::MeanFreePath)) {
            let (tc, th) = (self.medium(slab), self.field(slab, Field::Thickness));
            // Down to the base and back up, along the view's slant.
            let _ = writeln!(self.w, "        c.transmittance = pow({tc}, vec3(2.0 * max({th}, 0.0) / n_v));");
        }
        if set(Field::Normal) {
            let normal = self.field(slab, Field::Normal);
            let _ = writeln!(self.w, "        c.normal = normalize({normal});");
        }
        if set(Field::SpecularAnisotropy) {
            let (a, turns) = (self.field(slab, Field::SpecularAnisotropy), self.field(slab, Field::SpecularRotation));
            // Where the point has no tangent the lobe stays isotropic.
            let _ = writeln!(
                self.w,
                "        c.tangent = material_tangent(n, p.tangent, {turns});\n        c.anisotropy = select(0.0, saturate({a}), dot(c.tangent, c.tangent) > 0.0);"
            );
        }
        if set(Field::TransmissionWeight) {
            let (tw, ior) = (self.field(slab, Field::TransmissionWeight), self.field(slab, Field::SpecularIor));
            let (thin, tc) = (self.field(slab, Field::ThinWalled), self.medium(slab));
            // Metal does not transmit; an IOR of 1 would make refraction's
            // half vector undefined (v + η l = 0), so η stays above it.
            let _ = writeln!(
                self.w,
                "        c.transmission = saturate({tw}) * (1.0 - metallic);\n        c.eta = max({ior}, 1.01);\n        c.thin = select(0.0, 1.0, {thin} > 0.5);\n        c.tint = {tc};"
            );
        }
        if set(Field::ThinFilmWeight) {
            let (fw, ft, fi) =
                (self.field(slab, Field::ThinFilmWeight), self.field(slab, Field::ThinFilmThickness), self.field(slab, Field::ThinFilmIor));
            let (ior, tint, weight) =
                (self.field(slab, Field::SpecularIor), self.field(slab, Field::SpecularColor), self.field(slab, Field::SpecularWeight));
            // The base under the film: the dielectric's IOR, a metal's
            // from its colour (its F0); the specular weight and the
            // dielectric's tint scale the film's Fresnel as they scale F0.
            // The spectral sum, once per shading point at n·v, serves
            // every light and direction there (as glTF's reference viewer
            // does): taken per light and lobe, it took lavapipe minutes
            // to compile the library scene's passes.
            let _ = writeln!(
                self.w,
                "        c.film = saturate({fw});\n        let film_base = mix(vec3(max({ior}, 1.0)), f0_to_ior(base_color), metallic);\n        c.film_fresnel = mix(saturate({tint}), vec3(1.0), metallic) * saturate({weight}) * thin_film_fresnel(n_v, max({ft}, 0.0), max({fi}, 1.0), film_base);"
            );
        }
        let _ = writeln!(self.w, "        s.closures[{k}] = c;\n    }}");
    }

    /// The colour the slab's medium keeps over one unit of distance: from
    /// its mean free path when set, else its transmission colour.
    fn medium(&self, slab: &super::tree::Slab) -> String {
        match slab.get(Field::MeanFreePath) {
            Some(_) => format!("exp(-1.0 / max({}, vec3(1e-6)))", self.field(slab, Field::MeanFreePath)),
            None => format!("saturate({})", self.field(slab, Field::TransmissionColor)),
        }
    }

    fn expr(&self, id: ExprId) -> String {
        let d = self.d;
        let e = d.expr(id);
        match &e.kind {
            ExprKind::Const(v) => value(*v),
            ExprKind::Param(i) => {
                let swizzle = if matches!(d.params[*i as usize].ty, Type::Float | Type::Texture) { "x" } else { "xyz" };
                format!("material_params[slot + {i}u].{swizzle}")
            }
            ExprKind::Neg(a) => format!("(-{})", self.expr(*a)),
            ExprKind::Binary(op, a, b) => {
                let op = match op {
                    BinOp::Add => "+",
                    BinOp::Sub => "-",
                    BinOp::Mul => "*",
                    BinOp::Div => "/",
                };
                format!("({} {op} {})", self.expr(*a), self.expr(*b))
            }
            ExprKind::Call(f, args) => {
                // Floats among colour arguments are splatted: WGSL's
                // built-ins take one type.
                let splat = e.ty != Type::Float
                    && !matches!(f, Builtin::Rgb | Builtin::Grey | Builtin::TransmittanceToMfp | Builtin::Sample | Builtin::NormalMap);
                let args: Vec<String> = args
                    .iter()
                    .map(|a| {
                        let text = self.expr(*a);
                        if splat && d.expr(*a).ty == Type::Float { format!("vec3<f32>({text})") } else { text }
                    })
                    .collect();
                call(*f, &args)
            }
        }
    }
}

fn call(f: Builtin, a: &[String]) -> String {
    let all = a.join(", ");
    match f {
        Builtin::Rgb => format!("vec3<f32>({all})"),
        Builtin::Grey => format!("vec3<f32>({all})"),
        Builtin::Lerp => format!("mix({all})"),
        Builtin::Luminance => format!("luminance_of({all})"),
        Builtin::Srgb => format!("srgb_to_linear({all})"),
        Builtin::IorToF0 => format!("ior_reflectance({all})"),
        Builtin::TransmittanceToMfp => format!("transmittance_to_mfp({all})"),
        // A texture argument is its param's layer (`.x` of the slot).
        Builtin::Sample => format!("material_texel({all}, p).rgb"),
        Builtin::NormalMap => format!("material_normal_map(material_texel({}, p).rgb, {}, n, p.tangent)", a[0], a[1]),
        Builtin::Clamp | Builtin::Saturate | Builtin::Min | Builtin::Max | Builtin::Pow | Builtin::Sqrt | Builtin::Abs => {
            format!("{}({all})", f.name())
        }
    }
}

/// A WGSL literal of `v`: Rust's shortest round-trip form, which WGSL
/// reads back to the same f32.
fn value(v: Value) -> String {
    let f = |x: f32| {
        let s = format!("{x:?}");
        if x < 0.0 { format!("({s})") } else { s }
    };
    match v {
        Value::Float(x) => f(x),
        Value::Vec3([r, g, b]) => format!("vec3<f32>({}, {}, {})", f(r), f(g), f(b)),
        // Lowering lets only params reach `sample` and `normal_map`.
        Value::Texture(_) => unreachable!("a texture is never a constant in the tree"),
    }
}

fn dispatch(w: &mut String, count: usize, f: Features) {
    w.push_str(POINT);
    // `material_surface_at` stops before the energy compensation: the
    // G-buffer packs that surface and the unpacking compensates at the
    // lighting's n·v (`pack.rs`), so F90 stays the grey the core word holds.
    w.push_str("// The surface of `instance` at a point with normal `n`, seen from `v`.\nfn material_init_at(instance: u32, n: vec3<f32>, v: vec3<f32>, p: MaterialPoint) -> Surface {\n    var s = material_surface_at(instance, n, v, p);\n");
    if f.compensated {
        w.push_str("    if material_instances[instance].z != 0u {\n        s = material_compensate(s, max(dot(n, v), 1e-4));\n    }\n");
    }
    w.push_str("    return s;\n}\n\n");
    w.push_str("// `material_init_at` before the energy compensation.\nfn material_surface_at(instance: u32, n: vec3<f32>, v: vec3<f32>, p: MaterialPoint) -> Surface {\n");
    w.push_str("    let header = material_instances[instance];\n    var s: Surface;\n    switch header.x {\n");
    for i in 1..count {
        let _ = writeln!(w, "        case {i}u: {{ s = material_{i}_init(header.y, n, v, p); }}");
    }
    // A scene without materials (media alone) still links: no closures.
    let fallback = if count == 0 { "" } else { "s = material_0_init(header.y, n, v, p);" };
    let _ = writeln!(w, "        default: {{ {fallback} }}\n    }}");
    w.push_str("    return s;\n}\n\n");
    if f.compensated {
        // Once, after the operators, for every closure: one copy of the
        // fit in the module, not one per slab (with one per slab,
        // lavapipe's pipeline compiles took four times as long).
        w.push_str("// Multiple-scattering compensation of every closure's lobes at n·v.\nfn material_compensate(surface: Surface, n_v: f32) -> Surface {\n    var s = surface;\n    for (var k = 0u; k < s.count; k++) {\n        // Turquin's factor scales the whole lobe: F0 and F90 alike.\n");
        let factor = "energy_compensation(s.closures[k].reflectance, n_v, s.closures[k].roughness)";
        if f.anisotropy {
            // The isotropic table misjudges a stretched lobe's loss (it
            // returned 1.02 of the light at n·v 0.1 for the library's
            // white brushed metal): such a lobe is left uncompensated.
            let _ = writeln!(w, "        let e = select({factor}, vec3(1.0), s.closures[k].anisotropy > 0.0);");
        } else {
            let _ = writeln!(w, "        let e = {factor};");
        }
        if f.haze {
            // The haze lobe loses what GGX loses at its own roughness:
            // the first lobe's factor on it would leave a white hazy
            // metal 9 % dark head-on and 4 % over 1 at grazing views.
            w.push_str("        s.closures[k].haze_compensation = energy_compensation(s.closures[k].reflectance, n_v, s.closures[k].haze.y) / e;\n");
        }
        if f.thin_film {
            w.push_str("        s.closures[k].film_fresnel *= e;\n");
        }
        w.push_str("        s.closures[k].reflectance *= e;\n        s.closures[k].edge *= e;\n    }\n    return s;\n}\n\n");
    }
    w.push_str("// `material_init_at` where no UV is known: textures read their corner texel.\nfn material_init(instance: u32, n: vec3<f32>, v: vec3<f32>) -> Surface {\n    return material_init_at(instance, n, v, material_point(vec2(0.0), vec4(0.0)));\n}\n\n");
}

/// Where a material is evaluated, beyond its normal: what textures read.
const POINT: &str = "// Where a material is evaluated: the UV, its screen-space derivatives
// (zero: the finest mip level) and the tangent (xyz, w: the bitangent's sign;
// zero: none, so normal maps are flat).
struct MaterialPoint {
    uv: vec2<f32>,
    duv_dx: vec2<f32>,
    duv_dy: vec2<f32>,
    tangent: vec4<f32>,
}

fn material_point(uv: vec2<f32>, tangent: vec4<f32>) -> MaterialPoint {
    return MaterialPoint(uv, vec2(0.0), vec2(0.0), tangent);
}

";

/// Texture reads: explicit gradients, so they work in any control flow
/// and any stage (the path tracer is a compute pass).
const TEXTURES: &str = "fn material_texel(layer: f32, p: MaterialPoint) -> vec4<f32> {
    return textureSampleGrad(material_textures, material_sampler, p.uv, i32(layer), p.duv_dx, p.duv_dy);
}

// A tangent-space normal map's texel (rgb in [0, 1]) as a world normal
// about n, its tilt scaled by `strength`.
fn material_normal_map(texel: vec3<f32>, strength: f32, n: vec3<f32>, tangent: vec4<f32>) -> vec3<f32> {
    let m = texel * 2.0 - 1.0;
    // The tangent made perpendicular to the shading normal.
    let t = tangent.xyz - n * dot(n, tangent.xyz);
    if dot(t, t) < 1e-12 {
        return n;
    }
    let tn = normalize(t);
    let b = cross(n, tn) * select(1.0, -1.0, tangent.w < 0.0);
    return normalize((tn * m.x + b * m.y) * strength + n * max(m.z, 1e-4));
}

";

/// The direction an anisotropic slab's `specular_rotation` names.
const TANGENT: &str = "// The direction `turns` of a turn from the surface's tangent toward its
// bitangent (cross(n, t) · w, glTF's), in the plane of n; zero where the
// point has no tangent.
fn material_tangent(n: vec3<f32>, tangent: vec4<f32>, turns: f32) -> vec3<f32> {
    let t = tangent.xyz - n * dot(n, tangent.xyz);
    if dot(t, t) < 1e-12 {
        return vec3(0.0);
    }
    let tn = normalize(t);
    let b = cross(n, tn) * select(1.0, -1.0, tangent.w < 0.0);
    let angle = 2.0 * PI * turns;
    return tn * cos(angle) + b * sin(angle);
}

";

/// The per-closure loops: the same text for every program, with the
/// optional parts switched by `f`.
fn common(f: Features) -> String {
    let f90 = if f.edge { "c.edge" } else { "vec3(1.0)" };
    // The haze lobe's F0 and F90, compensated at its own roughness.
    let (haze_f0, haze_f90) =
        if f.compensated { ("c.reflectance * c.haze_compensation", "c.edge * c.haze_compensation") } else { ("c.reflectance", f90) };
    let mut w = String::new();
    w.push_str(HELPERS);
    // Directional albedo of one closure toward v, for layering and for
    // choosing which closure to sample.
    let _ = writeln!(
        w,
        "fn closure_albedo(c: Closure, n_v: f32) -> vec3<f32> {{\n    let fr = f_schlick_edge(c.reflectance, {f90}, n_v);\n    var e = fr + (1.0 - c.metallic) * c.base_color * (vec3(1.0) - fr);"
    );
    if f.thin_film {
        w.push_str(
            "    let film = c.film_fresnel;\n    e = mix(e, film + (1.0 - c.metallic) * c.base_color * (vec3(1.0) - film), c.film);\n",
        );
    }
    if f.transmission {
        w.push_str("    // The transmitting share reflects only what its interface does.\n    e = mix(e, vec3(fresnel_dielectric(n_v, c.eta)), c.transmission);\n");
    }
    if f.fuzz {
        w.push_str("    e = e * (1.0 - max3(c.fuzz_color)) + c.fuzz_color;\n");
    }
    w.push_str("    return min(e, vec3(1.0));\n}\n\n");
    if f.thin_film {
        w.push_str(FILM);
    }
    let t = if f.absorption { "c.transmittance" } else { "vec3(1.0)" };
    let _ = writeln!(w, "fn closure_transmittance(c: Closure) -> vec3<f32> {{\n    return {t};\n}}\n");

    // With normals of their own, closures shade about theirs.
    let (ng, own) = if f.normal { ("n_geometry", "    let n = closure_normal(c, n_geometry);\n") } else { ("n", "") };
    if f.normal {
        w.push_str("fn closure_normal(c: Closure, n: vec3<f32>) -> vec3<f32> {\n    return select(n, c.normal, dot(c.normal, c.normal) > 0.0);\n}\n\n");
    }
    // A film's Fresnel is constant at the point and Schlick's is linear in
    // F0 and F90, so one lobe with both mixed toward the film's is the
    // mix of the bare lobe and the film's: one GGX, not two.
    let (film, lobe_f0, lobe_f90) = if f.thin_film {
        (
            format!("    let f0 = mix(c.reflectance, c.film_fresnel, c.film);\n    let f90 = mix({f90}, c.film_fresnel, c.film);\n"),
            "f0",
            "f90",
        )
    } else {
        (String::new(), "c.reflectance", f90)
    };
    let _ = write!(
        w,
        "// BSDF × cosine of one closure, without its weight.\nfn closure_cos(c: Closure, {ng}: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {{\n{own}{film}{}",
        lobe(
            f,
            "var f",
            &format!("slab_cos(n, v, l, c.base_color, c.metallic, {lobe_f0}, {lobe_f90}, c.roughness)"),
            &format!("slab_cos_aniso(n, c.tangent, v, l, c.base_color, c.metallic, {lobe_f0}, {lobe_f90}, c.roughness, c.anisotropy)"),
        )
    );
    if f.haze {
        let _ = writeln!(w, "    f = mix(f, slab_cos(n, v, l, c.base_color, c.metallic, {haze_f0}, {haze_f90}, c.haze.y), c.haze.x);");
    }
    if f.transmission {
        w.push_str("    f = mix(f, dielectric_cos(n, v, l, c.eta, c.roughness, c.thin, c.tint), c.transmission);\n");
    }
    if f.fuzz {
        w.push_str("    f = f * (1.0 - max3(c.fuzz_color)) + c.fuzz_color * fuzz_cos(n, v, l, c.fuzz_roughness);\n");
    }
    w.push_str("    return f;\n}\n\n");

    // The F0 the lobe choice reads: with a film, the Schlick F0 that
    // matches its Fresnel at n·v.
    let (f0, own) = if f.thin_film {
        ("f0", format!("{own}    let f0 = mix(c.reflectance, closure_film_f0(c, max(dot(n, v), 1e-4)), c.film);\n"))
    } else {
        ("c.reflectance", own.to_owned())
    };
    let _ = write!(
        w,
        "// The pdf of `closure_direction`'s directions.\nfn closure_pdf(c: Closure, {ng}: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> f32 {{\n{own}{}",
        lobe(
            f,
            "var p",
            &format!("slab_pdf(n, v, l, c.base_color, c.metallic, {f0}, c.roughness)"),
            &format!("slab_pdf_aniso(n, c.tangent, v, l, c.base_color, c.metallic, {f0}, c.roughness, c.anisotropy)"),
        )
    );
    if f.haze {
        let _ = writeln!(w, "    p = mix(p, slab_pdf(n, v, l, c.base_color, c.metallic, {f0}, c.haze.y), c.haze.x);");
    }
    if f.transmission {
        w.push_str("    p = mix(p, dielectric_pdf(n, v, l, c.eta, c.roughness, c.thin), c.transmission);\n");
    }
    if f.fuzz {
        w.push_str("    p = mix(p, max(dot(n, l), 0.0) / PI, fuzz_share(c));\n");
    }
    w.push_str("    return p;\n}\n\n");

    let _ = write!(
        w,
        "// A direction from one closure; u.x picks the lobe, u.yz place it.\nfn closure_direction(c: Closure, {ng}: vec3<f32>, v: vec3<f32>, u: vec3<f32>) -> vec3<f32> {{\n{own}    var x = u.x;\n    var roughness = c.roughness;\n"
    );
    if f.fuzz {
        w.push_str("    let q = fuzz_share(c);\n    if x < q {\n        return cosine_about(n, u.yz);\n    }\n    x = min((x - q) / max(1.0 - q, 1e-8), 0.99999994);\n");
    }
    if f.transmission {
        w.push_str("    if x < c.transmission {\n        return dielectric_direction(n, v, vec3(x / c.transmission, u.yz), c.eta, c.roughness, c.thin);\n    }\n    x = min((x - c.transmission) / max(1.0 - c.transmission, 1e-8), 0.99999994);\n");
    }
    if f.anisotropy {
        // The haze lobe is isotropic: drawing it draws no stretched lobe.
        let binding = if f.haze { "var" } else { "let" };
        let _ = writeln!(w, "    {binding} anisotropy = c.anisotropy;");
    }
    if f.haze {
        let isotropic = if f.anisotropy { "        anisotropy = 0.0;\n" } else { "" };
        let _ = write!(w, "    if x < c.haze.x {{\n{isotropic}");
        w.push_str("        roughness = c.haze.y;\n        x = x / c.haze.x;\n    } else {\n        x = (x - c.haze.x) / max(1.0 - c.haze.x, 1e-8);\n    }\n    x = min(x, 0.99999994);\n");
    }
    let reflected = lobe(
        f,
        "let l",
        &format!("slab_direction(n, v, vec3(x, u.yz), c.base_color, c.metallic, {f0}, roughness)"),
        &format!("slab_direction_aniso(n, c.tangent, v, vec3(x, u.yz), c.base_color, c.metallic, {f0}, roughness, anisotropy)"),
    );
    if f.transmission {
        // Below the surface only the transmitting lobe's pdf counts: a
        // reflection drawn below must end the path, not pass for one.
        let _ = write!(w, "{reflected}    return select(vec3(0.0), l, dot(n, l) > 0.0);\n}}\n\n");
    } else if f.anisotropy {
        let _ = write!(w, "{reflected}    return l;\n}}\n\n");
    } else {
        let _ = write!(w, "    return slab_direction(n, v, vec3(x, u.yz), c.base_color, c.metallic, {f0}, roughness);\n}}\n\n");
    }
    if f.fuzz {
        w.push_str("fn fuzz_share(c: Closure) -> f32 {\n    return max3(c.fuzz_color) * 0.5;\n}\n\n");
        w.push_str("fn cosine_about(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {\n    let s = select(-1.0, 1.0, n.z >= 0.0);\n    let a = -1.0 / (s + n.z);\n    let b = n.x * n.y * a;\n    let t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);\n    let bt = vec3(b, s + n.y * n.y * a, -n.y);\n    let r = sqrt(u.x);\n    let phi = 2.0 * PI * u.y;\n    return t * (r * cos(phi)) + bt * (r * sin(phi)) + n * sqrt(max(1.0 - u.x, 0.0));\n}\n\n");
    }

    w.push_str(LOOPS);
    if f.transmission {
        w.push_str(TRANSMISSION);
    }
    let emission = if f.emission { "        e += s.closures[k].weight * s.closures[k].emission;\n" } else { "" };
    let _ = writeln!(
        w,
        "// Radiance the surface emits toward v.\nfn material_emission(s: Surface) -> vec3<f32> {{\n    var e = vec3(0.0);\n    for (var k = 0u; k < s.count; k++) {{\n{emission}    }}\n    return e;\n}}\n"
    );

    // The raster's environment light: the split sum per closure.
    w.push_str("// Light from the environment's gradient (`loupe::ambient`), closure by closure.\nfn material_ambient(s: Surface, n: vec3<f32>, v: vec3<f32>, top: vec3<f32>, bottom: vec3<f32>, dfg: texture_2d<f32>) -> vec3<f32> {\n    var e = vec3(0.0);\n    for (var k = 0u; k < s.count; k++) {\n        let c = s.closures[k];\n");
    if f.normal {
        w.push_str("        let n = closure_normal(c, n);\n");
    }
    w.push_str("        var a = ambient_light(top, bottom, n, v, c.base_color, c.metallic, c.reflectance, c.roughness, dfg);\n");
    if f.haze {
        let _ = writeln!(
            w,
            "        a = mix(a, ambient_light(top, bottom, n, v, c.base_color, c.metallic, {haze_f0}, c.haze.y, dfg), c.haze.x);"
        );
    }
    if f.thin_film {
        // The split sum with the film's Fresnel at n·v as Schlick's F0.
        w.push_str("        a = mix(a, ambient_light(top, bottom, n, v, c.base_color, c.metallic, closure_film_f0(c, max(dot(n, v), 1e-4)), c.roughness, dfg), c.film);\n");
    }
    if f.transmission {
        // The raster's approximation: the transmitting share reflects the
        // split-sum specular and shows the environment behind, along the
        // view bent once by the interface (straight through a thin wall),
        // tinted once by its colour.
        w.push_str("        let through = select(refract(-v, n, 1.0 / c.eta), -v, c.thin > 0.5);\n        let behind = (1.0 - fresnel_dielectric(dot(n, v), c.eta)) * c.tint * gradient_radiance(top, bottom, through);\n        a = mix(a, ambient_light(top, bottom, n, v, vec3(0.0), 0.0, c.reflectance, c.roughness, dfg) + behind, c.transmission);\n");
    }
    if f.fuzz {
        w.push_str("        a = a * (1.0 - max3(c.fuzz_color)) + c.fuzz_color / PI * gradient_irradiance(top, bottom, n);\n");
    }
    w.push_str("        e += c.weight * a;\n    }\n    return e;\n}\n\n");

    // Rect lights by LTC: each closure's lobes at its roughness.
    let _ = writeln!(
        w,
        "#ifdef LIGHT_RECT\n// A rect light through the LTC tables, closure by closure.\nfn material_rect(s: Surface, n: vec3<f32>, v: vec3<f32>, p: vec3<f32>, corners: array<vec3<f32>, 4>, two_sided: bool, ltc_matrix: texture_2d<f32>, ltc_amplitude: texture_2d<f32>) -> vec3<f32> {{\n    var e = vec3(0.0);\n    for (var k = 0u; k < s.count; k++) {{\n        let c = s.closures[k];\n{}        let r = ltc_rect(n, v, p, c.roughness, corners, two_sided, ltc_matrix, ltc_amplitude);\n        let diffuse = c.base_color * (1.0 - c.metallic) * r.diffuse;\n        var lit = diffuse + c.reflectance * r.specular.x + {};",
        if f.normal { "        let n = closure_normal(c, n);\n" } else { "" },
        if f.edge { "c.edge * r.specular.y" } else { "r.specular.y" }
    );
    if f.haze {
        let _ = writeln!(
            w,
            "        let h = ltc_rect(n, v, p, c.haze.y, corners, two_sided, ltc_matrix, ltc_amplitude);\n        lit = mix(lit, diffuse + {haze_f0} * h.specular.x + {haze_f90} * h.specular.y, c.haze.x);"
        );
    }
    if f.thin_film {
        // The film's Fresnel at the lobe's mirror direction (v·h = n·v)
        // on both of the LTC's Fresnel terms.
        w.push_str("        lit = mix(lit, diffuse + c.film_fresnel * (r.specular.x + r.specular.y), c.film);\n");
    }
    if f.transmission {
        w.push_str("        lit -= c.transmission * diffuse;\n");
    }
    if f.fuzz {
        w.push_str("        lit = lit * (1.0 - max3(c.fuzz_color)) + c.fuzz_color * r.diffuse;\n");
    }
    w.push_str("        e += c.weight * lit;\n    }\n    return e;\n}\n#endif\n");
    w
}

/// A closure's film, when a definition has one.
const FILM: &str = "// The Schlick F0 matching the film's Fresnel at n·v.
fn closure_film_f0(c: Closure, n_v: f32) -> vec3<f32> {
    return schlick_f0_of(c.film_fresnel, n_v);
}

";

/// `binding` (`var f`, `let l`) of the closure's main lobe: the
/// isotropic call, or in a module with anisotropy the anisotropic one for
/// every closure (at anisotropy 0 it is the isotropic lobe). One GGX per
/// call site, not both behind a branch: lavapipe compiles every inlined
/// copy, and the library scene's path tracer took half as long again.
fn lobe(f: Features, binding: &str, isotropic: &str, anisotropic: &str) -> String {
    format!("    {binding} = {};\n", if f.anisotropy { anisotropic } else { isotropic })
}

/// Helpers every module carries (small; the built-ins' and the loops').
const HELPERS: &str = "fn max3(x: vec3<f32>) -> f32 {
    return max(x.x, max(x.y, x.z));
}

fn ior_reflectance(ior: f32) -> vec3<f32> {
    let r = (ior - 1.0) / (ior + 1.0);
    return vec3(r * r);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3(2.4)), c / 12.92, c <= vec3(0.04045));
}

fn transmittance_to_mfp(color: vec3<f32>, distance: f32) -> vec3<f32> {
    return distance / max(-log(clamp(color, vec3(1e-6), vec3(0.999999))), vec3(1e-6));
}

";

/// `eval`, `pdf`, `sample` and the summaries, over the closures.
const LOOPS: &str = "// BSDF × cosine for light from l, seen from v.
fn material_eval(s: Surface, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    var f = vec3(0.0);
    for (var k = 0u; k < s.count; k++) {
        f += s.closures[k].weight * closure_cos(s.closures[k], n, v, l);
    }
    return f;
}

// How often each closure is sampled: its weighted albedo's share. A single
// closure is sampled always (exactly 1, so a one-slab material samples as
// brdf.wgsl does).
fn material_shares(s: Surface, n_v: f32) -> array<f32, MATERIAL_CLOSURES> {
    var shares: array<f32, MATERIAL_CLOSURES>;
    if s.count == 1u {
        shares[0] = 1.0;
        return shares;
    }
    var total = 0.0;
    for (var k = 0u; k < s.count; k++) {
        shares[k] = luminance_of(s.closures[k].weight * closure_albedo(s.closures[k], n_v));
        total += shares[k];
    }
    for (var k = 0u; k < s.count; k++) {
        shares[k] = select(1.0 / f32(s.count), shares[k] / total, total > 0.0);
    }
    return shares;
}

// The pdf (solid angle) of `material_sample` drawing l.
fn material_pdf(s: Surface, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> f32 {
    let shares = material_shares(s, max(dot(n, v), 1e-4));
    var p = 0.0;
    for (var k = 0u; k < s.count; k++) {
        p += shares[k] * closure_pdf(s.closures[k], n, v, l);
    }
    return p;
}

// A direction from u (three uniform numbers in [0, 1)): u.x picks the
// closure and then its lobe, u.yz place the direction.
fn material_sample(s: Surface, n: vec3<f32>, v: vec3<f32>, u: vec3<f32>) -> BrdfSample {
    let shares = material_shares(s, max(dot(n, v), 1e-4));
    var x = u.x;
    var k = 0u;
    for (; k + 1u < s.count; k++) {
        if x < shares[k] {
            break;
        }
        x -= shares[k];
    }
    x = min(x / max(shares[k], 1e-8), 0.99999994);
    let l = closure_direction(s.closures[k], n, v, vec3(x, u.yz));
    let pdf = material_pdf(s, n, v, l);
    // No direction (below the surface, or NaN from a NaN normal): the
    // path ends, as in brdf_sample.
    if !(pdf > 0.0) {
        return BrdfSample(vec3(0.0), 0.0, vec3(0.0));
    }
    return BrdfSample(l, pdf, material_eval(s, n, v, l) / pdf);
}

// The colour, metalness and roughness the G-buffer's debug views and the
// denoiser's albedo show: the closures' values by the luminance of their
// weights (a one-slab material's own).
fn material_base_color(s: Surface) -> vec3<f32> {
    var x = vec3(0.0);
    for (var k = 0u; k < s.count; k++) {
        x += luminance_of(s.closures[k].weight) * s.closures[k].base_color;
    }
    return x;
}

fn material_metallic(s: Surface) -> f32 {
    var x = 0.0;
    for (var k = 0u; k < s.count; k++) {
        x += luminance_of(s.closures[k].weight) * s.closures[k].metallic;
    }
    return x;
}

fn material_roughness(s: Surface) -> f32 {
    var x = 0.0;
    for (var k = 0u; k < s.count; k++) {
        x += luminance_of(s.closures[k].weight) * s.closures[k].roughness;
    }
    return x;
}

";

/// What the path tracer needs of solids beyond the loops (under its
/// `MATERIAL_TRANSMISSION` def, on when a definition transmits).
const TRANSMISSION: &str = "// The surface seen from inside its solid: the interface's relative IOR
// inverts (thin walls have no inside).
fn material_inside(s: Surface) -> Surface {
    var t = s;
    for (var k = 0u; k < t.count; k++) {
        t.closures[k].eta = select(1.0 / t.closures[k].eta, t.closures[k].eta, t.closures[k].thin > 0.5);
    }
    return t;
}

// The colour light keeps per unit of distance inside the solid: the solid
// closures' transmission colours by their transmitting weights (white when
// none transmits).
fn material_medium(s: Surface) -> vec3<f32> {
    var sum = vec3(0.0);
    var total = 0.0;
    for (var k = 0u; k < s.count; k++) {
        let w = luminance_of(s.closures[k].weight) * s.closures[k].transmission * (1.0 - s.closures[k].thin);
        sum += w * s.closures[k].tint;
        total += w;
    }
    return select(vec3(1.0), sum / total, total > 0.0);
}

";
