//! The little linear algebra meshes need: 3-vectors and glTF's column-major
//! affine 4×4 node matrices.

pub type Vec3 = [f32; 3];

/// Column-major, as glTF stores `node.matrix`: element (row r, column c) is
/// `m[c * 4 + r]`.
pub type Mat4 = [f32; 16];

pub const IDENTITY: Mat4 = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];

pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn scale(a: Vec3, s: f32) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn dot(a: Vec3, b: Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `v` scaled to unit length, or +Y when it has no direction (a degenerate
/// triangle's normal, a collapsed transform): shaders normalise nothing and a
/// zero or NaN normal would poison lighting.
pub fn normalize_or_up(v: Vec3) -> Vec3 {
    let len = dot(v, v).sqrt();
    if len > 0.0 && len.is_finite() { scale(v, 1.0 / len) } else { [0.0, 1.0, 0.0] }
}

pub fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut m = [0.0; 16];
    for c in 0..4 {
        for r in 0..4 {
            m[c * 4 + r] = (0..4).map(|k| a[k * 4 + r] * b[c * 4 + k]).sum();
        }
    }
    m
}

/// translation · rotation · scale, glTF's order; `q` is a unit quaternion
/// (x, y, z, w).
pub fn from_trs(t: Vec3, q: [f32; 4], s: Vec3) -> Mat4 {
    let [x, y, z, w] = q;
    let rotation = [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + z * w), 2.0 * (x * z - y * w)],
        [2.0 * (x * y - z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + x * w)],
        [2.0 * (x * z + y * w), 2.0 * (y * z - x * w), 1.0 - 2.0 * (x * x + y * y)],
    ];
    let mut m = IDENTITY;
    for (c, column) in rotation.iter().enumerate() {
        for r in 0..3 {
            m[c * 4 + r] = column[r] * s[c];
        }
    }
    m[12..15].copy_from_slice(&t);
    m
}

/// Node matrices are affine (glTF requires them to decompose into TRS), so
/// the bottom row is ignored.
pub fn transform_point(m: &Mat4, p: Vec3) -> Vec3 {
    let mut out = [m[12], m[13], m[14]];
    for (c, &pc) in p.iter().enumerate() {
        for (r, o) in out.iter_mut().enumerate() {
            *o += m[c * 4 + r] * pc;
        }
    }
    out
}

/// The columns of the upper 3×3: how the transform acts on directions
/// (tangents) as opposed to normals.
pub fn linear_columns(m: &Mat4) -> [Vec3; 3] {
    [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]]
}

/// How a transform acts on normals.
pub struct NormalTransform {
    /// The inverse-transpose of the upper 3×3, up to a positive factor:
    /// columns of the cofactor matrix, with the determinant's sign. Unlike a
    /// real inverse it exists for singular matrices (a zero scale) too.
    columns: [Vec3; 3],
    /// The transform mirrors (negative determinant): triangles must be wound
    /// the other way round to stay counter-clockwise seen from the front.
    pub mirrors: bool,
}

impl NormalTransform {
    pub fn of(m: &Mat4) -> Self {
        let a = linear_columns(m);
        // With columns a0, a1, a2: Aᵀ · [a1×a2, a2×a0, a0×a1] = det(A) · I.
        let cof = [cross(a[1], a[2]), cross(a[2], a[0]), cross(a[0], a[1])];
        let det = dot(a[0], cof[0]);
        let sign = if det < 0.0 { -1.0 } else { 1.0 };
        NormalTransform { columns: cof.map(|c| scale(c, sign)), mirrors: det < 0.0 }
    }

    pub fn apply(&self, n: Vec3) -> Vec3 {
        let [c0, c1, c2] = self.columns;
        normalize_or_up(add(add(scale(c0, n[0]), scale(c1, n[1])), scale(c2, n[2])))
    }
}
