//! The inspector's prints (client/prints.js) and history
//! (client/pixel_history.js): pinning a pixel selects it on the server,
//! its `debugPrintf` lines show under the readout, grouped by pass and
//! call with the call's source line, following an edit to the print, and
//! its history through the frame in the Pixel history panel.

use loupe_tests::{Project, Server};

use super::{browser, until};
use crate::printf::{TONEMAP, with_print};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_pinned_pixel_shows_its_prints_and_follows_an_edit() {
    let p = Project::copy_of_repo("browser-prints");
    let good = p.read(TONEMAP);
    p.write(TONEMAP, with_print(&good, "debugPrintf(\"at %v2f\", in.position.xy);"));
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    let shown = c.execute_async("window.loupe.inspect('tonemap', 'color').then(arguments[0]);", vec![]).await.unwrap();
    assert_eq!(shown, true);
    c.execute("window.loupe.pin(7, 4); return true;", vec![]).await.unwrap();
    let lines = "document.querySelector('#pixel-prints .prints-lines')?.textContent";
    until(&c, &s, "the pixel's print", &format!("{lines} === 'at 7.500000, 4.500000'")).await;
    let pass = c.execute("return document.querySelector('#pixel-prints .prints-pass-name').textContent;", vec![]).await.unwrap();
    assert_eq!(pass, "tonemap");

    until(
        &c,
        &s,
        "the call's source line",
        "document.querySelector('#pixel-prints .prints-source').textContent.startsWith('debugPrintf(\"at %v2f\"')",
    )
    .await;

    p.write(TONEMAP, with_print(&good, "debugPrintf(\"now %.1v2f\", in.position.xy);"));
    until(&c, &s, "the edited print", &format!("{lines} === 'now 7.5, 4.5'")).await;
    until(
        &c,
        &s,
        "its source line again",
        "document.querySelector('#pixel-prints .prints-source').textContent.startsWith('debugPrintf(\"now')",
    )
    .await;

    // A pixel of the knot: its history lists the G-buffer's draw with the
    // fragments' depth verdicts, and the tonemap's one fullscreen
    // fragment with the value it wrote.
    c.execute("window.loupe.pin(320, 200); return true;", vec![]).await.unwrap();
    let panel = "document.querySelector('#history-panel')";
    until(
        &c,
        &s,
        "the knot pixel's history",
        &format!("!{panel}.hidden && {panel}.querySelector('.panel-meta').textContent.startsWith('(320, 200) through frame') && {panel}.querySelector('.history-pass[data-pass=gbuffer] tr[data-fragment]') !== null"),
    )
    .await;
    let shown = c
        .execute(
            "const p = document.querySelector('#history-panel');
             const rows = (pass) => [...p.querySelectorAll(`.history-pass[data-pass=${pass}] tr[data-fragment]`)].map((r) => [r.dataset.draw, r.dataset.verdict]);
             const after = p.querySelector('.history-pass[data-pass=tonemap] tr[data-output=\"tonemap/color\"] td.after').textContent;
             return [rows('gbuffer'), rows('tonemap'), after];",
            vec![],
        )
        .await
        .unwrap();
    let gbuffer = shown[0].as_array().expect("rows");
    assert!(gbuffer.iter().all(|r| r[0] == "object0"), "{shown}");
    let verdicts: Vec<&str> = gbuffer.iter().map(|r| r[1].as_str().unwrap()).collect();
    assert!(verdicts.contains(&"passed") && verdicts.contains(&"failed_depth"), "the knot is in front of itself there: {shown}");
    assert_eq!(shown[1], serde_json::json!([["fullscreen triangle", "not_tested"]]), "{shown}");
    let after: Vec<f64> = shown[2].as_str().unwrap().split(", ").map(|v| v.parse().expect("a number")).collect();
    assert_eq!(after.len(), 4, "{shown}");
    c.close().await.unwrap();
}
