//! Passes over a material's tree, between the front end and the back end:
//! constant folding, pruning, and what the back end and the report need to
//! know (each slab's features, the closures, each node's depth, whether the
//! material conserves energy).
//!
//! `analyse` runs them in order: `fold` (every expression without a
//! parameter becomes a constant), then `prune` (operators whose constant
//! weight leaves one side become that side; what the root no longer reaches
//! is dropped and the ids renumbered), then the facts. The result is again a
//! valid `Definition`, children before parents, which the back end compiles.

use std::collections::BTreeSet;

use serde::Serialize;

use super::operators::{lerp, saturate};
use super::tree::{BinOp, Builtin, Definition, Expr, ExprId, ExprKind, Field, Node, NodeId, NodeKind, Slab, Value};
use crate::diag::Location;

/// What a slab needs the generated code to simulate. A feature no slab of a
/// program has generates no code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Feature {
    /// A dielectric's diffuse lobe: metalness below 1 and a base colour
    /// that is not black.
    Diffuse,
    /// A dielectric's specular lobe: metalness below 1 and a specular
    /// weight above 0.
    Specular,
    /// A metal's specular lobe: metalness above 0.
    Metal,
    /// A grazing colour (F90) other than white, on a specular or metal lobe.
    EdgeTint,
    /// The second, wider specular lobe: a haze weight above 0, on a
    /// specular or metal lobe.
    Haze,
    /// Sheen: a fuzz weight above 0 and a fuzz colour that is not black.
    Fuzz,
    /// A luminance above 0 and an emission colour that is not black.
    Emission,
    /// A medium that absorbs: the slab is in the top of a layer, with a
    /// thickness above 0 and a transmission colour other than white.
    Absorption,
    /// A dielectric that lets light through its interface (refracting into
    /// a solid, or straight through a thin wall): a transmission weight
    /// above 0 and metalness below 1.
    Transmission,
    /// A thin film over the interface (iridescence): a film weight above
    /// 0, on a specular or metal lobe.
    ThinFilm,
    /// A GGX lobe stretched along a direction on the surface: a roughness
    /// anisotropy above 0, on a specular or metal lobe.
    Anisotropy,
}

/// Why a material is not energy-conserving.
#[derive(Debug, Clone, PartialEq)]
pub enum Breach {
    /// An `add` node: its two sides' energy sums.
    Add(Location),
    /// A slab field whose constant value lies outside the field's range
    /// (a colour above 1 reflects more than it receives). Emission fields
    /// are not judged: emitted light is no reflection.
    OutOfRange { field: Field, value: Value, location: Location },
}

/// One material after the passes, and what they found.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// The folded and pruned definition: what the back end compiles, whose
    /// node ids the report and the browser show.
    pub def: Definition,
    /// Per node of `def`: its distance from the root (the root's is 0; a
    /// node reached along several paths takes the longest).
    pub depth: Vec<u32>,
    /// Per node of `def`: a slab's features; empty for operators.
    pub features: Vec<BTreeSet<Feature>>,
    /// The slabs left after pruning, in id order: the closures the
    /// generated code evaluates.
    pub closures: Vec<NodeId>,
    /// Empty when the material conserves energy.
    pub breaches: Vec<Breach>,
    /// Constant expressions that evaluate to infinity or NaN (a division by
    /// zero, `sqrt` of a negative number): the caller reports each as an
    /// error at its location.
    pub non_finite: Vec<Location>,
}

impl Analysis {
    pub fn energy_conserving(&self) -> bool {
        self.breaches.is_empty()
    }

    /// The union of its slabs' features.
    pub fn features(&self) -> BTreeSet<Feature> {
        self.features.iter().flatten().copied().collect()
    }
}

/// The features a program's generated code must simulate: the union over
/// its materials.
pub fn program_features<'a>(analyses: impl IntoIterator<Item = &'a Analysis>) -> BTreeSet<Feature> {
    analyses.into_iter().flat_map(Analysis::features).collect()
}

/// Folds, prunes and analyses one definition.
pub fn analyse(def: &Definition) -> Analysis {
    let def = prune(&fold(def));
    let depth = depths(&def);
    let in_top = in_layer_tops(&def);
    let features = def
        .nodes
        .iter()
        .zip(in_top)
        .map(|(node, in_top)| match &node.kind {
            NodeKind::Slab(slab) => slab_features(&def, slab, in_top),
            _ => BTreeSet::new(),
        })
        .collect();
    let closures = (0..def.nodes.len() as u32).map(NodeId).filter(|&id| matches!(def.node(id).kind, NodeKind::Slab(_))).collect();
    let breaches = breaches(&def);
    let non_finite = def
        .exprs
        .iter()
        .filter(|e| matches!(e.kind, ExprKind::Const(v) if !channels(v).iter().all(|c| c.is_finite())))
        .map(|e| e.location.clone())
        .collect();
    Analysis { def, depth, features, closures, breaches, non_finite }
}

