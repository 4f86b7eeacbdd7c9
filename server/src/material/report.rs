//! The compile report of one material (JSON, and in the browser): its tree
//! after the analysis with each node's id, depth, fields written back as
//! text, features and children; its closures; whether it conserves energy
//! and, when not, why; the G-buffer's bytes for it; and the size and compile
//! time of its generated WGSL, which the caller fills once the back end has
//! run.

use serde::Serialize;

use super::analysis::{Analysis, Breach, Feature, children};
use super::layout::{StorageClass, leaves};
use super::simplify::{Rule, Simplified};
use super::tree::{BinOp, Definition, ExprId, ExprKind, NodeKind, Value};
use crate::diag::Location;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    pub material: String,
    pub location: Location,
    /// The root's id.
    pub root: u32,
    /// In id order: children before parents.
    pub nodes: Vec<ReportNode>,
    /// The slabs the generated code evaluates, by id.
    pub closures: Vec<u32>,
    /// The union of the slabs' features.
    pub features: Vec<Feature>,
    pub energy_conserving: bool,
    /// Why not, one sentence per cause with its location; empty when it
    /// conserves energy.
    pub energy_reasons: Vec<String>,
    /// What the G-buffer pass writes per pixel of this material: its words
    /// in the material buffer (`budget.bytes_after`) and the inspection
    /// targets every material shares
    /// (`render::passes::gbuffer::BYTES_PER_PIXEL`); `None` until the
    /// daemon fills it in.
    pub gbuffer_bytes_per_pixel: Option<u32>,
    /// The material brought to `quality.material_bytes`; `None` until the
    /// loader has simplified the program.
    pub budget: Option<Budget>,
    /// The generated WGSL's size; `None` until the back end has run.
    pub wgsl_bytes: Option<usize>,
    /// Parse to WGSL, in milliseconds; `None` until the back end has run.
    pub compile_ms: Option<f64>,
}

/// What the budget did to a material (`simplify`): the adaptive
/// G-buffer's bytes per pixel and storage class before and after, the
/// rules applied, each with the node of the tree above it changed, and the
/// closures the raster keeps.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Budget {
    /// `quality.material_bytes`.
    pub budget: u32,
    pub bytes_before: u32,
    pub bytes_after: u32,
    pub class_before: StorageClass,
    pub class_after: StorageClass,
    /// Whether the raster renders a simplified tree ("simplified here").
    pub simplified: bool,
    pub rules: Vec<Rule>,
    /// The closures the raster's tree makes (the full tree's: `closures`
    /// counted once per path that reaches them).
    pub closures_kept: u32,
}

