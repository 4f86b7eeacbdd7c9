//! Display presets (client/presets.js): outputs open by their format and
//! the meaning their pass declares, and keep what the user changed.

use serde_json::Value;

use super::{Project, Server, browser_sized, until};

/// What the inspector shows of the output it has open: its display
/// options, the channel select's labels, the names in the readout of a
/// hovered pixel, the stats line's range and a 16×9 grid of displayed
/// pixels with their raw values.
const LOOK: &str = "const s = window.loupe.state.inspector;
    const [x, y] = arguments[0];
    window.loupe.hover(x, y);
    const grid = [];
    for (let j = 0; j < 9; j++) for (let i = 0; i < 16; i++) {
      const gx = Math.floor((i + 0.5) * s.width / 16), gy = Math.floor((j + 0.5) * s.height / 9);
      grid.push([window.loupe.valueAt(gx, gy), window.loupe.displayedAt(gx, gy, 'a')]);
    }
    return {
      options: s.options,
      meaning: document.querySelector('#inspector').dataset.meaning,
      channels: [...document.querySelector('#channel').options].map((o) => o.textContent),
      readout: [...document.querySelectorAll('#pixel-value .ch-name')].map((e) => e.textContent),
      distance: document.querySelector('#pixel-value .distance')?.textContent ?? null,
      range: document.querySelector('#stats .range').textContent,
      linearizeShown: !document.querySelector('#linearize').closest('label').hidden,
      value: window.loupe.valueAt(x, y),
      shown: window.loupe.displayedAt(x, y, 'a'),
      grid,
    };";

/// Opens `pass/output` in the inspector; the page waits for a new
/// subscription's first capture (app.js `awaitCapture`).
async fn open(c: &fantoccini::Client, pass: &str, output: &str) {
    let loaded = c
        .execute_async("window.loupe.inspect(arguments[0], arguments[1]).then(arguments[2]);", vec![pass.into(), output.into()])
        .await
        .unwrap();
    assert_eq!(loaded, true, "the inspector loads {pass}/{output}");
}

