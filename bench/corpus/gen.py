#!/usr/bin/env python3
"""Generate the WGSL corpus used by bench/check.sh.

The corpus is generated rather than committed: it is large (tens of thousands
of lines), entirely synthetic, and cheap to rebuild. Generation is
deterministic -- a fixed seed drives a private `random.Random`, no set/dict
iteration order or time is involved -- so every machine benchmarks the same
bytes, and a timing change means a checker change, not a corpus change.

What it writes (flat, so `naga --bulk-validate DIR/*.wgsl` sees every file):

  ok_NNN_<family>.wgsl       realistic valid shaders (vertex/fragment/compute
                             entry points, structs, uniforms, textures and
                             samplers, loops, helpers, lighting math)
  bad_NNN_<kind>.wgsl        one of those with one error injected (type
                             mismatch, undefined identifier, syntax error,
                             wrong binding type, missing return, misc)
  ok_L0N_large_<lines>.wgsl  large generated "material graph" modules
  bad_L0N_large_<lines>.wgsl (2k-20k lines), a couple of them broken near the
                             end so the checker has to get through the file
  MANIFEST.tsv               file, expected (ok/bad), kind, lines
  .gen-stamp                 sha256 of this script, so check.sh can tell a
                             stale corpus from a current one

Everything is plain WGSL (no naga_oil `#import`/`#ifdef`), so naga's own CLI
can read every file and the comparison is like for like.

`--verify NAGA` runs the given naga binary on every file (one process per
file, then once in --bulk-validate mode) and fails unless exactly the ok_*
files validate and exactly the bad_* files are rejected.

Python 3.11 standard library only.
"""

from __future__ import annotations

import argparse
import hashlib
import random
import re
import subprocess
import sys
from pathlib import Path
from string import Template

SEED = 0x100BE  # fixed: the corpus must be byte-identical on every run
N_VALID = 96
N_INVALID = 32
# Target line counts of the large files; the last two of them get an error.
LARGE_SIZES = [2000, 2600, 3400, 4500, 6000, 8000, 10000, 12500, 16000, 20000]
N_LARGE_INVALID = 2


def fl(x: float) -> str:
    """A WGSL float literal (always with a decimal point, never an int)."""
    return f"{x:.4f}"


def t(src: str, **kw) -> str:
    # string.Template uses `$name`, which never occurs in WGSL, so shader
    # text can be written with its braces as-is (no f-string doubling).
    return Template(src).substitute(**kw)


# ---------------------------------------------------------------------------
# Shared helper functions, sampled into valid shaders. Real shader code
# carries a lot of these (colour, hashing, quaternion, packing helpers), and
# validating them is part of the work a checker does.
# ---------------------------------------------------------------------------

HELPERS = [
    """
fn rgb_to_hsv(c: vec3<f32>) -> vec3<f32> {
    let k = vec4<f32>(0.0, -1.0 / 3.0, 2.0 / 3.0, -1.0);
    let p = mix(vec4<f32>(c.bg, k.wz), vec4<f32>(c.gb, k.xy), step(c.b, c.g));
    let q = mix(vec4<f32>(p.xyw, c.r), vec4<f32>(c.r, p.yzx), step(p.x, c.r));
    let d = q.x - min(q.w, q.y);
    let e = 1.0e-10;
    return vec3<f32>(abs(q.z + (q.w - q.y) / (6.0 * d + e)), d / (q.x + e), q.x);
}
""",
    """
fn hsv_to_rgb(c: vec3<f32>) -> vec3<f32> {
    let k = vec4<f32>(1.0, 2.0 / 3.0, 1.0 / 3.0, 3.0);
    let p = abs(fract(c.xxx + k.xyz) * 6.0 - k.www);
    return c.z * mix(k.xxx, clamp(p - k.xxx, vec3<f32>(0.0), vec3<f32>(1.0)), c.y);
}
""",
    """
fn quat_mul(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(
        a.w * b.xyz + b.w * a.xyz + cross(a.xyz, b.xyz),
        a.w * b.w - dot(a.xyz, b.xyz),
    );
}

fn quat_rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}
""",
    """
fn pcg_hash(seed: u32) -> u32 {
    let state = seed * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn random_float(seed: ptr<function, u32>) -> f32 {
    *seed = pcg_hash(*seed);
    return f32(*seed) / 4294967295.0;
}
""",
    """
fn hash22(p: vec2<f32>) -> vec2<f32> {
    var p3 = fract(vec3<f32>(p.xyx) * vec3<f32>(0.1031, 0.1030, 0.0973));
    p3 += dot(p3, p3.yzx + 33.33);
    return fract((p3.xx + p3.yz) * p3.zy);
}
""",
    """
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let cutoff = c < vec3<f32>(0.04045);
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(high, low, cutoff);
}
""",
    """
fn inverse_mat3(m: mat3x3<f32>) -> mat3x3<f32> {
    let a = m[0];
    let b = m[1];
    let c = m[2];
    let r0 = cross(b, c);
    let r1 = cross(c, a);
    let r2 = cross(a, b);
    let inv_det = 1.0 / dot(r2, c);
    return transpose(mat3x3<f32>(r0 * inv_det, r1 * inv_det, r2 * inv_det));
}
""",
    """
fn octahedral_encode(n: vec3<f32>) -> vec2<f32> {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    var p = n.xy / l1;
    if (n.z < 0.0) {
        let s = select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
        p = (vec2<f32>(1.0) - abs(p.yx)) * s;
    }
    return p;
}

fn octahedral_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}
""",
    """
fn rotate2d(angle: f32) -> mat2x2<f32> {
    let s = sin(angle);
    let c = cos(angle);
    return mat2x2<f32>(c, s, -s, c);
}

fn remap(v: f32, in_min: f32, in_max: f32, out_min: f32, out_max: f32) -> f32 {
    return out_min + (v - in_min) * (out_max - out_min) / (in_max - in_min);
}
""",
    """
fn pack_unorm_rgb10a2(c: vec4<f32>) -> u32 {
    let q = vec4<u32>(round(clamp(c, vec4<f32>(0.0), vec4<f32>(1.0)) * vec4<f32>(1023.0, 1023.0, 1023.0, 3.0)));
    return q.x | (q.y << 10u) | (q.z << 20u) | (q.w << 30u);
}

fn unpack_unorm_rgb10a2(v: u32) -> vec4<f32> {
    let q = vec4<u32>(v & 1023u, (v >> 10u) & 1023u, (v >> 20u) & 1023u, v >> 30u);
    return vec4<f32>(q) / vec4<f32>(1023.0, 1023.0, 1023.0, 3.0);
}
""",
    """
fn interleave_bits(v: u32) -> u32 {
    var x = v & 0x0000ffffu;
    x = (x | (x << 8u)) & 0x00ff00ffu;
    x = (x | (x << 4u)) & 0x0f0f0f0fu;
    x = (x | (x << 2u)) & 0x33333333u;
    x = (x | (x << 1u)) & 0x55555555u;
    return x;
}

fn morton2d(p: vec2<u32>) -> u32 {
    return interleave_bits(p.x) | (interleave_bits(p.y) << 1u);
}
""",
    """
fn spherical_harmonics_l1(n: vec3<f32>, sh: array<vec3<f32>, 4>) -> vec3<f32> {
    var coeffs = sh;
    let c0 = 0.282095;
    let c1 = 0.488603;
    var result = coeffs[0] * c0;
    result += coeffs[1] * (c1 * n.y);
    result += coeffs[2] * (c1 * n.z);
    result += coeffs[3] * (c1 * n.x);
    return max(result, vec3<f32>(0.0));
}
""",
]


def pick_helpers(rng: random.Random) -> str:
    chosen = rng.sample(range(len(HELPERS)), rng.randint(0, 4))
    return "".join(HELPERS[i] for i in sorted(chosen))


# ---------------------------------------------------------------------------
# Valid shader families. Each returns a complete module; the rng varies
# constants, sizes, names and optional parts so no two files are identical.
# ---------------------------------------------------------------------------