// --- Evaluation -----------------------------------------------------------

/// The value of `expr` for an instance whose parameters are `params`, by
/// index (a parameter past its end takes its default). The arithmetic is the
/// WGSL the back end writes: a float with a colour applies to each channel.
/// A call with the wrong number of arguments (the front end rejects those)
/// evaluates to NaN.
pub fn eval(def: &Definition, expr: ExprId, params: &[Value]) -> Value {
    let param = |i: u32| Some(params.get(i as usize).copied().unwrap_or(def.params[i as usize].default));
    operate(&def.expr(expr).kind, |e| Some(eval(def, e, params)), param).unwrap_or(Value::Float(f32::NAN))
}

/// The value of `id` among `exprs` when no parameter lies below it (the
/// front end's check of defaults, ranges and constant fields, before a
/// definition exists).
pub fn constant(exprs: &[Expr], id: ExprId) -> Option<Value> {
    operate(&exprs[id.0 as usize].kind, |e| constant(exprs, e), |_| None)
}

/// One expression's value from its operands' values (`None`: unknown, and
/// so is the result).
fn operate(kind: &ExprKind, operand: impl Fn(ExprId) -> Option<Value>, param: impl Fn(u32) -> Option<Value>) -> Option<Value> {
    Some(match kind {
        ExprKind::Const(v) => *v,
        ExprKind::Param(i) => param(*i)?,
        ExprKind::Neg(x) => map(operand(*x)?, |x| -x),
        ExprKind::Binary(op, a, b) => {
            let f: fn(f32, f32) -> f32 = match op {
                BinOp::Add => |x, y| x + y,
                BinOp::Sub => |x, y| x - y,
                BinOp::Mul => |x, y| x * y,
                BinOp::Div => |x, y| x / y,
            };
            zip(operand(*a)?, operand(*b)?, f)
        }
        ExprKind::Call(builtin, args) => {
            let args = args.iter().map(|&a| operand(a)).collect::<Option<Vec<_>>>()?;
            call(*builtin, &args).unwrap_or(Value::Float(f32::NAN))
        }
    })
}

/// A built-in's value; `None` for the wrong number of arguments.
fn call(builtin: Builtin, args: &[Value]) -> Option<Value> {
    use Value::{Float, Vec3};
    let x = |i: usize| channel(args[i], 0);
    Some(match (builtin, args) {
        (Builtin::Rgb, [_, _, _]) => Vec3([x(0), x(1), x(2)]),
        (Builtin::Grey, [_]) => Vec3([x(0); 3]),
        (Builtin::Lerp, &[a, b, t]) => zip3(a, b, t, lerp),
        // WGSL's clamp is min(max(x, lo), hi), whatever the bounds' order.
        (Builtin::Clamp, &[v, lo, hi]) => zip3(v, lo, hi, |v, lo, hi| v.max(lo).min(hi)),
        (Builtin::Saturate, &[v]) => map(v, saturate),
        (Builtin::Min, &[a, b]) => zip(a, b, f32::min),
        (Builtin::Max, &[a, b]) => zip(a, b, f32::max),
        (Builtin::Pow, &[a, b]) => zip(a, b, f32::powf),
        (Builtin::Sqrt, &[v]) => map(v, f32::sqrt),
        (Builtin::Abs, &[v]) => map(v, f32::abs),
        (Builtin::Luminance, &[c]) => Float(0.2126 * channel(c, 0) + 0.7152 * channel(c, 1) + 0.0722 * channel(c, 2)),
        (Builtin::Srgb, &[c]) => map(c, srgb_to_linear),
        (Builtin::IorToF0, &[ior]) => map(ior, |n| ((n - 1.0) / (n + 1.0)).powi(2)),
        (Builtin::TransmittanceToMfp, &[color, distance]) => zip(color, distance, transmittance_to_mfp),
        _ => return None,
    })
}

/// The sRGB EOTF: an encoded channel to linear.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// The mean free path after which `distance` keeps `kept` of the light
/// (`kept = exp(-distance / mfp)`). A clear medium (kept 1, or more) gets a
/// long but finite path, so the WGSL never divides by zero.
fn transmittance_to_mfp(kept: f32, distance: f32) -> f32 {
    distance / (-kept.ln()).max(1e-6)
}

fn channel(v: Value, i: usize) -> f32 {
    match v {
        Value::Float(x) => x,
        Value::Vec3(c) => c[i],
        // A texture has no channels to compute with (lowering lets none in).
        Value::Texture(_) => f32::NAN,
    }
}