async fn look(c: &fantoccini::Client, x: u32, y: u32) -> Value {
    c.execute(LOOK, vec![serde_json::json!([x, y])]).await.unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap_or_else(|| panic!("an array: {v}")).iter().map(f).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn depth_and_normals_open_readable_and_keep_what_the_user_changed() {
    let p = Project::copy_of_repo("browser-presets");
    // minimal.toml: the knot in the middle of an empty sky, so the depth
    // buffer keeps its clear value (1) around it; camera near 0.05, far 200.
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    let (_driver, c) = browser_sized(1280, 720).await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    let depth = until(
        &c,
        &s,
        "the pass list with the depth output's meaning",
        "window.loupe.state.passes.find((p) => p.name === 'depth_prepass')?.writes.find((w) => w.meaning === 'depth')?.depth",
    )
    .await;
    let (near, far) = (f(&depth["near"]), f(&depth["far"]));
    assert_eq!((near, far, &depth["reversed"]), (0.05, 200.0, &Value::Bool(false)), "the camera's planes: {depth}");

    for (width, height) in [(1280, 720), (1600, 857)] {
        c.set_window_size(width, height).await.unwrap();
        c.execute("localStorage.clear();", vec![]).await.unwrap();
        let at = format!("{width}×{height}");

        // Depth: one grey channel, linearised, fitted without the clear value.
        open(&c, "tonemap", "color").await;
        open(&c, "depth_prepass", "depth").await;
        let d = look(&c, 320, 180).await;
        assert_eq!(d["meaning"], "depth", "{at}");
        assert_eq!(d["channels"], serde_json::json!(["depth"]), "{at}: the channel select has the format's one channel");
        assert_eq!(d["readout"], serde_json::json!(["depth"]), "{at}: the readout names only depth");
        let raw = f(&d["value"][0]);
        let distance: f64 = d["distance"].as_str().and_then(|t| t.strip_prefix("distance ")).map_or(f64::NAN, |t| t.parse().unwrap());
        let want = near * far / (far - raw * (far - near));
        assert!((distance - want).abs() < 1e-4 * want, "{at}: depth {raw} reads as distance {want}: {}", d["distance"]);
        assert_eq!(
            d["range"].as_str().unwrap().split_whitespace().count(),
            4,
            "{at}: the stats' min and max of one channel: {}",
            d["range"]
        );
        let o = &d["options"];
        assert_eq!(
            (o["channel"].as_str(), o["srgb"].as_bool(), o["linearize"].as_bool()),
            (Some("r"), Some(false), Some(true)),
            "{at}: {o}"
        );
        assert_eq!(d["linearizeShown"], true, "{at}");
        let (min, max) = (f(&o["min"]), f(&o["max"]));
        let grid = d["grid"].as_array().unwrap();
        let cleared = grid.iter().filter(|g| f(&g[0][0]) == 1.0).count();
        assert!(cleared > 0 && cleared < grid.len(), "{at}: the samples cover both sky and knot ({cleared} cleared)");
        // The fitted range spans the knot's distances, well inside the
        // planes: the clear value (at `far`) is not in it.
        assert!(near < min && min < max && max < 10.0, "{at}: range {min}…{max} of view distance, without the sky at {far}");
        let mut greys = std::collections::BTreeSet::new();
        for g in grid {
            let shown = floats(&g[1]);
            assert!(shown[0] == shown[1] && shown[1] == shown[2], "{at}: depth shows grey, got {shown:?}");
            greys.insert(shown[0] as u8);
        }
        assert!(greys.len() >= 4, "{at}: the depth image is not a solid colour: {greys:?}");

        // Normals: n·0.5+0.5 without sRGB, at a pixel on the knot.
        open(&c, "gbuffer", "normal").await;
        let n = look(&c, 320, 180).await;
        assert_eq!(n["meaning"], "normal", "{at}");
        assert_eq!(n["readout"], serde_json::json!(["R", "G", "B", "A"]), "{at}: Rgba16Float has four channels");
        assert_eq!(n["linearizeShown"], false, "{at}: only depth linearises");
        assert_eq!(n["distance"], Value::Null, "{at}: only depth reads as distance");
        assert_eq!(floats(&n["value"]).len(), 4, "{at}: the hovered pixel has a value");
        let mut negative = 0;
        for g in n["grid"].as_array().unwrap() {
            let (value, shown) = (floats(&g[0]), floats(&g[1]));
            negative += usize::from(value[..3].iter().any(|v| *v < -0.05));
            for k in 0..3 {
                let want = ((value[k] * 0.5 + 0.5) * 255.0).round();
                assert!((shown[k] - want).abs() <= 1.0, "{at}: channel {k} of {value:?} shows {} (want {want})", shown[k]);
            }
        }
        assert!(negative > 0, "{at}: the samples include normals with a negative component");

        // A preset the user changes is the output's from then on.
        open(&c, "depth_prepass", "depth").await;
        c.execute(
            "const l = document.querySelector('#linearize'); l.click();
             const m = document.querySelector('#range-max'); m.value = '0.9995'; m.dispatchEvent(new Event('input'));
             const n = document.querySelector('#range-min'); n.value = '0.99'; n.dispatchEvent(new Event('input'));",
            vec![],
        )
        .await
        .unwrap();
        open(&c, "gbuffer", "normal").await;
        let again = look(&c, 320, 180).await;
        assert_eq!((f(&again["options"]["min"]), f(&again["options"]["max"])), (-1.0, 1.0), "{at}: normals keep their own preset");
        open(&c, "depth_prepass", "depth").await;
        let kept = look(&c, 320, 180).await;
        let o = &kept["options"];
        assert_eq!(
            (o["linearize"].as_bool(), f(&o["min"]), f(&o["max"])),
            (Some(false), 0.99, 0.9995),
            "{at}: the user's depth preset: {o}"
        );
        assert_eq!(c.execute("return document.querySelector('#linearize').checked;", vec![]).await.unwrap(), false, "{at}");
    }
    c.close().await.unwrap();
}
