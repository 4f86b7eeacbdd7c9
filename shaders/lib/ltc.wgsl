// Rectangular area lights shaded with Linearly Transformed Cosines
// (Heitz, Dupuy, Hill, Neubelt 2016) for a GGX specular lobe and a Lambert
// diffuse lobe.
//
// The two tables come from `render::ltc::create_textures` (64 x 64,
// unfilterable float, read here with `textureLoad` and a manual bilinear
// filter). Texel (i, j) holds the fit for
//     roughness      = i / 63   (perceptual; GGX alpha = roughness^2)
//     sqrt(1 - N.V)  = j / 63
// so a lookup at texel coordinate (roughness * 63, sqrt(1 - N.V) * 63)
// lands exactly on the fitted samples.
//
// Light convention: `corners` are the rectangle's four vertices in order,
// counter-clockwise as seen from the side that emits, i.e. the emitting
// normal is normalize(cross(c1 - c0, c3 - c0)). With `two_sided` both faces
// emit.
//
// Horizon: clipped exactly, not approximated with the sphere trick. The
// polygon is clipped to the surface's hemisphere (so the diffuse term is the
// exact form factor even for a light partly below the surface), then, for
// the specular term, after the inverse LTC transform, to the cosine's
// hemisphere (Sutherland-Hodgman each time: 4 vertices in, at most 6 out).
//
// Accuracy (tests in render/ltc.rs, on lavapipe): diffuse within 4e-7 of the
// exact form factor; specular within LTC's own fit error of true GGX, a few
// percent for the highlight, more in the tails at grazing views.
#define_import_path loupe::ltc

const LTC_SIZE: u32 = 64u;
const LTC_PI: f32 = 3.14159265358979;

struct LtcResult {
    // Lambert form factor of the light seen from p: (1/pi) * integral of
    // max(cos, 0) over the rectangle's solid angle. Outgoing radiance is
    // albedo * light_radiance * diffuse.
    diffuse: f32,
    // GGX specular, already multiplied by the fitted magnitude and Fresnel
    // terms and split by Schlick weight: outgoing radiance is
    //     light_radiance * (f0 * specular.x + f90 * specular.y)
    // (f0/f90 may be vec3 colours; f90 = 1 for plain Schlick).
    specular: vec2<f32>,
}

// Manual bilinear filter at a texel-space coordinate (0 = first texel's
// centre, 63 = last's). The renderer binds these tables unfilterable, and
// f32 filtering is an optional feature anyway.
fn ltc_fetch(tex: texture_2d<f32>, at: vec2<f32>) -> vec4<f32> {
    let last = f32(LTC_SIZE - 1u);
    let c = clamp(at, vec2(0.0), vec2(last));
    // The lower texel stops one short of the edge so the upper one always
    // exists; at the edge the weight then reaches exactly 1.
    let i = min(vec2<u32>(floor(c)), vec2(LTC_SIZE - 2u));
    let f = c - vec2<f32>(i);
    let a = textureLoad(tex, vec2<i32>(i), 0);
    let b = textureLoad(tex, vec2<i32>(i + vec2(1u, 0u)), 0);
    let d = textureLoad(tex, vec2<i32>(i + vec2(0u, 1u)), 0);
    let e = textureLoad(tex, vec2<i32>(i + vec2(1u, 1u)), 0);
    return mix(mix(a, b, f.x), mix(d, e, f.x), f.y);
}

// Texel coordinate of the fit for a roughness and cos(theta_v).
fn ltc_table_coord(roughness: f32, n_dot_v: f32) -> vec2<f32> {
    let last = f32(LTC_SIZE - 1u);
    let u = clamp(roughness, 0.0, 1.0);
    let v = sqrt(1.0 - clamp(n_dot_v, 0.0, 1.0));
    return vec2(u, v) * last;
}

// Rows of the shading frame (t1, t2, n), with t1 towards v: the tables
// were fitted with the view vector at (sin theta, 0, cos theta).
fn ltc_frame(n: vec3<f32>, v: vec3<f32>) -> mat3x3<f32> {
    var t = v - n * dot(n, v);
    if dot(t, t) < 1e-12 {
        // v along n: the fit is isotropic there, so any tangent will do.
        // Pick the axis least aligned with n to keep the cross product large.
        let a = abs(n);
        var axis = vec3(1.0, 0.0, 0.0);
        if a.y <= a.x && a.y <= a.z {
            axis = vec3(0.0, 1.0, 0.0);
        } else if a.z <= a.x && a.z <= a.y {
            axis = vec3(0.0, 0.0, 1.0);
        }
        t = cross(axis, n);
    }
    let t1 = normalize(t);
    let t2 = cross(n, t1);
    // mat * x takes columns; transposing turns (t1, t2, n) into rows, so
    // frame * w = (t1.w, t2.w, n.w).
    return transpose(mat3x3(t1, t2, n));
}

// Contribution of one great-circle arc a -> b (unit vectors) to the
// z-component of the vector form factor, times 2 pi. atan2 keeps small
// arcs accurate where acos(dot) would lose them in f32.
fn ltc_edge(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let c = cross(a, b);
    let s = length(c);
    let theta = atan2(s, dot(a, b));
    // theta / sin(theta) tends to 1 as the arc vanishes.
    let k = select(theta / s, 1.0, s < 1e-8);
    return c.z * k;
}