/// Every channel of a value.
pub fn channels(v: Value) -> Vec<f32> {
    match v {
        Value::Float(x) => vec![x],
        Value::Vec3(c) => c.to_vec(),
        Value::Texture(_) => Vec::new(),
    }
}

fn map(v: Value, f: impl Fn(f32) -> f32) -> Value {
    match v {
        Value::Float(x) => Value::Float(f(x)),
        Value::Vec3(c) => Value::Vec3(c.map(f)),
        Value::Texture(_) => v,
    }
}

/// Applies `f` channel by channel, broadcasting a float over a colour.
fn zip(a: Value, b: Value, f: impl Fn(f32, f32) -> f32) -> Value {
    match (a, b) {
        (Value::Float(x), Value::Float(y)) => Value::Float(f(x, y)),
        _ => Value::Vec3(std::array::from_fn(|i| f(channel(a, i), channel(b, i)))),
    }
}

fn zip3(a: Value, b: Value, c: Value, f: impl Fn(f32, f32, f32) -> f32) -> Value {
    match (a, b, c) {
        (Value::Float(x), Value::Float(y), Value::Float(z)) => Value::Float(f(x, y, z)),
        _ => Value::Vec3(std::array::from_fn(|i| f(channel(a, i), channel(b, i), channel(c, i)))),
    }
}

// --- Folding and pruning --------------------------------------------------

/// Every expression without a parameter becomes a constant, keeping its
/// type and location. Operands are folded before their users when their ids
/// are lower (as the front end creates them); the operands stay, unused,
/// until `prune` drops them.
pub fn fold(def: &Definition) -> Definition {
    let mut known: Vec<Option<Value>> = Vec::with_capacity(def.exprs.len());
    for expr in &def.exprs {
        let value = operate(&expr.kind, |e| known.get(e.0 as usize).copied().flatten(), |_| None);
        known.push(value);
    }
    let exprs = def
        .exprs
        .iter()
        .zip(known)
        .map(|(expr, value)| match value {
            Some(v) => Expr { kind: ExprKind::Const(v), ..expr.clone() },
            None => expr.clone(),
        })
        .collect();
    Definition { exprs, ..def.clone() }
}

/// A node's children, in the order written.
pub fn children(kind: &NodeKind) -> Vec<NodeId> {
    match *kind {
        NodeKind::Slab(_) => vec![],
        NodeKind::Mix { a, b, .. } | NodeKind::Add { a, b } => vec![a, b],
        NodeKind::Layer { top, base } => vec![top, base],
        NodeKind::Coverage { a, .. } => vec![a],
    }
}

/// The expressions a node reads directly.
fn node_exprs(kind: &NodeKind) -> Vec<ExprId> {
    match kind {
        NodeKind::Slab(slab) => slab.fields.iter().map(|&(_, e)| e).collect(),
        NodeKind::Mix { weight, .. } | NodeKind::Coverage { weight, .. } => vec![*weight],
        NodeKind::Layer { .. } | NodeKind::Add { .. } => vec![],
    }
}

fn operands(kind: &ExprKind) -> Vec<ExprId> {
    match kind {
        ExprKind::Const(_) | ExprKind::Param(_) => vec![],
        ExprKind::Neg(x) => vec![*x],
        ExprKind::Binary(_, a, b) => vec![*a, *b],
        ExprKind::Call(_, args) => args.clone(),
    }
}

/// The value of an expression that folding made a constant.
fn folded(def: &Definition, expr: ExprId) -> Option<Value> {
    match def.expr(expr).kind {
        ExprKind::Const(v) => Some(v),
        _ => None,
    }
}

