//! Substrate's simplification: a material whose closures need more bytes
//! per pixel than `quality.material_bytes` (`layout::bytes`) has its tree
//! collapsed, deepest operator first, by parameter blending, until it fits.
//! A pure function of (definition, budget) between the analysis and the
//! back end: the raster compiles the simplified tree, the path tracer the
//! full one (or, on request, the simplified one), so the budget's error is
//! measured against the truth.
//!
//! The rules (docs/materials.md "Budget and simplification"):
//! - `mix(a, b, w)` → one slab whose fields are `lerp(a.f, b.f, w)` (a field
//!   one side leaves unset takes its default there), normals lerped (the
//!   back end normalises), emission and fuzz blended as colour × amount;
//! - `layer(top, base)` → the base, its roughness widened by the top's
//!   (`(r_b⁴ + r_t⁴)^¼`, the back end's layer rule), its colour tinted by
//!   what the top lets through there and back at normal incidence (and
//!   behind the top's own diffuse), the top's fuzz and emission kept, and a
//!   clear dielectric coat's lobe kept as the base's haze lobe;
//! - `coverage(a, w)` is kept (its weight is the closure's, in the core: no
//!   bytes); when the operator above collapses, its weight joins the blend;
//! - `add(a, b)` → the blend by the two weights, reflection clamped to
//!   weight 1, emission summed;
//! - one slab still too big drops features: `DROPS`, in order.
//!
//! Architecture Invariant: the result never takes more bytes than the
//! input, and is the input itself when that fits.

use serde::Serialize;

use super::analysis::{self, Feature, children};
use super::layout::{self, StorageClass};
use super::tree::{BinOp, Builtin, Definition, Expr, ExprId, ExprKind, Field, Node, NodeId, NodeKind, Slab, Type, Value};
use crate::diag::Location;

/// A definition brought to a budget, and how.
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    /// What the back end compiles: the input when it fits.
    pub def: Definition,
    pub budget: u32,
    pub bytes_before: u32,
    pub bytes_after: u32,
    pub class_before: StorageClass,
    pub class_after: StorageClass,
    /// In the order applied; empty when the material fits.
    pub rules: Vec<Rule>,
}

impl Simplified {
    /// "Simplified here": the header bit the packer writes.
    pub fn simplified(&self) -> bool {
        !self.rules.is_empty()
    }
}

/// One step of the simplification.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rule {
    /// `mix`, `layer` or `add` (an operator collapsed), or `drop <feature>`.
    pub rule: String,
    /// The node it changed, by its id in the full tree (the report's).
    pub node: u32,
    pub location: Location,
    /// The material's bytes per pixel after it.
    pub bytes: u32,
}

/// The features a lone slab still over the budget loses, first to last,
/// with the fields that make each: the cheapest to lose to the eye first,
/// transmission (which changes what a surface is) last. A slab's own
/// normal is no analysis feature: `None` stands for it.
const DROPS: [(&str, Option<Feature>, &[Field]); 8] = [
    ("haze", Some(Feature::Haze), &[Field::HazeWeight, Field::HazeRoughness]),
    ("fuzz", Some(Feature::Fuzz), &[Field::FuzzWeight, Field::FuzzColor, Field::FuzzRoughness]),
    ("thin film", Some(Feature::ThinFilm), &[Field::ThinFilmWeight, Field::ThinFilmThickness, Field::ThinFilmIor]),
    ("anisotropy", Some(Feature::Anisotropy), &[Field::SpecularAnisotropy, Field::SpecularRotation]),
    ("edge tint", Some(Feature::EdgeTint), &[Field::SpecularEdgeColor]),
    ("normal", None, &[Field::Normal]),
    ("emission", Some(Feature::Emission), &[Field::EmissionLuminance, Field::EmissionColor]),
    ("transmission", Some(Feature::Transmission), &[Field::TransmissionWeight, Field::ThinWalled]),
];

