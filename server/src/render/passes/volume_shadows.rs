//! The volume grid (`shaders/passes/volume_shadows.wgsl`): the
//! transmittance from points over the media toward each light, which the
//! volume march samples instead of marching toward every light at every
//! step. One invocation per point and light runs `quality.volume_shadow_steps`
//! steps, so no invocation loops for long: llvmpipe cuts every loop of an
//! invocation short after 65,535 iterations in all, which made the march
//! drift once steps × shadow steps passed that.

use glam::Vec3;

use super::{LIGHTS, MEDIA, VIEW};
use crate::gpu::pipeline::{COMPUTE, FRAG, Group, PipelineSpec, Stages, storage_rw, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Element, Handle, PipelineKey, TensorLayout};
use crate::render::scene_gpu::medium_bounds;
use crate::scene::Scene;

/// The shader's workgroup side.
const TILE: u32 = 4;
/// Bytes of `VolumeGrid` (lib/volume_grid.wgsl): three vec4.
pub const GRID_BYTES: u64 = 48;
/// At most this many points × lights (64 MiB of vec4<f32>, within wgpu's
/// default storage binding limit of 128 MiB): a finer grid asked for with
/// many lights is made coarser.
const MAX_VALUES: u64 = 1 << 22;

pub static VOLUME_SHADOWS: PipelineSpec = PipelineSpec {
    name: "volume_shadows",
    shader: "passes/volume_shadows.wgsl",
    stages: Stages::Compute { entry: "main" },
    groups: &[Group::always(0, &[VIEW, LIGHTS, uniform("grid", 2, COMPUTE, GRID_BYTES), storage_rw("cells", 3)]), Group::always(3, MEDIA)],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&VOLUME_SHADOWS];

/// The grid's uniform binding in a pass that samples it.
pub const GRID_UNIFORM: crate::gpu::pipeline::Binding = uniform("grid", 4, FRAG, GRID_BYTES);

/// Where the grid's points lie: `dims` points per axis from `lo`, `spacing`
/// apart, covering the box around every medium.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridLayout {
    pub lo: Vec3,
    pub spacing: Vec3,
    pub dims: [u32; 3],
    pub lights: u32,
}

impl GridLayout {
    /// `quality.volume_grid` points along the box's longest side, the other
    /// sides in proportion (2 at least), fewer when points × lights would
    /// pass `MAX_VALUES`. `None` without media.
    pub fn of(scene: &Scene) -> Option<GridLayout> {
        let (lo, hi) = scene.media.iter().map(medium_bounds).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
        let lights = scene.lights.len() as u32;
        let extent = (hi - lo).max(Vec3::splat(1e-6));
        let longest = extent.max_element();
        let mut side = scene.quality.volume_grid.max(2);
        let dims = loop {
            let dims = extent.to_array().map(|e| ((side - 1) as f32 * e / longest).ceil().max(1.0) as u32 + 1);
            let values = dims.iter().map(|&d| u64::from(d)).product::<u64>() * u64::from(lights.max(1));
            if values <= MAX_VALUES || side == 2 {
                break dims;
            }
            side = (side * 7 / 8).max(2);
        };
        let spacing = extent / Vec3::from(dims.map(|d| (d - 1) as f32));
        Some(GridLayout { lo, spacing, dims, lights })
    }

    /// `VolumeGrid` as the shaders read it.
    pub fn uniform_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(GRID_BYTES as usize);
        for v in [self.lo.extend(0.0).to_array(), self.spacing.extend(0.0).to_array()] {
            out.extend_from_slice(bytemuck::cast_slice(&v));
        }
        let [x, y, z] = self.dims;
        out.extend_from_slice(bytemuck::cast_slice(&[x, y, z, self.lights]));
        out
    }

    /// One light's worth at least: a binding cannot be empty, and a medium
    /// without lights still glows (the march reads no light then).
    fn tensor(&self) -> TensorLayout {
        let [x, y, z] = self.dims;
        TensorLayout::new(&[("light", self.lights.max(1)), ("z", z), ("y", y), ("x", x), ("channel", 4)], Element::F32)
    }
}

/// The grid and where its points lie, for the march.
#[derive(Debug, Clone, Copy)]
pub struct VolumeGrid {
    pub layout: GridLayout,
    pub cells: Handle,
}

/// Fills the grid, or culls the pass (`None`) when the scene has no media.
pub fn volume_shadows(g: &mut GraphBuilder, scene: &Scene) -> Option<VolumeGrid> {
    let Some(layout) = GridLayout::of(scene) else {
        g.cull("volume_shadows", "the scene has no participating media");
        return None;
    };
    let mut p = g.pass("volume_shadows", PassKind::Compute);
    let key = p.pipeline(PipelineKey::new(&VOLUME_SHADOWS, &[]));
    let cells = p.create("transmittance", Meaning::Data, layout.tensor(), Access::StorageWrite);
    let params = layout.uniform_bytes();
    let [x, y, z] = layout.dims;
    let groups = [x.div_ceil(TILE), y.div_ceil(TILE), (z * layout.lights).div_ceil(TILE)];
    p.execute(move |ctx| {
        let s = ctx.scene;
        let u = ctx.uniform(&params);
        let b = [
            ("view", s.view.as_entire_binding()),
            ("lights", s.lights.as_entire_binding()),
            ("grid", u.as_entire_binding()),
            ("cells", ctx.bind(cells)),
            ("media", s.media.as_entire_binding()),
        ];
        ctx.dispatch(&key, &b, groups);
    });
    Some(VolumeGrid { layout, cells })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(text: &str) -> Scene {
        crate::scene::parse("grid.toml", text).unwrap_or_else(|d| panic!("{d}"))
    }

    const MEDIUM: &str = "[[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\n\
        [[media]]\nabsorption = [0, 0, 0]\nscattering = [1, 1, 1]\nshapes = [{ type = \"box\", center = [0, 0, 0], half_extents = [4, 1, 2] }]\n";

    /// The points cover the media's box exactly, corners included, in
    /// proportion to its sides.
    #[test]
    fn the_grid_spans_the_media_bounds_in_proportion() {
        let g = GridLayout::of(&scene(&format!("{MEDIUM}[quality]\nvolume_grid = 33\n"))).unwrap();
        assert_eq!(g.dims, [33, 9, 17]);
        assert_eq!(g.lo, Vec3::new(-4.0, -1.0, -2.0));
        let hi = g.lo + g.spacing * Vec3::from(g.dims.map(|d| (d - 1) as f32));
        assert!((hi - Vec3::new(4.0, 1.0, 2.0)).abs().max_element() < 1e-5, "{hi}");
        assert_eq!(g.uniform_bytes().len() as u64, GRID_BYTES);
    }

    /// Many lights coarsen the grid to stay within `MAX_VALUES`.
    #[test]
    fn many_lights_coarsen_the_grid() {
        let lights = "[[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\n".repeat(64);
        let g = GridLayout::of(&scene(&format!("{lights}{}[quality]\nvolume_grid = 256\n", &MEDIUM[MEDIUM.find("[[media]]").unwrap()..]))).unwrap();
        let values: u64 = g.dims.iter().map(|&d| u64::from(d)).product::<u64>() * 64;
        assert!(values <= MAX_VALUES && g.dims[0] > 32, "{:?}", g.dims);
    }
}