def fam_textured_mesh(rng: random.Random) -> str:
    return t(
        """
struct Camera {
    view_proj: mat4x4<f32>,
    position: vec3<f32>,
    time: f32,
};

struct Model {
    transform: mat4x4<f32>,
    normal_matrix: mat3x3<f32>,
    tint: vec4<f32>,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(1) @binding(0) var<uniform> model: Model;
@group(2) @binding(0) var albedo_texture: texture_2d<f32>;
@group(2) @binding(1) var albedo_sampler: sampler;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) world_position: vec3<f32>,
};

@vertex
fn vs_main(vertex: VertexInput) -> VertexOutput {
    var out: VertexOutput;
    let world = model.transform * vec4<f32>(vertex.position, 1.0);
    out.clip_position = camera.view_proj * world;
    out.world_normal = normalize(model.normal_matrix * vertex.normal);
    out.uv = vertex.uv * $uv_scale + vec2<f32>(camera.time * $scroll, 0.0);
    out.world_position = world.xyz;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let base = textureSample(albedo_texture, albedo_sampler, in.uv) * model.tint;
    let light_dir = normalize(vec3<f32>($lx, $ly, $lz));
    let n = normalize(in.world_normal);
    let ndotl = max(dot(n, light_dir), 0.0);
    let view_dir = normalize(camera.position - in.world_position);
    let half_dir = normalize(light_dir + view_dir);
    let spec = pow(max(dot(n, half_dir), 0.0), $shininess);
    let rim = pow(1.0 - max(dot(n, view_dir), 0.0), $rim_power) * $rim;
    let lit = base.rgb * ($ambient + ndotl) + vec3<f32>(spec + rim);
    return vec4<f32>(lit, base.a);
}
""",
        uv_scale=fl(rng.uniform(0.5, 4.0)),
        scroll=fl(rng.uniform(0.0, 0.2)),
        lx=fl(rng.uniform(-1, 1)),
        ly=fl(rng.uniform(0.2, 1)),
        lz=fl(rng.uniform(-1, 1)),
        shininess=fl(rng.choice([8, 16, 32, 64, 128])),
        rim_power=fl(rng.uniform(1.5, 5.0)),
        rim=fl(rng.uniform(0.0, 0.5)),
        ambient=fl(rng.uniform(0.02, 0.2)),
    )


def fam_pbr(rng: random.Random) -> str:
    vertex = ""
    if rng.random() < 0.5:
        vertex = """
struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
};

@vertex
fn vs_main(v: VertexInput) -> FragmentInput {
    var out: FragmentInput;
    out.frag_coord = view.view_proj * vec4<f32>(v.position, 1.0);
    out.world_position = v.position;
    out.world_normal = v.normal;
    out.uv = v.uv;
    out.world_tangent = v.tangent;
    return out;
}
"""
    fog = ""
    fog_call = ""
    if rng.random() < 0.5:
        fog = t(
            """
fn apply_fog(color: vec3<f32>, world_position: vec3<f32>) -> vec3<f32> {
    let d = length(view.camera_position - world_position);
    let f = 1.0 - exp(-d * $density);
    return mix(color, vec3<f32>($fr, $fg, $fb), clamp(f, 0.0, 1.0));
}
""",
            density=fl(rng.uniform(0.001, 0.05)),
            fr=fl(rng.uniform(0.3, 0.8)),
            fg=fl(rng.uniform(0.3, 0.8)),
            fb=fl(rng.uniform(0.5, 1.0)),
        )
        fog_call = "    color = apply_fog(color, in.world_position);\n"
    return t(
        """
const PI: f32 = 3.14159265359;

struct View {
    view_proj: mat4x4<f32>,
    inverse_view: mat4x4<f32>,
    camera_position: vec3<f32>,
    exposure: f32,
};

struct PointLight {
    position: vec3<f32>,
    radius: f32,
    color: vec3<f32>,
    intensity: f32,
};

struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>,
    metallic: f32,
    roughness: f32,
    reflectance: f32,
    flags: u32,
    alpha_cutoff: f32,
};

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> lights: array<PointLight>;
@group(1) @binding(0) var<uniform> material: Material;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var normal_map: texture_2d<f32>;
@group(1) @binding(3) var material_sampler: sampler;

struct FragmentInput {
    @builtin(position) frag_coord: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) world_tangent: vec4<f32>,
};
$vertex
fn distribution_ggx(n_dot_h: f32, roughness: f32) -> f32 {
    let a = roughness * roughness;
    let a2 = a * a;
    let d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / max(PI * d * d, 1e-6);
}

fn geometry_schlick_ggx(n_dot_v: f32, roughness: f32) -> f32 {
    let r = roughness + 1.0;
    let k = (r * r) / 8.0;
    return n_dot_v / (n_dot_v * (1.0 - k) + k);
}

fn geometry_smith(n_dot_v: f32, n_dot_l: f32, roughness: f32) -> f32 {
    return geometry_schlick_ggx(n_dot_v, roughness) * geometry_schlick_ggx(n_dot_l, roughness);
}

fn fresnel_schlick(cos_theta: f32, f0: vec3<f32>) -> vec3<f32> {
    return f0 + (vec3<f32>(1.0) - f0) * pow(clamp(1.0 - cos_theta, 0.0, 1.0), 5.0);
}

fn light_attenuation(dist: f32, radius: f32) -> f32 {
    let ratio = dist / radius;
    let falloff = clamp(1.0 - ratio * ratio * ratio * ratio, 0.0, 1.0);
    return falloff * falloff / (dist * dist + 1.0);
}

fn perturb_normal(in: FragmentInput, sampled: vec3<f32>) -> vec3<f32> {
    let n = normalize(in.world_normal);
    let t = normalize(in.world_tangent.xyz);
    let b = cross(n, t) * in.world_tangent.w;
    let tbn = mat3x3<f32>(t, b, n);
    return normalize(tbn * (sampled * 2.0 - 1.0));
}
$fog
@fragment
fn fs_main(in: FragmentInput) -> @location(0) vec4<f32> {
    let albedo = textureSample(base_color_texture, material_sampler, in.uv) * material.base_color;
    let sampled_normal = textureSample(normal_map, material_sampler, in.uv).xyz;
    if ((material.flags & 1u) != 0u && albedo.a < material.alpha_cutoff) {
        discard;
    }
    let n = perturb_normal(in, sampled_normal);
    let v = normalize(view.camera_position - in.world_position);
    let roughness = clamp(material.roughness, 0.045, 1.0);
    let f0 = mix(vec3<f32>(0.16 * material.reflectance * material.reflectance), albedo.rgb, material.metallic);
    let n_dot_v = max(dot(n, v), 1e-4);
    var radiance = vec3<f32>(0.0);
    let light_count = min(arrayLength(&lights), $max_lights);
    for (var i = 0u; i < light_count; i = i + 1u) {
        let light = lights[i];
        let to_light = light.position - in.world_position;
        let dist = length(to_light);
        if (dist > light.radius) {
            continue;
        }
        let l = to_light / dist;
        let h = normalize(v + l);
        let n_dot_l = max(dot(n, l), 0.0);
        let n_dot_h = max(dot(n, h), 0.0);
        let d = distribution_ggx(n_dot_h, roughness);
        let g = geometry_smith(n_dot_v, n_dot_l, roughness);
        let f = fresnel_schlick(max(dot(h, v), 0.0), f0);
        let specular = d * g * f / (4.0 * n_dot_v * n_dot_l + 1e-4);
        let kd = (vec3<f32>(1.0) - f) * (1.0 - material.metallic);
        let diffuse = kd * albedo.rgb / PI;
        radiance += (diffuse + specular) * light.color * light.intensity * light_attenuation(dist, light.radius) * n_dot_l;
    }
    let ambient = albedo.rgb * $ambient;
    var color = (radiance + ambient + material.emissive) * view.exposure;
$fog_call    color = color / (color + vec3<f32>(1.0));
    color = pow(color, vec3<f32>(1.0 / 2.2));
    return vec4<f32>(color, albedo.a);
}
""",
        vertex=vertex,
        fog=fog,
        fog_call=fog_call,
        max_lights=f"{rng.choice([16, 32, 64, 128, 256])}u",
        ambient=fl(rng.uniform(0.01, 0.1)),
    )