/// Replaces the operators a constant weight decides (`mix` at weight ≤ 0 or
/// ≥ 1, `coverage` at ≥ 1) by the side that is left, drops the nodes and
/// expressions the root no longer reaches, and renumbers what is left in
/// its original order (so children still come before parents). Run after
/// `fold`: only constant weights decide.
pub fn prune(def: &Definition) -> Definition {
    // What each node stands for once decided operators are replaced.
    let mut stand_in: Vec<NodeId> = Vec::with_capacity(def.nodes.len());
    for (i, node) in def.nodes.iter().enumerate() {
        let resolve = |id: NodeId| stand_in.get(id.0 as usize).copied().unwrap_or(id);
        let weight = |e: ExprId| folded(def, e).map(|v| channel(v, 0));
        let id = match node.kind {
            NodeKind::Mix { a, b, weight: w } => match weight(w) {
                Some(w) if w <= 0.0 => resolve(a),
                Some(w) if w >= 1.0 => resolve(b),
                _ => NodeId(i as u32),
            },
            NodeKind::Coverage { a, weight: w } if weight(w).is_some_and(|w| w >= 1.0) => resolve(a),
            _ => NodeId(i as u32),
        };
        stand_in.push(id);
    }
    let resolve = |id: NodeId| stand_in[id.0 as usize];

    let root = resolve(def.root);
    let node_kept =
        reach_all(def.nodes.len(), vec![root.0], |n| children(&def.nodes[n as usize].kind).into_iter().map(|c| resolve(c).0).collect());
    let expr_roots: Vec<u32> = node_kept.iter().flat_map(|&n| node_exprs(&def.nodes[n as usize].kind)).map(|e| e.0).collect();
    let expr_kept = reach_all(def.exprs.len(), expr_roots, |e| operands(&def.exprs[e as usize].kind).into_iter().map(|o| o.0).collect());

    let node_ids = renumber(def.nodes.len(), &node_kept);
    let expr_ids = renumber(def.exprs.len(), &expr_kept);
    let node_id = |id: NodeId| NodeId(node_ids[resolve(id).0 as usize]);
    let expr_id = |id: ExprId| ExprId(expr_ids[id.0 as usize]);

    let nodes = node_kept
        .iter()
        .map(|&n| {
            let node = &def.nodes[n as usize];
            let kind = match &node.kind {
                NodeKind::Slab(slab) => NodeKind::Slab(Slab { fields: slab.fields.iter().map(|&(f, e)| (f, expr_id(e))).collect() }),
                &NodeKind::Mix { a, b, weight } => NodeKind::Mix { a: node_id(a), b: node_id(b), weight: expr_id(weight) },
                &NodeKind::Layer { top, base } => NodeKind::Layer { top: node_id(top), base: node_id(base) },
                &NodeKind::Coverage { a, weight } => NodeKind::Coverage { a: node_id(a), weight: expr_id(weight) },
                &NodeKind::Add { a, b } => NodeKind::Add { a: node_id(a), b: node_id(b) },
            };
            Node { kind, location: node.location.clone() }
        })
        .collect();
    let exprs = expr_kept
        .iter()
        .map(|&e| {
            let expr = &def.exprs[e as usize];
            let kind = match &expr.kind {
                ExprKind::Const(v) => ExprKind::Const(*v),
                ExprKind::Param(i) => ExprKind::Param(*i),
                ExprKind::Neg(x) => ExprKind::Neg(expr_id(*x)),
                ExprKind::Binary(op, a, b) => ExprKind::Binary(*op, expr_id(*a), expr_id(*b)),
                ExprKind::Call(f, args) => ExprKind::Call(*f, args.iter().map(|&a| expr_id(a)).collect()),
            };
            Expr { kind, ..expr.clone() }
        })
        .collect();
    Definition { nodes, exprs, root: node_id(def.root), ..def.clone() }
}

/// The indices reachable from `starts` (without recursion: trees may be
/// deep), sorted.
fn reach_all(len: usize, starts: Vec<u32>, next: impl Fn(u32) -> Vec<u32>) -> Vec<u32> {
    let mut seen = vec![false; len];
    let mut stack = starts;
    while let Some(i) = stack.pop() {
        if !std::mem::replace(&mut seen[i as usize], true) {
            stack.extend(next(i));
        }
    }
    (0..len as u32).filter(|&i| seen[i as usize]).collect()
}

/// Old index → new index, for the kept indices (sorted).
fn renumber(len: usize, kept: &[u32]) -> Vec<u32> {
    let mut ids = vec![u32::MAX; len];
    for (new, &old) in kept.iter().enumerate() {
        ids[old as usize] = new as u32;
    }
    ids
}

// --- Facts ----------------------------------------------------------------

/// Depths, parents first: after `prune` every node is the root or below a
/// node with a higher id.
fn depths(def: &Definition) -> Vec<u32> {
    let mut depth = vec![0; def.nodes.len()];
    for i in (0..def.nodes.len()).rev() {
        for c in children(&def.nodes[i].kind) {
            depth[c.0 as usize] = depth[c.0 as usize].max(depth[i] + 1);
        }
    }
    depth
}

/// Whether each node is inside the top of some layer (where a slab's
/// medium filters the light reaching the base).
fn in_layer_tops(def: &Definition) -> Vec<bool> {
    let mut in_top = vec![false; def.nodes.len()];
    for i in (0..def.nodes.len()).rev() {
        let kind = &def.nodes[i].kind;
        for c in children(kind) {
            let is_top = matches!(*kind, NodeKind::Layer { top, .. } if top == c);
            in_top[c.0 as usize] |= in_top[i] || is_top;
        }
    }
    in_top
}

/// A field's value when it is known at compile time: its default when
/// unset, its constant when folded to one.
fn known(def: &Definition, slab: &Slab, field: Field) -> Option<Value> {
    match slab.get(field) {
        None => Some(field.default()),
        Some(e) => folded(def, e),
    }
}

