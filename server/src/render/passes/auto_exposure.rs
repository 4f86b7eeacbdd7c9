//! Auto exposure as two compute passes: `exposure_histogram` meters the
//! lit frame into a 256-bin histogram of log2 luminance, and
//! `exposure_adapt` turns it into an exposure, adapted over time in a
//! history buffer (the `exposure` pass applies it). Off unless
//! `post.auto_exposure`.

use crate::gpu::pipeline::{COMPUTE, Group, PipelineSpec, Stages, sizes, storage_rw, texture, uniform};
use crate::render::graph::{GraphBuilder, PassKind};
use crate::render::resource::{Access, Meaning, Element, Handle, PipelineKey, TensorLayout};
use crate::scene::{Post, Scene};

const SHADER: &str = "post/auto_exposure.wgsl";
/// Bins of the histogram; bin 0 holds pixels darker than the range.
pub const BINS: u32 = 256;
/// The histogram pass's workgroup side, as the shader declares it.
const TILE: u32 = 16;

pub static HISTOGRAM: PipelineSpec = PipelineSpec {
    name: "post.exposure_histogram",
    shader: SHADER,
    stages: Stages::Compute { entry: "histogram" },
    groups: &[Group::always(0, &[uniform("metering", 0, COMPUTE, sizes::VEC4), texture("hdr", 1), storage_rw("bins", 2)])],
    defs: &[],
};
pub static ADAPT: PipelineSpec = PipelineSpec {
    name: "post.exposure_adapt",
    shader: SHADER,
    stages: Stages::Compute { entry: "adapt" },
    groups: &[Group::always(0, &[uniform("metering", 0, COMPUTE, sizes::VEC4), storage_rw("bins", 2), storage_rw("state", 3)])],
    defs: &[],
};
pub const SPECS: &[&PipelineSpec] = &[&HISTOGRAM, &ADAPT];

/// The adapted state's fields, in the order the shader keeps them.
pub const STATE_FIELDS: [&str; 4] = ["ev", "target_ev", "mean_log2", "valid"];

/// The uniform both passes read: the metering range and this frame's
/// adaptation rate.
fn metering(p: &Post, dt: f32) -> [f32; 4] {
    let rate = 1.0 - (-dt.max(0.0) * p.auto_exposure_speed).exp();
    [p.auto_exposure_min_ev, 1.0 / (p.auto_exposure_max_ev - p.auto_exposure_min_ev), rate, 0.0]
}

/// The adapted exposure state (a history buffer of `STATE_FIELDS`), or
/// `None` when auto exposure is off.
pub fn auto_exposure(g: &mut GraphBuilder, scene: &Scene, hdr: Handle) -> Option<Handle> {
    if !scene.post.auto_exposure {
        for pass in ["exposure_histogram", "exposure_adapt"] {
            g.cull(pass, "post.auto_exposure is off");
        }
        return None;
    }
    let (w, h) = (scene.width, scene.height);
    let mut p = g.pass("exposure_histogram", PassKind::Compute);
    let key = p.pipeline(PipelineKey::new(&HISTOGRAM, &[]));
    p.sample(hdr);
    let bins = p.create("histogram", Meaning::Data, TensorLayout::new(&[("bin", BINS)], Element::U32), Access::StorageWrite);
    p.access(bins, Access::CopyDst);
    let post = scene.post.clone();
    p.execute(move |ctx| {
        let m = ctx.uniform(&super::vec4_bytes(metering(&post, ctx.dt)));
        // A frame buffer is reused from the last frame: start from zero.
        ctx.encoder.clear_buffer(ctx.buffer(bins), 0, None);
        let b = [("metering", m.as_entire_binding()), ("hdr", ctx.bind(hdr)), ("bins", ctx.bind(bins))];
        ctx.dispatch(&key, &b, [w.div_ceil(TILE), h.div_ceil(TILE), 1]);
    });

    let mut p = g.pass("exposure_adapt", PassKind::Compute);
    let key = p.pipeline(PipelineKey::new(&ADAPT, &[]));
    p.access(bins, Access::StorageRead);
    let state = p.history("state", Meaning::Data, TensorLayout::new(&[("field", STATE_FIELDS.len() as u32)], Element::F32), Access::StorageWrite);
    let post = scene.post.clone();
    p.execute(move |ctx| {
        let m = ctx.uniform(&super::vec4_bytes(metering(&post, ctx.dt)));
        let b = [("metering", m.as_entire_binding()), ("bins", ctx.bind(bins)), ("state", ctx.bind(state))];
        ctx.dispatch(&key, &b, [1, 1, 1]);
    });
    Some(state)
}

#[cfg(test)]
mod tests {
    //! The passes run on the device (lavapipe without a GPU) from the real
    //! shader, after an input pass that copies in an image of known
    //! luminance.
    use std::sync::Arc;

    use super::*;
    use crate::gpu::pipeline::HDR;
    use crate::render::frame::FrameResult;
    use crate::render::resource::TextureDesc;
    use crate::render::session::Session;

    const W: u32 = 40;
    const H: u32 = 24;

    struct Rig {
        session: Session,
        source: Arc<wgpu::Texture>,
    }