def fam_blur_compute(rng: random.Random) -> str:
    wg = rng.choice([8, 16])
    radius = rng.randint(2, 6)
    fmt = rng.choice(["rgba8unorm", "rgba16float", "rgba32float"])
    return t(
        """
struct BlurParams {
    direction: vec2<i32>,
    radius: i32,
    sigma: f32,
};

@group(0) @binding(0) var input_texture: texture_2d<f32>;
@group(0) @binding(1) var output_texture: texture_storage_2d<$fmt, write>;
@group(0) @binding(2) var<uniform> params: BlurParams;

const TILE: u32 = ${wg}u;
var<workgroup> tile: array<vec4<f32>, $tile_len>;

fn gaussian(x: f32, sigma: f32) -> f32 {
    return exp(-(x * x) / (2.0 * sigma * sigma)) / (2.5066282746 * sigma);
}

fn clamp_coord(p: vec2<i32>, dims: vec2<u32>) -> vec2<i32> {
    return clamp(p, vec2<i32>(0), vec2<i32>(dims) - vec2<i32>(1));
}

@compute @workgroup_size($wg, $wg, 1)
fn blur(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(local_invocation_index) lindex: u32,
) {
    let dims = textureDimensions(input_texture);
    let coord = clamp_coord(vec2<i32>(gid.xy), dims);
    tile[lindex] = textureLoad(input_texture, coord, 0);
    workgroupBarrier();

    var sum = vec4<f32>(0.0);
    var weight_sum = 0.0;
    for (var i = -$radius; i <= $radius; i++) {
        let w = gaussian(f32(i), params.sigma);
        let offset = params.direction * i;
        let local = vec2<i32>(lid.xy) + offset;
        var sample_value: vec4<f32>;
        if (all(local >= vec2<i32>(0)) && all(local < vec2<i32>(i32(TILE)))) {
            sample_value = tile[u32(local.y) * TILE + u32(local.x)];
        } else {
            sample_value = textureLoad(input_texture, clamp_coord(coord + offset, dims), 0);
        }
        sum += sample_value * w;
        weight_sum += w;
    }
    if (all(gid.xy < dims)) {
        textureStore(output_texture, coord, sum / weight_sum);
    }
}
""",
        fmt=fmt,
        wg=wg,
        tile_len=wg * wg,
        radius=radius,
    )


def fam_particles(rng: random.Random) -> str:
    return t(
        """
struct Particle {
    position: vec3<f32>,
    life: f32,
    velocity: vec3<f32>,
    seed: u32,
    color: vec4<f32>,
};

struct SimParams {
    gravity: vec3<f32>,
    delta_time: f32,
    emitter_position: vec3<f32>,
    count: u32,
    damping: f32,
    spawn_radius: f32,
    max_life: f32,
    frame: u32,
};

@group(0) @binding(0) var<uniform> params: SimParams;
@group(0) @binding(1) var<storage, read_write> particles: array<Particle>;
@group(0) @binding(2) var<storage, read_write> alive_count: atomic<u32>;
@group(0) @binding(3) var<storage, read_write> draw_args: array<u32, 4>;

fn hash(n: u32) -> u32 {
    var x = n;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

fn rand01(state: ptr<function, u32>) -> f32 {
    *state = hash(*state);
    return f32(*state) / 4294967295.0;
}

fn random_in_sphere(state: ptr<function, u32>) -> vec3<f32> {
    let u = rand01(state) * 2.0 - 1.0;
    let phi = rand01(state) * 6.2831853;
    let r = pow(rand01(state), 1.0 / 3.0);
    let s = sqrt(1.0 - u * u);
    return vec3<f32>(s * cos(phi), s * sin(phi), u) * r;
}

fn respawn(index: u32) -> Particle {
    var state = hash(index ^ (params.frame * 0x9e3779b9u));
    var p: Particle;
    p.position = params.emitter_position + random_in_sphere(&state) * params.spawn_radius;
    p.velocity = random_in_sphere(&state) * $speed + vec3<f32>(0.0, $lift, 0.0);
    p.life = params.max_life * (0.5 + 0.5 * rand01(&state));
    p.seed = state;
    p.color = vec4<f32>($cr, $cg, $cb, 1.0);
    return p;
}

@compute @workgroup_size($wg)
fn simulate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let index = gid.x;
    if (index >= params.count) {
        return;
    }
    var p = particles[index];
    p.life -= params.delta_time;
    if (p.life <= 0.0) {
        p = respawn(index);
    } else {
        p.velocity += params.gravity * params.delta_time;
        p.velocity *= pow(params.damping, params.delta_time);
        p.position += p.velocity * params.delta_time;
        if (p.position.y < $floor) {
            p.position.y = $floor;
            p.velocity.y = -p.velocity.y * $bounce;
        }
        p.color.a = clamp(p.life / params.max_life, 0.0, 1.0);
    }
    particles[index] = p;
    atomicAdd(&alive_count, 1u);
}

@compute @workgroup_size(1)
fn write_draw_args() {
    draw_args[0] = 6u;
    draw_args[1] = atomicLoad(&alive_count);
    draw_args[2] = 0u;
    draw_args[3] = 0u;
    atomicStore(&alive_count, 0u);
}
""",
        speed=fl(rng.uniform(0.5, 5.0)),
        lift=fl(rng.uniform(0.0, 6.0)),
        cr=fl(rng.random()),
        cg=fl(rng.random()),
        cb=fl(rng.random()),
        wg=rng.choice([64, 128, 256]),
        floor=fl(rng.uniform(-2.0, 0.0)),
        bounce=fl(rng.uniform(0.1, 0.9)),
    )


def fam_noise(rng: random.Random) -> str:
    octaves = rng.randint(3, 8)
    return t(
        """
struct Globals {
    time: f32,
    resolution: vec2<f32>,
    mouse: vec2<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;

fn hash2(p: vec2<f32>) -> f32 {
    let h = dot(p, vec2<f32>(127.1, 311.7));
    return fract(sin(h) * 43758.5453123);
}

fn value_noise(p: vec2<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let a = hash2(i);
    let b = hash2(i + vec2<f32>(1.0, 0.0));
    let c = hash2(i + vec2<f32>(0.0, 1.0));
    let d = hash2(i + vec2<f32>(1.0, 1.0));
    return mix(mix(a, b, u.x), mix(c, d, u.x), u.y);
}

fn fbm(p_in: vec2<f32>) -> f32 {
    var p = p_in;
    var amplitude = 0.5;
    var total = 0.0;
    let rot = mat2x2<f32>(0.8, 0.6, -0.6, 0.8);
    for (var i = 0; i < $octaves; i++) {
        total += amplitude * value_noise(p);
        p = rot * p * $lacunarity;
        amplitude *= $gain;
    }
    return total;
}

fn domain_warp(p: vec2<f32>) -> f32 {
    let q = vec2<f32>(fbm(p), fbm(p + vec2<f32>(5.2, 1.3)));
    let r = vec2<f32>(
        fbm(p + 4.0 * q + vec2<f32>(1.7, 9.2) + 0.15 * globals.time),
        fbm(p + 4.0 * q + vec2<f32>(8.3, 2.8) + 0.126 * globals.time),
    );
    return fbm(p + 4.0 * r);
}

fn palette(x: f32) -> vec3<f32> {
    let a = vec3<f32>(0.5, 0.5, 0.5);
    let b = vec3<f32>(0.5, 0.5, 0.5);
    let c = vec3<f32>(1.0, 1.0, 1.0);
    let d = vec3<f32>($d0, $d1, $d2);
    return a + b * cos(6.28318 * (c * x + d));
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_noise(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    let uv = (frag_coord.xy - 0.5 * globals.resolution) / globals.resolution.y;
    let n = domain_warp(uv * $scale);
    let col = palette(n + 0.1 * globals.time);
    return vec4<f32>(col * (0.6 + 0.4 * n), 1.0);
}
""",
        octaves=octaves,
        lacunarity=fl(rng.uniform(1.8, 2.2)),
        gain=fl(rng.uniform(0.4, 0.6)),
        d0=fl(rng.random()),
        d1=fl(rng.random()),
        d2=fl(rng.random()),
        scale=fl(rng.uniform(1.0, 6.0)),
    )


