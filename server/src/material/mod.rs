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
pub mod front;
pub mod gltf;
pub mod operators;
pub mod pack;
pub mod report;
pub mod simple;
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
    pub definitions: Vec<Definition>,
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
    /// The WGSL module every material pass imports.
    pub fn wgsl(&self) -> String {
        back::wgsl(&self.definitions, back::Bindings::RENDERER)
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