// A convex polygon of up to 6 vertices: a quad clipped by two planes.
struct LtcPolygon {
    v: array<vec3<f32>, 6>,
    count: u32,
}

// The part of a convex polygon with z >= 0 (Sutherland-Hodgman: keep the
// vertices above, insert the crossing point on every edge that changes
// side). The crossing is taken on the straight edge, whose projection onto
// the sphere is the same great arc, so the clip is exact for the spherical
// polygon too.
fn ltc_clip(p: LtcPolygon) -> LtcPolygon {
    var src = p.v;
    var out: LtcPolygon;
    out.count = 0u;
    for (var i = 0u; i < p.count; i++) {
        let a = src[i];
        let b = src[select(i + 1u, 0u, i + 1u == p.count)];
        // A convex polygon changes side at most twice, so at most one
        // vertex is added; the bound only guards against rounding making a
        // nearly degenerate polygon look otherwise.
        if a.z >= 0.0 && out.count < 6u {
            out.v[out.count] = a;
            out.count++;
        }
        if (a.z >= 0.0) != (b.z >= 0.0) && out.count < 6u {
            out.v[out.count] = mix(a, b, a.z / (a.z - b.z));
            out.count++;
        }
    }
    return out;
}

// Signed (1/pi) * integral of the cosine (z) over the polygon's solid
// angle, polygon positions relative to the shaded point; the polygon must
// already lie in z >= 0. Positive when its vertices run clockwise as seen
// from the origin.
fn ltc_integral(p: LtcPolygon) -> f32 {
    if p.count < 3u {
        return 0.0;
    }
    var v = p.v;
    var sum = 0.0;
    for (var i = 0u; i < p.count; i++) {
        let a = v[i];
        let b = v[select(i + 1u, 0u, i + 1u == p.count)];
        // A vertex at the origin (the point lies on the light) has no
        // direction; skip its edges rather than produce NaN.
        if dot(a, a) > 0.0 && dot(b, b) > 0.0 {
            sum += ltc_edge(normalize(a), normalize(b));
        }
    }
    return sum / (2.0 * LTC_PI);
}

// Applies the light's sidedness to a signed integral. A lit origin sees the
// corners counter-clockwise (it is on the emitting side), which makes the
// signed integral negative. Both transforms applied before (the frame and
// the inverse LTC matrix) have a positive determinant, so they keep this.
fn ltc_sided(signed_integral: f32, two_sided: bool) -> f32 {
    let lit = -signed_integral;
    return select(max(lit, 0.0), abs(lit), two_sided);
}

// Diffuse and GGX specular from one rectangular light.
//   n          unit surface normal
//   v          unit vector from the surface towards the eye
//   p          the shaded position (same space as `corners`)
//   roughness  perceptual roughness in [0, 1]; GGX alpha = roughness^2
//   corners    the rectangle, see the convention at the top
//   m_tex      table 0: inverse LTC matrix (render::ltc)
//   amp_tex    table 1: magnitude and Fresnel terms (render::ltc)
fn ltc_rect(
    n: vec3<f32>,
    v: vec3<f32>,
    p: vec3<f32>,
    roughness: f32,
    corners: array<vec3<f32>, 4>,
    two_sided: bool,
    m_tex: texture_2d<f32>,
    amp_tex: texture_2d<f32>,
) -> LtcResult {
    let frame = ltc_frame(n, v);
    var quad: LtcPolygon;
    quad.count = 4u;
    for (var i = 0u; i < 4u; i++) {
        quad.v[i] = frame * (corners[i] - p);
    }
    // Below the surface both lobes are zero: clip to its hemisphere first.
    let above = ltc_clip(quad);

    let at = ltc_table_coord(roughness, dot(n, v));
    let m = ltc_fetch(m_tex, at);
    let amp = ltc_fetch(amp_tex, at);
    // The inverse matrix with its middle element normalised to 1:
    //     | m.x  0  m.z |
    //     |  0   1   0  |
    //     | m.y  0  m.w |
    // (the scale drops out: only directions matter).
    let minv = mat3x3(vec3(m.x, 0.0, m.y), vec3(0.0, 1.0, 0.0), vec3(m.z, 0.0, m.w));
    var warped = above;
    for (var i = 0u; i < above.count; i++) {
        warped.v[i] = minv * warped.v[i];
    }
    // Then to the cosine's own hemisphere in the transformed space.
    // Heitz et al. clip only here; the first clip also drops the part of
    // the fitted lobe that leaks under the surface, where GGX is zero
    // (measured on a light standing on the surface, roughness 0.5: the
    // error against GGX falls from 23% to 12% at 60 degrees from the
    // normal, from 38% to 21% at 80).
    warped = ltc_clip(warped);

    // Identity LTC: the clamped cosine itself, i.e. Lambert.
    let diffuse = ltc_sided(ltc_integral(above), two_sided);
    let spec = ltc_sided(ltc_integral(warped), two_sided);
    // amp.x = integral of the BRDF (F = 1) times cosine; amp.y = the same
    // weighted by the Schlick factor (1 - V.H)^5. With
    // F = f0 + (f90 - f0) (1 - V.H)^5 the lobe scales by
    // f0 (amp.x - amp.y) + f90 amp.y.
    var r: LtcResult;
    r.diffuse = diffuse;
    r.specular = spec * vec2(amp.x - amp.y, amp.y);
    return r;
}
