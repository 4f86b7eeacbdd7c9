//! Shapes, the bundled meshes and the glTF loader, good input and bad.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::{Value, json};

use super::import::{Limits, load};
use super::math::{Vec3, add, cross, dot, normalize_or_up, scale, sub};
use super::*;
use crate::diag::{Code, Diagnostic};
use crate::testing::line_col;

const NODES: &str = include_str!("fixtures/nodes.gltf");
const TEXTURED: &str = include_str!("fixtures/textured.gltf");

/// Every vertex attribute `encode` can write besides POSITION.
const ALL: &[&str] = &["NORMAL", "TEXCOORD_0", "TANGENT"];

fn close(a: Vec3, b: Vec3, eps: f32) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= eps)
}

/// Indices in range, unit normals, and every triangle wound counter-clockwise
/// seen from the side its vertex normals face.
fn assert_consistent(m: &MeshData) {
    assert_eq!(m.positions.len(), m.normals.len());
    assert_tangent_frames(m);
    assert_eq!(m.indices.len() % 3, 0);
    assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
    for n in &m.normals {
        assert!((dot(*n, *n).sqrt() - 1.0).abs() < 1e-5, "normal {n:?} is not unit length");
    }
    for (k, t) in m.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
        let geometric = normalize_or_up(cross(sub(b, a), sub(c, a)));
        for &i in t {
            let d = dot(geometric, m.normals[i as usize]);
            assert!(d > 0.0, "triangle {k} {t:?} is wound against vertex {i}'s normal (cos {d})");
        }
    }
}

/// One UV and tangent per vertex; every tangent unit length, perpendicular
/// to its normal, with w = ±1; every UV finite.
fn assert_tangent_frames(m: &MeshData) {
    assert_eq!((m.uvs.len(), m.tangents.len()), (m.positions.len(), m.positions.len()));
    for (i, (t, n)) in m.tangents.iter().zip(&m.normals).enumerate() {
        let xyz = [t[0], t[1], t[2]];
        assert!((dot(xyz, xyz).sqrt() - 1.0).abs() < 1e-5, "vertex {i}: tangent {t:?} is not unit length");
        assert!(dot(xyz, *n).abs() < 1e-5, "vertex {i}: tangent {t:?} is not perpendicular to normal {n:?}");
        assert!(t[3] == 1.0 || t[3] == -1.0, "vertex {i}: tangent handedness {}", t[3]);
        assert!(m.uvs[i].iter().all(|c| c.is_finite()), "vertex {i}: uv {:?}", m.uvs[i]);
    }
}

/// Each vertex's tangent lies along its triangles' dP/du (projected on its
/// tangent plane; cosine at least `min_cos`), and its bitangent
/// `cross(n, t) * w` along −dP/dv (up the image), for every triangle whose
/// UVs span an area.
fn assert_tangents_follow_uvs(m: &MeshData, min_cos: f32) {
    for (k, t) in m.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
        let (e1, e2) = (sub(m.positions[b], m.positions[a]), sub(m.positions[c], m.positions[a]));
        let (d1, d2) = ([m.uvs[b][0] - m.uvs[a][0], m.uvs[b][1] - m.uvs[a][1]], [m.uvs[c][0] - m.uvs[a][0], m.uvs[c][1] - m.uvs[a][1]]);
        let r = d1[0] * d2[1] - d2[0] * d1[1];
        if r.abs() < 1e-9 {
            continue;
        }
        let dp_du = scale(sub(scale(e1, d2[1]), scale(e2, d1[1])), 1.0 / r);
        let dp_dv = scale(sub(scale(e2, d1[0]), scale(e1, d2[0])), 1.0 / r);
        for i in [a, b, c] {
            let (n, tangent) = (m.normals[i], m.tangents[i]);
            let xyz = [tangent[0], tangent[1], tangent[2]];
            let along = normalize_or_up(sub(dp_du, scale(n, dot(n, dp_du))));
            let cos = dot(along, xyz);
            assert!(cos >= min_cos, "triangle {k}, vertex {i}: tangent {tangent:?} is {cos} off dP/du {dp_du:?}");
            let bitangent = scale(cross(n, xyz), tangent[3]);
            assert!(dot(bitangent, dp_dv) < 0.0, "triangle {k}, vertex {i}: bitangent {bitangent:?} is not up the image (dP/dv {dp_dv:?})");
        }
    }
}

/// Closed and consistently oriented: every edge, by position, is used once
/// in each direction.
fn assert_closed(m: &MeshData) {
    let key = |i: u32| m.positions[i as usize].map(f32::to_bits);
    let mut edges: HashMap<_, u32> = HashMap::new();
    for t in m.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((key(a), key(b))).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "edge {a:?} → {b:?} is used {n} times");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a:?} → {b:?} has no twin");
    }
}

#[test]
fn sphere_is_a_closed_unit_sphere() {
    let s = sphere();
    assert_consistent(&s);
    assert_closed(&s);
    // A pole vertex per segment, and a seam column in every ring.
    assert_eq!((s.positions.len(), s.triangle_count()), (2 * 48 + 23 * 49, 2 * 48 * 23));
    for (p, n) in s.positions.iter().zip(&s.normals) {
        assert!((dot(*p, *p).sqrt() - 1.0).abs() < 1e-6, "{p:?} is not at radius 1");
        assert_eq!(p, n);
    }
    let (lo, hi) = s.bounds();
    assert!(close(lo, [-1.0; 3], 1e-3) && close(hi, [1.0; 3], 1e-3), "{lo:?} {hi:?}");
}

