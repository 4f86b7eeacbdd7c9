//! Test fixtures of the whole crate, shared by the unit tests of any
//! module and by the integration suites (the `testing` feature).

/// The 1-based line and column (in characters) of byte `k` of the first
/// `needle` in `text`: where a diagnostic about it must point, worked out
/// from the text rather than by the code under test.
pub fn line_col(text: &str, needle: &str, k: usize) -> (u32, u32) {
    let at = text.find(needle).unwrap_or_else(|| panic!("{needle:?} is not in {text:?}")) + k;
    let line = text[..at].matches('\n').count() + 1;
    let column = text[..at].rsplit('\n').next().unwrap().chars().count() + 1;
    (line as u32, column as u32)
}

/// A small PCG: the same random scenes and rays on every run.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn f(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        let x = (((self.0 >> 18) ^ self.0) >> 27) as u32;
        (x.rotate_right((self.0 >> 59) as u32) >> 8) as f32 / (1u32 << 24) as f32
    }

    /// Uniform in the box from `lo` to `hi`.
    pub fn in_box(&mut self, lo: glam::Vec3, hi: glam::Vec3) -> glam::Vec3 {
        lo + (hi - lo) * glam::Vec3::new(self.f(), self.f(), self.f())
    }

    /// Uniform in the cube of side `side` centred on the origin.
    pub fn centered(&mut self, side: f32) -> glam::Vec3 {
        glam::Vec3::new(self.f() - 0.5, self.f() - 0.5, self.f() - 0.5) * side
    }

    /// A uniform unit direction (rejection from the unit ball).
    pub fn dir(&mut self) -> glam::Vec3 {
        loop {
            let d = glam::Vec3::new(self.f(), self.f(), self.f()) * 2.0 - 1.0;
            if d.length_squared() > 1e-4 && d.length_squared() <= 1.0 {
                return d.normalize();
            }
        }
    }
}

/// `n` triples of uniform numbers in [0, 1), the same on every run: the
/// random numbers the BRDF's sampler is tested with.
pub fn uniforms(n: usize) -> Vec<[f32; 3]> {
    let mut rng = Rng(0x853c_49e6_748f_ea9b);
    (0..n).map(|_| [rng.f(), rng.f(), rng.f()]).collect()
}
