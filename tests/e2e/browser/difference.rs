//! The path − raster difference in the inspector: opened from the path
//! panel with the page's raster reference as B, zoomed, read at a pixel,
//! its statistics recomputed here from the server's exact floats, with and
//! without masks; and the path panel's samples per second and time to the
//! target.

use fantoccini::{Client, Locator};
use loupe_tests::{Capture, Project, Server};

use super::{browser, number_after, until};

/// The small minimal scene with a rect light the camera sees beside the
/// knot: the raster draws no rect light, so its pixels are the emitters.
fn scene(p: &Project, spp: u32) {
    let small = p.read("scenes/minimal.toml").replacen("width = 640", "width = 96", 1).replacen("height = 360", "height = 54", 1);
    assert!(small.contains("width = 96") && !small.contains("[quality]"), "minimal.toml's settings moved: update this test");
    let light = "\n[[lights]]\ntype = \"rect\"\nposition = [1.3, 0.6, -0.5]\ndirection = [0.0, 0.0, 1.0]\nsize = [0.5, 0.3]\nintensity = 8.0\nshadows = false\n";
    p.write("scenes/small.toml", format!("{small}{light}\n[quality]\npath_spp = {spp}\n"));
}

/// Per pixel over RGB, as client/difference.js defines it: the relative
/// error mean |a − b| / (|b| + 0.01) and the absolute mean |a − b|.
fn errors(a: &[f32], b: &[f32]) -> (f64, f64, f64) {
    let (mut rel, mut abs, mut square) = (0.0, 0.0, 0.0);
    for ch in 0..3 {
        let d = (f64::from(a[ch]) - f64::from(b[ch])).abs();
        rel += d / (f64::from(b[ch]).abs() + 0.01);
        abs += f64::from((a[ch] - b[ch]).abs());
        square += d * d;
    }
    (rel / 3.0, abs / 3.0, square)
}

/// Nearest-rank quantile of ascending values.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

struct Stats {
    median: f64,
    p95: f64,
    relative: f64,
    rmse: f64,
    pixels: usize,
    top99: f64,
}

/// The statistics of path against raster over the pixels `masked` leaves in.
fn stats(traced: &Capture, raster: &Capture, masked: impl Fn(usize) -> bool) -> Stats {
    let (mut rels, mut abs, mut squares) = (vec![], vec![], 0.0);
    for (i, (t, r)) in traced.data.chunks_exact(4).zip(raster.data.chunks_exact(4)).enumerate() {
        if masked(i) {
            continue;
        }
        assert!(t.iter().chain(r).all(|v| v.is_finite()), "finite images");
        let (rel, a, square) = errors(t, r);
        rels.push(rel);
        abs.push(a);
        squares += square;
    }
    let n = rels.len();
    let relative = rels.iter().sum::<f64>() / n as f64;
    rels.sort_by(f64::total_cmp);
    abs.sort_by(f64::total_cmp);
    Stats {
        median: quantile(&rels, 0.5),
        p95: quantile(&rels, 0.95),
        relative,
        rmse: (squares / (3 * n) as f64).sqrt(),
        pixels: n,
        top99: quantile(&abs, 0.99),
    }
}

/// The figures `#compare-stats` (or the path panel's) carries.
async fn shown(c: &Client, selector: &str) -> serde_json::Value {
    c.execute(
        &format!(
            "const d = document.querySelector('{selector}').dataset;
             return [Number(d.median), Number(d.p95), Number(d.relative), Number(d.rmse), Number(d.pixels), document.querySelector('{selector}').textContent];"
        ),
        vec![],
    )
    .await
    .unwrap()
}

