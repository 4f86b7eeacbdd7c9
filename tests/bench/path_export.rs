//! `bench-path-export`: a loupe scene as another renderer can read it, for
//! comparing the path tracer with Mitsuba 3 (`bench/mitsuba/paths.py`).
//! It writes exactly the triangles the path tracer traces
//! (`render::scene_gpu::world_triangles`), one binary little-endian PLY per
//! object in world space (flat: three vertices per triangle, no normals),
//! and `scene.json` with the camera, output size, materials, lights and
//! environment in loupe's units:
//!
//! - point and spot `radiant_intensity`: W/sr per channel (colour × intensity);
//!   spot cones as loupe's half-angles (smoothstep in cosine between them);
//! - directional `irradiance`: W/m² on a surface facing the light;
//! - rect `radiance`: emitted radiance, on the side `normal` points to (both
//!   with `two_sided`), spanning ±`half_size` along `right` and `up`;
//! - environment: radiance from unit direction d is
//!   `intensity · mix(bottom, top, d.y · 0.5 + 0.5)`.
//!
//! Media are not exported (only counted): the comparison is of surfaces.
//!
//! ```sh
//! cargo run --release -p loupe-tests --bin bench-path-export -- scenes/showcase.toml /tmp/showcase
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use glam::Vec3;
use loupe::scene::LightKind;
use serde_json::{Value, json};

/// One object's triangles as a PLY mesh; vertices are not shared, so every
/// triangle keeps its own (flat) normal.
fn write_ply(path: &Path, tris: &[[Vec3; 3]]) -> std::io::Result<()> {
    let n = tris.len();
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {n}\nproperty list uchar int vertex_indices\nend_header\n",
        3 * n
    )
    .into_bytes();
    for v in tris.iter().flatten() {
        for c in v.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in 0..n as i32 {
        out.push(3);
        for k in 0..3 {
            out.extend_from_slice(&(3 * i + k).to_le_bytes());
        }
    }
    std::fs::write(path, out)
}

fn scaled(color: [f32; 3], intensity: f32) -> [f32; 3] {
    color.map(|c| c * intensity)
}

fn light_json(l: &loupe::scene::Light) -> Value {
    let power = scaled(l.color, l.intensity);
    match l.kind {
        LightKind::Directional { direction } => json!({"type": "directional", "direction": direction, "irradiance": power}),
        LightKind::Point { position } => json!({"type": "point", "position": position, "radiant_intensity": power}),
        LightKind::Spot { position, direction, inner_deg, outer_deg } => json!({
            "type": "spot", "position": position, "direction": direction,
            "inner_deg": inner_deg, "outer_deg": outer_deg, "radiant_intensity": power,
        }),
        LightKind::Rect { position, direction, size, two_sided } => {
            // The emitter's axes as `scene_gpu::light_bytes` builds them
            // (width along `right`, height along `up`).
            let n = Vec3::from(direction);
            let helper = if n.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
            let right = helper.cross(n).normalize();
            let up = n.cross(right);
            json!({
                "type": "rect", "position": position, "normal": direction,
                "right": right.to_array(), "up": up.to_array(),
                "half_size": [size[0] * 0.5, size[1] * 0.5], "two_sided": two_sided, "radiance": power,
            })
        }
    }
}

fn export(scene_path: &Path, out: &Path) -> Result<usize, String> {
    let loaded = loupe::scene::load(scene_path).map_err(|d| d.to_string())?;
    let scene = &loaded.scene;
    let tris = loupe::render::scene_gpu::world_triangles(scene, &loaded.meshes);
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut objects = Vec::new();
    for (index, o) in scene.objects.iter().enumerate() {
        let mine: Vec<[Vec3; 3]> = tris.iter().filter(|(_, id)| id[0] == index as u32).map(|(t, _)| *t).collect();
        // An empty mesh has nothing to trace; other renderers reject it.
        if mine.is_empty() {
            continue;
        }
        let ply = format!("object-{index}.ply");
        write_ply(&out.join(&ply), &mine).map_err(|e| format!("{ply}: {e}"))?;
        // Mitsuba's principled BSDF takes the shorthand's three values;
        // a material from a `.mat` file has no counterpart there.
        let loupe::scene::MaterialSource::Shorthand { base_color, metallic, roughness } = scene.materials[o.material].source else {
            return Err(format!("object {}: only the scene file's shorthand materials export to Mitsuba", o.name));
        };
        objects.push(json!({
            "name": o.name, "ply": ply, "triangles": mine.len(),
            "base_color": base_color, "metallic": metallic, "roughness": roughness,
        }));
    }
    let (c, e) = (&scene.camera, &scene.environment);
    let doc = json!({
        "scene": loupe::diag::display_path(scene_path),
        "width": scene.width, "height": scene.height,
        "camera": {"position": c.position, "target": c.target, "up": c.up, "fov_deg": c.fov_deg, "near": c.near, "far": c.far},
        "objects": objects,
        "lights": scene.lights.iter().map(light_json).collect::<Vec<_>>(),
        "environment": {"top": e.top, "bottom": e.bottom, "intensity": e.intensity},
        "media": scene.media.len(),
    });
    let text = serde_json::to_string_pretty(&doc).expect("JSON values serialize");
    std::fs::write(out.join("scene.json"), text).map_err(|e| format!("scene.json: {e}"))?;
    Ok(tris.len())
}

fn main() -> ExitCode {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [scene, out] = args.as_slice() else {
        eprintln!("usage: bench-path-export SCENE.toml OUT_DIR");
        return ExitCode::FAILURE;
    };
    match export(scene, out) {
        Ok(n) => {
            println!("{}: {n} triangles -> {}", scene.display(), out.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{}: {e}", scene.display());
            ExitCode::FAILURE
        }
    }
}
