//! The materials report (`GET /api/materials`, the `materials` event): the
//! scene's material instances with their parameters, each saying which
//! scene override path sets it, beside their definitions' compile reports.

use crate::diag::display_path;
use crate::loaded::Loaded;
use crate::material::Program;
use crate::material::tree::{Param, Type, Value};
use crate::protocol::{MaterialEntry, MaterialParam, MaterialsReport};
use crate::scene::MaterialSource;

/// The report of `loaded`'s materials; `scene` is the scene file as shown.
pub fn report(scene: &str, loaded: &Loaded) -> MaterialsReport {
    let program = &loaded.materials;
    let materials = loaded
        .scene
        .materials
        .iter()
        .zip(&program.instances)
        .enumerate()
        .map(|(i, (m, instance))| {
            let def = &program.definitions[instance.definition as usize];
            // The shorthand's parameters are the entry's own keys; a
            // material file's live in its `params` table.
            let (file, prefix) = match &m.source {
                MaterialSource::Shorthand { .. } => (None, format!("materials[{i}]")),
                MaterialSource::File { file, .. } => (Some(file.clone()), format!("materials[{i}].params")),
            };
            let params = def.params.iter().zip(&instance.values).map(|(p, v)| param(program, p, *v, &prefix)).collect();
            MaterialEntry {
                index: i as u32,
                name: m.name.clone(),
                file,
                material: def.name.clone(),
                definition: instance.definition,
                params,
            }
        })
        .collect();
    MaterialsReport { scene: scene.to_owned(), materials, definitions: loaded.reports.to_vec() }
}

fn param(program: &Program, p: &Param, value: Value, prefix: &str) -> MaterialParam {
    let ty = match p.ty {
        Type::Float => "float",
        Type::Color => "color",
        Type::Vec3 => "vec3",
        Type::Texture => "texture",
    };
    MaterialParam {
        name: p.name.clone(),
        path: format!("{prefix}.{}", p.name),
        ty,
        value: json(program, value),
        default: json(program, p.default),
        min: p.range.map(|r| r.0),
        max: p.range.map(|r| r.1),
        unit: p.unit.clone(),
        doc: p.doc.clone(),
    }
}

/// A texture is shown as the path of its image.
fn json(program: &Program, v: Value) -> serde_json::Value {
    match v {
        Value::Float(x) => x.into(),
        Value::Vec3(c) => c.to_vec().into(),
        Value::Texture(k) => display_path(&program.textures[k as usize].path).into(),
    }
}