/// `def` (analysed: folded and pruned) within `budget` bytes per pixel.
/// Below `layout::MIN_BYTES` a material may stay over the budget.
pub fn simplify(def: &Definition, budget: u32) -> Simplified {
    let full = analysis::analyse(def);
    let (bytes_before, class_before) = (layout::bytes(&full), layout::class(&full));
    let mut out = Simplified {
        def: def.clone(),
        budget,
        bytes_before,
        bytes_after: bytes_before,
        class_before,
        class_after: class_before,
        rules: Vec::new(),
    };
    if bytes_before <= budget {
        return out;
    }
    // Ids stay those of the full tree while rules apply (new nodes go at
    // the end), so each rule names the node the report shows.
    let mut work = full.def;
    loop {
        let a = analysis::analyse(&ordered(&work));
        out.bytes_after = layout::bytes(&a);
        if out.bytes_after <= budget {
            break;
        }
        let step = match deepest_operator(&work) {
            Some(op) => Some(collapse(&mut work, op)),
            None => drop_feature(&mut work, &a),
        };
        let Some((rule, node)) = step else { break };
        let bytes = layout::bytes(&analysis::analyse(&ordered(&work)));
        out.rules.push(Rule { rule, node: node.0, location: work.node(node).location.clone(), bytes });
    }
    let a = analysis::analyse(&ordered(&work));
    out.class_after = layout::class(&a);
    out.def = a.def;
    out
}

/// Renumbered children before parents (the order the analysis and the back
/// end expect), from the root.
fn ordered(def: &Definition) -> Definition {
    fn visit(def: &Definition, id: NodeId, new_id: &mut [u32], order: &mut Vec<NodeId>) {
        if new_id[id.0 as usize] != u32::MAX {
            return;
        }
        for c in children(&def.node(id).kind) {
            visit(def, c, new_id, order);
        }
        new_id[id.0 as usize] = order.len() as u32;
        order.push(id);
    }
    let mut new_id = vec![u32::MAX; def.nodes.len()];
    let mut order = Vec::new();
    visit(def, def.root, &mut new_id, &mut order);
    let id = |n: NodeId| NodeId(new_id[n.0 as usize]);
    let nodes = order
        .iter()
        .map(|&n| {
            let node = def.node(n);
            let kind = match &node.kind {
                NodeKind::Slab(s) => NodeKind::Slab(s.clone()),
                &NodeKind::Mix { a, b, weight } => NodeKind::Mix { a: id(a), b: id(b), weight },
                &NodeKind::Layer { top, base } => NodeKind::Layer { top: id(top), base: id(base) },
                &NodeKind::Coverage { a, weight } => NodeKind::Coverage { a: id(a), weight },
                &NodeKind::Add { a, b } => NodeKind::Add { a: id(a), b: id(b) },
            };
            Node { kind, location: node.location.clone() }
        })
        .collect();
    Definition { nodes, root: id(def.root), ..def.clone() }
}

/// The deepest `mix`, `layer` or `add` the root reaches (the first written
/// among equals). Its children are slabs, each maybe under coverage: an
/// operator below would be deeper.
fn deepest_operator(def: &Definition) -> Option<NodeId> {
    let mut best: Option<(u32, NodeId)> = None;
    let mut stack = vec![(def.root, 0u32)];
    while let Some((id, depth)) = stack.pop() {
        let kind = &def.node(id).kind;
        if matches!(kind, NodeKind::Mix { .. } | NodeKind::Layer { .. } | NodeKind::Add { .. })
            && best.is_none_or(|(d, b)| depth > d || (depth == d && id < b))
        {
            best = Some((depth, id));
        }
        stack.extend(children(kind).into_iter().map(|c| (c, depth + 1)));
    }
    best.map(|(_, id)| id)
}

