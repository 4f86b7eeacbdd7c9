//! The materials report (`GET /api/materials`, the `materials` event): the
//! scene's material instances with their parameters, each saying which
//! scene override path sets it, beside their definitions' compile reports.

use crate::diag::display_path;
use crate::loaded::Loaded;
use crate::material::Program;
use crate::material::report::Report;
use crate::material::tree::{Param, Type, Value};
use crate::protocol::{MaterialEntry, MaterialParam, MaterialsReport};
use crate::scene::MaterialSource;

/// The report of `loaded`'s materials; `scene` is the scene file as shown.
pub fn report(scene: &str, loaded: &Loaded) -> MaterialsReport {
    let program = &loaded.materials;
    let entries = loaded.scene.materials.iter().zip(&program.instances).enumerate().map(|(i, (m, instance))| {
        let def = &program.definitions[instance.definition as usize];
        // The shorthand's parameters are the entry's own keys; a
        // material file's live in its `params` table.
        let (file, prefix) = match &m.source {
            MaterialSource::Shorthand { .. } => (None, format!("materials[{i}]")),
            MaterialSource::File { file, .. } => (Some(file.clone()), format!("materials[{i}].params")),
        };
        entry(program, i, m.name.clone(), file, def.name.clone(), Some(&prefix))
    });
    // A glTF's own materials: the instances past the scene's entries, each
    // named by its definition (`FILE::MATERIAL`); no override sets them.
    let gltf = program.instances.iter().enumerate().skip(loaded.scene.materials.len()).map(|(i, instance)| {
        let name = program.definitions[instance.definition as usize].name.clone();
        let (file, material) = name.rsplit_once("::").map_or((None, name.clone()), |(f, m)| (Some(f.to_owned()), m.to_owned()));
        entry(program, i, name, file, material, None)
    });
    let materials = entries.chain(gltf).collect();
    // Its words in the material buffer, and the inspection targets every
    // material shares.
    let inspection = crate::render::passes::gbuffer::BYTES_PER_PIXEL;
    let definitions = loaded
        .reports
        .iter()
        .map(|r| Report { gbuffer_bytes_per_pixel: r.budget.as_ref().map(|b| b.bytes_after + inspection), ..r.clone() })
        .collect();
    MaterialsReport { scene: scene.to_owned(), materials, definitions }
}

/// Instance `i`'s entry; `prefix` is where its parameters' override paths
/// start (`None`: it has none).
fn entry(program: &Program, i: usize, name: String, file: Option<String>, material: String, prefix: Option<&str>) -> MaterialEntry {
    let instance = &program.instances[i];
    let def = &program.definitions[instance.definition as usize];
    let params = def.params.iter().zip(&instance.values).map(|(p, v)| param(program, p, *v, prefix)).collect();
    MaterialEntry { index: i as u32, name, file, material, definition: instance.definition, params }
}

fn param(program: &Program, p: &Param, value: Value, prefix: Option<&str>) -> MaterialParam {
    let ty = match p.ty {
        Type::Float => "float",
        Type::Color => "color",
        Type::Vec3 => "vec3",
        Type::Texture => "texture",
    };
    MaterialParam {
        name: p.name.clone(),
        path: prefix.map(|prefix| format!("{prefix}.{}", p.name)),
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    /// The showcase's glTF crate names no material: its two glTF materials
    /// follow the scene's entries, at the instance indices the G-buffer
    /// stores, with no override path.
    #[test]
    fn a_gltfs_own_materials_follow_the_scenes_and_have_no_override_path() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/showcase.toml");
        let loaded = crate::loaded::load(&path).unwrap_or_else(|d| panic!("{d}"));
        let r = super::report("showcase.toml", &loaded);
        assert_eq!(r.materials.len(), loaded.materials.instances.len(), "one entry per instance");
        let scene = loaded.scene.materials.len();
        let gltf: Vec<_> = r.materials[scene..].iter().collect();
        assert_eq!(gltf.len(), 2, "{:?}", r.materials.iter().map(|m| &m.name).collect::<Vec<_>>());
        for (k, m) in gltf.iter().enumerate() {
            assert_eq!(m.index as usize, scene + k);
            assert!(m.file.as_deref().is_some_and(|f| f.ends_with(".gltf")), "{:?}", m.file);
            assert_eq!(m.name, format!("{}::{}", m.file.as_deref().unwrap(), m.material));
            assert!(!m.params.is_empty() && m.params.iter().all(|p| p.path.is_none()), "{}", m.name);
        }
        assert!(r.materials[..scene].iter().all(|m| m.params.iter().all(|p| p.path.is_some())));
    }
}