fn slab_features(def: &Definition, slab: &Slab, in_layer_top: bool) -> BTreeSet<Feature> {
    let is = |field: Field, off: fn(f32) -> bool| known(def, slab, field).is_some_and(|v| channels(v).into_iter().all(off));
    let zero = |x: f32| x <= 0.0;
    let white = |x: f32| x == 1.0;
    let metal_only = is(Field::BaseMetalness, |x| x >= 1.0);
    let specular = !metal_only && !is(Field::SpecularWeight, zero);
    let metal = !is(Field::BaseMetalness, zero);
    let lobe = specular || metal;
    // A mean free path, when set, decides the medium's colour instead.
    let absorbs = match slab.get(Field::MeanFreePath) {
        Some(_) => !is(Field::MeanFreePath, |x| x == f32::MAX),
        None => !is(Field::TransmissionColor, white),
    };
    [
        (Feature::Diffuse, !metal_only && !is(Field::BaseColor, zero)),
        (Feature::Specular, specular),
        (Feature::Metal, metal),
        (Feature::EdgeTint, lobe && !is(Field::SpecularEdgeColor, white)),
        (Feature::Haze, lobe && !is(Field::HazeWeight, zero)),
        (Feature::Fuzz, !is(Field::FuzzWeight, zero) && !is(Field::FuzzColor, zero)),
        (Feature::Emission, !is(Field::EmissionLuminance, zero) && !is(Field::EmissionColor, zero)),
        (Feature::Absorption, in_layer_top && !is(Field::Thickness, zero) && absorbs),
        (Feature::Transmission, !metal_only && !is(Field::TransmissionWeight, zero)),
        (Feature::ThinFilm, lobe && !is(Field::ThinFilmWeight, zero)),
        (Feature::Anisotropy, lobe && !is(Field::SpecularAnisotropy, zero)),
    ]
    .into_iter()
    .filter_map(|(feature, on)| on.then_some(feature))
    .collect()
}

