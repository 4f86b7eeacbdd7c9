// Ray queries against the scene's triangles: the hierarchy built on the
// CPU by `server/src/bvh` (binned SAH), whose flat layout this module
// mirrors, and the same Möller–Trumbore test as its CPU traversal, so the
// two hit the same triangles. Bound at group 1 by the passes that trace.
#define_import_path loupe::bvh

struct Node {
    min: vec3<f32>,
    // A leaf's first triangle; an interior node's first child (the second
    // follows it).
    first: u32,
    max: vec3<f32>,
    // A leaf's triangle count, or INTERIOR.
    count: u32,
}

struct Triangle {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> nodes: array<Node>;
@group(1) @binding(1) var<storage, read> triangles: array<Triangle>;

const INTERIOR: u32 = 0xffffffffu;
// `bvh::MAX_DEPTH` + 1: the build makes no deeper tree, so the stack of
// far children never overflows.
const STACK: u32 = 49u;
const NO_HIT: u32 = 0xffffffffu;

struct Hit {
    t: f32,
    // Index into the triangles (and the per-triangle shading data), or NO_HIT.
    triangle: u32,
    // Barycentrics of vertices 1 and 2.
    u: f32,
    v: f32,
}

// Where the ray enters the box within (t_min, t_max), or -1 when it misses.
// NaN from 0·∞ on a face compares false in min/max and drops out.
fn enter_box(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv: vec3<f32>, t_min: f32, t_max: f32) -> f32 {
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let a = min(t0, t1);
    let b = max(t0, t1);
    let near = max(max(max(a.x, a.y), a.z), t_min);
    let far = min(min(min(b.x, b.y), b.z), t_max);
    return select(-1.0, near, near <= far);
}

// (t, u, v) of a hit with t_min < t < t_max; t < 0 when none.
fn hit_triangle(tri: Triangle, origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> vec3<f32> {
    let e1 = tri.b.xyz - tri.a.xyz;
    let e2 = tri.c.xyz - tri.a.xyz;
    let p = cross(dir, e2);
    let det = dot(e1, p);
    if abs(det) < 1e-12 {
        return vec3(-1.0);
    }
    let inv = 1.0 / det;
    let s = origin - tri.a.xyz;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return vec3(-1.0);
    }
    let q = cross(s, e1);
    let v = dot(dir, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return vec3(-1.0);
    }
    let t = dot(e2, q) * inv;
    return select(vec3(-1.0), vec3(t, u, v), t > t_min && t < t_max);
}

// Nearest hit with t_min < t < t_max, or any hit when `any_hit` (shadow
// rays stop at the first). Nearer children are visited first.
fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, any_hit: bool) -> Hit {
    var best = Hit(t_max, NO_HIT, 0.0, 0.0);
    let inv = 1.0 / dir;
    var stack: array<u32, STACK>;
    var top = 1u;
    stack[0] = 0u;
    while top > 0u {
        top -= 1u;
        let node = nodes[stack[top]];
        if node.count != INTERIOR {
            for (var i = node.first; i < node.first + node.count; i++) {
                let h = hit_triangle(triangles[i], origin, dir, t_min, best.t);
                if h.x >= 0.0 {
                    best = Hit(h.x, i, h.y, h.z);
                    if any_hit {
                        return best;
                    }
                }
            }
            continue;
        }
        let a = nodes[node.first];
        let b = nodes[node.first + 1u];
        let ta = enter_box(a.min, a.max, origin, inv, t_min, best.t);
        let tb = enter_box(b.min, b.max, origin, inv, t_min, best.t);
        // Push the farther first so the nearer is visited first.
        let a_first = ta >= 0.0 && (tb < 0.0 || ta <= tb);
        let near = select(node.first + 1u, node.first, a_first);
        let far = select(node.first, node.first + 1u, a_first);
        let t_near = select(tb, ta, a_first);
        let t_far = select(ta, tb, a_first);
        if t_far >= 0.0 && top < STACK {
            stack[top] = far;
            top += 1u;
        }
        if t_near >= 0.0 && top < STACK {
            stack[top] = near;
            top += 1u;
        }
    }
    return best;
}

fn trace(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> Hit {
    return traverse(origin, dir, t_min, t_max, false);
}

fn occluded(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> bool {
    return traverse(origin, dir, t_min, t_max, true).triangle != NO_HIT;
}