/// Longitude and latitude: u = φ/2π with φ from +X towards −Z, v = θ/π from
/// the north pole; the tangent is the unit dP/dφ, right-handed.
#[test]
fn sphere_uvs_are_longitude_and_latitude() {
    let s = sphere();
    assert_tangents_follow_uvs(&s, 0.99);
    for (i, (p, uv)) in s.positions.iter().zip(&s.uvs).enumerate() {
        let v = p[1].clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        assert!((uv[1] - v).abs() < 1e-5, "vertex {i} at {p:?}: v {} ≠ {v}", uv[1]);
        if p[1].abs() < 0.999 {
            let phi = (-p[2]).atan2(p[0]).rem_euclid(std::f32::consts::TAU);
            let u = phi / std::f32::consts::TAU;
            // The seam's second column is u = 1 where φ is 0.
            assert!((uv[0] - u).abs() < 1e-5 || ((uv[0] - 1.0).abs() < 1e-5 && u < 1e-5), "vertex {i} at {p:?}: u {} ≠ {u}", uv[0]);
            let east = [-phi.sin(), 0.0, -phi.cos()];
            assert!(close([s.tangents[i][0], s.tangents[i][1], s.tangents[i][2]], east, 1e-5), "vertex {i}: {:?}", s.tangents[i]);
        }
    }
    let (lo, hi) = s
        .uvs
        .iter()
        .fold(([f32::MAX; 2], [f32::MIN; 2]), |(lo, hi), uv| ([lo[0].min(uv[0]), lo[1].min(uv[1])], [hi[0].max(uv[0]), hi[1].max(uv[1])]));
    assert_eq!((lo, hi), ([0.0, 0.0], [1.0, 1.0]));
}

/// Every cube face and the plane span the UV square, corner to corner.
#[test]
fn cube_and_plane_faces_span_the_uv_square() {
    for (name, m) in [("cube", cube()), ("plane", plane())] {
        assert_tangents_follow_uvs(&m, 0.9999);
        for (f, uvs) in m.uvs.chunks_exact(4).enumerate() {
            let mut corners: Vec<[f32; 2]> = uvs.to_vec();
            corners.sort_by(|a, b| a.partial_cmp(b).unwrap());
            assert_eq!(corners, [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0]], "{name} face {f}");
        }
    }
    // The plane's u along +X, the image's top towards −Z.
    let p = plane();
    for (pos, uv) in p.positions.iter().zip(&p.uvs) {
        assert_eq!(*uv, [(pos[0] + 1.0) * 0.5, (pos[2] + 1.0) * 0.5]);
    }
}

#[test]
fn cube_has_flat_faces_at_distance_one() {
    let c = cube();
    assert_consistent(&c);
    assert_closed(&c);
    assert_eq!((c.positions.len(), c.triangle_count()), (24, 12));
    assert_eq!(c.bounds(), ([-1.0; 3], [1.0; 3]));
    for (p, n) in c.positions.iter().zip(&c.normals) {
        assert_eq!(dot(*n, *n), 1.0, "flat normals are axis vectors");
        assert_eq!(dot(*p, *n), 1.0, "{p:?} is not on the face facing {n:?}");
    }
    let mut facing: Vec<_> = c.normals.iter().map(|n| n.map(f32::to_bits)).collect();
    facing.dedup();
    assert_eq!(facing.len(), 6);
}

#[test]
fn plane_faces_up() {
    let p = plane();
    assert_consistent(&p);
    assert_eq!((p.positions.len(), p.triangle_count()), (4, 2));
    assert_eq!(p.bounds(), ([-1.0, 0.0, -1.0], [1.0, 0.0, 1.0]));
    assert!(p.normals.iter().all(|&n| n == [0.0, 1.0, 0.0]));
}

#[test]
fn shapes_by_name() {
    for name in SHAPES {
        assert!(shape(name).is_some_and(|m| m.triangle_count() > 0), "{name}");
    }
    assert_eq!(shape("cube"), Some(cube()));
    assert_eq!(shape("teapot"), None);
}

#[test]
fn vertex_bytes_interleave_position_normal_uv_and_tangent() {
    let c = cube();
    let bytes = c.vertex_bytes();
    assert_eq!(bytes.len(), c.positions.len() * VERTEX_STRIDE);
    let f = |at: usize| f32::from_ne_bytes(bytes[at..at + 4].try_into().unwrap());
    let v = 5;
    let read = |at: usize| [f(at), f(at + 4), f(at + 8)];
    assert_eq!(read(v * VERTEX_STRIDE), c.positions[v]);
    assert_eq!(read(v * VERTEX_STRIDE + 12), c.normals[v]);
    assert_eq!([f(v * VERTEX_STRIDE + 24), f(v * VERTEX_STRIDE + 28)], c.uvs[v]);
    assert_eq!(read(v * VERTEX_STRIDE + 32), c.tangents[v][..3]);
    assert_eq!(f(v * VERTEX_STRIDE + 44), c.tangents[v][3]);
    assert_eq!(MeshData::default().bounds(), ([0.0; 3], [0.0; 3]));
}