/// Replaces the operator `id` by one slab (under coverage where the
/// weights need it); returns the rule's name and `id`.
fn collapse(work: &mut Definition, id: NodeId) -> (String, NodeId) {
    let at = work.node(id).location.clone();
    let mut e = Exprs { def: work, at };
    let (name, kind) = match e.def.node(id).kind.clone() {
        NodeKind::Mix { a, b, weight } => {
            let ((sa, ca), (sb, cb)) = (e.unit(a), e.unit(b));
            let t = e.call(Builtin::Saturate, &[weight], Type::Float);
            let kind = match (ca, cb) {
                (None, None) => NodeKind::Slab(e.blend(&sa, &sb, t, None)),
                (ca, cb) => {
                    // (1 − t)·ca·A + t·cb·B = W·blend(A, B, t·cb / W).
                    let one = e.float(1.0);
                    let (ca, cb) = (ca.unwrap_or(one), cb.unwrap_or(one));
                    let rest = e.bin(BinOp::Sub, one, t);
                    let (wa, wb) = (e.bin(BinOp::Mul, rest, ca), e.bin(BinOp::Mul, t, cb));
                    let (total, share) = e.share(wa, wb);
                    let slab = e.blend(&sa, &sb, share, None);
                    e.covered(slab, total)
                }
            };
            ("mix", kind)
        }
        NodeKind::Add { a, b } => {
            let ((sa, ca), (sb, cb)) = (e.unit(a), e.unit(b));
            let one = e.float(1.0);
            let (total, share) = e.share(ca.unwrap_or(one), cb.unwrap_or(one));
            ("add", NodeKind::Slab(e.blend(&sa, &sb, share, Some(total))))
        }
        NodeKind::Layer { top, base } => {
            let ((st, ct), (sb, cb)) = (e.unit(top), e.unit(base));
            let slab = e.layered(&st, &sb, ct);
            let kind = match (ct, cb) {
                // C = Ct + Cb (1 − Ct): whole when either side is.
                (Some(ct), Some(cb)) => {
                    let one = e.float(1.0);
                    let rest = e.bin(BinOp::Sub, one, ct);
                    let under = e.bin(BinOp::Mul, cb, rest);
                    let total = e.bin(BinOp::Add, ct, under);
                    e.covered(slab, total)
                }
                _ => NodeKind::Slab(slab),
            };
            ("layer", kind)
        }
        NodeKind::Slab(_) | NodeKind::Coverage { .. } => unreachable!("`deepest_operator` gives mix, layer or add"),
    };
    work.nodes[id.0 as usize].kind = kind;
    *work = analysis::fold(work);
    (name.to_owned(), id)
}

/// Drops the first feature in `DROPS` the lone slab has; `None` when it
/// has none left to lose.
fn drop_feature(work: &mut Definition, a: &analysis::Analysis) -> Option<(String, NodeId)> {
    let lone = *layout::leaves(work, work.root).first()?;
    let analysed = *layout::leaves(&a.def, a.def.root).first()?;
    let NodeKind::Slab(slab) = work.node(lone).kind.clone() else { return None };
    let features = &a.features[analysed.0 as usize];
    let (name, _, fields) = DROPS.into_iter().find(|(_, feature, fields)| match feature {
        Some(f) => features.contains(f),
        None => slab.get(fields[0]).is_some(),
    })?;
    let at = work.node(lone).location.clone();
    let mut e = Exprs { def: work, at };
    let mut kept = Slab { fields: slab.fields.iter().copied().filter(|(f, _)| !fields.contains(f)).collect() };
    if name == "haze" {
        // One lobe between the two: the roughness lerped by the haze's share.
        let (r, hr, hw) =
            (e.field(&slab, Field::SpecularRoughness), e.field(&slab, Field::HazeRoughness), e.field(&slab, Field::HazeWeight));
        let hw = e.call(Builtin::Saturate, &[hw], Type::Float);
        set(&mut kept, Field::SpecularRoughness, e.lerp(r, hr, hw));
    }
    work.nodes[lone.0 as usize].kind = NodeKind::Slab(kept);
    *work = analysis::fold(work);
    Some((format!("drop {name}"), lone))
}

fn set(slab: &mut Slab, field: Field, e: ExprId) {
    match slab.fields.iter_mut().find(|(f, _)| *f == field) {
        Some(entry) => entry.1 = e,
        None => slab.fields.push((field, e)),
    }
}

/// New expressions and nodes in the tree being simplified, each at the
/// collapsed operator's location.
struct Exprs<'a> {
    def: &'a mut Definition,
    at: Location,
}