fn assert_stats(got: &serde_json::Value, want: &Stats, what: &str) {
    let close = |g: f64, w: f64| (g - w).abs() <= 1e-9 * w.abs().max(1e-12);
    let g = |i: usize| got[i].as_f64().unwrap_or_else(|| panic!("{what}: {got}"));
    assert!(
        close(g(0), want.median) && close(g(1), want.p95) && close(g(2), want.relative) && close(g(3), want.rmse),
        "{what}: shown {got}, recomputed median {} p95 {} relative {} rmse {}",
        want.median,
        want.p95,
        want.relative,
        want.rmse
    );
    assert_eq!(g(4) as usize, want.pixels, "{what}: pixels counted {got}");
    let text = got[5].as_str().unwrap();
    // Three significant digits shown: within half a unit of the third.
    for (label, value) in [("median ", 100.0 * want.median), ("p95 ", 100.0 * want.p95), ("mean relative ", 100.0 * want.relative)] {
        assert!((number_after(text, label) - value).abs() <= 0.0051 * value.abs(), "{what}: {label}in {text:?}, want {value}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_path_raster_difference_opens_in_the_inspector_with_values_statistics_and_masks() {
    let p = Project::copy_of_repo("browser-difference");
    scene(&p, 48);
    let s = Server::start(&p.root, &["--render", "continuous", "--scene", "scenes/small.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "the raster image and its G-buffer normal kept by the page", "window.loupe.state.path.referenceNormal").await;

    // Samples per second and the time to the target, while accumulating.
    c.find(Locator::Css("#renderer-path")).await.unwrap().click().await.unwrap();
    let rate = until(
        &c,
        &s,
        "a rate and a time to the target",
        "(e => Number(e.dataset.rate) > 0 && Number(e.dataset.seconds) > 0 && [Number(e.dataset.rate), e.textContent])(document.querySelector('#path-rate'))",
    )
    .await;
    let text = rate[1].as_str().unwrap();
    assert!(text.contains(" samples/s · ~") && text.ends_with(" to 48 spp"), "{text:?}");
    until(&c, &s, "convergence", "document.querySelector('#path-samples[data-converged=\"true\"]')").await;
    let text = until(
        &c,
        &s,
        "the rate kept, the time gone",
        "document.querySelector('#path-rate').textContent.endsWith('converged') && document.querySelector('#path-rate').textContent",
    )
    .await;
    assert!(text.as_str().unwrap().contains(" samples/s"), "{text}");

    // Opened from the path panel: A the path-traced colour, B the reference.
    c.find(Locator::Css("#path-difference-open")).await.unwrap().click().await.unwrap();
    let b = until(
        &c,
        &s,
        "the difference in the inspector",
        "(i => i.pass === 'path_trace' && i.output === 'color' && i.compare.mode === 'diff' && i.compare.loaded && i.compare.bLabel)(window.loupe.state.inspector)",
    )
    .await;
    assert!(b.as_str().unwrap().starts_with("raster reference · frame "), "{b}");
    until(
        &c,
        &s,
        "the emitter mask",
        "window.loupe.state.path.tracedAlbedo && !document.querySelector('#compare-stats').textContent.includes('mask yet')",
    )
    .await;
    // Converged and culled, the server's last captures are what the page compares.
    let traced = s.capture_f32("path_trace/color").expect("the path-traced image");
    let raster = s.capture_f32("lighting/color").expect("the last raster image is still captured");
    let albedo = s.capture_f32("path_trace/albedo").expect("the path-traced albedo");
    let normal = s.capture_f32("gbuffer/normal").expect("the last G-buffer normal is still captured");
    assert!(raster.frame < traced.frame && (traced.width, traced.height) == (96, 54) && (raster.width, raster.height) == (96, 54));
    let emitter = |i: usize| albedo.data[4 * i + 3] > 0.0;
    let background = |i: usize| normal.data[4 * i + 3] <= 0.0;
    let emitters = (0..96 * 54).filter(|&i| emitter(i)).count();
    let backgrounds = (0..96 * 54).filter(|&i| background(i)).count();
    assert!(
        emitters > 4 && emitters < 96 * 54 / 8 && backgrounds > 100,
        "the scene shows the rect light ({emitters} px) and background ({backgrounds} px)"
    );

    // Zoom.
    let before = c
        .execute("return [window.loupe.state.inspector.view.scale, document.querySelector('#zoom-level').textContent];", vec![])
        .await
        .unwrap();
    c.execute(
        "const cv = document.querySelector('#inspector canvas'); const r = cv.getBoundingClientRect();
         cv.dispatchEvent(new WheelEvent('wheel', {deltaY: -240, clientX: r.left + r.width / 2, clientY: r.top + r.height / 2, bubbles: true, cancelable: true}));
         return true;",
        vec![],
    )
    .await
    .unwrap();
    let after = c
        .execute("return [window.loupe.state.inspector.view.scale, document.querySelector('#zoom-level').textContent];", vec![])
        .await
        .unwrap();
    assert!(
        (after[0].as_f64().unwrap() / before[0].as_f64().unwrap() - 2.0).abs() < 1e-9,
        "the wheel doubles the zoom: {before} → {after}"
    );
    assert_ne!(before[1], after[1], "the zoom shown follows");

    // Hover: path, raster and difference at one pixel, as the exact floats.
    let (x, y) = (30usize, 20usize);
    let read = c
        .execute(
            &format!(
                "window.loupe.hover({x}, {y});
                 const ro = (id) => ['r', 'g', 'b'].map((k) => Number(document.querySelector(id).dataset[k]));
                 const at = (w) => window.loupe.valueAt({x}, {y}, w).slice(0, 3);
                 return [ro('#pixel-value'), ro('#pixel-value-b'), ro('#pixel-value-diff'), at('a'), at('b'), at('diff'), document.querySelector('#pixel-value-b').hidden, document.querySelector('#pixel-value-diff').hidden];"
            ),
            vec![],
        )
        .await
        .unwrap();
    assert_eq!((read[6].as_bool(), read[7].as_bool()), (Some(false), Some(false)), "B and the difference are read out: {read}");
    assert_eq!((&read[0], &read[1], &read[2]), (&read[3], &read[4], &read[5]), "the readout is valueAt's");
    let i = 4 * (y * 96 + x);
    let floats = |v: &serde_json::Value| v.as_array().unwrap().iter().map(|f| f.as_f64().unwrap() as f32).collect::<Vec<_>>();
    assert_eq!(floats(&read[0]), traced.data[i..i + 3], "A is the path-traced pixel");
    assert_eq!(floats(&read[1]), raster.data[i..i + 3], "B is the raster pixel");
    let diff: Vec<f32> = (0..3).map(|k| (traced.data[i + k] - raster.data[i + k]).abs()).collect();
    assert_eq!(floats(&read[2]), diff, "the difference is |path − raster|");

    // Statistics, emitters masked (as opened): the inspector's and the path panel's.
    let want = stats(&traced, &raster, emitter);
    assert_eq!(want.pixels, 96 * 54 - emitters);
    assert_stats(&shown(&c, "#compare-stats").await, &want, "emitters masked");
    let on = c.execute("return document.querySelector('#path-difference').checked;", vec![]).await.unwrap();
    assert_eq!(on, true, "opening turns the path panel's difference on");
    until(
        &c,
        &s,
        "the path panel's figures",
        &format!("Number(document.querySelector('#path-difference-stats').dataset.pixels) === {}", want.pixels),
    )
    .await;
    assert_stats(&shown(&c, "#path-difference-stats").await, &want, "the path panel, emitters masked");
    // The scale: the 99th percentile of |path − raster| over the unmasked pixels, shown.
    let top = c.execute("return [document.querySelector('#diff-scale').value, Number(document.querySelector('#diff-scale-value').value), window.loupe.state.inspector.compare.scaleTop];", vec![]).await.unwrap();
    assert_eq!(top[0], "p99");
    assert!((top[2].as_f64().unwrap() - want.top99).abs() <= 1e-6 * want.top99, "scale top {top}, want {}", want.top99);
    assert!((top[1].as_f64().unwrap() - want.top99).abs() <= 1e-3 * want.top99, "scale shown {top}, want {}", want.top99);

    // Shown as a heat map, its legend up to the scale's top, an emitter in the masked grey.
    let e = (0..96 * 54).find(|&i| emitter(i)).unwrap();
    let look = c
        .execute(
            &format!(
                "return [window.loupe.displayedAt({}, {}, 'diff'), window.loupe.state.inspector.compare.heat, document.querySelector('#diff-legend').hidden, document.querySelector('#diff-legend').textContent];",
                e % 96,
                e / 96
            ),
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(look[0], serde_json::json!([48, 48, 48, 255]), "a masked pixel is grey: {look}");
    assert_eq!((look[1].as_bool(), look[2].as_bool()), (Some(true), Some(false)), "{look}");
    assert!(look[3].as_str().unwrap().starts_with('0'), "the legend runs from 0: {look}");

    // A fixed scale is the value typed.
    let fixed = c
        .execute(
            "const sel = document.querySelector('#diff-scale'); sel.value = 'fixed'; sel.dispatchEvent(new Event('change'));
             const v = document.querySelector('#diff-scale-value'); v.value = '0.5'; v.dispatchEvent(new Event('input'));
             return true;",
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(fixed, true);
    until(&c, &s, "the fixed scale", "window.loupe.state.inspector.compare.scaleTop === 0.5").await;

    // A mask more changes them; none gives the whole image.
    c.find(Locator::Css("#mask-background")).await.unwrap().click().await.unwrap();
    let both = stats(&traced, &raster, |i| emitter(i) || background(i));
    until(&c, &s, "the background masked", &format!("Number(document.querySelector('#compare-stats').dataset.pixels) === {}", both.pixels))
        .await;
    assert_stats(&shown(&c, "#compare-stats").await, &both, "emitters and background masked");
    for id in ["#mask-background", "#mask-emitters"] {
        c.find(Locator::Css(id)).await.unwrap().click().await.unwrap();
    }
    let all = stats(&traced, &raster, |_| false);
    until(&c, &s, "no mask", &format!("Number(document.querySelector('#compare-stats').dataset.pixels) === {}", all.pixels)).await;
    assert_stats(&shown(&c, "#compare-stats").await, &all, "no mask");
    assert!(all.p95 > want.p95 && all.relative > want.relative, "the emitters dominate the unmasked figures");

    // Split: A on the left, the raster reference on the right, read out alike.
    c.execute(
        "const m = document.querySelector('#compare-mode'); m.value = 'split'; m.dispatchEvent(new Event('change')); return true;",
        vec![],
    )
    .await
    .unwrap();
    until(&c, &s, "the split view", "(i => i.compare.mode === 'split' && i.compare.loaded)(window.loupe.state.inspector)").await;
    let split = c
        .execute(
            &format!(
                "window.loupe.hover({x}, {y}); const d = document.querySelector('#pixel-value-b').dataset;
                 return [[d.r, d.g, d.b].map(Number), window.loupe.state.inspector.compare.bLabel, window.loupe.state.problems];"
            ),
            vec![],
        )
        .await
        .unwrap();
    assert_eq!(floats(&split[0]), raster.data[i..i + 3], "B in the split view is the raster pixel");
    assert!(split[1].as_str().unwrap().starts_with("raster reference · frame "), "{split}");
    assert_eq!(split[2], serde_json::json!([]), "no client problems on the way");
    c.close().await.unwrap();
}