/// Writes `files` (name, contents) into a fresh directory, loads the first
/// with the file name as display, and removes them.
fn load_files(files: &[(&str, &[u8])], limits: &Limits) -> Result<MeshData, Diagnostic> {
    static N: AtomicUsize = AtomicUsize::new(0);
    let n = N.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("loupe-mesh-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let result = load(&dir.join(files[0].0), files[0].0, limits);
    std::fs::remove_dir_all(&dir).unwrap();
    result
}

const LIMITS: Limits = Limits { triangles: MAX_TRIANGLES, vertices: MAX_VERTICES, file_bytes: MAX_FILE_BYTES };

fn load_one(name: &str, bytes: &[u8]) -> Result<MeshData, Diagnostic> {
    load_files(&[(name, bytes)], &LIMITS)
}

/// A glTF document holding `mesh` as one primitive, and its binary buffer
/// (`buffers[0]` has no uri yet). POSITION and the `attributes` named
/// (of `ALL`) are interleaved in one strided view. `index_size` is 1, 2 or
/// 4 bytes, or `None` to write every triangle's vertices out in order,
/// unindexed.
fn encode(mesh: &MeshData, index_size: Option<usize>, attributes: &[&str]) -> (Value, Vec<u8>) {
    fn pick<T: Copy>(v: &[T], indices: &[u32]) -> Vec<T> {
        indices.iter().filter_map(|&i| v.get(i as usize).copied()).collect()
    }
    let mesh = match index_size {
        Some(_) => mesh.clone(),
        None => MeshData {
            positions: pick(&mesh.positions, &mesh.indices),
            normals: pick(&mesh.normals, &mesh.indices),
            uvs: pick(&mesh.uvs, &mesh.indices),
            tangents: pick(&mesh.tangents, &mesh.indices),
            indices: (0..mesh.indices.len() as u32).collect(),
        },
    };
    let count = mesh.positions.len();
    fn rows<const N: usize>(v: &[[f32; N]]) -> Vec<Vec<f32>> {
        v.iter().map(|e| e.to_vec()).collect()
    }
    // (name, glTF type, each element's floats)
    let columns: Vec<(&str, &str, Vec<Vec<f32>>)> = [
        ("POSITION", "VEC3", rows(&mesh.positions)),
        ("NORMAL", "VEC3", rows(&mesh.normals)),
        ("TEXCOORD_0", "VEC2", rows(&mesh.uvs)),
        ("TANGENT", "VEC4", rows(&mesh.tangents)),
    ]
    .into_iter()
    .filter(|(name, ..)| *name == "POSITION" || attributes.contains(name))
    .collect();
    let stride: usize = columns.iter().map(|(.., elements)| 4 * elements[0].len()).sum();
    let mut bin = Vec::new();
    for k in 0..count {
        for (.., elements) in &columns {
            bin.extend(elements[k].iter().flat_map(|f| f.to_le_bytes()));
        }
    }
    let (lo, hi) = mesh.bounds();
    let mut accessors = Vec::new();
    let mut attribute_map = json!({});
    let mut offset = 0;
    for (name, type_, elements) in &columns {
        attribute_map[*name] = json!(accessors.len());
        let mut accessor = json!({ "bufferView": 0, "byteOffset": offset, "componentType": 5126, "count": count, "type": type_ });
        if *name == "POSITION" {
            (accessor["min"], accessor["max"]) = (json!(lo), json!(hi));
        }
        accessors.push(accessor);
        offset += 4 * elements[0].len();
    }
    let mut views = vec![json!({ "buffer": 0, "byteOffset": 0, "byteLength": bin.len(), "byteStride": stride, "target": 34962 })];
    let mut primitive = json!({ "attributes": attribute_map, "mode": 4 });
    if let Some(size) = index_size {
        let start = bin.len();
        for &i in &mesh.indices {
            bin.extend_from_slice(&i.to_le_bytes()[..size]);
        }
        let component = match size {
            1 => 5121,
            2 => 5123,
            _ => 5125,
        };
        primitive["indices"] = json!(accessors.len());
        accessors.push(json!({ "bufferView": 1, "componentType": component, "count": mesh.indices.len(), "type": "SCALAR" }));
        views.push(json!({ "buffer": 0, "byteOffset": start, "byteLength": bin.len() - start, "target": 34963 }));
    }
    bin.resize(bin.len().next_multiple_of(4), 0);
    let json = json!({
        "asset": { "version": "2.0", "generator": "loupe mesh tests" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [primitive] }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "byteLength": bin.len() }]
    });
    (json, bin)
}

fn to_glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    text.resize(text.len().next_multiple_of(4), b' ');
    glb::write(&[(glb::CHUNK_JSON, &text), (glb::CHUNK_BIN, bin)])
}

/// A .gltf with its buffer in `mesh.bin` beside it.
fn load_gltf_and_bin(mut json: Value, bin: &[u8]) -> Result<MeshData, Diagnostic> {
    json["buffers"][0]["uri"] = json!("mesh.bin");
    load_files(&[("mesh.gltf", json.to_string().as_bytes()), ("mesh.bin", bin)], &LIMITS)
}

fn assert_same_mesh(got: &MeshData, want: &MeshData) {
    assert_eq!((got.positions.len(), got.indices.len()), (want.positions.len(), want.indices.len()));
    assert_eq!(got.positions, want.positions);
    assert_eq!(got.indices, want.indices);
    assert_eq!(got.uvs, want.uvs);
    for (g, w) in got.normals.iter().zip(&want.normals) {
        assert!(close(*g, *w, 1e-6), "{g:?} ≠ {w:?}");
    }
    for (g, w) in got.tangents.iter().zip(&want.tangents) {
        assert!(close([g[0], g[1], g[2]], [w[0], w[1], w[2]], 1e-6) && g[3] == w[3], "{g:?} ≠ {w:?}");
    }
}