def fam_skinning(rng: random.Random) -> str:
    return t(
        """
struct Camera {
    view_proj: mat4x4<f32>,
};

struct Instance {
    model: mat4x4<f32>,
    joint_offset: u32,
    morph_weight: f32,
    _pad: vec2<f32>,
};

@group(0) @binding(0) var<uniform> camera: Camera;
@group(1) @binding(0) var<storage, read> joints: array<mat4x4<f32>>;
@group(1) @binding(1) var<storage, read> instances: array<Instance>;

struct SkinnedVertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) joint_indices: vec4<u32>,
    @location(4) joint_weights: vec4<f32>,
    @location(5) morph_delta: vec3<f32>,
};

struct Varyings {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) @interpolate(flat) instance: u32,
};

fn skin_matrix(offset: u32, indices: vec4<u32>, weights: vec4<f32>) -> mat4x4<f32> {
    var m = joints[offset + indices.x] * weights.x;
    m += joints[offset + indices.y] * weights.y;
    m += joints[offset + indices.z] * weights.z;
    m += joints[offset + indices.w] * weights.w;
    return m;
}

fn normal_from_skin(m: mat4x4<f32>, n: vec3<f32>) -> vec3<f32> {
    let m3 = mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz);
    return normalize(m3 * n);
}

@vertex
fn vs_skinned(v: SkinnedVertex, @builtin(instance_index) instance_index: u32) -> Varyings {
    let inst = instances[instance_index];
    let total = dot(v.joint_weights, vec4<f32>(1.0));
    let weights = v.joint_weights / max(total, $eps);
    let skin = inst.model * skin_matrix(inst.joint_offset, v.joint_indices, weights);
    let morphed = v.position + v.morph_delta * inst.morph_weight;
    var out: Varyings;
    out.clip = camera.view_proj * skin * vec4<f32>(morphed, 1.0);
    out.normal = normal_from_skin(skin, v.normal);
    out.uv = v.uv;
    out.instance = instance_index;
    return out;
}

@fragment
fn fs_debug(in: Varyings) -> @location(0) vec4<f32> {
    let n = in.normal * 0.5 + 0.5;
    let checker = select($dark, 1.0, (u32(floor(in.uv.x * $checks)) + u32(floor(in.uv.y * $checks))) % 2u == 0u);
    return vec4<f32>(n * checker, 1.0);
}
""",
        eps=fl(rng.choice([1e-4, 1e-5, 1e-3])),
        dark=fl(rng.uniform(0.2, 0.7)),
        checks=fl(rng.choice([4, 8, 16, 32])),
    )


def fam_tonemap(rng: random.Random) -> str:
    return t(
        """
struct PostParams {
    exposure: f32,
    gamma: f32,
    vignette_strength: f32,
    grain: f32,
    frame: u32,
    operator_index: u32,
};

@group(0) @binding(0) var hdr_texture: texture_2d<f32>;
@group(0) @binding(1) var hdr_sampler: sampler;
@group(0) @binding(2) var<uniform> post: PostParams;
@group(0) @binding(3) var bloom_texture: texture_2d<f32>;

struct FullscreenVertex {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenVertex {
    let uv = vec2<f32>(f32(vertex_index >> 1u), f32(vertex_index & 1u)) * 2.0;
    var out: FullscreenVertex;
    out.position = vec4<f32>(uv * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0), 0.0, 1.0);
    out.uv = uv;
    return out;
}

fn aces_filmic(x: vec3<f32>) -> vec3<f32> {
    let a = 2.51;
    let b = 0.03;
    let c = 2.43;
    let d = 0.59;
    let e = 0.14;
    return clamp((x * (a * x + b)) / (x * (c * x + d) + e), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn reinhard_extended(x: vec3<f32>, white: f32) -> vec3<f32> {
    let l = dot(x, vec3<f32>(0.2126, 0.7152, 0.0722));
    let scaled = l * (1.0 + l / (white * white)) / (1.0 + l);
    return x * (scaled / max(l, 1e-5));
}

fn uncharted2_partial(x: vec3<f32>) -> vec3<f32> {
    let a = 0.15;
    let b = 0.50;
    let c = 0.10;
    let d = 0.20;
    let e = 0.02;
    let f = 0.30;
    return ((x * (a * x + c * b) + d * e) / (x * (a * x + b) + d * f)) - e / f;
}

fn uncharted2(x: vec3<f32>) -> vec3<f32> {
    let white = uncharted2_partial(vec3<f32>(11.2));
    return uncharted2_partial(x * 2.0) / white;
}

fn interleaved_gradient_noise(p: vec2<f32>, frame: u32) -> f32 {
    let q = p + 5.588238 * f32(frame % 64u);
    return fract(52.9829189 * fract(dot(q, vec2<f32>(0.06711056, 0.00583715))));
}

@fragment
fn tonemap(in: FullscreenVertex) -> @location(0) vec4<f32> {
    let hdr = textureSample(hdr_texture, hdr_sampler, in.uv).rgb;
    let bloom = textureSample(bloom_texture, hdr_sampler, in.uv).rgb;
    var color = (hdr + bloom * $bloom) * post.exposure;
    switch post.operator_index {
        case 0u: {
            color = aces_filmic(color);
        }
        case 1u: {
            color = reinhard_extended(color, $white);
        }
        case 2u, 3u: {
            color = uncharted2(color);
        }
        default: {
            color = clamp(color, vec3<f32>(0.0), vec3<f32>(1.0));
        }
    }
    let centered = in.uv - 0.5;
    let vignette = 1.0 - dot(centered, centered) * post.vignette_strength;
    color *= vignette;
    let grain = (interleaved_gradient_noise(in.position.xy, post.frame) - 0.5) * post.grain;
    color = pow(max(color + grain, vec3<f32>(0.0)), vec3<f32>(1.0 / post.gamma));
    return vec4<f32>(color, 1.0);
}
""",
        bloom=fl(rng.uniform(0.02, 0.3)),
        white=fl(rng.uniform(2.0, 12.0)),
    )


def fam_shadow(rng: random.Random) -> str:
    pcf = rng.randint(1, 3)
    cascades = rng.choice([2, 3, 4])
    return t(
        """
struct Cascade {
    view_proj: mat4x4<f32>,
    split_depth: vec4<f32>,
};

struct ShadowUniforms {
    cascades: array<Cascade, $cascades>,
    light_direction: vec3<f32>,
    cascade_count: u32,
    depth_bias: f32,
    normal_bias: f32,
    texel_size: vec2<f32>,
};

@group(0) @binding(0) var<uniform> shadow: ShadowUniforms;
@group(0) @binding(1) var shadow_map: texture_depth_2d_array;
@group(0) @binding(2) var shadow_sampler: sampler_comparison;
@group(1) @binding(0) var<uniform> view_proj: mat4x4<f32>;

struct ShadowVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) view_depth: f32,
};

@vertex
fn vs_shadowed(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
) -> ShadowVertex {
    var out: ShadowVertex;
    out.clip = view_proj * vec4<f32>(position, 1.0);
    out.world_position = position;
    out.normal = normal;
    out.view_depth = out.clip.w;
    return out;
}

fn select_cascade(view_depth: f32) -> u32 {
    var index = 0u;
    for (var i = 0u; i < shadow.cascade_count - 1u; i++) {
        if (view_depth > shadow.cascades[i].split_depth.x) {
            index = i + 1u;
        }
    }
    return index;
}

fn sample_shadow(world_position: vec3<f32>, normal: vec3<f32>, cascade: u32) -> f32 {
    let biased = world_position + normal * shadow.normal_bias;
    let light_clip = shadow.cascades[cascade].view_proj * vec4<f32>(biased, 1.0);
    if (light_clip.w <= 0.0) {
        return 1.0;
    }
    let ndc = light_clip.xyz / light_clip.w;
    let uv = ndc.xy * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
    let depth = ndc.z - shadow.depth_bias;
    var visibility = 0.0;
    for (var y = -$pcf; y <= $pcf; y++) {
        for (var x = -$pcf; x <= $pcf; x++) {
            let offset = vec2<f32>(f32(x), f32(y)) * shadow.texel_size;
            visibility += textureSampleCompareLevel(shadow_map, shadow_sampler, uv + offset, i32(cascade), depth);
        }
    }
    return visibility / $taps;
}

@fragment
fn fs_shadowed(in: ShadowVertex) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let ndotl = max(dot(n, -normalize(shadow.light_direction)), 0.0);
    let cascade = select_cascade(in.view_depth);
    let visibility = sample_shadow(in.world_position, n, cascade);
    let debug_tint = vec3<f32>(f32(cascade == 0u), f32(cascade == 1u), f32(cascade >= 2u)) * $debug;
    let color = vec3<f32>($ambient) + vec3<f32>(ndotl * visibility) + debug_tint;
    return vec4<f32>(color, 1.0);
}
""",
        cascades=cascades,
        pcf=pcf,
        taps=fl((2 * pcf + 1) ** 2),
        debug=fl(rng.choice([0.0, 0.1, 0.25])),
        ambient=fl(rng.uniform(0.05, 0.2)),
    )


