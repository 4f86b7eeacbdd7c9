//! The files a glTF reads besides itself (external buffers), found even
//! when the file does not load: hot reload must watch a `.bin` that is
//! missing now and written next.

use std::path::{Path, PathBuf};

use super::uri::{self, Uri};

/// External buffer files of the glTF at `path`, best effort: a file that
/// cannot be read or parsed has none (its own diagnostics come from
/// loading it).
pub fn external_buffers(path: &Path) -> Vec<PathBuf> {
    let Ok(bytes) = std::fs::read(path) else { return Vec::new() };
    let json = if bytes.starts_with(super::glb::MAGIC) {
        match super::glb::parse(&bytes) {
            Ok(glb) => glb.json.to_vec(),
            Err(_) => return Vec::new(),
        }
    } else {
        bytes
    };
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(&json) else { return Vec::new() };
    let base = path.parent().unwrap_or(Path::new("."));
    doc["buffers"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|b| b["uri"].as_str())
        .filter_map(|u| match uri::parse(u) {
            Ok(Uri::Relative(file)) => Some(base.join(file)),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn external_buffers_are_found_even_when_missing_and_data_uris_are_not_files() {
        let dir = std::env::temp_dir().join(format!("loupe-mesh-deps-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gltf = dir.join("m.gltf");
        std::fs::write(&gltf, r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"geo%20main.bin","byteLength":4},{"uri":"data:application/octet-stream;base64,AAAAAA==","byteLength":4}]}"#).unwrap();
        assert_eq!(external_buffers(&gltf), vec![dir.join("geo main.bin")], "percent-decoded, relative to the glTF");
        std::fs::write(&gltf, "{ not json").unwrap();
        assert_eq!(external_buffers(&gltf), Vec::<PathBuf>::new());
        let knot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/meshes/torus_knot.gltf");
        assert_eq!(external_buffers(&knot), vec![knot.parent().unwrap().join("torus_knot.bin")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
