//! Objects drawn with their glTF's own materials (`Object::gltf_materials`:
//! a mesh object that names no material). Each such object is split into
//! one object per glTF material its primitives use, each drawing those
//! primitives' triangles with an instance appended to the program (past
//! the scene's own `[[materials]]`). Splitting the object keeps one
//! material per draw, so nothing downstream changes: the G-buffer's
//! material index comes from the object as before, and the path tracer's
//! per-triangle object carries it too.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use crate::diag::{Diagnostic, LineIndex, display_path};
use crate::material::gltf::{self, Document};
use crate::material::report::Report;
use crate::material::{Instance, Program};
use crate::mesh::{Doc, MeshData};
use crate::scene::{Geometry, Object, Scene};

/// Splits `scene`'s glTF-material objects (see the module doc), adding
/// their meshes to `meshes` and their definitions, reports and instances
/// to `program` and `reports`. Returns what the glTF materials could not
/// represent, as warnings located in the glTF files.
pub(super) fn split(
    dir: &Path,
    scene: &mut Scene,
    meshes: &mut BTreeMap<String, Arc<MeshData>>,
    program: &mut Program,
    reports: &mut Vec<Report>,
) -> Result<Vec<Diagnostic>, Diagnostic> {
    let mut warnings = Vec::new();
    // Per glTF file: per part, its mesh key, instance and name.
    let mut done: BTreeMap<String, Vec<(String, usize, String)>> = BTreeMap::new();
    let mut objects = Vec::with_capacity(scene.objects.len());
    for o in std::mem::take(&mut scene.objects) {
        let Geometry::Mesh { file, at } = &o.geometry else {
            objects.push(o);
            continue;
        };
        if !o.gltf_materials {
            objects.push(o);
            continue;
        }
        if !done.contains_key(file) {
            let start = Instant::now();
            let path = dir.join(file);
            let display = display_path(&path);
            let parts = crate::mesh::load_gltf_parts(&path, &display).map_err(|d| d.with_label(at.clone(), "referenced here", false))?;
            let doc = Doc { display: &display, text: parts.text.as_deref().map(|t| (t, LineIndex::new(t))) };
            let document = Document { json: &parts.json, doc: &doc, dir: path.parent().unwrap_or(Path::new(".")) };
            warnings.extend(gltf::document_warnings(&document));
            let parse_ms = start.elapsed().as_secs_f64() * 1e3;
            let mut made = Vec::new();
            for (k, (material, mesh)) in parts.parts.into_iter().enumerate() {
                let start = Instant::now();
                let name = material_name(&parts.json, material);
                let imported = gltf::definition(&document, material, &format!("{display}::{name}"));
                warnings.extend(imported.warnings);
                let mut def = imported.definition;
                super::index_textures(program, &mut def, &imported.textures);
                let analysed = crate::material::analysed(&def).map_err(|ds| super::first_of(ds, at))?;
                let (def, report) = super::compiled(analysed, start, parse_ms);
                let compensated = super::compensated(scene, &def);
                let values = def.params.iter().map(|p| p.default).collect();
                program.definitions.push(def);
                reports.push(report);
                program.instances.push(Instance { definition: program.definitions.len() as u32 - 1, values, compensated });
                let key = format!("{file}#material{k}");
                meshes.insert(key.clone(), Arc::new(mesh));
                made.push((key, program.instances.len() - 1, name));
            }
            done.insert(file.clone(), made);
        }
        let parts = &done[file];
        for (key, instance, name) in parts {
            let name = if parts.len() == 1 { o.name.clone() } else { format!("{}/{name}", o.name) };
            let geometry = Geometry::Mesh { file: key.clone(), at: at.clone() };
            objects.push(Object { name, geometry, material: *instance, ..o.clone() });
        }
    }
    if let Some(o) = objects.get(crate::scene::MAX_OBJECTS).filter(|_| objects.len() > crate::scene::MAX_OBJECTS) {
        let at = match &o.geometry {
            Geometry::Mesh { at, .. } => Some(at.clone()),
            Geometry::Shape(_) => None,
        };
        let message = format!("split by their glTF materials, the objects number {}: at most {}", objects.len(), crate::scene::MAX_OBJECTS);
        let d = Diagnostic::error(crate::diag::Code::Scene, message);
        return Err(match at {
            Some(at) => d.with_label(at, "this object's glTF materials", true),
            None => d,
        });
    }
    scene.objects = objects;
    Ok(warnings)
}

/// A glTF material's name: its `name`, else `material{i}`; `default` for
/// primitives without one.
fn material_name(json: &serde_json::Value, material: Option<usize>) -> String {
    let Some(i) = material else { return "default".to_owned() };
    let named = json.get("materials").and_then(|m| m.get(i)).and_then(|m| m.get("name")).and_then(|n| n.as_str());
    named.filter(|n| !n.is_empty()).map_or_else(|| format!("material{i}"), str::to_owned)
}