def fam_raymarch(rng: random.Random) -> str:
    return t(
        """
const MAX_STEPS: i32 = $steps;
const MAX_DISTANCE: f32 = $max_dist;
const SURFACE_EPSILON: f32 = 0.001;

struct Scene {
    camera_origin: vec3<f32>,
    time: f32,
    camera_forward: vec3<f32>,
    fov: f32,
    resolution: vec2<f32>,
    blend: f32,
};

@group(0) @binding(0) var<uniform> scene: Scene;
@group(0) @binding(1) var output: texture_storage_2d<rgba16float, write>;

struct Hit {
    distance: f32,
    steps: i32,
    material: u32,
};

fn sd_sphere(p: vec3<f32>, r: f32) -> f32 {
    return length(p) - r;
}

fn sd_box(p: vec3<f32>, b: vec3<f32>) -> f32 {
    let q = abs(p) - b;
    return length(max(q, vec3<f32>(0.0))) + min(max(q.x, max(q.y, q.z)), 0.0);
}

fn sd_torus(p: vec3<f32>, t: vec2<f32>) -> f32 {
    let q = vec2<f32>(length(p.xz) - t.x, p.y);
    return length(q) - t.y;
}

fn op_smooth_union(a: f32, b: f32, k: f32) -> f32 {
    let h = clamp(0.5 + 0.5 * (b - a) / k, 0.0, 1.0);
    return mix(b, a, h) - k * h * (1.0 - h);
}

fn map(p: vec3<f32>) -> vec2<f32> {
    let sphere = sd_sphere(p - vec3<f32>(sin(scene.time) * $amp, 0.0, 0.0), $radius);
    let box = sd_box(p - vec3<f32>(0.0, -1.0, 0.0), vec3<f32>(3.0, 0.1, 3.0));
    let torus = sd_torus(p - vec3<f32>(0.0, 0.5, 0.0), vec2<f32>($major, $minor));
    let blob = op_smooth_union(sphere, torus, scene.blend);
    return select(vec2<f32>(box, 1.0), vec2<f32>(blob, 2.0), blob < box);
}

fn calc_normal(p: vec3<f32>) -> vec3<f32> {
    let e = vec2<f32>(SURFACE_EPSILON, 0.0);
    return normalize(vec3<f32>(
        map(p + e.xyy).x - map(p - e.xyy).x,
        map(p + e.yxy).x - map(p - e.yxy).x,
        map(p + e.yyx).x - map(p - e.yyx).x,
    ));
}

fn march(origin: vec3<f32>, direction: vec3<f32>) -> Hit {
    var hit: Hit;
    hit.distance = 0.0;
    hit.material = 0u;
    for (hit.steps = 0; hit.steps < MAX_STEPS; hit.steps++) {
        let d = map(origin + direction * hit.distance);
        if (d.x < SURFACE_EPSILON) {
            hit.material = u32(d.y);
            break;
        }
        hit.distance += d.x;
        if (hit.distance > MAX_DISTANCE) {
            break;
        }
    }
    return hit;
}

fn soft_shadow(origin: vec3<f32>, direction: vec3<f32>, k: f32) -> f32 {
    var result = 1.0;
    var t = 0.02;
    loop {
        if (t > 10.0) {
            break;
        }
        let h = map(origin + direction * t).x;
        if (h < SURFACE_EPSILON) {
            return 0.0;
        }
        result = min(result, k * h / t);
        continuing {
            t += clamp(h, 0.01, 0.5);
        }
    }
    return result;
}

@compute @workgroup_size(8, 8)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    let dims = textureDimensions(output);
    if (any(gid.xy >= dims)) {
        return;
    }
    let uv = (vec2<f32>(gid.xy) + 0.5 - 0.5 * scene.resolution) / scene.resolution.y;
    let forward = normalize(scene.camera_forward);
    let right = normalize(cross(vec3<f32>(0.0, 1.0, 0.0), forward));
    let up = cross(forward, right);
    let dir = normalize(forward * scene.fov + right * uv.x - up * uv.y);
    let hit = march(scene.camera_origin, dir);
    var color = vec3<f32>($sky_r, $sky_g, 1.0) * (1.0 - 0.5 * uv.y);
    if (hit.material != 0u) {
        let p = scene.camera_origin + dir * hit.distance;
        let n = calc_normal(p);
        let light = normalize(vec3<f32>(0.6, 0.8, -0.4));
        let diffuse = max(dot(n, light), 0.0) * soft_shadow(p + n * 0.01, light, $softness);
        let albedo = select(vec3<f32>(0.8, 0.3, 0.2), vec3<f32>(0.7), hit.material == 1u);
        color = albedo * (0.1 + diffuse) + 0.002 * f32(hit.steps);
    }
    textureStore(output, vec2<i32>(gid.xy), vec4<f32>(color, 1.0));
}
""",
        steps=rng.choice([64, 96, 128, 256]),
        max_dist=fl(rng.choice([20, 50, 100])),
        amp=fl(rng.uniform(0.5, 2.0)),
        radius=fl(rng.uniform(0.5, 1.2)),
        major=fl(rng.uniform(1.0, 1.6)),
        minor=fl(rng.uniform(0.1, 0.4)),
        sky_r=fl(rng.uniform(0.3, 0.6)),
        sky_g=fl(rng.uniform(0.5, 0.8)),
        softness=fl(rng.uniform(4.0, 32.0)),
    )


def fam_matmul(rng: random.Random) -> str:
    tile = rng.choice([8, 16])
    return t(
        """
struct Dimensions {
    m: u32,
    n: u32,
    k: u32,
    alpha: f32,
};

@group(0) @binding(0) var<uniform> dims: Dimensions;
@group(0) @binding(1) var<storage, read> lhs: array<f32>;
@group(0) @binding(2) var<storage, read> rhs: array<f32>;
@group(0) @binding(3) var<storage, read_write> result: array<f32>;

const TILE: u32 = ${tile}u;
var<workgroup> tile_a: array<array<f32, $tile>, $tile>;
var<workgroup> tile_b: array<array<f32, $tile>, $tile>;

fn load_or_zero(buffer_index: u32, row: u32, col: u32, rows: u32, cols: u32) -> f32 {
    if (row >= rows || col >= cols) {
        return 0.0;
    }
    if (buffer_index == 0u) {
        return lhs[row * cols + col];
    }
    return rhs[row * cols + col];
}

@compute @workgroup_size($tile, $tile, 1)
fn matmul(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    let row = gid.y;
    let col = gid.x;
    var acc = 0.0;
    let tiles = (dims.k + TILE - 1u) / TILE;
    for (var t = 0u; t < tiles; t++) {
        tile_a[lid.y][lid.x] = load_or_zero(0u, row, t * TILE + lid.x, dims.m, dims.k);
        tile_b[lid.y][lid.x] = load_or_zero(1u, t * TILE + lid.y, col, dims.k, dims.n);
        workgroupBarrier();
        for (var i = 0u; i < TILE; i++) {
            acc = fma(tile_a[lid.y][i], tile_b[i][lid.x], acc);
        }
        workgroupBarrier();
    }
    if (row < dims.m && col < dims.n) {
        result[row * dims.n + col] = acc * dims.alpha;
    }
}

@compute @workgroup_size($wg1d)
fn scale_in_place(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i < arrayLength(&result)) {
        result[i] = result[i] * dims.alpha + $bias;
    }
}
""",
        tile=tile,
        wg1d=rng.choice([64, 128, 256]),
        bias=fl(rng.uniform(-0.1, 0.1)),
    )


