//! `loupe bench tradeoffs`: what accuracy costs in time. Each quality
//! setting the scene calls for (`sweep`) is swept on one session; every
//! point is timed (the passes the setting affects, median of repeated
//! frames after warm-up) and its image compared with the series'
//! reference (`metric`). References are cached on disk, keyed by the scene
//! file, the overrides, the size and the shaders' hashes. `report` writes
//! `tradeoffs.json`, a Markdown table and an SVG plot, which carries the
//! scene and a hash of what was measured ([`Provenance`]) so `loupe serve`
//! can tell results of this scene and these sources from older or other
//! ones.

pub mod metric;
pub mod report;
pub mod sweep;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::offline::{OfflineError, frame, frames_to_finish};
use crate::render::capture::CapturedImage;
use crate::render::frame::FrameResult;
use crate::render::resource::ResourceDesc;
use crate::render::session::Session;
use crate::scene::overrides::Overrides;
use crate::scene::settings;
use crate::scene::settings::Value;
use crate::shader::library::Library;
use metric::Rgba;
use sweep::{Reference, Series};

pub struct Job {
    pub scene: PathBuf,
    pub shader_root: PathBuf,
    pub size: (u32, u32),
    /// Timed frames per point, after the warm-up.
    pub repeats: u32,
    /// The path tracer's samples in path-traced references.
    pub reference_spp: u32,
    /// Where references are kept between runs.
    pub cache: PathBuf,
    /// Applied under every point's own (`--set`): e.g. a `[denoiser]`.
    pub overrides: Overrides,
}

/// One value of a series.
#[derive(Debug, Serialize)]
pub struct Point {
    pub value: Value,
    /// The affected passes' time: the median frame's, or for a point that
    /// accumulates samples, the frames' sum (their median × frames).
    pub time_ms: f64,
    /// The fastest and slowest frame, scaled as `time_ms` is.
    pub time_range_ms: (f64, f64),
    /// `time_ms` over the series' most accurate value's.
    pub time_ratio: f64,
    pub relative_mse: f64,
    pub psnr_db: f64,
    pub ssim: f64,
    /// Helper lanes of the fullscreen passes (`post.two_triangles` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub helper_lanes: Option<u64>,
    /// The tonemapped image, relative to the output directory.
    pub image: String,
}

#[derive(Debug, Serialize)]
pub struct SeriesReport {
    pub name: String,
    pub setting: String,
    pub with: Overrides,
    /// What the images are compared with, in words.
    pub reference: String,
    /// The passes timed.
    pub passes: Vec<String>,
    pub points: Vec<Point>,
}

/// What a sweep measured: the scene (as diagnostics name it) and a hash
/// of the scene file's bytes and of every shader source's content (names
/// left out, so a run from another directory hashes the same). Overrides
/// (`--set`) and the size are not in it: they are in the results.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Provenance {
    pub scene: String,
    pub hash: String,
}

impl Provenance {
    pub fn new(scene: &Path, text: &[u8], lib: &Library) -> Self {
        let mut sources: Vec<&blake3::Hash> = lib.files().map(|f| &f.hash).collect();
        sources.sort_by_key(|h| *h.as_bytes());
        let mut h = blake3::Hasher::new();
        h.update(blake3::hash(text).as_bytes());
        for s in sources {
            h.update(s.as_bytes());
        }
        Provenance { scene: crate::diag::display_path(scene), hash: h.finalize().to_hex()[..32].to_owned() }
    }
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub scene: String,
    /// [`Provenance::hash`].
    pub hash: String,
    pub adapter: String,
    pub cpu_adapter: bool,
    /// `serial` (each pass submitted alone, wall clock) or `gpu` (timestamps).
    pub timing: String,
    pub width: u32,
    pub height: u32,
    pub repeats: u32,
    pub series: Vec<SeriesReport>,
}

/// A frame's two images: the HDR one the exposure reads, and the final.
struct Images {
    hdr: CapturedImage,
    ldr: CapturedImage,
}

