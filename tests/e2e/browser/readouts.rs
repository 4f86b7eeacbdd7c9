//! Readouts under the overlays and the inspector's keyboard shortcuts: the
//! quad maps' count under the cursor is the server's, the per-draw table
//! states each draw's culling, keys pressed as a person presses them change
//! the channel (not to one the output lacks, not while typing), and `?`
//! lists the shortcuts until Esc.

use fantoccini::actions::{InputSource, KeyAction, KeyActions};
use fantoccini::key::Key;
use fantoccini::{Client, Locator};

use super::{browser, small_showcase, until};

/// Presses and releases `key` on whatever has the focus, through WebDriver's
/// key actions (real key events, not synthesized in the page).
async fn press(c: &Client, key: char) {
    let keys = KeyActions::new("keyboard".into()).then(KeyAction::Down { value: key }).then(KeyAction::Up { value: key });
    c.perform_actions(keys).await.unwrap();
}

async fn js(c: &Client, code: &str) -> serde_json::Value {
    c.execute(code, vec![]).await.unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_quad_maps_read_the_servers_count_under_the_cursor_and_the_table_states_culling() {
    let (_p, s) = small_showcase("browser-quad-readout");
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    // Inspected before quads are on: a frame with quad statistics takes
    // longer than the page waits for a first capture.
    let passes = s.get_json("/api/passes");
    let gbuffer = passes.as_array().unwrap().iter().find(|p| p["name"] == "gbuffer").expect("the showcase has a gbuffer pass");
    let output = gbuffer["writes"][0]["name"].as_str().unwrap().to_owned();
    let shown = c.execute_async(&format!("window.loupe.inspect('gbuffer', '{output}').then(arguments[0]);"), vec![]).await.unwrap();
    let why = js(&c, "return window.loupe.state.inspector;").await;
    assert_eq!(shown, true, "gbuffer/{output}: {why}");
    c.find(Locator::Css("#quad-stats")).await.unwrap().click().await.unwrap();
    until(&c, &s, "gbuffer's quad table", "document.querySelector('#quad-panel[data-pass=\"gbuffer\"] #quad-table tr.total')").await;

    // Culling: every draw's row states its pipeline's cull mode, as served.
    let report = s.get_json("/api/quads");
    let served = report["passes"].as_array().unwrap().iter().find(|p| p["pass"] == "gbuffer").unwrap();
    let rows = js(
        &c,
        "return Array.from(document.querySelectorAll('#quad-table tbody tr[data-draw]:not(.sub)'), r => {
             const td = r.querySelector('td[data-key=cull_mode]'); return [r.dataset.draw, td.dataset.value, td.textContent]; });",
    )
    .await;
    let rows = rows.as_array().unwrap();
    let draws = served["draws"].as_array().unwrap();
    assert!(!draws.is_empty());
    for d in draws.iter().chain([&served["quads"]]) {
        let row = rows.iter().find(|r| r[0] == d["name"]).unwrap_or_else(|| panic!("a row for {}: {rows:?}", d["name"]));
        assert_eq!(d["cull_mode"], "none", "loupe's mesh pipelines cull no face: {d}");
        assert_eq!(row[1], d["cull_mode"], "{row:?}");
        assert_eq!(row[2], "off (cull_mode none)", "{row:?}");
    }

    // Each map: the readout under the cursor is the served map's value there.
    // The o key steps through the maps: none, overdraw, helpers.
    js(&c, "document.querySelector('#inspector canvas').focus();").await;
    for kind in ["overdraw", "helpers"] {
        press(&c, 'o').await;
        assert_eq!(js(&c, "return document.querySelector('#quad-overlay').value;").await, kind, "o chooses the next map");
        let size = until(
            &c,
            &s,
            &format!("the {kind} map"),
            &format!("(o => o && o.kind === '{kind}' && [o.width, o.height])(window.loupe.state.inspector.overlay)"),
        )
        .await;
        let (w, h) = (size[0].as_u64().unwrap() as usize, size[1].as_u64().unwrap() as usize);
        let (status, bytes) = s.get(&format!("/api/quads/gbuffer/{kind}.f32"));
        assert_eq!(status, 200);
        let values: Vec<f32> = bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        assert_eq!(values.len(), w * h);
        // The pixel with the highest count, and one with none.
        let top = (0..values.len()).max_by(|&a, &b| values[a].total_cmp(&values[b])).unwrap();
        let zero = values.iter().position(|&v| v == 0.0).expect("a pixel no quad reached");
        assert!(values[top] >= 1.0, "{kind}: the knot launches quads");
        for i in [top, zero] {
            let (x, y) = (i % w, i / w);
            let read = js(
                &c,
                &format!(
                    "window.loupe.hover({x}, {y}); const q = document.querySelector('#quad-value');
                     return [q.hidden, q.dataset.kind, Number(q.dataset.x), Number(q.dataset.y), Number(q.dataset.count), q.textContent];"
                ),
            )
            .await;
            assert_eq!(read[0], false, "{kind}: the count line is shown");
            assert_eq!((read[1].as_str(), read[2].as_u64(), read[3].as_u64()), (Some(kind), Some(x as u64), Some(y as u64)), "{read}");
            assert_eq!(read[4].as_f64(), Some(f64::from(values[i])), "{kind} at ({x}, {y}): the readout is the served count: {read}");
            let word = if kind == "overdraw" { "quad overdraw" } else { "helper lanes" };
            assert!(read[5].as_str().unwrap().contains(&format!("{word} {}", values[i])), "{read}");
        }
    }
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn keys_change_the_channel_and_output_and_question_mark_lists_every_shortcut() {
    let (_p, s) = small_showcase("browser-shortcuts");
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "an output inspected", "window.loupe.state.inspector.loaded").await;
    let channel = "[document.querySelector('#channel').value, window.loupe.state.inspector.options.channel]";
    let focus_image = "document.querySelector('#inspector canvas').focus();";

    js(&c, focus_image).await;
    press(&c, 'g').await;
    assert_eq!(js(&c, &format!("return {channel};")).await, serde_json::json!(["g", "g"]), "g shows the green channel");

    // 1 is one image pixel per device pixel; + and - double and halve it; f
    // fits the view again.
    let scale = "return window.loupe.state.inspector.view.scale;";
    let fitted = js(&c, scale).await.as_f64().unwrap();
    press(&c, '1').await;
    let actual = js(&c, "return [window.loupe.state.inspector.view.scale, devicePixelRatio];").await;
    assert_eq!(actual[0], actual[1], "1: one image pixel per device pixel");
    press(&c, '+').await;
    assert_eq!(js(&c, scale).await.as_f64(), actual[0].as_f64().map(|s| s * 2.0), "+ doubles the zoom");
    press(&c, '-').await;
    press(&c, '-').await;
    assert_eq!(js(&c, scale).await.as_f64(), actual[0].as_f64().map(|s| s / 2.0), "- halves it");
    press(&c, 'f').await;
    assert_eq!(js(&c, scale).await.as_f64(), Some(fitted), "f fits the image to the view again");

    // A channel the output lacks (its option disabled, as a format's
    // preset leaves it) does nothing; another still works.
    js(&c, "document.querySelector('#channel option[value=b]').disabled = true;").await;
    press(&c, 'b').await;
    assert_eq!(js(&c, &format!("return {channel};")).await, serde_json::json!(["g", "g"]), "no blue channel to show");
    press(&c, 'l').await;
    assert_eq!(js(&c, &format!("return {channel};")).await, serde_json::json!(["luminance", "luminance"]));

    // Typing in a field is typing.
    js(&c, "document.querySelector('#range-max').focus();").await;
    press(&c, 'r').await;
    assert_eq!(js(&c, &format!("return {channel};")).await, serde_json::json!(["luminance", "luminance"]), "r typed into max");

    // ? lists every shortcut; Esc closes the list.
    js(&c, focus_image).await;
    press(&c, '?').await;
    let listed = js(
        &c,
        "const h = document.querySelector('#shortcuts-help');
         return [h.hidden, Array.from(h.querySelectorAll('tr[data-action]'), r => r.dataset.action), h.textContent];",
    )
    .await;
    assert_eq!(listed[0], false, "? opens the list");
    let actions: Vec<&str> = listed[1].as_array().unwrap().iter().map(|a| a.as_str().unwrap()).collect();
    for action in
        ["channel:rgb", "channel:r", "channel:luminance", "fit", "actual", "zoom-in", "zoom-out", "next", "previous", "help", "close"]
    {
        assert!(actions.contains(&action), "{action} listed: {actions:?}");
    }
    press(&c, Key::Escape.into()).await;
    assert_eq!(js(&c, "return document.querySelector('#shortcuts-help').hidden;").await, true, "Esc closes the list");

    // ] opens the next output of the A list.
    let next = js(
        &c,
        "const s = document.querySelector('#inspect-a'); const o = Array.from(s.options).filter(o => o.value && !o.disabled);
         return o[(o.findIndex(x => x.value === s.value) + 1) % o.length].value;",
    )
    .await;
    press(&c, ']').await;
    let target = format!("(i => `${{i.pass}}/${{i.output}}` === {next})(window.loupe.state.inspector)");
    until(&c, &s, "the next output inspected", &target).await;
    c.close().await.unwrap();
}