def fam_pathtrace(rng: random.Random) -> str:
    n_spheres = rng.randint(3, 6)
    spheres = ",\n".join(
        f"        Sphere(vec3<f32>({fl(rng.uniform(-3, 3))}, {fl(rng.uniform(-1, 2))}, "
        f"{fl(rng.uniform(2, 8))}), {fl(rng.uniform(0.3, 1.5))}, "
        f"vec3<f32>({fl(rng.random())}, {fl(rng.random())}, {fl(rng.random())}), "
        f"{fl(rng.choice([0.0, 0.0, 1.0]))})"
        for _ in range(n_spheres)
    )
    return t(
        """
struct Ray {
    origin: vec3<f32>,
    direction: vec3<f32>,
};

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    albedo: vec3<f32>,
    metal: f32,
};

struct HitRecord {
    t: f32,
    normal: vec3<f32>,
    albedo: vec3<f32>,
    metal: f32,
    hit: bool,
};

struct Frame {
    camera_position: vec3<f32>,
    sample_index: u32,
    resolution: vec2<u32>,
    bounces: u32,
    _pad: u32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read_write> accumulation: array<vec4<f32>>;
@group(0) @binding(2) var target_texture: texture_storage_2d<rgba8unorm, write>;

var<private> rng_state: u32;

fn next_random() -> f32 {
    rng_state = rng_state * 747796405u + 2891336453u;
    var word = ((rng_state >> ((rng_state >> 28u) + 4u)) ^ rng_state) * 277803737u;
    word = (word >> 22u) ^ word;
    return f32(word) / 4294967295.0;
}

fn random_unit_vector() -> vec3<f32> {
    let z = next_random() * 2.0 - 1.0;
    let a = next_random() * 6.2831853;
    let r = sqrt(1.0 - z * z);
    return vec3<f32>(r * cos(a), r * sin(a), z);
}

fn hit_sphere(s: Sphere, ray: Ray, t_min: f32, t_max: f32) -> f32 {
    let oc = ray.origin - s.center;
    let a = dot(ray.direction, ray.direction);
    let half_b = dot(oc, ray.direction);
    let c = dot(oc, oc) - s.radius * s.radius;
    let discriminant = half_b * half_b - a * c;
    if (discriminant < 0.0) {
        return -1.0;
    }
    let sq = sqrt(discriminant);
    var root = (-half_b - sq) / a;
    if (root < t_min || root > t_max) {
        root = (-half_b + sq) / a;
        if (root < t_min || root > t_max) {
            return -1.0;
        }
    }
    return root;
}

fn trace_scene(ray: Ray) -> HitRecord {
    var spheres = array<Sphere, $n>(
$spheres,
    );
    var rec: HitRecord;
    rec.hit = false;
    rec.t = 1.0e30;
    for (var i = 0; i < $n; i++) {
        let t = hit_sphere(spheres[i], ray, 0.001, rec.t);
        if (t > 0.0) {
            rec.hit = true;
            rec.t = t;
            rec.normal = normalize(ray.origin + ray.direction * t - spheres[i].center);
            rec.albedo = spheres[i].albedo;
            rec.metal = spheres[i].metal;
        }
    }
    return rec;
}

fn radiance(primary: Ray) -> vec3<f32> {
    var ray = primary;
    var throughput = vec3<f32>(1.0);
    for (var bounce = 0u; bounce < frame.bounces; bounce++) {
        let rec = trace_scene(ray);
        if (!rec.hit) {
            let k = 0.5 * (ray.direction.y + 1.0);
            return throughput * mix(vec3<f32>(1.0), vec3<f32>(0.5, 0.7, 1.0), k);
        }
        let p = ray.origin + ray.direction * rec.t;
        let diffuse_dir = normalize(rec.normal + random_unit_vector());
        let reflect_dir = reflect(ray.direction, rec.normal);
        ray = Ray(p, normalize(mix(diffuse_dir, reflect_dir, rec.metal)));
        throughput *= rec.albedo;
    }
    return vec3<f32>(0.0);
}

@compute @workgroup_size(8, 8, 1)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (any(gid.xy >= frame.resolution)) {
        return;
    }
    let pixel = gid.y * frame.resolution.x + gid.x;
    rng_state = pixel * 9781u + frame.sample_index * 6271u;
    let uv = (vec2<f32>(gid.xy) + vec2<f32>(next_random(), next_random())) / vec2<f32>(frame.resolution);
    let aspect = f32(frame.resolution.x) / f32(frame.resolution.y);
    let dir = normalize(vec3<f32>((uv.x * 2.0 - 1.0) * aspect, 1.0 - uv.y * 2.0, $focal));
    let color = radiance(Ray(frame.camera_position, dir));
    let previous = accumulation[pixel];
    let accumulated = (previous.rgb * f32(frame.sample_index) + color) / f32(frame.sample_index + 1u);
    accumulation[pixel] = vec4<f32>(accumulated, 1.0);
    textureStore(target_texture, vec2<i32>(gid.xy), vec4<f32>(sqrt(accumulated), 1.0));
}
""",
        n=n_spheres,
        spheres=spheres,
        focal=fl(rng.uniform(1.0, 2.5)),
    )


def fam_overrides(rng: random.Random) -> str:
    bins = rng.choice([64, 128, 256])
    return t(
        """
@id(0) override workgroup_width: u32 = ${wg}u;
override histogram_scale: f32 = $scale;
override use_log_luminance: bool = true;

const BINS: u32 = ${bins}u;

@group(0) @binding(0) var source_image: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> histogram: array<atomic<u32>, $bins>;
@group(0) @binding(2) var<storage, read_write> average: f32;

var<workgroup> local_bins: array<atomic<u32>, $bins>;

fn luminance_bin(color: vec3<f32>) -> u32 {
    let l = dot(color, vec3<f32>(0.2126, 0.7152, 0.0722));
    if (l < 0.0001) {
        return 0u;
    }
    var v = l;
    if (use_log_luminance) {
        v = log2(l) * 0.0625 + 0.5;
    }
    return u32(clamp(v * histogram_scale, 0.0, 1.0) * f32(BINS - 2u)) + 1u;
}

@compute @workgroup_size(workgroup_width, 1, 1)
fn build_histogram(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lindex: u32,
) {
    if (lindex < BINS) {
        atomicStore(&local_bins[lindex], 0u);
    }
    workgroupBarrier();
    let dims = textureDimensions(source_image);
    let width = dims.x;
    let coord = vec2<u32>(gid.x % width, gid.x / width);
    if (coord.y < dims.y) {
        let color = textureLoad(source_image, coord, 0).rgb;
        atomicAdd(&local_bins[luminance_bin(color)], 1u);
    }
    workgroupBarrier();
    if (lindex < BINS) {
        atomicAdd(&histogram[lindex], atomicLoad(&local_bins[lindex]));
    }
}

@compute @workgroup_size(1)
fn average_histogram() {
    var weighted = 0.0;
    var total = 0.0;
    for (var i = 1u; i < BINS; i++) {
        let count = f32(atomicLoad(&histogram[i]));
        weighted += count * f32(i);
        total += count;
    }
    average = weighted / max(total, 1.0);
}
""",
        wg=rng.choice([64, 128, 256]),
        scale=fl(rng.uniform(0.5, 2.0)),
        bins=bins,
    )


FAMILIES = [
    ("textured_mesh", fam_textured_mesh),
    ("pbr", fam_pbr),
    ("blur_compute", fam_blur_compute),
    ("particles", fam_particles),
    ("noise", fam_noise),
    ("skinning", fam_skinning),
    ("tonemap", fam_tonemap),
    ("shadow", fam_shadow),
    ("raymarch", fam_raymarch),
    ("matmul", fam_matmul),
    ("pathtrace", fam_pathtrace),
    ("histogram", fam_overrides),
]


def valid_shader(rng: random.Random, family: int) -> tuple[str, str]:
    name, fn = FAMILIES[family % len(FAMILIES)]
    body = fn(rng)
    header = f"// loupe bench corpus: {name} (valid)\n"
    return name, header + pick_helpers(rng) + body


# ---------------------------------------------------------------------------
# Error injection. Each mutator takes a valid module and returns a broken one.
# They mimic the mistakes people make while editing shaders, and every one
# is checked against naga by --verify.
# ---------------------------------------------------------------------------


def _function_headers(src: str) -> list[int]:
    """Indices of lines that open a function body (`fn name(...) ... {`)."""
    lines = src.split("\n")
    return [i for i, line in enumerate(lines) if line.startswith("fn ") and line.rstrip().endswith("{")]


def _insert_in_function(rng: random.Random, src: str, stmt: str) -> str:
    lines = src.split("\n")
    at = rng.choice(_function_headers(src))
    lines.insert(at + 1, "    " + stmt)
    return "\n".join(lines)


def _append_top_level(rng: random.Random, src: str, item: str) -> str:
    # Put the item between two top-level declarations, not always at the end.
    lines = src.split("\n")
    spots = [i for i, line in enumerate(lines) if line == "}"] or [len(lines) - 1]
    at = rng.choice(spots) + 1
    lines[at:at] = ["", *item.strip("\n").split("\n")]
    return "\n".join(lines)


def mut_type_mismatch(rng: random.Random, src: str, n: int) -> str:
    options = [
        f"fn scale_mixed_{n}(a: f32, b: i32) -> f32 {{\n    return a * b;\n}}",
        f"fn widen_{n}(v: vec3<f32>) -> vec4<f32> {{\n    let w: vec4<f32> = v;\n    return w;\n}}",
        f"fn count_up_{n}() -> u32 {{\n    var count: u32 = 0u;\n    count = count + 1.5;\n    return count;\n}}",
        f"fn as_flag_{n}(x: f32) -> bool {{\n    return x;\n}}",
        f"fn gate_{n}(x: f32) -> f32 {{\n    if (x) {{\n        return 1.0;\n    }}\n    return 0.0;\n}}",
        f"fn tint_{n}(c: vec3<f32>) -> vec3<f32> {{\n    return c * vec4<f32>(0.5);\n}}",
    ]
    return _append_top_level(rng, src, rng.choice(options))


