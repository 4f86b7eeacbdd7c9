//! Materials: a layered material language compiled to WGSL for the raster
//! and the path tracer. Laid out as naga is: the front end (the `*.mat`
//! parser, and `shorthand` for the scene file's own materials) → `tree`
//! (the IR) → `analysis` (folding, pruning, features, the `report`) →
//! `back` (the `loupe::material` WGSL module).
//! [docs/materials.md](../../../docs/materials.md) is the language.

pub mod analysis;
pub mod back;
#[cfg(test)]
mod build;
pub mod features;
pub mod front;
pub mod gltf;
pub mod layout;
pub mod operators;
pub mod pack;
pub mod report;
pub mod simple;
pub mod simplify;
pub mod single;
pub mod texture;
pub mod tree;

use crate::diag::{Code, Diagnostic, Location};
use std::sync::Arc;

use tree::{Definition, Expr, ExprId, ExprKind, Field, Node, NodeId, NodeKind, Param, Slab, TextureSource, Type, Value};

/// The materials a scene uses, compiled: each definition once, and one
/// instance per `[[materials]]` entry (in the scene's order, so an
/// object's material index is its instance).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Program {
    /// The full definitions: the path tracer's truth.
    pub definitions: Vec<Definition>,
    /// Each of `definitions` brought to `quality.material_bytes`, index for
    /// index (the definition itself where it fits): what the raster
    /// compiles. Empty until `simplify` runs; the raster then compiles
    /// `definitions`.
    pub simplified: Vec<simplify::Simplified>,
    /// `quality.path_simplified_materials`: the path tracer compiles the
    /// simplified definitions too, to see what the budget costs.
    pub path_simplified: bool,
    pub instances: Vec<Instance>,
    /// The images the definitions' defaults and the instances name, each
    /// once (`Value::Texture` indexes it).
    pub textures: Vec<TextureSource>,
    /// Those images decoded, one layer each (`textures[i]` is layer `i`).
    pub layers: Arc<texture::Layers>,
}

/// A definition with values for its parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Instance {
    pub definition: u32,
    /// One per `Definition::params`.
    pub values: Vec<Value>,
    /// Whether its GGX lobes are compensated for multiple scattering: the
    /// definition asks for it and `quality.energy_compensation` is on. A
    /// value, so the setting rebuilds no pipeline.
    pub compensated: bool,
}

impl Program {
    /// Brings every definition to `budget` bytes per pixel.
    pub fn simplify(&mut self, budget: u32, path_simplified: bool) {
        self.simplified = self.definitions.iter().map(|d| simplify::simplify(d, budget)).collect();
        self.path_simplified = path_simplified;
    }

    /// The raster's module (`back::IMPORT_PATH`): the simplified definitions.
    pub fn wgsl(&self) -> String {
        self.module(true, back::IMPORT_PATH)
    }

    /// The path tracer's module (`back::PATH_IMPORT_PATH`): the full
    /// definitions, or the simplified ones when `path_simplified`.
    pub fn path_wgsl(&self) -> String {
        self.module(self.path_simplified, back::PATH_IMPORT_PATH)
    }

    fn module(&self, simplified: bool, import_path: &str) -> String {
        let (definitions, flags) = self.compiled(simplified);
        back::module(&definitions, back::Bindings::RENDERER, import_path, &flags)
    }

    /// The definitions a module compiles, and which were simplified.
    fn compiled(&self, simplified: bool) -> (Vec<Definition>, Vec<bool>) {
        if simplified && !self.simplified.is_empty() {
            self.simplified.iter().map(|s| (s.def.clone(), s.simplified())).unzip()
        } else {
            (self.definitions.clone(), vec![false; self.definitions.len()])
        }
    }

    /// The definitions the raster compiles: simplified to the budget.
    pub fn raster_definitions(&self) -> Vec<Definition> {
        self.compiled(true).0
    }

    /// The material buffer's words per pixel: the most a pixel of the
    /// raster's (simplified) definitions takes, within the budget.
    pub fn raster_words(&self) -> u32 {
        pack::program_words(&self.raster_definitions())
    }

    /// Whether `other` generates the same two modules.
    pub fn same_code(&self, other: &Program) -> bool {
        self.definitions == other.definitions && self.simplified == other.simplified && self.path_simplified == other.path_simplified
    }

    /// The two buffers the module reads: the parameters (one `vec4` each,
    /// instance after instance) and per instance its definition and first
    /// slot. Never empty: a scene without materials binds one zero entry.
    pub fn buffers(&self) -> (Vec<[f32; 4]>, Vec<[u32; 4]>) {
        let mut params = Vec::new();
        let mut instances = Vec::new();
        for i in &self.instances {
            instances.push([i.definition, params.len() as u32, u32::from(i.compensated), 0]);
            params.extend(i.values.iter().map(|v| match *v {
                Value::Float(x) => [x, 0.0, 0.0, 0.0],
                Value::Vec3([r, g, b]) => [r, g, b, 0.0],
                // Its layer in the texture array.
                Value::Texture(layer) => [layer as f32, 0.0, 0.0, 0.0],
            }));
        }
        if params.is_empty() {
            params.push([0.0; 4]);
        }
        if instances.is_empty() {
            instances.push([0; 4]);
        }
        (params, instances)
    }
}

/// A definition through the analysis passes: folded and pruned, as the
/// back end compiles it. A constant that is no finite number (a division
/// by zero, the root of a negative) is an error where it is written.
pub fn analysed(d: &Definition) -> Result<analysis::Analysis, Vec<Diagnostic>> {
    let a = analysis::analyse(d);
    if a.non_finite.is_empty() {
        return Ok(a);
    }
    Err(a
        .non_finite
        .iter()
        .map(|at| {
            Diagnostic::error(Code::Material, format!("material `{}`: this is not a finite number", d.name)).with_label(
                at.clone(),
                "a division by zero, or a root or power of a negative number",
                true,
            )
        })
        .collect())
}

/// The definition of the scene file's shorthand (`base_color`, `metallic`,
/// `roughness`): one slab with those as parameters, without energy
/// compensation, so it renders what loupe rendered before the language.
pub fn shorthand(at: Location) -> Definition {
    let param = |name: &str, ty, default| Param {
        name: name.to_owned(),
        ty,
        default,
        range: Some((0.0, 1.0)),
        unit: None,
        doc: None,
        location: at.clone(),
    };
    let expr = |i: u32, ty| Expr { kind: ExprKind::Param(i), ty, location: at.clone() };
    Definition {
        name: "shorthand".to_owned(),
        location: at.clone(),
        params: vec![
            param("base_color", Type::Color, Value::Vec3([0.8; 3])),
            param("metallic", Type::Float, Value::Float(0.0)),
            param("roughness", Type::Float, Value::Float(0.5)),
        ],
        exprs: vec![expr(0, Type::Color), expr(1, Type::Float), expr(2, Type::Float)],
        nodes: vec![Node {
            kind: NodeKind::Slab(Slab {
                fields: vec![(Field::BaseColor, ExprId(0)), (Field::BaseMetalness, ExprId(1)), (Field::SpecularRoughness, ExprId(2))],
            }),
            location: at,
        }],
        root: NodeId(0),
        energy_compensation: false,
    }
}

#[cfg(test)]
mod tests;
