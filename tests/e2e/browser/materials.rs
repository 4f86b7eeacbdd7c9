//! The materials panel (client/materials.js) on the library scene at
//! 64×36, in one page session: the list, the tree (collapsible), the
//! report, a parameter slider that re-renders the frame through the
//! parameter buffer alone (no pipeline generation moves), save writing the
//! value into the scene file's `params` keeping its comments, the preview
//! (raster and path traced) following the slider, and a pinned pixel
//! naming its material.

use super::{Server, browser, shown, until, until_within};
use crate::materials::generations;
use crate::materials_api::{LIMIT, SCENE, small_materials};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_materials_panel_shows_tree_report_and_live_parameters_and_names_a_pixels_material() {
    let p = small_materials("browser-materials");
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", SCENE]);
    // The library's first frame builds its pipelines (glass and textures
    // included): longer on two busy cores than the page's wait allows.
    s.wait_for("a first frame", LIMIT, || (s.get_json("/api/status")["frame"].as_u64() > Some(0)).then_some(()));
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    until(&c, &s, "the thirteen materials", "document.querySelectorAll('#materials-list [data-index]').length === 13").await;

    // Car paint: a layer over a mix; the tree folds and unfolds.
    let run = |js: String| {
        let c = c.clone();
        async move { c.execute(&js, vec![]).await.unwrap() }
    };
    run("document.querySelector('#materials-list [data-index=\"1\"]').click(); return true;".into()).await;
    let root = "document.querySelector('#material-tree > details')";
    until(&c, &s, "the layer at the root", &format!("{root}?.dataset.kind === 'layer'")).await;
    let inner = format!("{root}.querySelector('details[data-kind=\"mix\"]')");
    assert_eq!(run(format!("return {inner}.checkVisibility();")).await, true, "open: the mix below shows");
    run(format!("{root}.querySelector('summary').click(); return true;")).await;
    until(&c, &s, "folded", &format!("!{root}.open && !{inner}.checkVisibility()")).await;
    run(format!("{root}.querySelector('summary').click(); return true;")).await;
    until(&c, &s, "unfolded", &format!("{root}.open && {inner}.checkVisibility()")).await;
    let closures = run("return document.querySelector('#material-report [data-key=\"closures\"]').textContent;".into()).await;
    assert!(closures.as_str().is_some_and(|t| t.starts_with('3') || t.starts_with('2')), "{closures}");

    // Plastic's roughness slider: a new frame, no pipeline rebuilt.
    run("document.querySelector('#materials-list [data-index=\"7\"]').click(); return true;".into()).await;
    let slider = "document.querySelector('#material-params [data-path=\"materials[7].params.specular_roughness\"]')";
    until(&c, &s, "plastic's roughness control", slider).await;
    until(&c, &s, "its value from the scene", &format!("Number({slider}.value).toFixed(2) === '0.20'")).await;

    // Its preview, raster and path traced: the scene's green on a sphere.
    let figure = |r: &str| format!("document.querySelector('#material-preview [data-renderer=\"{r}\"]')");
    let preview = |r: &str, renders: u64| {
        let f = figure(r);
        // The image's middle pixel and the sum of all its bytes, once a
        // render past `renders` of material 7 has landed and decoded.
        format!(
            "{f}.dataset.state === 'ready' && {f}.dataset.index === '7' && Number({f}.dataset.renders) > {renders}
             && {f}.querySelector('img').complete && {f}.querySelector('img').naturalWidth === 128
             && (() => {{ const img = {f}.querySelector('img'); const cv = document.createElement('canvas');
                 cv.width = cv.height = 128; const g = cv.getContext('2d'); g.drawImage(img, 0, 0);
                 const d = g.getImageData(0, 0, 128, 128).data; let sum = 0; for (const v of d) sum += v;
                 const m = (64 * 128 + 64) * 4; return {{ middle: [d[m], d[m + 1], d[m + 2]], sum, renders: Number({f}.dataset.renders) }}; }})()"
        )
    };
    let green = |v: &serde_json::Value| {
        let m: Vec<u64> = v["middle"].as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect();
        m[1] > m[0] + 20 && m[1] > m[2] + 20
    };
    // Car paint's previews go first (its click turned them on), and the
    // first builds the path tracer's pipeline, on cores the server's
    // frames share: with the thirteen materials' module, lavapipe takes
    // about three minutes to compile it with a cold shader cache.
    let path = until_within(&c, &s, "plastic's path-traced preview", &preview("path", 0), 2 * LIMIT).await;
    assert!(green(&path), "{path}");
    let raster = until(&c, &s, "plastic's raster preview", &preview("raster", 0)).await;
    assert!(green(&raster), "{raster}");
    let caption = run(format!("return {}.querySelector('figcaption').textContent;", figure("path"))).await;
    assert_eq!(caption, "path traced · 16 spp · 24 B/px", "its samples and what the plastic costs the G-buffer");
    let before = generations(&s);
    let frame = shown(&c).await;
    run(format!("const i = {slider}; i.value = '0.9'; i.dispatchEvent(new Event('change')); return true;")).await;
    until(&c, &s, "the override counted", "document.querySelector('#overrides-count').textContent === '1 unsaved'").await;
    let start = std::time::Instant::now();
    loop {
        let now = shown(&c).await;
        if now.frame > frame.frame && now.pixels != frame.pixels {
            break;
        }
        assert!(start.elapsed() < super::LIMIT, "no new frame showing the rougher plastic\n{}", s.log());
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
    assert_eq!(generations(&s), before, "a parameter changes a buffer, no pipeline");
    // The preview follows: rougher, the highlight spreads.
    let rougher = until(&c, &s, "the rougher preview", &preview("raster", raster["renders"].as_u64().unwrap())).await;
    assert!(green(&rougher) && rougher["sum"] != raster["sum"], "{raster} then {rougher}");

    // Save: the value lands in the entry's params, every comment stays.
    let file = p.read(SCENE);
    run("document.querySelector('#save-scene').click(); return true;".into()).await;
    until(&c, &s, "saved", "document.querySelector('#overrides-count').textContent === 'as in the file'").await;
    let saved = p.read(SCENE);
    let old = "params = { base_color = [0.05, 0.35, 0.1], specular_roughness = 0.2 }";
    assert!(file.contains(old), "materials.toml's plastic moved: update this test");
    assert_eq!(saved, file.replace(old, "params = { base_color = [0.05, 0.35, 0.1], specular_roughness = 0.9 }"), "only the value changed");

    // A pinned pixel names its material: the G-buffer's index there.
    let opened = c.execute_async("window.loupe.inspect('gbuffer', 'material').then(arguments[0]);", vec![]).await.unwrap();
    assert_eq!(opened, true);
    // The first pixel of the middle row that a sphere (not the floor) covers.
    let found = run("const s = window.loupe.state.inspector; const y = s.height >> 1;
        for (let x = 0; x < s.width; x++) { const v = window.loupe.valueAt(x, y); if (v[3] > 0 && v[2] > 0.5) return [x, y, v[2]]; }
        return null;"
        .into())
    .await;
    let (x, y, index) = (found[0].as_u64().unwrap(), found[1].as_u64().unwrap(), found[2].as_f64().unwrap() as usize);
    let name = s.get_json("/api/materials")["materials"][index]["name"].as_str().unwrap().to_owned();
    run(format!("window.loupe.pin({x}, {y}); return true;")).await;
    let named = until(&c, &s, "the pixel's material", "document.querySelector('#pixel-material').dataset.name").await;
    assert_eq!(named, name.as_str());
    let selected = run("return document.querySelector('#materials-list [aria-selected=\"true\"]').dataset.index;".into()).await;
    assert_eq!(selected, index.to_string(), "the panel selects it");
    c.close().await.unwrap();
}