fn breaches(def: &Definition) -> Vec<Breach> {
    let mut found = Vec::new();
    for node in &def.nodes {
        match &node.kind {
            NodeKind::Add { .. } => found.push(Breach::Add(node.location.clone())),
            NodeKind::Slab(slab) => {
                for &(field, e) in &slab.fields {
                    if matches!(field, Field::EmissionColor | Field::EmissionLuminance) {
                        continue;
                    }
                    let (Some(value), Some((lo, hi))) = (folded(def, e), field.range()) else { continue };
                    if !channels(value).iter().all(|c| (lo..=hi).contains(c)) {
                        found.push(Breach::OutOfRange { field, value, location: def.expr(e).location.clone() });
                    }
                }
            }
            _ => {}
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::super::build::Build;
    use super::*;
    use crate::material::tree::Type;

    fn feats(list: &[Feature]) -> BTreeSet<Feature> {
        list.iter().copied().collect()
    }

    #[test]
    fn eval_matches_the_wgsl_arithmetic() {
        let mut b = Build::new("m");
        let half = b.float(0.5);
        let red = b.rgb([1.0, 0.0, 0.0]);
        let blue = b.rgb([0.0, 0.0, 1.0]);
        let lerped = b.call(Builtin::Lerp, &[red, blue, half]);
        let scaled = b.bin(BinOp::Mul, half, red);
        let ior = b.float(1.5);
        let f0 = b.call(Builtin::IorToF0, &[ior]);
        let encoded = b.float(0.5);
        let grey = b.call(Builtin::Grey, &[encoded]);
        let linear = b.call(Builtin::Srgb, &[grey]);
        let hi = b.float(0.2);
        let lo = b.float(0.8);
        let clamped = b.call(Builtin::Clamp, &[half, lo, hi]);
        let luma = b.call(Builtin::Luminance, &[red]);
        let kept = b.float(0.5);
        let one = b.float(1.0);
        let mfp = b.call(Builtin::TransmittanceToMfp, &[kept, one]);
        let clear = b.call(Builtin::TransmittanceToMfp, &[one, one]);
        let p = b.param("p", Type::Float, Value::Float(0.25), None);
        let plus = b.bin(BinOp::Add, p, half);
        let slab = b.slab(&[]);
        let def = b.finish(slab);

        assert_eq!(eval(&def, lerped, &[]), Value::Vec3([0.5, 0.0, 0.5]));
        assert_eq!(eval(&def, scaled, &[]), Value::Vec3([0.5, 0.0, 0.0]), "a float broadcasts over a colour");
        let Value::Float(f0) = eval(&def, f0, &[]) else { panic!() };
        assert!((f0 - 0.04).abs() < 1e-7, "{f0}");
        let Value::Vec3(l) = eval(&def, linear, &[]) else { panic!() };
        assert!((l[0] - 0.21404114).abs() < 1e-6, "{l:?}");
        assert_eq!(eval(&def, clamped, &[]), Value::Float(0.2), "WGSL's clamp with crossed bounds gives hi");
        assert_eq!(eval(&def, luma, &[]), Value::Float(0.2126));
        let Value::Float(m) = eval(&def, mfp, &[]) else { panic!() };
        assert!((m - 1.0 / std::f32::consts::LN_2).abs() < 1e-5, "{m}");
        let Value::Float(c) = eval(&def, clear, &[]) else { panic!() };
        assert!(c.is_finite() && c >= 1e6, "{c}");
        assert_eq!(eval(&def, plus, &[]), Value::Float(0.75), "a parameter past the instance's values takes its default");
        assert_eq!(eval(&def, plus, &[Value::Float(1.0)]), Value::Float(1.5));
    }

    #[test]
    fn folding_makes_constant_subtrees_constants_and_keeps_parameters() {
        let mut b = Build::new("m");
        let two = b.float(2.0);
        let tenth = b.float(0.1);
        let product = b.bin(BinOp::Mul, two, tenth);
        let grey = b.call(Builtin::Grey, &[product]);
        let p = b.param("r", Type::Float, Value::Float(0.3), Some((0.0, 1.0)));
        let rough = b.bin(BinOp::Mul, p, product);
        let slab = b.slab(&[(Field::BaseColor, grey), (Field::SpecularRoughness, rough)]);
        let def = b.finish(slab);
        let out = fold(&def);
        assert_eq!(out.expr(grey).kind, ExprKind::Const(Value::Vec3([0.2; 3])));
        assert_eq!(out.expr(grey).location, def.expr(grey).location);
        assert_eq!(out.expr(rough).kind, ExprKind::Binary(BinOp::Mul, p, product), "a parameter keeps its expression");
        assert_eq!(out.expr(product).kind, ExprKind::Const(Value::Float(0.2)));

        let pruned = analyse(&def).def;
        // 0: the folded product, 1: the folded grey, 2: the parameter, 3: the
        // roughness; the constants 2 and 0.1 are gone.
        assert_eq!(pruned.exprs.len(), 4, "{:#?}", pruned.exprs);
        assert_eq!(pruned.exprs[3].kind, ExprKind::Binary(BinOp::Mul, ExprId(2), ExprId(0)));
        let NodeKind::Slab(s) = &pruned.node(pruned.root).kind else { panic!() };
        assert_eq!(s.fields, vec![(Field::BaseColor, ExprId(1)), (Field::SpecularRoughness, ExprId(3))]);
    }

    #[test]
    fn pruning_replaces_decided_operators_and_renumbers() {
        let mut b = Build::new("m");
        let red = b.rgb([1.0, 0.0, 0.0]);
        let a = b.slab(&[(Field::BaseColor, red)]);
        let metal = b.float(1.0);
        let bslab = b.slab(&[(Field::BaseMetalness, metal)]);
        let one = b.float(1.0);
        let zero = b.bin(BinOp::Sub, one, one);
        let mix0 = b.mix(a, bslab, zero);
        let full = b.float(1.5);
        let cov = b.coverage(mix0, full);
        let half = b.float(0.5);
        let mix1 = b.mix(bslab, cov, half);
        let out = analyse(&b.finish(mix1)).def;
        // The coverage is its child, the weight-0 mix its `a`; `mix1` stays.
        assert_eq!(out.nodes.len(), 3, "{:#?}", out.nodes);
        assert_eq!(out.root, NodeId(2));
        let NodeKind::Mix { a: ma, b: mb, weight } = out.node(out.root).kind else { panic!("{:?}", out.node(out.root)) };
        assert_eq!((ma, mb), (NodeId(1), NodeId(0)), "the metal slab is node 1, the red one node 0");
        assert_eq!(out.expr(weight).kind, ExprKind::Const(Value::Float(0.5)));
        let NodeKind::Slab(red_slab) = &out.node(NodeId(0)).kind else { panic!() };
        assert_eq!(out.expr(red_slab.get(Field::BaseColor).unwrap()).kind, ExprKind::Const(Value::Vec3([1.0, 0.0, 0.0])));
        // Every kept expression is used, the dropped weights are gone.
        assert_eq!(out.exprs.len(), 3, "{:#?}", out.exprs);
        assert_valid(&out);
    }

    #[test]
    fn a_mix_at_weight_one_is_its_b_and_a_partial_coverage_stays() {
        let mut b = Build::new("m");
        let x = b.slab(&[]);
        let y = b.slab(&[]);
        let w = b.float(1.0);
        let m = b.mix(x, y, w);
        let c = b.float(0.5);
        let cov = b.coverage(m, c);
        let out = analyse(&b.finish(cov)).def;
        assert_eq!(out.nodes.len(), 2);
        assert!(matches!(out.node(NodeId(1)).kind, NodeKind::Coverage { a: NodeId(0), .. }));
        assert_eq!(out.node(NodeId(0)).location.line, 2, "the kept slab is `y`, written second");
        assert_valid(&out);
    }

    /// Children before parents, every id in bounds, every node reached.
    fn assert_valid(def: &Definition) {
        for (i, node) in def.nodes.iter().enumerate() {
            assert!(children(&node.kind).iter().all(|c| (c.0 as usize) < i), "{i}: {node:?}");
            assert!(node_exprs(&node.kind).iter().all(|e| (e.0 as usize) < def.exprs.len()));
        }
        assert_eq!(def.root.0 as usize, def.nodes.len() - 1);
        for (i, e) in def.exprs.iter().enumerate() {
            assert!(operands(&e.kind).iter().all(|o| (o.0 as usize) < i), "{i}: {e:?}");
        }
    }

    #[test]
    fn features_follow_the_fields_and_their_constants() {
        let mut b = Build::new("m");
        let plastic = b.slab(&[]);
        let one = b.float(1.0);
        let tint = b.rgb([0.9, 0.8, 0.5]);
        let metal = b.slab(&[(Field::BaseMetalness, one), (Field::SpecularEdgeColor, tint)]);
        let zero = b.float(0.0);
        let wool = b.rgb([0.4, 0.1, 0.1]);
        let fuzz_off = b.slab(&[(Field::FuzzWeight, zero), (Field::BaseColor, wool)]);
        let amount = b.param("fuzz", Type::Float, Value::Float(0.5), Some((0.0, 1.0)));
        let fuzz_on = b.slab(&[(Field::FuzzWeight, amount)]);
        let lum = b.float(3.0);
        let black = b.call(Builtin::Grey, &[zero]);
        let lamp = b.slab(&[(Field::EmissionLuminance, lum), (Field::BaseColor, black)]);
        let green = b.rgb([0.5, 1.0, 0.5]);
        let thick = b.float(0.2);
        let coat = b.slab(&[(Field::BaseColor, black), (Field::TransmissionColor, green), (Field::Thickness, thick)]);
        let m1 = b.mix(plastic, metal, thick);
        let m2 = b.mix(fuzz_off, fuzz_on, thick);
        let m3 = b.mix(m1, m2, thick);
        let m4 = b.mix(m3, lamp, thick);
        let root = b.layer(coat, m4);
        let a = analyse(&b.finish(root));
        use Feature::*;
        let of = |n: NodeId| a.features[n.0 as usize].clone();
        assert_eq!(of(plastic), feats(&[Diffuse, Specular]));
        assert_eq!(of(metal), feats(&[Metal, EdgeTint]));
        assert_eq!(of(fuzz_off), feats(&[Diffuse, Specular]), "fuzz_weight: 0 is no fuzz");
        assert_eq!(of(fuzz_on), feats(&[Diffuse, Specular, Fuzz]), "a parameter may turn it on");
        assert_eq!(of(lamp), feats(&[Specular, Emission]));
        assert_eq!(of(coat), feats(&[Specular, Absorption]));
        assert_eq!(of(m1), feats(&[]), "operators have none");
        assert_eq!(a.closures, vec![plastic, metal, fuzz_off, fuzz_on, lamp, coat]);
        assert_eq!(a.features(), feats(&[Diffuse, Specular, Metal, EdgeTint, Fuzz, Emission, Absorption]));
        assert_eq!(a.depth[root.0 as usize], 0);
        assert_eq!(a.depth[coat.0 as usize], 1);
        assert_eq!(a.depth[plastic.0 as usize], 4);
        assert!(a.energy_conserving());
    }

    #[test]
    fn absorption_needs_the_top_of_a_layer() {
        let mut b = Build::new("m");
        let green = b.rgb([0.5, 1.0, 0.5]);
        let thick = b.float(0.2);
        let base = b.slab(&[(Field::TransmissionColor, green), (Field::Thickness, thick)]);
        let clear = b.rgb([1.0; 3]);
        let clear_top = b.slab(&[(Field::TransmissionColor, clear), (Field::Thickness, thick)]);
        let tinted_top = b.slab(&[(Field::TransmissionColor, green), (Field::Thickness, thick)]);
        let inner = b.layer(clear_top, base);
        let root = b.layer(tinted_top, inner);
        let a = analyse(&b.finish(root));
        let absorbs = |n: NodeId| a.features[n.0 as usize].contains(&Feature::Absorption);
        assert!(!absorbs(base), "a base's medium is not crossed: {:?}", a.features);
        assert!(!absorbs(clear_top), "a clear medium absorbs nothing");
        assert!(absorbs(tinted_top));
    }

    #[test]
    fn transmission_needs_a_weight_and_a_dielectric() {
        let mut b = Build::new("m");
        let one = b.float(1.0);
        let zero = b.float(0.0);
        let glass = b.slab(&[(Field::TransmissionWeight, one)]);
        let opaque = b.slab(&[(Field::TransmissionWeight, zero)]);
        let metal = b.slab(&[(Field::TransmissionWeight, one), (Field::BaseMetalness, one)]);
        let half = b.float(0.5);
        let m1 = b.mix(glass, opaque, half);
        let root = b.mix(m1, metal, half);
        let a = analyse(&b.finish(root));
        let transmits = |n: NodeId| a.features[n.0 as usize].contains(&Feature::Transmission);
        assert!(transmits(glass), "{:?}", a.features);
        assert!(!transmits(opaque), "transmission_weight: 0 transmits nothing");
        assert!(!transmits(metal), "metal does not transmit");
    }

    #[test]
    fn a_thin_film_needs_a_weight_and_a_lobe() {
        let mut b = Build::new("m");
        let one = b.float(1.0);
        let zero = b.float(0.0);
        let film = b.slab(&[(Field::ThinFilmWeight, one)]);
        let none = b.slab(&[(Field::ThinFilmWeight, zero)]);
        let bare = b.slab(&[(Field::ThinFilmWeight, one), (Field::SpecularWeight, zero)]);
        let half = b.float(0.5);
        let m1 = b.mix(film, none, half);
        let root = b.mix(m1, bare, half);
        let a = analyse(&b.finish(root));
        let filmed = |n: NodeId| a.features[n.0 as usize].contains(&Feature::ThinFilm);
        assert!(filmed(film), "{:?}", a.features);
        assert!(!filmed(none), "thin_film_weight: 0 is no film");
        assert!(!filmed(bare), "no specular lobe, nothing for a film to change");
    }

    #[test]
    fn a_mean_free_path_decides_the_absorption() {
        let mut b = Build::new("m");
        let thick = b.float(0.2);
        let short = b.rgb([0.1, 1.0, 5.0]);
        let clear = b.rgb([f32::MAX; 3]);
        let white = b.rgb([1.0; 3]);
        let green = b.rgb([0.5, 1.0, 0.5]);
        let absorbing = b.slab(&[(Field::MeanFreePath, short), (Field::Thickness, thick), (Field::TransmissionColor, white)]);
        let infinite = b.slab(&[(Field::MeanFreePath, clear), (Field::Thickness, thick), (Field::TransmissionColor, green)]);
        let base = b.slab(&[]);
        let inner = b.layer(infinite, base);
        let root = b.layer(absorbing, inner);
        let a = analyse(&b.finish(root));
        let absorbs = |n: NodeId| a.features[n.0 as usize].contains(&Feature::Absorption);
        assert!(absorbs(absorbing), "a mean free path absorbs, whatever the colour says: {:?}", a.features);
        assert!(!absorbs(infinite), "an endless mean free path absorbs nothing, whatever the colour says");
    }

    #[test]
    fn add_and_out_of_range_constants_break_energy_conservation() {
        let mut b = Build::new("m");
        let bright = b.float(1.25);
        let over = b.bin(BinOp::Mul, bright, bright);
        let hot = b.slab(&[(Field::BaseColor, over), (Field::EmissionColor, over)]);
        let other = b.slab(&[]);
        let root = b.add(hot, other);
        let a = analyse(&b.finish(root));
        assert!(!a.energy_conserving());
        assert_eq!(a.breaches.len(), 2, "emission is not judged: {:?}", a.breaches);
        assert!(matches!(&a.breaches[0], Breach::OutOfRange { field: Field::BaseColor, value: Value::Float(v), .. } if *v == 1.5625));
        assert!(matches!(&a.breaches[1], Breach::Add(l) if l.line == 5));
    }

    #[test]
    fn a_division_by_zero_is_reported_where_it_is_written() {
        let mut b = Build::new("m");
        let one = b.float(1.0);
        let zero = b.float(0.0);
        let inf = b.bin(BinOp::Div, one, zero);
        let slab = b.slab(&[(Field::Thickness, inf)]);
        let a = analyse(&b.finish(slab));
        assert_eq!(a.non_finite.iter().map(|l| l.line).collect::<Vec<_>>(), vec![3]);
    }

    #[test]
    fn program_features_are_the_union() {
        let mut b = Build::new("a");
        let one = b.float(1.0);
        let s = b.slab(&[(Field::BaseMetalness, one)]);
        let metal = analyse(&b.finish(s));
        let mut b = Build::new("b");
        let one = b.float(1.0);
        let s = b.slab(&[(Field::FuzzWeight, one)]);
        let fabric = analyse(&b.finish(s));
        use Feature::*;
        assert_eq!(program_features([&metal, &fabric]), feats(&[Diffuse, Specular, Metal, Fuzz]));
    }
}