impl Budget {
    pub fn of(s: &Simplified) -> Budget {
        Budget {
            budget: s.budget,
            bytes_before: s.bytes_before,
            bytes_after: s.bytes_after,
            class_before: s.class_before,
            class_after: s.class_after,
            simplified: s.simplified(),
            rules: s.rules.clone(),
            closures_kept: leaves(&s.def, s.def.root).len() as u32,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportNode {
    pub id: u32,
    pub depth: u32,
    /// `slab`, `mix`, `layer`, `coverage` or `add`.
    pub kind: &'static str,
    pub location: Location,
    /// A slab's fields as written (unset ones take their defaults), or an
    /// operator's `weight`.
    pub fields: Vec<FieldText>,
    /// A slab's features; empty for operators.
    pub features: Vec<Feature>,
    pub children: Vec<u32>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldText {
    pub field: &'static str,
    /// The (folded) expression, printed back in the language's syntax.
    pub value_text: String,
}

impl Report {
    pub fn new(analysis: &Analysis) -> Report {
        let def = &analysis.def;
        let nodes = def
            .nodes
            .iter()
            .enumerate()
            .map(|(i, node)| {
                let text = |field: &'static str, e: ExprId| FieldText { field, value_text: expr_text(def, e) };
                let (kind, fields) = match &node.kind {
                    NodeKind::Slab(slab) => ("slab", slab.fields.iter().map(|&(f, e)| text(f.name(), e)).collect()),
                    NodeKind::Mix { weight, .. } => ("mix", vec![text("weight", *weight)]),
                    NodeKind::Layer { .. } => ("layer", vec![]),
                    NodeKind::Coverage { weight, .. } => ("coverage", vec![text("weight", *weight)]),
                    NodeKind::Add { .. } => ("add", vec![]),
                };
                ReportNode {
                    id: i as u32,
                    depth: analysis.depth[i],
                    kind,
                    location: node.location.clone(),
                    fields,
                    features: analysis.features[i].iter().copied().collect(),
                    children: children(&node.kind).into_iter().map(|c| c.0).collect(),
                }
            })
            .collect();
        Report {
            material: def.name.clone(),
            location: def.location.clone(),
            root: def.root.0,
            nodes,
            closures: analysis.closures.iter().map(|c| c.0).collect(),
            features: analysis.features().into_iter().collect(),
            energy_conserving: analysis.energy_conserving(),
            energy_reasons: analysis.breaches.iter().map(breach_text).collect(),
            gbuffer_bytes_per_pixel: None,
            budget: None,
            wgsl_bytes: None,
            compile_ms: None,
        }
    }
}

fn breach_text(breach: &Breach) -> String {
    match breach {
        Breach::Add(at) => format!("add at {at}"),
        Breach::OutOfRange { field, value, location } => {
            let range = match field.range() {
                Some((lo, hi)) if hi == f32::MAX => format!("≥ {lo:?}"),
                Some((lo, hi)) => format!("in [{lo:?}, {hi:?}]"),
                None => "finite".to_owned(),
            };
            format!("{} = {} at {location}, not {range}", field.name(), value_text(*value))
        }
    }
}

/// A constant as the language writes it.
pub fn value_text(value: Value) -> String {
    match value {
        Value::Float(x) => format!("{x:?}"),
        Value::Vec3([r, g, b]) if r == g && g == b => format!("grey({r:?})"),
        Value::Vec3([r, g, b]) => format!("rgb({r:?}, {g:?}, {b:?})"),
        Value::Texture(i) => format!("texture {i}"),
    }
}

/// Binding strength, for the parentheses the printed text needs.
fn precedence(kind: &ExprKind) -> u8 {
    match kind {
        ExprKind::Binary(BinOp::Add | BinOp::Sub, ..) => 1,
        ExprKind::Binary(BinOp::Mul | BinOp::Div, ..) => 2,
        ExprKind::Neg(_) => 3,
        ExprKind::Const(_) | ExprKind::Param(_) | ExprKind::Call(..) => 4,
    }
}

/// An expression printed back in the language's syntax, parameters by name,
/// with only the parentheses its structure needs (operators group to the
/// left).
pub fn expr_text(def: &Definition, expr: ExprId) -> String {
    let kind = &def.expr(expr).kind;
    let operand = |e: ExprId, tighter_than: u8| {
        let text = expr_text(def, e);
        if precedence(&def.expr(e).kind) < tighter_than { format!("({text})") } else { text }
    };
    match kind {
        ExprKind::Const(v) => value_text(*v),
        ExprKind::Param(i) => def.params[*i as usize].name.clone(),
        ExprKind::Neg(x) => format!("-{}", operand(*x, 3)),
        ExprKind::Binary(op, a, b) => {
            let p = precedence(kind);
            let symbol = match op {
                BinOp::Add => "+",
                BinOp::Sub => "-",
                BinOp::Mul => "*",
                BinOp::Div => "/",
            };
            format!("{} {symbol} {}", operand(*a, p), operand(*b, p + 1))
        }
        ExprKind::Call(f, args) => {
            let args: Vec<String> = args.iter().map(|&a| expr_text(def, a)).collect();
            format!("{}({})", f.name(), args.join(", "))
        }
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::super::analysis::analyse;
    use super::super::build::Build;
    use super::super::tree::{Builtin, Field, Type};
    use super::*;

    fn at(line: u32) -> serde_json::Value {
        json!({ "file": "test.mat", "line": line, "column": 1, "end_line": line, "end_column": 2 })
    }

    #[test]
    fn expressions_print_back_with_the_parentheses_they_need() {
        let mut b = Build::new("m");
        let p = b.param("paint", Type::Color, Value::Vec3([0.5, 0.0, 0.0]), None);
        let q = b.param("amount", Type::Float, Value::Float(0.5), Some((0.0, 1.0)));
        let one = b.float(1.0);
        let diff = b.bin(BinOp::Sub, one, q);
        let scaled = b.bin(BinOp::Mul, p, diff);
        let nested = b.bin(BinOp::Sub, q, diff);
        let left = b.bin(BinOp::Sub, diff, q);
        let neg = b.neg(diff);
        let call = b.call(Builtin::Lerp, &[p, scaled, q]);
        let s = b.slab(&[]);
        let def = b.finish(s);
        assert_eq!(expr_text(&def, scaled), "paint * (1.0 - amount)");
        assert_eq!(expr_text(&def, nested), "amount - (1.0 - amount)");
        assert_eq!(expr_text(&def, left), "1.0 - amount - amount");
        assert_eq!(expr_text(&def, neg), "-(1.0 - amount)");
        assert_eq!(expr_text(&def, call), "lerp(paint, paint * (1.0 - amount), amount)");
        assert_eq!(value_text(Value::Vec3([0.8; 3])), "grey(0.8)");
        assert_eq!(value_text(Value::Vec3([0.55, 0.02, 0.03])), "rgb(0.55, 0.02, 0.03)");
    }

    #[test]
    fn a_layered_material_reports_its_tree() {
        // layer(coat, mix(plastic(paint), metal, 0.3)), the coat's roughness
        // a parameter, its base colour `grey(0.5 - 0.5)` folded.
        let mut b = Build::new("paint");
        let paint = b.param("paint", Type::Color, Value::Vec3([0.55, 0.02, 0.03]), None);
        let plastic = b.slab(&[(Field::BaseColor, paint)]);
        let one = b.float(1.0);
        let metal = b.slab(&[(Field::BaseMetalness, one)]);
        let w = b.float(0.3);
        let base = b.mix(plastic, metal, w);
        let half = b.float(0.5);
        let zero = b.bin(BinOp::Sub, half, half);
        let black = b.call(Builtin::Grey, &[zero]);
        let rough = b.param("coat_roughness", Type::Float, Value::Float(0.03), Some((0.0, 1.0)));
        let coat = b.slab(&[(Field::BaseColor, black), (Field::SpecularRoughness, rough)]);
        let root = b.layer(coat, base);
        let analysis = analyse(&b.finish(root));
        let mut report = Report::new(&analysis);
        report.budget = Some(Budget::of(&super::super::simplify::simplify(&analysis.def, 28)));
        report.gbuffer_bytes_per_pixel = Some(36);
        report.wgsl_bytes = Some(4096);
        let expected = json!({
            "material": "paint",
            "location": { "file": "test.mat", "line": 1, "column": 1, "end_line": 1, "end_column": 1 },
            "root": 4,
            "nodes": [
                { "id": 0, "depth": 2, "kind": "slab", "location": at(3),
                  "fields": [{ "field": "base_color", "value_text": "paint" }],
                  "features": ["diffuse", "specular"], "children": [] },
                { "id": 1, "depth": 2, "kind": "slab", "location": at(5),
                  "fields": [{ "field": "base_metalness", "value_text": "1.0" }],
                  "features": ["metal"], "children": [] },
                { "id": 2, "depth": 1, "kind": "mix", "location": at(7),
                  "fields": [{ "field": "weight", "value_text": "0.3" }],
                  "features": [], "children": [0, 1] },
                { "id": 3, "depth": 1, "kind": "slab", "location": at(13),
                  "fields": [
                      { "field": "base_color", "value_text": "grey(0.0)" },
                      { "field": "specular_roughness", "value_text": "coat_roughness" },
                  ],
                  "features": ["specular"], "children": [] },
                { "id": 4, "depth": 0, "kind": "layer", "location": at(14),
                  "fields": [], "features": [], "children": [3, 2] },
            ],
            "closures": [0, 1, 3],
            "features": ["diffuse", "specular", "metal"],
            "energy_conserving": true,
            "energy_reasons": [],
            "gbuffer_bytes_per_pixel": 36,
            // The mix first (deepest), then the coat into a haze lobe.
            "budget": {
                "budget": 28, "bytes_before": 56, "bytes_after": 28,
                "class_before": "complex", "class_after": "single", "simplified": true,
                "rules": [
                    { "rule": "mix", "node": 2, "location": at(7), "bytes": 40 },
                    { "rule": "layer", "node": 4, "location": at(14), "bytes": 28 },
                ],
                "closures_kept": 1,
            },
            "wgsl_bytes": 4096,
            "compile_ms": null,
        });
        assert_eq!(serde_json::to_value(&report).unwrap(), expected);
    }

    #[test]
    fn a_pruned_add_with_a_bright_colour_says_why_it_is_not_energy_conserving() {
        // coverage(add(mix(a, b, 1.0), slab { base_color: 1.2 }), 1.0):
        // the coverage and the mix are pruned, the add and the colour stay.
        let mut b = Build::new("glow");
        let dull = b.slab(&[]);
        let sheen = b.float(1.0);
        let fuzzy = b.slab(&[(Field::FuzzWeight, sheen)]);
        let m = b.mix(dull, fuzzy, sheen);
        let bright = b.float(1.2);
        let hot = b.slab(&[(Field::BaseColor, bright)]);
        let sum = b.add(m, hot);
        let full = b.coverage(sum, sheen);
        let mut report = Report::new(&analyse(&b.finish(full)));
        report.gbuffer_bytes_per_pixel = Some(24);
        let value = serde_json::to_value(&report).unwrap();
        let expected = json!({
            "material": "glow",
            "location": { "file": "test.mat", "line": 1, "column": 1, "end_line": 1, "end_column": 1 },
            "root": 2,
            "nodes": [
                { "id": 0, "depth": 1, "kind": "slab", "location": at(3),
                  "fields": [{ "field": "fuzz_weight", "value_text": "1.0" }],
                  "features": ["diffuse", "specular", "fuzz"], "children": [] },
                { "id": 1, "depth": 1, "kind": "slab", "location": at(6),
                  "fields": [{ "field": "base_color", "value_text": "1.2" }],
                  "features": ["diffuse", "specular"], "children": [] },
                { "id": 2, "depth": 0, "kind": "add", "location": at(7),
                  "fields": [], "features": [], "children": [0, 1] },
            ],
            "closures": [0, 1],
            "features": ["diffuse", "specular", "fuzz"],
            "energy_conserving": false,
            "energy_reasons": [
                "base_color = 1.2 at test.mat:5:1, not in [0.0, 1.0]",
                "add at test.mat:7:1",
            ],
            "gbuffer_bytes_per_pixel": 24,
            "budget": null,
            "wgsl_bytes": null,
            "compile_ms": null,
        });
        assert_eq!(value, expected);
    }
}