/// Sweeps every series of the scene; `out` receives each point's image.
pub fn run(job: &Job, out: &Path) -> Result<Report, OfflineError> {
    let base = crate::offline::Job {
        scene: job.scene.clone(),
        shader_root: job.shader_root.clone(),
        size: Some(job.size),
        overrides: job.overrides.clone(),
    };
    let mut session = crate::offline::prepare(&base)?;
    let serial = session.gpu().is_cpu();
    let text = std::fs::read(&job.scene).map_err(|e| OfflineError::Io(format!("cannot read {}: {e}", job.scene.display())))?;
    let measured = Provenance::new(&job.scene, &text, session.library());
    let all = sweep::series(session.scene(), session.materials(), job.reference_spp);
    let images = out.join("points");
    std::fs::create_dir_all(&images).map_err(|e| OfflineError::Io(format!("cannot create {}: {e}", images.display())))?;
    let mut reports = Vec::new();
    for (i, series) in all.iter().enumerate() {
        let reference = reference(&mut session, job, &measured, series)?;
        let mut points = Vec::new();
        let mut passes = Vec::new();
        for value in &series.values {
            let m = measure(&mut session, job, series, value, serial)?;
            passes = m.passes;
            let file = format!("points/{i}-{}.png", value.to_string().trim_matches('"'));
            std::fs::write(out.join(&file), m.images.ldr.to_png()).map_err(|e| OfflineError::Io(format!("cannot write {file}: {e}")))?;
            points.push(Point {
                value: value.clone(),
                time_ms: m.time_ms,
                time_range_ms: m.range_ms,
                time_ratio: 0.0,
                relative_mse: metric::relative_mse(&view(&m.images.hdr), &view(&reference.hdr)),
                psnr_db: metric::psnr(&view(&m.images.ldr), &view(&reference.ldr)),
                ssim: metric::ssim(&view(&m.images.ldr), &view(&reference.ldr)),
                helper_lanes: m.helper_lanes,
                image: file,
            });
        }
        // The series' values are cheapest first: the last is the most accurate.
        let top = points.last().map_or(1.0, |p| p.time_ms);
        for p in &mut points {
            p.time_ratio = if top > 0.0 { p.time_ms / top } else { 0.0 };
        }
        let reference = match &series.reference {
            Reference::Highest(o) => {
                format!("the same passes with {}", o.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", "))
            }
            Reference::PathTraced(spp) => format!("the path tracer at {spp} samples per pixel"),
        };
        reports.push(SeriesReport {
            name: series.name.clone(),
            setting: series.setting.to_owned(),
            with: series.with.clone(),
            reference,
            passes,
            points,
        });
    }
    Ok(Report {
        scene: measured.scene,
        hash: measured.hash,
        adapter: session.gpu().adapter_name(),
        cpu_adapter: serial,
        timing: if serial { "serial" } else { "gpu" }.into(),
        width: job.size.0,
        height: job.size.1,
        repeats: job.repeats,
        series: reports,
    })
}

fn view(c: &CapturedImage) -> Rgba<'_> {
    Rgba { width: c.width as usize, height: c.height as usize, data: &c.data }
}

/// Loads the scene with `overrides` into the session and builds what its
/// frame lacks.
fn load(session: &mut Session, job: &Job, overrides: &Overrides) -> Result<(), OfflineError> {
    let mut loaded = crate::loaded::load_with(&job.scene, &merged(job, overrides)).map_err(|d| OfflineError::Input(vec![d]))?;
    (loaded.scene.width, loaded.scene.height) = job.size;
    let errors = session.set_scene_now(&loaded);
    if errors.is_empty() { Ok(()) } else { Err(OfflineError::Input(errors)) }
}

/// The job's overrides under a point's.
fn merged(job: &Job, point: &Overrides) -> Overrides {
    job.overrides.iter().chain(point).map(|(k, v)| (k.clone(), v.clone())).collect()
}

/// The names of the renderer's HDR image (what the exposure reads, or the
/// tonemap when there is no exposure to apply) and of the final one.
fn image_names(session: &Session) -> BTreeSet<String> {
    let graph = session.graph();
    let reader = ["exposure", "tonemap"].into_iter().find_map(|name| graph.passes.iter().find(|p| p.name == name));
    let hdr = reader
        .and_then(|p| p.reads().map(|h| graph.resource(h)).find(|r| matches!(r.desc, ResourceDesc::Texture(_))).map(|r| r.name.clone()));
    hdr.into_iter().chain(graph.final_name()).collect()
}

/// The frame's images from a capture of `image_names`.
fn images(session: &Session, r: &FrameResult) -> Result<Images, OfflineError> {
    let names: Vec<String> = image_names(session).into_iter().collect();
    let find = |want: &str| r.captures.iter().find(|c| c.key() == want).cloned();
    let fin = session.graph().final_name().unwrap_or_default();
    let hdr = names.iter().find(|n| **n != fin).and_then(|n| find(n));
    match (hdr, find(&fin)) {
        (Some(hdr), Some(ldr)) => Ok(Images { hdr, ldr }),
        _ => Err(OfflineError::Io(format!("the frame lacks its HDR or final image ({names:?})"))),
    }
}

/// Renders the frames a finished image of the loaded scene takes, only
/// the last capturing `names`; `each` sees every frame. Returns the last.
fn finish(session: &mut Session, names: &BTreeSet<String>, mut each: impl FnMut(&FrameResult)) -> FrameResult {
    let none = BTreeSet::new();
    for _ in 1..frames_to_finish(session.scene()) {
        each(&frame(session, Some(&none)));
    }
    let last = frame(session, Some(names));
    each(&last);
    last
}