impl Exprs<'_> {
    fn push(&mut self, kind: ExprKind, ty: Type) -> ExprId {
        self.def.exprs.push(Expr { kind, ty, location: self.at.clone() });
        ExprId(self.def.exprs.len() as u32 - 1)
    }

    fn ty(&self, e: ExprId) -> Type {
        self.def.expr(e).ty
    }

    fn float(&mut self, x: f32) -> ExprId {
        self.push(ExprKind::Const(Value::Float(x)), Type::Float)
    }

    /// A float with a colour is a colour (the back end splats it).
    fn bin(&mut self, op: BinOp, a: ExprId, b: ExprId) -> ExprId {
        let ty = if self.ty(a) == Type::Float { self.ty(b) } else { self.ty(a) };
        self.push(ExprKind::Binary(op, a, b), ty)
    }

    fn call(&mut self, f: Builtin, args: &[ExprId], ty: Type) -> ExprId {
        self.push(ExprKind::Call(f, args.to_vec()), ty)
    }

    /// `lerp(a, b, t)`, or `a` when both are the same value.
    fn lerp(&mut self, a: ExprId, b: ExprId, t: ExprId) -> ExprId {
        let same = a == b || matches!((&self.def.expr(a).kind, &self.def.expr(b).kind), (ExprKind::Const(x), ExprKind::Const(y)) if x == y);
        if same {
            return a;
        }
        let ty = if self.ty(a) == Type::Float { self.ty(b) } else { self.ty(a) };
        self.call(Builtin::Lerp, &[a, b, t], ty)
    }

    /// A field's expression: the slab's, or its default as a constant.
    fn field(&mut self, slab: &Slab, field: Field) -> ExprId {
        match slab.get(field) {
            Some(e) => e,
            None => self.push(ExprKind::Const(field.default()), field.ty()),
        }
    }

    /// The slab under `id` and the product of the coverage weights above
    /// it (`None`: whole).
    fn unit(&mut self, id: NodeId) -> (Slab, Option<ExprId>) {
        match self.def.node(id).kind.clone() {
            NodeKind::Slab(s) => (s, None),
            NodeKind::Coverage { a, weight } => {
                let (s, below) = self.unit(a);
                let w = self.call(Builtin::Saturate, &[weight], Type::Float);
                (s, Some(below.map_or(w, |b| self.bin(BinOp::Mul, b, w))))
            }
            _ => unreachable!("the deepest operator's children are slabs under coverage"),
        }
    }

    /// The sum of two weights and the second's share of it.
    fn share(&mut self, wa: ExprId, wb: ExprId) -> (ExprId, ExprId) {
        let total = self.bin(BinOp::Add, wa, wb);
        let tiny = self.float(1e-6);
        let floor = self.call(Builtin::Max, &[total, tiny], Type::Float);
        (total, self.bin(BinOp::Div, wb, floor))
    }

    /// `slab` (a new node) under coverage `weight`.
    fn covered(&mut self, slab: Slab, weight: ExprId) -> NodeKind {
        self.def.nodes.push(Node { kind: NodeKind::Slab(slab), location: self.at.clone() });
        NodeKind::Coverage { a: NodeId(self.def.nodes.len() as u32 - 1), weight }
    }

    /// `a` and `b` lerped field by field at `t`. Emission and fuzz blend
    /// as colour × amount (the amount becomes 1, or `emission` for the
    /// emission's, where an `add` sums the two).
    fn blend(&mut self, a: &Slab, b: &Slab, t: ExprId, emission: Option<ExprId>) -> Slab {
        let products = [(Field::EmissionColor, Field::EmissionLuminance), (Field::FuzzColor, Field::FuzzWeight)];
        let mut out = Slab::default();
        for (colour, amount) in products {
            if [colour, amount].iter().all(|&f| a.get(f).is_none() && b.get(f).is_none()) {
                continue;
            }
            let mut side = |s: &Slab| {
                let (c, w) = (self.field(s, colour), self.field(s, amount));
                self.bin(BinOp::Mul, c, w)
            };
            let (pa, pb) = (side(a), side(b));
            let blended = self.lerp(pa, pb, t);
            set(&mut out, colour, blended);
            let amount_value = match (colour, emission) {
                (Field::EmissionColor, Some(total)) => total,
                _ => self.float(1.0),
            };
            set(&mut out, amount, amount_value);
        }
        for field in Field::ALL {
            let (fa, fb) = (a.get(field), b.get(field));
            if (fa.is_none() && fb.is_none()) || products.iter().any(|&(c, w)| field == c || field == w) {
                continue;
            }
            let value = match (field, fa, fb) {
                // An unset normal is the geometry's, which no expression
                // names: the side that sets one gives it.
                (Field::Normal, Some(n), None) | (Field::Normal, None, Some(n)) => n,
                _ => {
                    let (x, y) = (self.field(a, field), self.field(b, field));
                    self.lerp(x, y, t)
                }
            };
            set(&mut out, field, value);
        }
        out
    }

    /// `top` folded into `base` (the top covering `ct` of the pixel).
    fn layered(&mut self, top: &Slab, base: &Slab, ct: Option<ExprId>) -> Slab {
        let mut out = base.clone();
        let one = self.float(1.0);
        let scale = |e: &mut Self, x: ExprId| ct.map_or(x, |c| e.bin(BinOp::Mul, x, c));
        // What crosses the top's medium, down and back up at normal
        // incidence (the back end's at n·v = 1), where the top covers.
        let crossed =
            top.get(Field::Thickness).filter(|_| top.get(Field::TransmissionColor).is_some() || top.get(Field::MeanFreePath).is_some());
        let through = crossed.map(|thickness| {
            let two = self.float(2.0);
            let path = self.bin(BinOp::Mul, two, thickness);
            let t = match top.get(Field::MeanFreePath) {
                Some(mfp) => {
                    let e = self.push(ExprKind::Const(Value::Vec3([std::f32::consts::E; 3])), Type::Color);
                    let ratio = self.bin(BinOp::Div, path, mfp);
                    let exponent = self.push(ExprKind::Neg(ratio), self.ty(ratio));
                    self.call(Builtin::Pow, &[e, exponent], Type::Color)
                }
                None => {
                    let colour = self.field(top, Field::TransmissionColor);
                    let colour = self.call(Builtin::Saturate, &[colour], Type::Color);
                    self.call(Builtin::Pow, &[colour, path], Type::Color)
                }
            };
            match ct {
                Some(c) => self.lerp(one, t, c),
                None => t,
            }
        });
        // The base's colour behind the top's own diffuse and medium:
        // d_t + (1 − d_t) T c_b.
        let clear = matches!(top.get(Field::BaseColor).map(|e| &self.def.expr(e).kind), Some(ExprKind::Const(v)) if analysis::channels(*v).iter().all(|&c| c <= 0.0));
        let bc = self.field(base, Field::BaseColor);
        let tinted = through.map_or(bc, |t| self.bin(BinOp::Mul, t, bc));
        let colour = if clear {
            tinted
        } else {
            let d = self.field(top, Field::BaseColor);
            let d = scale(self, d);
            let rest = self.bin(BinOp::Sub, one, d);
            let behind = self.bin(BinOp::Mul, rest, tinted);
            self.bin(BinOp::Add, d, behind)
        };
        if colour != bc {
            set(&mut out, Field::BaseColor, colour);
        }
        // Roughness: α² add, as the back end's layer widens the base.
        let (rb, rt) = (self.field(base, Field::SpecularRoughness), self.field(top, Field::SpecularRoughness));
        let four = self.float(4.0);
        let (pb, pt) = (self.call(Builtin::Pow, &[rb, four], Type::Float), self.call(Builtin::Pow, &[rt, four], Type::Float));
        let sum = self.bin(BinOp::Add, pb, pt);
        let quarter = self.float(0.25);
        let root = self.call(Builtin::Pow, &[sum, quarter], Type::Float);
        let widened = self.call(Builtin::Min, &[root, one], Type::Float);
        set(&mut out, Field::SpecularRoughness, widened);
        // A clear dielectric coat: its lobe becomes the base's haze, with
        // the coat's share of the specular reflectance head-on.
        let dielectric =
            top.get(Field::BaseMetalness).is_none_or(|e| matches!(self.def.expr(e).kind, ExprKind::Const(Value::Float(m)) if m <= 0.0));
        let lobe =
            top.get(Field::SpecularWeight).is_none_or(|e| !matches!(self.def.expr(e).kind, ExprKind::Const(Value::Float(w)) if w <= 0.0));
        if clear && dielectric && lobe && base.get(Field::HazeWeight).is_none() {
            // ((η − 1) / (η + 1))² × specular weight, written out: the
            // back end's `ior_to_f0` is a colour in WGSL.
            let f0 = |e: &mut Self, s: &Slab| {
                let ior = e.field(s, Field::SpecularIor);
                let (up, down) = (e.bin(BinOp::Sub, ior, one), e.bin(BinOp::Add, ior, one));
                let r = e.bin(BinOp::Div, up, down);
                let f0 = e.bin(BinOp::Mul, r, r);
                let w = e.field(s, Field::SpecularWeight);
                e.bin(BinOp::Mul, f0, w)
            };
            let coat = f0(self, top);
            let dielectric_base = f0(self, base);
            let bc = self.field(base, Field::BaseColor);
            let metal_f0 = self.call(Builtin::Luminance, &[bc], Type::Float);
            let m = self.field(base, Field::BaseMetalness);
            let under = self.lerp(dielectric_base, metal_f0, m);
            let coat = scale(self, coat);
            let (_, share) = self.share(under, coat);
            set(&mut out, Field::HazeWeight, share);
            set(&mut out, Field::HazeRoughness, rt);
        }
        // Fuzz lies over everything; emission adds what the top emits.
        if top.get(Field::FuzzWeight).is_some() {
            for f in [Field::FuzzColor, Field::FuzzRoughness] {
                let v = self.field(top, f);
                set(&mut out, f, v);
            }
            let w = self.field(top, Field::FuzzWeight);
            let w = scale(self, w);
            set(&mut out, Field::FuzzWeight, w);
        }
        if top.get(Field::EmissionLuminance).is_some() {
            let emitted = |e: &mut Self, s: &Slab| {
                let (c, l) = (e.field(s, Field::EmissionColor), e.field(s, Field::EmissionLuminance));
                e.bin(BinOp::Mul, c, l)
            };
            let from_top = emitted(self, top);
            let from_top = scale(self, from_top);
            let below = emitted(self, base);
            let below = through.map_or(below, |t| self.bin(BinOp::Mul, t, below));
            let sum = self.bin(BinOp::Add, from_top, below);
            set(&mut out, Field::EmissionColor, sum);
            set(&mut out, Field::EmissionLuminance, one);
        }
        if base.get(Field::Normal).is_none()
            && let Some(n) = top.get(Field::Normal)
        {
            set(&mut out, Field::Normal, n);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::super::analysis::analyse;
    use super::super::build::Build;
    use super::super::tree::{Type, Value};
    use super::*;

    fn bytes_of(def: &Definition) -> u32 {
        layout::bytes(&analyse(def))
    }

    /// The starter library's definitions, analysed, by name.
    fn library() -> Vec<Definition> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/materials");
        let mut files: Vec<_> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "mat")).collect();
        files.sort();
        files
            .iter()
            .flat_map(|p| super::super::front::load(p).unwrap_or_else(|d| panic!("{d:?}")).definitions)
            .map(|d| super::super::analysed(&d).unwrap().def)
            .collect()
    }

    /// What each library material needs (docs/materials.md quotes these),
    /// and that at the smallest budget each fits.
    #[test]
    fn the_library_needs_these_bytes_and_fits_the_smallest_budget() {
        let got: Vec<(String, u32, u32)> =
            library().iter().map(|d| (d.name.clone(), bytes_of(d), simplify(d, layout::MIN_BYTES).bytes_after)).collect();
        let want: Vec<(String, u32, u32)> = [
            ("brushed_metal", 28, 16),
            ("car_paint", 56, 16),
            ("fabric", 28, 24),
            ("thin_glass", 32, 24),
            ("solid_glass", 32, 24),
            ("hazy_metal", 28, 16),
            ("rough_metal", 16, 16),
            ("polished_metal", 28, 16),
            ("anodized_metal", 28, 16),
            ("openpbr", 108, 24),
            ("plastic", 24, 24),
            ("rust", 48, 16),
            ("skin", 40, 24),
        ]
        .iter()
        .map(|&(n, b, a)| (n.to_owned(), b, a))
        .collect();
        assert_eq!(got, want);
    }

    /// The byte model and the packer count the same words: a simple
    /// material's pixels take `SIMPLE_BYTES` (the packer's static count is
    /// the single class's, which its pixels take when a value leaves the
    /// shorthand), every other material's exactly what `pack::words` lets
    /// a pixel write. Full and simplified to the smallest budget.
    #[test]
    fn the_byte_model_counts_the_words_the_packer_writes() {
        for full in library() {
            for d in [full.clone(), simplify(&full, layout::MIN_BYTES).def] {
                let a = analyse(&d);
                let packed = 4 * super::super::pack::words(&a.def);
                match layout::class(&a) {
                    StorageClass::Simple => {
                        assert!(layout::bytes(&a) == layout::SIMPLE_BYTES && packed >= layout::SIMPLE_BYTES, "{}", d.name)
                    }
                    _ => assert_eq!(layout::bytes(&a), packed, "{}", d.name),
                }
            }
        }
    }

    #[test]
    fn a_mix_of_two_slabs_becomes_their_lerp() {
        let mut b = Build::new("m");
        let red = b.rgb([1.0, 0.0, 0.0]);
        let blue = b.rgb([0.0, 0.0, 1.0]);
        let x = b.slab(&[(Field::BaseColor, red)]);
        let one = b.float(1.0);
        let y = b.slab(&[(Field::BaseColor, blue), (Field::BaseMetalness, one)]);
        let quarter = b.float(0.25);
        let root = b.mix(x, y, quarter);
        let def = analyse(&b.finish(root)).def;
        let s = simplify(&def, 24);
        assert_eq!(s.rules.iter().map(|r| (r.rule.as_str(), r.node)).collect::<Vec<_>>(), vec![("mix", 2)]);
        let NodeKind::Slab(slab) = &s.def.node(s.def.root).kind else { panic!("{:?}", s.def.nodes) };
        let value = |f: Field| match s.def.expr(slab.get(f).unwrap()).kind {
            ExprKind::Const(v) => v,
            ref k => panic!("{f:?} did not fold: {k:?}"),
        };
        assert_eq!(value(Field::BaseColor), Value::Vec3([0.75, 0.0, 0.25]));
        assert_eq!(value(Field::BaseMetalness), Value::Float(0.25), "an unset side takes the default, 0");
        assert_eq!((s.bytes_before, s.bytes_after), (40, 16), "one metal-ish slab: the shorthand's F0, simple");
    }

    #[test]
    fn a_clear_coat_becomes_haze_over_the_widened_base() {
        let mut b = Build::new("m");
        let black = b.rgb([0.0; 3]);
        let smooth = b.float(0.1);
        let coat = b.slab(&[(Field::BaseColor, black), (Field::SpecularRoughness, smooth)]);
        let rough = b.param("r", Type::Float, Value::Float(0.6), Some((0.0, 1.0)));
        let base = b.slab(&[(Field::SpecularRoughness, rough)]);
        let root = b.layer(coat, base);
        let def = analyse(&b.finish(root)).def;
        let s = simplify(&def, 28);
        assert_eq!(s.rules.iter().map(|r| r.rule.as_str()).collect::<Vec<_>>(), vec!["layer"]);
        let a = analyse(&s.def);
        assert_eq!(a.features[a.def.root.0 as usize], [Feature::Diffuse, Feature::Specular, Feature::Haze].into_iter().collect());
        let NodeKind::Slab(slab) = &s.def.node(s.def.root).kind else { panic!() };
        let at = |f: Field, r: f32| analysis::eval(&s.def, slab.get(f).unwrap(), &[Value::Float(r)]);
        let Value::Float(widened) = at(Field::SpecularRoughness, 0.6) else { panic!() };
        assert!((widened - (0.6f32.powi(4) + 0.1f32.powi(4)).powf(0.25)).abs() < 1e-6, "{widened}");
        assert_eq!(at(Field::HazeRoughness, 0.6), Value::Float(0.1));
        let Value::Float(share) = at(Field::HazeWeight, 0.6) else { panic!() };
        assert!((share - 0.5).abs() < 1e-6, "two F0s of 0.04: half each, {share}");
        // At 24 bytes the haze goes too, into the roughness.
        let s = simplify(&def, 24);
        assert_eq!(s.rules.iter().map(|r| r.rule.as_str()).collect::<Vec<_>>(), vec!["layer", "drop haze"]);
    }

    /// A random tree: slabs with features on (constants or parameters)
    /// under the four operators.
    #[derive(Debug, Clone)]
    enum Tree {
        Slab(Vec<(usize, bool)>),
        Mix(Box<Tree>, Box<Tree>, bool),
        Layer(Box<Tree>, Box<Tree>),
        Coverage(Box<Tree>),
        Add(Box<Tree>, Box<Tree>),
    }

    /// Fields with a value that turns something on.
    const FIELDS: [(Field, Value); 14] = [
        (Field::BaseColor, Value::Vec3([0.6, 0.3, 0.1])),
        (Field::BaseMetalness, Value::Float(1.0)),
        (Field::SpecularRoughness, Value::Float(0.3)),
        (Field::SpecularColor, Value::Vec3([1.0, 0.8, 0.6])),
        (Field::SpecularEdgeColor, Value::Vec3([0.9, 0.8, 0.7])),
        (Field::HazeWeight, Value::Float(0.5)),
        (Field::FuzzWeight, Value::Float(0.8)),
        (Field::EmissionLuminance, Value::Float(2.0)),
        (Field::Thickness, Value::Float(0.1)),
        (Field::TransmissionColor, Value::Vec3([0.5, 0.8, 0.9])),
        (Field::TransmissionWeight, Value::Float(1.0)),
        (Field::ThinFilmWeight, Value::Float(1.0)),
        (Field::SpecularAnisotropy, Value::Float(0.5)),
        (Field::Normal, Value::Vec3([0.0, 0.6, 0.8])),
    ];

    fn tree() -> impl Strategy<Value = Tree> {
        let slab = proptest::collection::vec((0..FIELDS.len(), any::<bool>()), 0..5).prop_map(Tree::Slab);
        slab.prop_recursive(4, 16, 2, |inner| {
            prop_oneof![
                (inner.clone(), inner.clone(), any::<bool>()).prop_map(|(a, b, p)| Tree::Mix(Box::new(a), Box::new(b), p)),
                (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Layer(Box::new(a), Box::new(b))),
                inner.clone().prop_map(|a| Tree::Coverage(Box::new(a))),
                (inner.clone(), inner).prop_map(|(a, b)| Tree::Add(Box::new(a), Box::new(b))),
            ]
        })
    }

    fn build(b: &mut Build, t: &Tree) -> NodeId {
        let weight = |b: &mut Build, param: bool| {
            if param { b.param("w", Type::Float, Value::Float(0.3), Some((0.0, 1.0))) } else { b.float(0.3) }
        };
        match t {
            Tree::Slab(fields) => {
                let mut set: Vec<(Field, ExprId)> = Vec::new();
                for &(i, param) in fields {
                    let (field, value) = FIELDS[i];
                    if set.iter().any(|(f, _)| *f == field) {
                        continue;
                    }
                    let e = match (param, value) {
                        (true, _) => b.param("p", field.ty(), value, None),
                        (false, Value::Float(x)) => b.float(x),
                        (false, Value::Vec3(c)) => b.rgb(c),
                        (false, Value::Texture(_)) => unreachable!(),
                    };
                    set.push((field, e));
                }
                b.slab(&set)
            }
            Tree::Mix(x, y, p) => {
                let (x, y) = (build(b, x), build(b, y));
                let w = weight(b, *p);
                b.mix(x, y, w)
            }
            Tree::Layer(x, y) => {
                let (x, y) = (build(b, x), build(b, y));
                b.layer(x, y)
            }
            Tree::Coverage(x) => {
                let x = build(b, x);
                let w = weight(b, true);
                b.coverage(x, w)
            }
            Tree::Add(x, y) => {
                let (x, y) = (build(b, x), build(b, y));
                b.add(x, y)
            }
        }
    }

    fn definition(t: &Tree) -> Definition {
        let mut b = Build::new("m");
        let root = build(&mut b, t);
        analyse(&b.finish(root)).def
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        #[test]
        fn simplification_never_grows_fits_every_budget_and_is_the_identity_when_it_fits(
            t in tree(),
            budget in (layout::MIN_BYTES / 4..=64).prop_map(|w| w * 4),
        ) {
            let def = definition(&t);
            let before = bytes_of(&def);
            let s = simplify(&def, budget);
            let after = bytes_of(&s.def);
            prop_assert!(after <= before, "{before} → {after} at {budget}: {:?}", s.rules);
            prop_assert!(after <= budget, "{after} over {budget}: {:?}", s.rules);
            prop_assert_eq!(after, s.bytes_after);
            if before <= budget {
                prop_assert!(s.def == def && s.rules.is_empty(), "the identity when it fits");
            }
            // Each rule shrinks or keeps the size, and the back end takes it.
            let mut last = before;
            for r in &s.rules {
                prop_assert!(r.bytes <= last, "{:?} grew {last} → {}", r, r.bytes);
                last = r.bytes;
            }
            let _ = super::super::back::wgsl(std::slice::from_ref(&s.def), super::super::back::Bindings::RENDERER);
        }
    }
}
