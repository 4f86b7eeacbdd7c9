//! Honest timings in the page (issue 21): every pass row shows its time
//! with its clock (GPU, wall) or "n/a"/"—" with the reason as its title,
//! never a bare number; no compute pass shows a GPU time under the
//! detection threshold; the Passes head splits the frame's wall time into
//! the passes' sum and the rest, and the fps title reconciles with it.

use loupe_tests::{Project, Server};

use super::{browser, until};
use crate::timings::{AUTO_EXPOSURE, assert_honest};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_pass_list_shows_each_time_with_its_clock_and_the_frame_split() {
    let p = Project::copy_of_repo("browser-timings");
    p.write("scenes/auto.toml", AUTO_EXPOSURE);
    let s = Server::start(&p.root, &["--render", "continuous", "--fps", "4", "--scene", "scenes/auto.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "the histogram pass timed", "document.querySelector('#passes li[data-pass=\"exposure_histogram\"][data-timing]')").await;
    until(&c, &s, "the frame split in the Passes head", "document.querySelector('#passes-total').dataset.frameMs").await;
    until(&c, &s, "a frame rate", "document.querySelector('#fps').title.includes('delivered')").await;
    // Asked once the daemon has rendered: before, the status is not yet
    // the adapter's.
    let cpu_adapter = s.get_json("/api/status")["cpu_adapter"].as_bool().unwrap();

    // Every row as the page shows it, beside the pass kinds the API lists.
    let rows = c
        .execute_async(
            "fetch('/api/passes').then(r => r.json()).then(list => arguments[0]([...document.querySelectorAll('#passes li.pass')].map(li => {
               const p = list.find(p => p.name === li.dataset.pass);
               return { name: li.dataset.pass, kind: p?.kind ?? null, status: li.dataset.status, timing: li.dataset.timing,
                        ms: li.querySelector('.pass-time .ms').textContent, title: li.querySelector('.pass-time .ms').title,
                        clock: li.querySelector('.pass-time .timing').textContent };
             })));",
            vec![],
        )
        .await
        .unwrap();
    let rows = rows.as_array().unwrap();
    assert!(rows.iter().any(|r| r["name"] == "exposure_histogram" && r["kind"] == "compute"), "{rows:?}");
    for r in rows {
        let text = r["ms"].as_str().unwrap();
        // What the row shows, read back into the protocol's terms.
        let shown = match r["timing"].as_str().unwrap() {
            "none" => {
                assert!(text == "n/a" || text == "—", "no figure, no number: {r}");
                assert_eq!(r["clock"], "", "{r}");
                serde_json::json!({ "time_ms": null, "timing": null, "timing_reason": r["title"] })
            }
            clock => {
                let ms: f64 = text.strip_suffix(" ms").and_then(|n| n.parse().ok()).unwrap_or_else(|| panic!("a time in ms: {r}"));
                let label = if clock == "gpu" { "GPU" } else { "wall" };
                assert_eq!(r["clock"], label, "the clock is named beside the figure: {r}");
                assert!(!r["title"].as_str().unwrap().is_empty(), "the clock is explained: {r}");
                serde_json::json!({ "time_ms": ms, "timing": clock, "timing_reason": null })
            }
        };
        if r["status"] != "culled" {
            assert_honest(&shown, r["kind"] == "compute", cpu_adapter);
        }
    }

    // The head: frame = passes + other, as figures and as text.
    let head = c
        .execute(
            "const t = document.querySelector('#passes-total');
             return [t.textContent, Number(t.dataset.frameMs), Number(t.dataset.passesMs), Number(t.dataset.unattributedMs), document.querySelector('#fps').title];",
            vec![],
        )
        .await
        .unwrap();
    let n = |i: usize| head[i].as_f64().unwrap();
    assert!((n(2) + n(3) - n(1)).abs() <= 1e-6 * n(1).max(1.0), "passes + other = frame: {head}");
    let text = head[0].as_str().unwrap();
    assert!(text.starts_with("frame ") && text.contains(" = passes ") && text.contains(" + other "), "{head}");
    assert!(head[4].as_str().unwrap().contains("newest frame: "), "the fps title splits the frame: {head}");
    c.close().await.unwrap();
}