/// The series' reference images, from the cache or rendered (and cached).
fn reference(session: &mut Session, job: &Job, measured: &Provenance, series: &Series) -> Result<Images, OfflineError> {
    let overrides = series.reference_overrides();
    let mut key = blake3::Hasher::new();
    key.update(measured.hash.as_bytes());
    key.update(format!("{:?} {:?}", merged(job, &overrides), job.size).as_bytes());
    let path = job.cache.join(format!("{}.bin", &key.finalize().to_hex()[..32]));
    if let Some(cached) = read_cached(&path) {
        return Ok(cached);
    }
    load(session, job, &overrides)?;
    let names = image_names(session);
    let r = finish(session, &names, |_| {});
    let images = images(session, &r)?;
    // A cache that cannot be written costs the next run time, nothing else.
    let _ = std::fs::create_dir_all(&job.cache).and_then(|()| std::fs::write(&path, encode(&images)));
    Ok(images)
}

/// What one point measured.
struct Measured {
    images: Images,
    passes: Vec<String>,
    time_ms: f64,
    range_ms: (f64, f64),
    helper_lanes: Option<u64>,
}

fn measure(session: &mut Session, job: &Job, series: &Series, value: &Value, serial: bool) -> Result<Measured, OfflineError> {
    load(session, job, &series.point(value))?;
    let affects = settings::find(series.setting).map_or(vec![], |s| crate::render::passes::affected(s.affects));
    let live: Vec<String> = session.graph().passes.iter().map(|p| p.name.clone()).collect();
    // The denoiser's passes are part of what a denoised sample costs.
    let passes: Vec<String> =
        live.iter().filter(|p| affects.contains(&p.as_str()) || (series.accumulates() && p.starts_with("denoise"))).cloned().collect();
    let names = image_names(session);
    let none = BTreeSet::new();
    let time = |r: &FrameResult| r.timings.iter().filter(|(n, _)| passes.contains(n)).map(|(_, t)| t).sum::<f64>();
    session.set_serial(serial);
    let mut times = Vec::new();
    let r = if series.accumulates() {
        // Every sample is a frame: time each of them, the last captured.
        finish(session, &names, |r| times.push(time(r)))
    } else {
        for _ in 0..2 {
            frame(session, Some(&none));
        }
        for _ in 0..job.repeats {
            times.push(time(&frame(session, Some(&none))));
        }
        frame(session, Some(&names))
    };
    session.set_serial(false);
    let helper_lanes = (series.setting == "post.two_triangles").then(|| {
        session.set_quads(true);
        let q = frame(session, Some(&none)).quads;
        session.set_quads(false);
        q.iter().map(|p| p.quads.shaded.helper_lanes()).sum()
    });
    times.sort_by(f64::total_cmp);
    let scale = if series.accumulates() { times.len() as f64 } else { 1.0 };
    let median = times.get(times.len() / 2).copied().unwrap_or(0.0);
    let range = (times.first().copied().unwrap_or(0.0) * scale, times.last().copied().unwrap_or(0.0) * scale);
    Ok(Measured { images: images(session, &r)?, passes, time_ms: median * scale, range_ms: range, helper_lanes })
}

/// A cache file: two images as their capture's name, size and RGBA f32.
fn encode(images: &Images) -> Vec<u8> {
    let mut out = Vec::new();
    for c in [&images.hdr, &images.ldr] {
        for s in [&c.pass, &c.output, &c.format] {
            out.extend((s.len() as u32).to_le_bytes());
            out.extend(s.as_bytes());
        }
        out.extend(c.width.to_le_bytes());
        out.extend(c.height.to_le_bytes());
        out.extend(c.data.iter().flat_map(|v| v.to_le_bytes()));
    }
    out
}

fn read_cached(path: &Path) -> Option<Images> {
    let bytes = std::fs::read(path).ok()?;
    let mut r = Reader { bytes: &bytes, at: 0 };
    Some(Images { hdr: r.image()?, ldr: r.image()? })
}

/// Reads back what `encode` wrote; `None` at anything short or malformed
/// (the reference is then rendered again).
struct Reader<'b> {
    bytes: &'b [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.bytes.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }

    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }

    fn text(&mut self) -> Option<String> {
        let n = self.u32()? as usize;
        String::from_utf8(self.take(n)?.to_vec()).ok()
    }

    fn image(&mut self) -> Option<CapturedImage> {
        let (pass, output, format) = (self.text()?, self.text()?, self.text()?);
        let (width, height) = (self.u32()?, self.u32()?);
        let n = (width as usize).checked_mul(height as usize)?.checked_mul(16)?;
        let data: Vec<f32> = self.take(n)?.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        let stats = crate::render::capture::ImageStats::of(&data, width);
        Some(CapturedImage { pass, output, frame: 0, width, height, format, data, stats })
    }
}