/// The trefoil of `scenes/meshes/torus_knot.gltf`: a tube of radius
/// `TUBE` around the (2, 3) torus knot, scaled to about unit radius, in
/// the XZ plane.
fn torus_knot() -> MeshData {
    const ALONG: u32 = 256;
    const AROUND: u32 = 24;
    const TUBE: f32 = 0.15;
    use std::f32::consts::TAU;
    let curve = |t: f32| {
        let r = 2.0 + (3.0 * t).cos();
        [r * (2.0 * t).cos() / 3.0, (3.0 * t).sin() / 3.0, -r * (2.0 * t).sin() / 3.0]
    };
    let mut m = MeshData::default();
    for i in 0..ALONG {
        let t = TAU * i as f32 / ALONG as f32;
        let (here, ahead) = (curve(t), curve(t + 0.01));
        // A frame that closes on itself around the knot (unlike parallel
        // transport): T along the curve, N towards the sum of two nearby
        // points (roughly away from the centre), B = T × N.
        let tangent = normalize_or_up(sub(ahead, here));
        let binormal = normalize_or_up(cross(tangent, add(ahead, here)));
        let normal = cross(binormal, tangent);
        for j in 0..AROUND {
            let a = TAU * j as f32 / AROUND as f32;
            let n = normalize_or_up(add(scale(normal, a.cos()), scale(binormal, a.sin())));
            m.positions.push(add(here, scale(n, TUBE)));
            m.normals.push(n);
        }
    }
    let v = |i: u32, j: u32| (i % ALONG) * AROUND + j % AROUND;
    for i in 0..ALONG {
        for j in 0..AROUND {
            // ∂p/∂j × ∂p/∂i points out of the tube.
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            m.indices.extend([a, d, c, a, c, b]);
        }
    }
    m
}

fn bundled(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/meshes").join(name)
}