def mut_undefined(rng: random.Random, src: str, n: int) -> str:
    choice = rng.randrange(3)
    if choice == 0:
        return _insert_in_function(rng, src, f"let debug_{n} = exposure_scale_{n} * 2.0;")
    if choice == 1:
        item = f"fn shade_{n}(n: vec3<f32>) -> vec3<f32> {{\n    return compute_lighting_v{n}(n, vec3<f32>(0.0, 1.0, 0.0));\n}}"
        return _append_top_level(rng, src, item)
    item = f"fn lerp_{n}(a: Vec3, b: Vec3, t: f32) -> Vec3 {{\n    return mix(a, b, t);\n}}"
    return _append_top_level(rng, src, item)


def mut_syntax(rng: random.Random, src: str, n: int) -> str:
    choice = rng.randrange(4)
    lines = src.split("\n")
    if choice == 0:
        # A forgotten semicolon after a let/var/return statement.
        cands = [i for i, l in enumerate(lines) if re.match(r"^\s+(let|var|return) .*;$", l)]
        i = rng.choice(cands)
        lines[i] = lines[i][:-1]
        return "\n".join(lines)
    if choice == 1:
        # An unclosed function body: drop the last closing brace.
        i = max(i for i, l in enumerate(lines) if l == "}")
        del lines[i]
        return "\n".join(lines)
    if choice == 2:
        item = f"fn broken_{n}(x: f32 -> f32 {{\n    return x * 2.0;\n}}"
        return _append_top_level(rng, src, item)
    return _insert_in_function(rng, src, f"let v{n} = vec3<f32>(1.0, 2.0, 3.0;")


def mut_binding(rng: random.Random, src: str, n: int) -> str:
    g = 3
    options = [
        # A texture can't live in the uniform address space.
        f"@group({g}) @binding({n % 8}) var<uniform> lut_{n}: texture_2d<f32>;",
        # Runtime-sized arrays are only allowed in storage buffers.
        f"@group({g}) @binding({n % 8}) var<uniform> weights_{n}: array<f32>;",
        # Atomics can't be uniforms (naga 30 does *not* reject an atomic in
        # read-only storage, so that variant would not be an invalid file).
        f"@group({g}) @binding({n % 8}) var<uniform> counter_{n}: atomic<u32>;\n\n"
        f"fn peek_counter_{n}() -> u32 {{\n    return atomicLoad(&counter_{n});\n}}",
        # Sampling a colour texture with a comparison sampler.
        f"@group({g}) @binding(0) var tex_{n}: texture_2d<f32>;\n"
        f"@group({g}) @binding(1) var cmp_{n}: sampler_comparison;\n\n"
        f"fn fetch_{n}(uv: vec2<f32>) -> vec4<f32> {{\n    return textureSampleLevel(tex_{n}, cmp_{n}, uv, 0.0);\n}}",
        # Writing through a read-only storage binding.
        f"@group({g}) @binding({n % 8}) var<storage, read> out_{n}: array<vec4<f32>>;\n\n"
        f"fn store_{n}(i: u32, v: vec4<f32>) {{\n    out_{n}[i] = v;\n}}",
        # Storing into a sampled texture (naga 30 accepts textureLoad from
        # a write-only storage texture, so that one is not used here).
        f"@group({g}) @binding({n % 8}) var img_{n}: texture_2d<f32>;\n\n"
        f"fn poke_{n}(p: vec2<i32>, c: vec4<f32>) {{\n    textureStore(img_{n}, p, c);\n}}",
    ]
    return _append_top_level(rng, src, rng.choice(options))


def mut_missing_return(rng: random.Random, src: str, n: int) -> str:
    options = [
        f"fn half_{n}(x: f32) -> f32 {{\n    let y = x * 0.5;\n}}",
        f"fn positive_part_{n}(x: f32) -> f32 {{\n    if (x > 0.0) {{\n        return x;\n    }}\n}}",
        f"fn pick_{n}(i: u32) -> vec3<f32> {{\n    switch i {{\n        case 0u: {{\n            return vec3<f32>(1.0, 0.0, 0.0);\n        }}\n        default: {{\n        }}\n    }}\n}}",
    ]
    return _append_top_level(rng, src, rng.choice(options))


def mut_misc(rng: random.Random, src: str, n: int) -> str:
    options = [
        # Assigning to an immutable `let`.
        ("fn", f"let frozen_{n} = 1.0;\n    frozen_{n} = 2.0;"),
        # Wrong number of arguments to a builtin.
        ("fn", f"let clamped_{n} = clamp(0.5, 1.0);"),
        # Redeclaring a name in the same scope.
        ("fn", f"let twice_{n} = 1u;\n    let twice_{n} = 2u;"),
        # A compute entry point without @workgroup_size.
        ("top", f"@compute\nfn orphan_kernel_{n}(@builtin(global_invocation_id) gid: vec3<u32>) {{\n}}"),
        # A vertex entry point that never outputs a position.
        ("top", f"@vertex\nfn vs_no_position_{n}(@location(0) p: vec3<f32>) -> @location(0) vec4<f32> {{\n    return vec4<f32>(p, 1.0);\n}}"),
    ]
    where, text = rng.choice(options)
    if where == "fn":
        return _insert_in_function(rng, src, text)
    return _append_top_level(rng, src, text)


MUTATORS = [
    ("type_mismatch", mut_type_mismatch),
    ("undefined_identifier", mut_undefined),
    ("syntax_error", mut_syntax),
    ("wrong_binding", mut_binding),
    ("missing_return", mut_missing_return),
    ("misc_semantic", mut_misc),
]


# ---------------------------------------------------------------------------
# Large files: a generated "material graph" -- the shape node-based editors
# and uber-shader generators produce: hundreds to thousands of small
# functions, each calling a couple of earlier ones, a few compute kernels
# sprinkled in, and a fragment entry point at the end.
# ---------------------------------------------------------------------------

LARGE_HEADER = """// loupe bench corpus: generated material graph (large)
struct Globals {
    time: f32,
    frame: u32,
    resolution: vec2<f32>,
    params: array<vec4<f32>, 16>,
};

struct GraphIn {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) normal: vec3<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;
@group(0) @binding(1) var graph_texture: texture_2d<f32>;
@group(0) @binding(2) var graph_sampler: sampler;
@group(0) @binding(3) var<storage, read_write> graph_cache: array<vec4<f32>>;

fn graph_hash(p: vec2<f32>) -> f32 {
    return fract(sin(dot(p, vec2<f32>(12.9898, 78.233))) * 43758.5453);
}
"""

SCALAR_EXPRS = [
    "sin(p.x * $a + t)",
    "cos(p.y * $a - t * $b)",
    "fract(dot(p, vec2<f32>($a, $b)))",
    "smoothstep($a, $b + 1.0, length(p))",
    "graph_hash(p * $a)",
    "abs(p.x - p.y) * $a",
    "exp(-dot(p, p) * $a)",
    "atan2(p.y, p.x + $a)",
]