    impl Rig {
        fn new() -> Rig {
            let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
            let lib = crate::shader::library::read_tree(&root).unwrap();
            let text = format!("[output]\nwidth = {W}\nheight = {H}\n[post]\nauto_exposure = true\nauto_exposure_speed = 3.0\n");
            let scene = crate::scene::parse("auto.toml", &text).unwrap();
            let loaded = crate::loaded::Loaded { scene: scene.clone(), meshes: Default::default(), materials: crate::loaded::materials_of(&scene), denoiser: None, files: vec![], reports: Default::default(), warnings: vec![] };
            let gpu = crate::gpu::open().unwrap_or_else(|e| panic!("these tests need a GPU device (lavapipe will do): {e}"));
            let source = Arc::new(gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("known luminance"),
                size: wgpu::Extent3d { width: W, height: H, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: HDR,
                usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            }));
            let mut session = Session::new(gpu, &root, lib, &loaded);
            let mut g = GraphBuilder::new();
            let mut p = g.pass("input", PassKind::Copy);
            let hdr = p.create("color", Meaning::Color, TextureDesc::d2(HDR, W, H), Access::CopyDst);
            let from = source.clone();
            p.execute(move |ctx| ctx.encoder.copy_texture_to_texture(from.as_image_copy(), ctx.texture(hdr).as_image_copy(), from.size()));
            let state = auto_exposure(&mut g, &scene, hdr).expect("auto exposure is on");
            g.output(state);
            session.use_graph(g.build());
            assert_eq!(session.install_missing(), vec![], "the auto-exposure shader builds");
            Rig { session, source }
        }

        /// Fills the input with `pixel(i)` (RGB, alpha 1) for pixel index i.
        fn input(&self, pixel: impl Fn(u32) -> f32) {
            let texels: Vec<u8> = (0..W * H)
                .flat_map(|i| {
                    let v = pixel(i);
                    [v, v, v, 1.0].map(|c| half::f16::from_f32(c).to_le_bytes())
                })
                .flatten()
                .collect();
            self.session.gpu().queue.write_texture(
                self.source.as_image_copy(),
                &texels,
                wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(W * 8), rows_per_image: Some(H) },
                self.source.size(),
            );
        }

        fn frame(&mut self, dt: f32) -> FrameResult {
            let pending = self.session.submit(None, dt);
            let r = self.session.wait(pending);
            assert_eq!(self.session.take_uncaptured(), Vec::<String>::new());
            r
        }

        /// (ev, target_ev, mean_log2, valid) after one frame.
        fn state(&mut self, dt: f32) -> [f32; 4] {
            let r = self.frame(dt);
            let t = r.tensors.iter().find(|t| t.key() == "exposure_adapt/state").expect("the state is captured");
            t.data.clone().try_into().unwrap()
        }
    }

    /// Middle grey over the mean luminance, in stops: what the test
    /// expects, written out from the definition.
    fn expected_ev(luminance: f32) -> f32 {
        (0.18f32 / luminance).log2()
    }

    #[test]
    fn a_known_luminance_gives_the_exposure_that_maps_it_to_middle_grey() {
        let mut rig = Rig::new();
        for l in [0.02f32, 0.5, 7.0] {
            rig.session.reset_history();
            rig.input(|_| l);
            let r = rig.frame(1.0 / 30.0);
            let bins = r.tensors.iter().find(|t| t.key() == "exposure_histogram/histogram").expect("the histogram is captured");
            assert_eq!(bins.data.len(), BINS as usize);
            assert_eq!(bins.data.iter().sum::<f32>(), (W * H) as f32, "every pixel is counted once");
            assert_eq!(bins.data.iter().filter(|c| **c > 0.0).count(), 1, "one luminance, one bin: {:?}", bins.data);
            let s: [f32; 4] = r.tensors.iter().find(|t| t.key() == "exposure_adapt/state").unwrap().data.clone().try_into().unwrap();
            // Half a bin of 16 EV / 255 bins is the most the histogram can be off.
            let tolerance = 16.0 / 255.0 / 2.0 + 1e-3;
            assert!((s[1] - expected_ev(l)).abs() <= tolerance, "luminance {l}: target {} EV, expected {}", s[1], expected_ev(l));
            assert_eq!(s[0], s[1], "with no history the exposure starts at its target");
            assert_eq!(s[3], 1.0);
        }
    }

    #[test]
    fn adaptation_converges_exponentially_toward_the_target() {
        let mut rig = Rig::new();
        rig.input(|_| 0.5);
        let start = rig.state(1.0 / 30.0);
        rig.input(|_| 4.0);
        let dt = 1.0 / 30.0;
        let keep = (-dt * 3.0f32).exp(); // the share of the error left each frame
        let mut error = f32::NAN;
        for n in 1..=90 {
            let s = rig.state(dt);
            let target = s[1];
            assert!((target - expected_ev(4.0)).abs() < 0.05, "the target follows the new input: {target}");
            let expected = (start[0] - target) * keep.powi(n);
            let now = s[0] - target;
            assert!((now - expected).abs() < 1e-3 * (1.0 + expected.abs()), "frame {n}: {now} EV from the target, expected {expected}");
            assert!(n == 1 || now.abs() < error.abs(), "frame {n}: the error must shrink");
            error = now;
        }
        assert!(error.abs() < 0.01, "after three seconds it has arrived: {error}");
    }

    #[test]
    fn nan_and_inf_pixels_do_not_poison_the_exposure_or_its_history() {
        let mut rig = Rig::new();
        // Every third pixel NaN, every seventh Inf: metered as the rest.
        rig.input(|i| if i % 3 == 0 { f32::NAN } else if i % 7 == 0 { f32::INFINITY } else { 0.5 });
        let s = rig.state(1.0 / 30.0);
        assert!(s.iter().all(|v| v.is_finite()), "{s:?}");
        assert!((s[1] - expected_ev(0.5)).abs() < 0.05, "{s:?}");
        // A frame of nothing but NaN meters nothing: the state stays.
        rig.input(|_| f32::NAN);
        let after = rig.state(1.0 / 30.0);
        assert_eq!(after, s, "an all-NaN frame leaves the history as it was");
        rig.input(|_| 0.5);
        assert!(rig.state(1.0 / 30.0).iter().all(|v| v.is_finite()));
    }
}