/// `LOUPE_BLESS=1` rewrites the bundled torus knot from `torus_knot()`.
#[test]
fn bundled_torus_knot_loads_as_generated() {
    let want = torus_knot();
    let (gltf, bin) = (bundled("torus_knot.gltf"), bundled("torus_knot.bin"));
    if std::env::var_os("LOUPE_BLESS").is_some() {
        let (mut json, bytes) = encode(&want, Some(2), &["NORMAL"]);
        json["asset"]["generator"] = json!("loupe (server/src/mesh/tests.rs, torus_knot)");
        json["nodes"][0]["name"] = json!("torus_knot");
        json["meshes"][0]["name"] = json!("torus_knot");
        json["buffers"][0]["uri"] = json!("torus_knot.bin");
        std::fs::write(&gltf, serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
        std::fs::write(&bin, bytes).unwrap();
    }
    let got = load_gltf(&gltf, "torus_knot.gltf").unwrap();
    assert_eq!((got.positions.len(), got.triangle_count()), (256 * 24, 2 * 256 * 24));
    assert_eq!(got.indices, want.indices);
    for (g, w) in got.positions.iter().zip(&want.positions).chain(got.normals.iter().zip(&want.normals)) {
        assert!(close(*g, *w, 1e-5), "{g:?} ≠ {w:?}: regenerate with LOUPE_BLESS=1");
    }
    assert_consistent(&got);
    assert_closed(&got);
    // glTF requires POSITION's min and max, exactly the data's bounds.
    let json: Value = serde_json::from_str(&std::fs::read_to_string(&gltf).unwrap()).unwrap();
    let (lo, hi) = got.bounds();
    let f32s = |v: &Value| -> Vec<f32> { v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect() };
    assert_eq!((f32s(&json["accessors"][0]["min"]), f32s(&json["accessors"][0]["max"])), (lo.to_vec(), hi.to_vec()));
    assert!(close(lo, [-0.937, -0.483, -1.092], 1e-3) && close(hi, [1.15, 0.483, 1.092], 1e-3), "{lo:?} {hi:?}");
    let size = std::fs::metadata(&gltf).unwrap().len() + std::fs::metadata(&bin).unwrap().len();
    assert!(size <= 300 << 10, "bundled mesh is {size} bytes");
}

#[test]
fn node_transforms_are_applied() {
    let m = load_gltf(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src/mesh/fixtures/nodes.gltf"), "nodes.gltf").unwrap();
    assert_consistent(&m);
    assert_eq!(m.triangle_count(), 3);
    let want: [(Vec3, [Vec3; 3]); 3] = [
        // nodes[0] translate (10, 0, 0) · scale 2, then its child nodes[1] translate (0, 0, 1)
        ([0.0, 0.0, 1.0], [[10.0, 0.0, 2.0], [12.0, 0.0, 2.0], [10.0, 2.0, 2.0]]),
        // nodes[2]: a quarter turn about +Y takes +X to −Z and +Z to +X
        ([1.0, 0.0, 0.0], [[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
        // nodes[3]: mirrored in X; wound the other way to stay counter-clockwise
        ([0.0, 0.0, 1.0], [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]),
    ];
    for (k, (normal, corners)) in want.iter().enumerate() {
        for (c, corner) in corners.iter().enumerate() {
            let i = m.indices[k * 3 + c] as usize;
            assert!(close(m.positions[i], *corner, 1e-6), "triangle {k} corner {c}: {:?}", m.positions[i]);
            assert!(close(m.normals[i], *normal, 1e-6), "triangle {k} normal: {:?}", m.normals[i]);
        }
    }
}

#[test]
fn files_without_a_scene_draw_every_node_tree_or_every_mesh() {
    let unscened = NODES.replacen("\"scene\": 0,\n  \"scenes\": [ { \"nodes\": [0, 2, 3] } ],\n", "", 1);
    assert!(!unscened.contains("scene"));
    let m = load_one("roots.gltf", unscened.as_bytes()).unwrap();
    let want = load_one("nodes.gltf", NODES.as_bytes()).unwrap();
    assert_eq!(m, want, "the parentless nodes 0, 2 and 3 are the roots");
    let (start, end) = (unscened.find("  \"nodes\"").unwrap(), unscened.find("  \"meshes\"").unwrap());
    let library = format!("{}{}", &unscened[..start], &unscened[end..]);
    let m = load_one("library.gltf", library.as_bytes()).unwrap();
    assert_eq!(m.positions, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    assert_eq!(m.normals, [[0.0, 0.0, 1.0]; 3]);
}

#[test]
fn glb_round_trip_with_u32_indices() {
    let (json, bin) = encode(&sphere(), Some(4), ALL);
    let got = load_one("sphere.glb", &to_glb(&json, &bin)).unwrap();
    assert_same_mesh(&got, &sphere());
}

#[test]
fn external_bin_round_trip_with_u16_indices() {
    let (json, bin) = encode(&cube(), Some(2), ALL);
    assert_same_mesh(&load_gltf_and_bin(json, &bin).unwrap(), &cube());
}

#[test]
fn unindexed_primitives_are_indexed_in_order() {
    let (json, bin) = encode(&cube(), None, ALL);
    let got = load_gltf_and_bin(json, &bin).unwrap();
    assert_eq!((got.positions.len(), &got.indices), (36, &(0..36).collect::<Vec<u32>>()));
    assert_consistent(&got);
}

#[test]
fn missing_normals_are_computed_smooth() {
    let (json, bin) = encode(&sphere(), Some(2), &[]);
    let got = load_gltf_and_bin(json, &bin).unwrap();
    assert_consistent(&got);
    for (p, n) in got.positions.iter().zip(&got.normals) {
        assert!(dot(*p, *n) > 0.99, "smooth normal {n:?} at {p:?} is not radial");
    }
}

/// Asserts `d` is an error with `code` whose message contains `message`,
/// located in `file` at `at`.
fn assert_diag(d: &Diagnostic, code: Code, message: &str, file: &str, at: (u32, u32)) {
    assert_eq!(d.code, code, "{d}");
    assert!(d.message.contains(message), "{:?} does not contain {message:?}", d.message);
    let l = d.location.as_ref().unwrap();
    assert_eq!((l.file.as_str(), l.line, l.column), (file, at.0, at.1), "{d}");
}

/// The fixture with `from` (which must be there) replaced by `to`, loaded;
/// the diagnostic must contain `message` and point at byte `k` of `needle`
/// in the edited text.
fn assert_edit_fails(from: &str, to: &str, message: &str, needle: &str, k: usize) {
    assert_fixture_edit_fails(NODES, from, to, message, needle, k);
}

/// `assert_edit_fails` on another fixture.
fn assert_fixture_edit_fails(fixture: &str, from: &str, to: &str, message: &str, needle: &str, k: usize) {
    assert!(fixture.contains(from), "{from:?} is not in the fixture");
    let text = fixture.replacen(from, to, 1);
    let d = load_one("edited.gltf", text.as_bytes()).expect_err(message);
    assert_diag(&d, Code::Scene, message, "edited.gltf", line_col(&text, needle, k));
}

#[test]
fn malformed_json_is_located_at_its_line_and_column() {
    // The comma after `"scene": 0` is gone: serde stops at the next key.
    let text = NODES.replacen("\"scene\": 0,", "\"scene\": 0", 1);
    let d = load_one("broken.gltf", text.as_bytes()).unwrap_err();
    assert_diag(&d, Code::Scene, "invalid glTF JSON: expected `,` or `}`", "broken.gltf", (4, 3));
    assert!(!d.message.contains("line"), "the location carries the position: {}", d.message);
    // Well-formed JSON of the wrong shape is located the same way.
    let text = NODES.replacen("\"count\": 3, \"type\": \"VEC3\"", "\"count\": \"3\", \"type\": \"VEC3\"", 1);
    let d = load_one("typed.gltf", text.as_bytes()).unwrap_err();
    assert_diag(&d, Code::Scene, "invalid type: string \"3\"", "typed.gltf", line_col(&text, "\"3\"", 2));
    // Columns count characters, not bytes.
    let text = NODES.replacen("\"name\": \"moved\",", "\"name\": \"verschobenüü\"", 1);
    let d = load_one("umlaut.gltf", text.as_bytes()).unwrap_err();
    assert_diag(&d, Code::Scene, "expected `,` or `}`", "umlaut.gltf", line_col(&text, "\"translation\": [10", 0));
}

#[test]
fn unreadable_files() {
    let d = load_gltf(Path::new("/nonexistent/loupe/mesh.gltf"), "mesh.gltf").unwrap_err();
    assert_diag(&d, Code::Io, "cannot read file: No such file", "mesh.gltf", (1, 1));
    let d = load_files(&[("big.gltf", NODES.as_bytes())], &Limits { file_bytes: 100, ..LIMITS }).unwrap_err();
    assert_diag(&d, Code::FileTooLarge, "the limit is 100 bytes", "big.gltf", (1, 1));
    let mut latin1 = NODES.as_bytes().to_vec();
    let h = NODES.find('h').unwrap();
    latin1[h] = 0xE9;
    let d = load_one("latin1.gltf", &latin1).unwrap_err();
    assert_diag(&d, Code::Encoding, "UTF-8", "latin1.gltf", line_col(NODES, "hand-written", 0));
}

#[test]
fn missing_bin_is_located_at_its_uri() {
    let uri = NODES.split("\"uri\": \"").nth(1).unwrap().split('"').next().unwrap();
    let text = NODES.replacen(uri, "missing.bin", 1);
    let d = load_one("edited.gltf", text.as_bytes()).unwrap_err();
    let message = "cannot read `missing.bin`, the data of buffers[0]: No such file";
    assert_diag(&d, Code::Io, message, "edited.gltf", line_col(&text, "\"missing.bin\"", 0));
}

#[test]
fn bad_data_uris_are_located_at_the_bad_character() {
    assert_edit_fails(";base64,AAAA", ";base64,AA!A", "buffers[0].uri: `!` is not a base64 character", "!", 0);
    assert_edit_fails("data:application/octet-stream;base64,", "data:application/octet-stream,", "not base64", "\"data:", 0);
    assert_edit_fails("\"uri\": \"data:", "\"uri\": \"https:", "`https:` is not supported", "https:", 0);
    assert_edit_fails("\"byteLength\": 40", "\"byteLength\": 400", "declares byteLength 400, but its data is 40 bytes", "400", 0);
}

#[test]
fn out_of_range_accessors_and_views() {
    assert_edit_fails(
        "\"count\": 3, \"type\": \"VEC3\"",
        "\"count\": 30, \"type\": \"VEC3\"",
        "accessors[0] reads 30 elements of 12 bytes every 12 from byte 0 of bufferViews[0], past its byteLength 36",
        "{ \"bufferView\": 0",
        0,
    );
    assert_edit_fails(
        "\"byteLength\": 36,",
        "\"byteLength\": 3600,",
        "bufferViews[0] covers bytes 0..3600 of buffers[0], which has 40 bytes",
        "{ \"buffer\": 0, \"byteOffset\": 0",
        0,
    );
    assert_edit_fails(
        "\"byteLength\": 36,",
        "\"byteLength\": 36, \"byteStride\": 8,",
        "bufferViews[0] has byteStride 8, less than the 12-byte elements of accessors[0]",
        "8, \"target\"",
        0,
    );
    assert_edit_fails("\"bufferView\": 0, ", "", "accessors[0] has no bufferView", "{ \"componentType\": 5126", 0);
    assert_edit_fails("\"indices\": 1", "\"indices\": 9", "indices refers to accessors[9], but the file has 2", "9, \"mode\"", 0);
    assert_edit_fails(
        "\"type\": \"VEC3\"",
        "\"type\": \"VEC2\"",
        "accessors[0], used as meshes[0].primitives[0].attributes[\"POSITION\"], is VEC2 of FLOAT; it must be VEC3 of FLOAT",
        "{ \"bufferView\": 0",
        0,
    );
    assert_edit_fails(
        "\"componentType\": 5121",
        "\"componentType\": 5126",
        "is SCALAR of FLOAT; it must be SCALAR of UNSIGNED_BYTE or UNSIGNED_SHORT or UNSIGNED_INT",
        "{ \"bufferView\": 1",
        0,
    );
}

#[test]
fn primitives_that_are_not_triangles() {
    assert_edit_fails("\"mode\": 4", "\"mode\": 1", "meshes[0].primitives[0] has mode 1 (LINES); loupe draws only TRIANGLES", "1 }", 0);
    assert_edit_fails("\"mode\": 4", "\"mode\": 9", "meshes[0].primitives[0].mode is not a glTF primitive mode", "9 }", 0);
    assert_edit_fails("\"POSITION\": 0", "\"TEXCOORD_0\": 0", "meshes[0].primitives[0] has no POSITION attribute", "{ \"TEXCOORD_0\"", 0);
    assert_edit_fails(
        "\"count\": 3, \"type\": \"SCALAR\"",
        "\"count\": 2, \"type\": \"SCALAR\"",
        "meshes[0].primitives[0] has 2 indices: TRIANGLES needs a multiple of 3",
        "{ \"attributes\"",
        0,
    );
}

#[test]
fn files_without_triangles() {
    let d = load_one("empty.gltf", b"{\n  \"asset\": { \"version\": \"2.0\" }\n}\n").unwrap_err();
    assert_diag(&d, Code::Scene, "the file has no meshes", "empty.gltf", (1, 1));
    assert_edit_fails("\"nodes\": [0, 2, 3]", "\"nodes\": []", "scenes[0] has no triangles to draw", "{ \"nodes\": []", 0);
    assert_edit_fails("\"scene\": 0", "\"scene\": 4", "scene 4 does not exist: the file has 1 scenes", "4,", 0);
}

#[test]
fn broken_node_trees() {
    assert_edit_fails("\"children\": [1]", "\"children\": [1, 0]", "nodes[0].children[1] reaches nodes[0] a second time", "0] }", 0);
    assert_edit_fails("[0, 2, 3]", "[0, 2, 3, 1]", "scenes[0].nodes[3] reaches nodes[1] a second time", "1] }", 0);
    assert_edit_fails("[0, 2, 3]", "[0, 2, 7]", "scenes[0].nodes[2] refers to nodes[7], but the file has 4 nodes", "7]", 0);
    assert_edit_fails(
        "\"mesh\": 0 },\n    { \"name\": \"turned\"",
        "\"mesh\": 5 },\n    { \"name\": \"turned\"",
        "nodes[1].mesh refers to meshes[5]",
        "5 }",
        0,
    );
    assert_edit_fails("[0, 0.7071068, 0, 0.7071068]", "[0, 0, 0, 0]", "nodes[2].rotation is not a unit quaternion", "[0, 0, 0, 0]", 0);
    assert_edit_fails("\"scale\": [2, 2, 2]", "\"scale\": [2e39, 2, 2]", "nodes[0].scale holds a number too large for f32", "[2e39", 0);
}

#[test]
fn required_compression_is_refused() {
    assert_edit_fails(
        "\"scene\": 0,",
        "\"scene\": 0, \"extensionsRequired\": [\"KHR_draco_mesh_compression\"],",
        "the file requires KHR_draco_mesh_compression",
        "\"KHR_draco",
        0,
    );
}

#[test]
fn non_finite_positions_are_refused() {
    let mut m = plane();
    m.positions[2][1] = f32::NAN;
    let (json, bin) = encode(&m, Some(1), &["NORMAL"]);
    let d = load_one("nan.glb", &to_glb(&json, &bin)).unwrap_err();
    let message = "accessors[0] (used as meshes[0].primitives[0].attributes[\"POSITION\"]) holds NaN in element 2";
    assert_diag(&d, Code::Scene, message, "nan.glb", (1, 1));
    m.positions[2][1] = f32::INFINITY;
    let (json, bin) = encode(&m, Some(1), &["NORMAL"]);
    let d = load_gltf_and_bin(json, &bin).unwrap_err();
    assert!(d.message.contains("holds inf in element 2"), "{d}");
}

#[test]
fn out_of_range_indices_are_refused() {
    let mut m = plane();
    m.indices[4] = 9;
    let (json, bin) = encode(&m, Some(2), &["NORMAL"]);
    let d = load_one("bad.glb", &to_glb(&json, &bin)).unwrap_err();
    let message = "meshes[0].primitives[0]: index 9 (element 4 of its indices) is out of range: the primitive has 4 vertices";
    assert_diag(&d, Code::Scene, message, "bad.glb", (1, 1));
}

#[test]
fn size_limits_hold_across_instances() {
    let text = NODES.as_bytes();
    let limits = Limits { triangles: 2, ..LIMITS };
    let d = load_files(&[("many.gltf", text)], &limits).unwrap_err();
    assert_diag(&d, Code::Scene, "with nodes[3].mesh the mesh has 9 vertices and 3 triangles", "many.gltf", line_col(NODES, "0 }\n  ]", 0));
    let limits = Limits { vertices: 2, ..LIMITS };
    let d = load_files(&[("many.gltf", text)], &limits).unwrap_err();
    assert!(d.message.contains("accessors[0] has 3 vertices; the limit is 2"), "{d}");
}

#[test]
fn broken_glb_files() {
    let (json, bin) = encode(&cube(), Some(1), &["NORMAL"]);
    let good = to_glb(&json, &bin);
    let d = load_one("cut.glb", &good[..good.len() - 8]).unwrap_err();
    assert_diag(&d, Code::Scene, "header says the file is", "cut.glb", (1, 1));
    let d = load_one("text.glb", b"{}").unwrap_err();
    assert_diag(&d, Code::Scene, "not a binary glTF file", "text.glb", (1, 1));
    let bad_json = glb::write(&[(glb::CHUNK_JSON, b"{\"asset\": }"), (glb::CHUNK_BIN, &bin)]);
    let d = load_one("json.glb", &bad_json).unwrap_err();
    assert_diag(&d, Code::Scene, "JSON chunk: expected value at line 1 column 11", "json.glb", (1, 1));
    let no_bin = glb::write(&[(glb::CHUNK_JSON, &serde_json::to_vec(&json).unwrap())]);
    let d = load_one("nobin.glb", &no_bin).unwrap_err();
    assert_diag(&d, Code::Scene, "buffers[0] has no uri and the binary file has no BIN chunk", "nobin.glb", (1, 1));
}

#[test]
fn garbage_never_panics() {
    // Every prefix of a .gltf and of a .glb, and every byte of the .glb
    // flipped: each must load or fail with a diagnostic.
    let (json, bin) = encode(&cube(), Some(2), &["NORMAL"]);
    let glb = to_glb(&json, &bin);
    for n in (0..NODES.len()).step_by(7) {
        let _ = load_one("cut.gltf", &NODES.as_bytes()[..n]);
    }
    for n in (0..glb.len()).step_by(13) {
        let _ = load_one("cut.glb", &glb[..n]);
        let mut flipped = glb.clone();
        flipped[n] ^= 0xA5;
        let _ = load_one("flipped.glb", &flipped);
    }
}

/// The fixture's first quad gives TEXCOORD_0 as floats and TANGENT; its
/// second gives normalized unsigned bytes, mirrored in u, and no tangents:
/// MikkTSpace's follow the mirror (−X, left-handed).
#[test]
fn texcoords_and_tangents_are_read() {
    let m = load_one("textured.gltf", TEXTURED.as_bytes()).unwrap();
    assert_consistent(&m);
    assert_eq!((m.positions.len(), m.triangle_count()), (8, 4));
    assert_eq!(m.uvs, [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0], [1.0, 0.0]]);
    assert_eq!(m.tangents[..4], [[1.0, 0.0, 0.0, 1.0]; 4]);
    for t in &m.tangents[4..] {
        assert!(close([t[0], t[1], t[2]], [-1.0, 0.0, 0.0], 1e-6) && t[3] == -1.0, "{t:?}");
    }
    assert_tangents_follow_uvs(&m, 0.9999);
}

/// A mesh with UVs and no tangents gets MikkTSpace's, which on the sphere
/// are close to its analytic ones (dP/du) away from the poles.
#[test]
fn missing_tangents_come_from_mikktspace() {
    let want = sphere();
    let (json, bin) = encode(&want, Some(2), &["NORMAL", "TEXCOORD_0"]);
    let got = load_gltf_and_bin(json, &bin).unwrap();
    assert_consistent(&got);
    assert_tangents_follow_uvs(&got, 0.95);
    for (i, (g, w)) in got.tangents.iter().zip(&want.tangents).enumerate() {
        if want.positions[i][1].abs() < 0.99 {
            let cos = dot([g[0], g[1], g[2]], [w[0], w[1], w[2]]);
            // Seam vertices see the faces on one side only: within 6°.
            assert!(cos > 0.995 && g[3] == w[3], "vertex {i}: {g:?} vs analytic {w:?}");
        }
    }
}

#[test]
fn meshes_without_uvs_get_zero_uvs_and_perpendicular_tangents() {
    let (json, bin) = encode(&cube(), Some(2), &["NORMAL"]);
    let got = load_gltf_and_bin(json, &bin).unwrap();
    assert_consistent(&got);
    assert!(got.uvs.iter().all(|&uv| uv == [0.0, 0.0]));
}

/// UVs that span no area (all equal, or collapsed triangles among good
/// ones), collapsed positions, and given tangents that are zero or along
/// the normal: every tangent still unit and perpendicular, never NaN.
#[test]
fn degenerate_uvs_and_tangents_give_unit_tangents() {
    let s = sphere();
    let mut same = s.clone();
    same.uvs = vec![[0.5, 0.5]; s.positions.len()];
    let mut some = s.clone();
    for uv in &mut some.uvs[..300] {
        *uv = [0.0, 0.0];
    }
    let mut collapsed = s.clone();
    for p in &mut collapsed.positions[200..400] {
        *p = [0.0, 0.0, 0.0];
    }
    for (name, mut m) in [("equal uvs", same), ("some collapsed uvs", some), ("collapsed positions", collapsed)] {
        m.tangents = super::tangents::mikktspace(&m.positions, &m.normals, &m.uvs, &m.indices);
        assert!(m.tangents.iter().flatten().all(|c| c.is_finite()), "{name}");
        assert_tangent_frames(&m);
    }
    for t in [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 2.0, 1.0], [0.0, 0.0, -1.0, 0.0]] {
        let got = super::tangents::given(t, [0.0, 0.0, 1.0]);
        assert!((dot([got[0], got[1], got[2]], [got[0], got[1], got[2]]) - 1.0).abs() < 1e-6 && got[2] == 0.0, "{t:?} → {got:?}");
        assert_eq!(got[3], 1.0, "w 0 reads as right-handed");
    }
}

#[test]
fn bad_texcoord_and_tangent_accessors_are_located() {
    let fails = |from: &str, to: &str, message: &str, needle: &str| assert_fixture_edit_fails(TEXTURED, from, to, message, needle, 0);
    let uvs = "{ \"name\": \"uvs\"";
    let tangents = "{ \"name\": \"tangents\"";
    fails(
        "\"count\": 4, \"type\": \"VEC2\" }",
        "\"count\": 4, \"type\": \"VEC3\" }",
        "accessors[2], used as meshes[0].primitives[0].attributes[\"TEXCOORD_0\"], is VEC3 of FLOAT; it must be VEC2 of FLOAT or UNSIGNED_BYTE or UNSIGNED_SHORT",
        uvs,
    );
    fails(
        "\"bufferView\": 2, \"componentType\": 5126",
        "\"bufferView\": 2, \"componentType\": 5125",
        "is VEC2 of UNSIGNED_INT; it must be VEC2 of FLOAT or UNSIGNED_BYTE or UNSIGNED_SHORT",
        uvs,
    );
    fails(
        "\"normalized\": true, ",
        "",
        "accessors[5], used as meshes[0].primitives[1].attributes[\"TEXCOORD_0\"], holds UNSIGNED_BYTE that are not normalized",
        "{ \"name\": \"mirrored uvs\"",
    );
    fails(
        "\"count\": 4, \"type\": \"VEC4\"",
        "\"count\": 4, \"type\": \"VEC3\"",
        "accessors[3], used as meshes[0].primitives[0].attributes[\"TANGENT\"], is VEC3 of FLOAT; it must be VEC4 of FLOAT",
        tangents,
    );
    fails(
        "\"count\": 4, \"type\": \"VEC4\"",
        "\"count\": 3, \"type\": \"VEC4\"",
        "meshes[0].primitives[0] has 3 tangents for 4 positions",
        "3 }, \"indices\"",
    );
    fails(
        "\"byteOffset\": 128, \"byteLength\": 64",
        "\"byteOffset\": 128, \"byteLength\": 60",
        "accessors[3] reads 4 elements of 16 bytes every 16 from byte 0 of bufferViews[3], past its byteLength 60",
        tangents,
    );
    let mut m = plane();
    m.tangents[1][0] = f32::NAN;
    let (json, bin) = encode(&m, Some(1), ALL);
    let d = load_one("nan.glb", &to_glb(&json, &bin)).unwrap_err();
    assert_diag(
        &d,
        Code::Scene,
        "accessors[3] (used as meshes[0].primitives[0].attributes[\"TANGENT\"]) holds NaN in element 1",
        "nan.glb",
        (1, 1),
    );
}