def _gen_node(rng: random.Random, i: int) -> list[str]:
    """One generated graph node: `fn node_i(p: vec2<f32>, t: f32) -> vec4<f32>`."""

    def expr() -> str:
        return Template(rng.choice(SCALAR_EXPRS)).substitute(
            a=fl(rng.uniform(0.1, 9.0)), b=fl(rng.uniform(0.1, 3.0))
        )

    body = [f"fn node_{i}(p_in: vec2<f32>, t: f32) -> vec4<f32> {{"]
    body.append(f"    let p = p_in * {fl(rng.uniform(0.5, 3.0))} + vec2<f32>({fl(rng.uniform(-1, 1))}, {fl(rng.uniform(-1, 1))});")
    body.append(f"    var acc = vec4<f32>({expr()}, {expr()}, {expr()}, 1.0);")
    kind = rng.randrange(5)
    if i > 0 and kind in (0, 1):
        # Blend with one or two earlier nodes (a DAG, never recursion).
        a = rng.randrange(max(0, i - 40), i)
        body.append(f"    acc = mix(acc, node_{a}(p.yx, t * {fl(rng.uniform(0.2, 2.0))}), {fl(rng.random())});")
        if i > 1 and kind == 1:
            b = rng.randrange(max(0, i - 40), i)
            body.append(f"    acc += node_{b}(p * 0.5, t) * {fl(rng.uniform(0.05, 0.5))};")
    elif kind == 2:
        body.append(f"    for (var k = 0; k < {rng.randint(2, 6)}; k++) {{")
        body.append(f"        let q = p + vec2<f32>(f32(k) * {fl(rng.uniform(0.1, 1.0))}, t);")
        body.append(f"        acc = acc * {fl(rng.uniform(0.5, 0.95))} + vec4<f32>(sin(q.x), cos(q.y), fract(q.x * q.y), 0.0) * 0.1;")
        body.append("    }")
    elif kind == 3:
        body.append(f"    switch u32(abs(p.x) * {fl(rng.uniform(1, 8))}) % 4u {{")
        for c in range(3):
            body.append(f"        case {c}u: {{")
            body.append(f"            acc = acc.yzxw * {fl(rng.uniform(0.5, 1.5))};")
            body.append("        }")
        body.append("        default: {")
        body.append("            acc = vec4<f32>(acc.rgb * 0.5, acc.a);")
        body.append("        }")
        body.append("    }")
    else:
        body.append(f"    let m = mat2x2<f32>({fl(rng.uniform(-1, 1))}, {fl(rng.uniform(-1, 1))}, {fl(rng.uniform(-1, 1))}, {fl(rng.uniform(-1, 1))});")
        body.append("    let r = m * p;")
        body.append(f"    if (r.x > {fl(rng.uniform(-1, 1))}) {{")
        body.append(f"        acc = vec4<f32>(acc.rgb * {fl(rng.uniform(0.5, 1.5))}, acc.a);")
        body.append("    } else {")
        body.append("        acc = vec4<f32>(acc.bgr, acc.a);")
        body.append("    }")
    body.append(f"    acc += globals.params[{rng.randrange(16)}] * {fl(rng.uniform(0.0, 0.2))};")
    body.append("    return clamp(acc, vec4<f32>(-4.0), vec4<f32>(4.0));")
    body.append("}")
    body.append("")
    return body


def _gen_kernel(rng: random.Random, i: int, last_node: int) -> list[str]:
    return [
        f"@compute @workgroup_size({rng.choice([64, 128, 256])})",
        f"fn bake_{i}(@builtin(global_invocation_id) gid: vec3<u32>) {{",
        "    let index = gid.x;",
        "    if (index >= arrayLength(&graph_cache)) {",
        "        return;",
        "    }",
        f"    let p = vec2<f32>(f32(index % 256u), f32(index / 256u)) / 256.0;",
        f"    graph_cache[index] = node_{last_node}(p, globals.time);",
        "}",
        "",
    ]


def large_shader(rng: random.Random, target_lines: int) -> str:
    lines = LARGE_HEADER.split("\n")
    i = 0
    kernels = 0
    while len(lines) < target_lines - 20:
        lines += _gen_node(rng, i)
        if i % 97 == 96:
            lines += _gen_kernel(rng, kernels, i)
            kernels += 1
        i += 1
    picks = sorted(rng.sample(range(i), min(4, i)))
    lines += [
        "@vertex",
        "fn graph_vs(@builtin(vertex_index) vi: u32) -> GraphIn {",
        "    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));",
        "    var out: GraphIn;",
        "    out.position = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);",
        "    out.uv = uv;",
        "    out.normal = vec3<f32>(0.0, 0.0, 1.0);",
        "    return out;",
        "}",
        "",
        "@fragment",
        "fn graph_fs(in: GraphIn) -> @location(0) vec4<f32> {",
        "    let base = textureSample(graph_texture, graph_sampler, in.uv);",
        "    var color = base;",
    ]
    lines += [f"    color += node_{k}(in.uv, globals.time) * 0.25;" for k in picks]
    lines += [
        "    return vec4<f32>(color.rgb * max(in.normal.z, 0.0), 1.0);",
        "}",
        "",
    ]
    return "\n".join(lines)


def break_large(rng: random.Random, src: str, n: int) -> tuple[str, str]:
    """Break a large module near its end, so the whole file must be read."""
    lines = src.split("\n")
    headers = [i for i, l in enumerate(lines) if l.startswith("fn node_")]
    at = headers[-1 - rng.randrange(min(5, len(headers)))]
    if n % 2 == 0:
        lines.insert(at + 1, f"    let warp_{n} = undefined_warp_strength * 2.0;")
        return "\n".join(lines), "undefined_identifier"
    lines.insert(at + 1, f"    let wrong_{n}: vec3<f32> = p_in;")
    return "\n".join(lines), "type_mismatch"


# ---------------------------------------------------------------------------


def generate(out: Path) -> list[tuple[str, str, str, int]]:
    rng = random.Random(SEED)
    out.mkdir(parents=True, exist_ok=True)
    # Only remove files this script writes; never wipe a directory wholesale.
    for old in list(out.glob("ok_*.wgsl")) + list(out.glob("bad_*.wgsl")):
        old.unlink()

    entries: list[tuple[str, str, str, int]] = []

    def write(name: str, expected: str, kind: str, text: str) -> None:
        if not text.endswith("\n"):
            text += "\n"
        (out / name).write_text(text, encoding="utf-8", newline="\n")
        entries.append((name, expected, kind, text.count("\n")))

    # Interleave valid and invalid files in index order so a checker that
    # sorts by name still sees a realistic mix rather than two blocks.
    total = N_VALID + N_INVALID
    invalid_slots = set(rng.sample(range(total), N_INVALID))
    valid_i = 0
    invalid_i = 0
    for idx in range(total):
        if idx in invalid_slots:
            kind, mutate = MUTATORS[invalid_i % len(MUTATORS)]
            family = rng.randrange(len(FAMILIES))
            _, base = valid_shader(rng, family)
            text = mutate(rng, base, idx).replace("(valid)", f"(invalid: {kind})", 1)
            write(f"bad_{idx:03d}_{kind}.wgsl", "bad", kind, text)
            invalid_i += 1
        else:
            family, text = valid_shader(rng, valid_i)
            write(f"ok_{idx:03d}_{family}.wgsl", "ok", family, text)
            valid_i += 1

    for j, size in enumerate(LARGE_SIZES):
        text = large_shader(rng, size)
        if j >= len(LARGE_SIZES) - N_LARGE_INVALID:
            text, kind = break_large(rng, text, j)
            write(f"bad_L{j:02d}_large_{size}.wgsl", "bad", f"large_{kind}", text)
        else:
            write(f"ok_L{j:02d}_large_{size}.wgsl", "ok", "large", text)

    with (out / "MANIFEST.tsv").open("w", encoding="utf-8", newline="\n") as f:
        f.write("file\texpected\tkind\tlines\n")
        for e in entries:
            f.write("\t".join(map(str, e)) + "\n")
    (out / ".gen-stamp").write_text(script_hash() + "\n", encoding="utf-8")
    return entries


def script_hash() -> str:
    return hashlib.sha256(Path(__file__).read_bytes()).hexdigest()


def verify(out: Path, entries: list[tuple[str, str, str, int]], naga: str) -> bool:
    """Check every file against naga: ok_* must validate, bad_* must not."""
    ok = True
    for name, expected, kind, _ in entries:
        r = subprocess.run([naga, str(out / name)], capture_output=True, text=True)
        valid = r.returncode == 0
        if valid != (expected == "ok"):
            ok = False
            print(f"MISMATCH {name}: expected {expected}, naga exit {r.returncode}", file=sys.stderr)
            print(r.stderr.strip()[:2000], file=sys.stderr)
    # Bulk mode must agree and name exactly the bad files.
    r = subprocess.run(
        [naga, "--bulk-validate", *[str(out / e[0]) for e in entries]],
        capture_output=True,
        text=True,
    )
    listed = set(re.findall(r"^  (\S+\.wgsl)$", r.stderr, re.M))
    want = {str(out / e[0]) for e in entries if e[1] == "bad"}
    if listed != want:
        ok = False
        print(f"bulk-validate disagrees: missing {sorted(want - listed)}, extra {sorted(listed - want)}", file=sys.stderr)
    return ok


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="?", default="target/bench-corpus", help="output directory (default: %(default)s)")
    ap.add_argument("--verify", metavar="NAGA", help="check every file's validity with this naga binary")
    args = ap.parse_args()

    out = Path(args.out)
    entries = generate(out)
    n_bad = sum(1 for e in entries if e[1] == "bad")
    n_lines = sum(e[3] for e in entries)
    print(f"wrote {len(entries)} files ({len(entries) - n_bad} valid, {n_bad} invalid, {n_lines} lines) to {out}")
    if args.verify:
        if not verify(out, entries, args.verify):
            print("corpus verification FAILED", file=sys.stderr)
            return 1
        print("verified with naga: every ok_* file validates, every bad_* file is rejected")
    return 0


if __name__ == "__main__":
    sys.exit(main())
