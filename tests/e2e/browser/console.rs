//! A quiet console and forms a person uses (issue 21): a page load logs no
//! failed request and no error in the browser's console, states (nothing
//! captured, no tradeoff results) included; a slider's typed entry sets
//! an override and refuses what it cannot set; a save names its file; the
//! renderer switched to path and back leaves no override; tradeoff results
//! show for their scene only, and stale ones are never ringed current.
//!
//! The console is read as chromium keeps it: `goog:loggingPrefs` asks
//! chromedriver to keep every level (`super::browser_logging`), and its
//! log endpoint (`POST /session/{id}/se/log`, not in fantoccini) hands
//! over the entries, failed requests among them (source `network`).

use fantoccini::Client;
use fantoccini::wd::WebDriverCompatibleCommand;
use loupe_tests::{Project, Server};

use super::{Driver, browser_logging, until};

/// chromedriver's `POST /session/{id}/se/log` for the `browser` log.
#[derive(Debug)]
struct BrowserLog;

impl WebDriverCompatibleCommand for BrowserLog {
    fn endpoint(&self, base: &url::Url, session: Option<&str>) -> Result<url::Url, url::ParseError> {
        base.join(&format!("session/{}/se/log", session.unwrap_or_default()))
    }

    fn method_and_body(&self, _: &url::Url) -> (http::Method, Option<String>) {
        (http::Method::POST, Some(r#"{"type":"browser"}"#.into()))
    }
}

/// The console entries logged since the last read, as
/// `LEVEL source: message` lines.
async fn browser_log(c: &Client) -> Vec<String> {
    let entries = c.issue_cmd(BrowserLog).await.expect("chromedriver's browser log");
    entries
        .as_array()
        .unwrap_or_else(|| panic!("the log is a list: {entries}"))
        .iter()
        .map(|e| format!("{} {}: {}", e["level"].as_str().unwrap_or("?"), e["source"].as_str().unwrap_or("?"), e["message"]))
        .collect()
}

async fn js(c: &Client, script: &str) -> serde_json::Value {
    c.execute(script, vec![]).await.unwrap_or_else(|e| panic!("{script}: {e}"))
}

/// A fresh copy of the repository served on minimal.toml, and a logging
/// chromium at 1600×857 showing its first frame.
async fn fresh_page(name: &str) -> (Project, Server, Driver, Client) {
    let p = Project::copy_of_repo(name);
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/minimal.toml"]);
    let (driver, c) = browser_logging(1600, 857).await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "a frame", "Number(document.querySelector('#frame').dataset.frame || 0)").await;
    (p, s, driver, c)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_page_load_logs_no_failed_request_and_no_error() {
    let (_p, s, _driver, c) = fresh_page("browser-console").await;
    until(&c, &s, "the final output inspected", "window.loupe.state.inspector.loaded").await;
    until(&c, &s, "the pass list", "window.loupe.state.passes.some((p) => p.name === 'gbuffer')").await;
    until(&c, &s, "the tradeoffs panel answered", "!document.querySelector('#tradeoffs-empty').hidden").await;
    let quiet = |log: &[String]| {
        let bad: Vec<&String> = log.iter().filter(|l| l.starts_with("SEVERE") || l.starts_with("WARNING")).collect();
        assert!(bad.is_empty(), "the console has failures or errors:\n{}", log.join("\n"));
    };
    quiet(&browser_log(&c).await);
    // No tradeoff results in a fresh project: a state, said in the panel.
    assert_eq!(js(&c, "return window.loupe.state.tradeoffs.state;").await, "not-written");
    let empty = js(&c, "return document.querySelector('#tradeoffs-empty').textContent;").await;
    assert!(empty.as_str().is_some_and(|t| t.starts_with("No results yet: run `loupe bench tradeoffs")), "{empty}");
    // An output no frame captured yet (not the final one), and A/B against
    // a last good version there is none of yet: both states, no failures.
    let loaded = c.execute_async("window.loupe.inspect('gbuffer', 'normal').then(arguments[0]);", vec![]).await.unwrap();
    assert_eq!(
        loaded,
        true,
        "the inspector loaded gbuffer/normal: {}",
        js(&c, "return JSON.stringify(window.loupe.state.inspector);").await
    );
    c.execute_async("window.loupe.compare('split', 'last_good').then(() => arguments[0](true));", vec![]).await.unwrap();
    until(&c, &s, "B's state said", "document.querySelector('#inspector').textContent.includes('no previous good version')").await;
    // A ResizeObserver loop notice, as the browser raises it (an
    // ErrorEvent without an Error), is not a client error; a thrown one is.
    js(&c, "window.dispatchEvent(new ErrorEvent('error', { message: 'ResizeObserver loop completed with undelivered notifications.' })); return true;").await;
    // (A page script of the page's origin: an error thrown by a WebDriver
    // script reads as a cross-origin "Script error.")
    js(&c, "const t = document.createElement('script'); t.textContent = \"throw new Error('a real script error')\"; document.head.append(t); return true;").await;
    let problems = until(&c, &s, "the script error shown", "window.loupe.state.problems.length && window.loupe.state.problems").await;
    assert_eq!(problems, serde_json::json!(["client error: Uncaught Error: a real script error"]));

    let log = browser_log(&c).await;
    assert!(log.iter().any(|l| l.contains("a real script error")), "the log is read at all:\n{}", log.join("\n"));
    quiet(&log.into_iter().filter(|l| !l.contains("a real script error")).collect::<Vec<_>>());
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn typed_entry_sets_an_override_a_save_names_its_file_and_the_renderer_comes_back_clean() {
    let (p, s, _driver, c) = fresh_page("browser-forms").await;
    let entry = "document.querySelector('#controls [data-entry=\"post.exposure_ev\"]')";
    until(&c, &s, "the exposure entry", entry).await;
    let range = js(&c, &format!("return {entry}.parentElement.querySelector('.range').textContent;")).await;
    assert_eq!(range, "−24 … 24");
    let overrides = || s.get_json("/api/controls")["overrides"].clone();
    let type_in = |text: &str| {
        format!("const e = {entry}; e.focus(); e.value = {text:?}; e.dispatchEvent(new Event('change')); e.blur(); return true;")
    };

    // Out of range, then not a number: a message, nothing set.
    js(&c, &type_in("30")).await;
    let message = format!("{entry}.parentElement.querySelector('.entry-error')");
    let said = until(&c, &s, "the range message", &format!("!{message}.hidden && {message}.textContent")).await;
    assert_eq!(said, "30 is out of range: −24 … 24");
    js(&c, &type_in("bright")).await;
    until(&c, &s, "the number message", &format!("{message}.textContent.includes('is not a number')")).await;
    assert_eq!(overrides(), serde_json::json!({}), "nothing was set");

    // A value in range is the override, and the slider follows it.
    js(&c, &type_in("-1.5")).await;
    until(&c, &s, "the override counted", "document.querySelector('#overrides-count').textContent === '1 unsaved'").await;
    assert_eq!(overrides(), serde_json::json!({ "post.exposure_ev": -1.5 }));
    assert_eq!(js(&c, &format!("return {message}.hidden;")).await, true, "the message goes");
    let slider = "document.querySelector('#controls input[type=range][data-path=\"post.exposure_ev\"]')";
    until(&c, &s, "the slider moved", &format!("{slider}.value === '-1.5'")).await;

    // Saving says where it saved.
    js(&c, "document.querySelector('#save-scene').click(); return true;").await;
    let saved = until(
        &c,
        &s,
        "the confirmation",
        "!document.querySelector('#save-status').hidden && document.querySelector('#save-status').textContent",
    )
    .await;
    assert_eq!(saved, "saved to scenes/minimal.toml");
    assert!(p.read("scenes/minimal.toml").contains("exposure_ev = -1.5"), "{}", p.read("scenes/minimal.toml"));
    until(&c, &s, "nothing unsaved", "document.querySelector('#overrides-count').textContent === 'as in the file'").await;

    // To the path tracer and back: nothing is left to save.
    let renderer = "document.querySelector('#controls select[data-path=\"quality.renderer\"]')";
    let pick = |v: &str| format!("const r = {renderer}; r.value = '{v}'; r.dispatchEvent(new Event('change')); return true;");
    until(&c, &s, "the renderer switch", renderer).await;
    js(&c, &pick("path")).await;
    until(&c, &s, "path traced", "document.querySelector('#overrides-count').textContent === '1 unsaved'").await;
    js(&c, &pick("raster")).await;
    until(&c, &s, "back to raster, nothing unsaved", "document.querySelector('#overrides-count').textContent === 'as in the file'").await;
    assert_eq!(overrides(), serde_json::json!({}));

    let log = browser_log(&c).await;
    assert!(!log.iter().any(|l| l.starts_with("SEVERE")), "the console has errors:\n{}", log.join("\n"));
    c.close().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tradeoff_results_are_shown_for_their_scene_only_and_stale_ones_never_ringed_current() {
    let (p, s, _driver, c) = fresh_page("browser-tradeoffs-state").await;
    until(&c, &s, "no results yet", "window.loupe.state.tradeoffs.state === 'not-written'").await;
    // One point at minimal.toml's own shadow map size: it would be ringed
    // were the results current.
    let results = |scene: &str| {
        serde_json::json!({
            "scene": scene, "hash": "made-before-an-edit", "adapter": "test", "cpu_adapter": true, "timing": "serial",
            "width": 32, "height": 18, "repeats": 1,
            "series": [{ "name": "shadow_map_size", "setting": "quality.shadow_map_size", "with": {}, "reference": "the same passes",
                "passes": ["shadows"], "points": [{ "value": 1024, "time_ms": 1.0, "time_range_ms": [1.0, 1.0], "time_ratio": 1.0,
                "relative_mse": 0.01, "psnr_db": 30.0, "ssim": 0.9, "image": "points/0-1024.png" }] }]
        })
        .to_string()
    };
    std::fs::create_dir_all(p.path("tradeoffs")).unwrap();
    let refresh = "document.querySelector('#tradeoffs-refresh').click(); return true;";

    std::fs::write(p.path("tradeoffs/tradeoffs.json"), results("scenes/minimal.toml")).unwrap();
    js(&c, refresh).await;
    until(&c, &s, "stale results plotted", "window.loupe.state.tradeoffs.state === 'stale' && window.loupe.state.tradeoffs.points === 1")
        .await;
    assert_eq!(js(&c, "return JSON.stringify(window.loupe.state.tradeoffs.current);").await, "[]", "a stale point is not current");
    let meta = js(&c, "return document.querySelector('#tradeoffs-meta').textContent;").await;
    assert!(meta.as_str().is_some_and(|m| m.contains("stale")), "{meta}");

    std::fs::write(p.path("tradeoffs/tradeoffs.json"), results("scenes/showcase.toml")).unwrap();
    js(&c, refresh).await;
    until(&c, &s, "another scene's results", "window.loupe.state.tradeoffs.state === 'other-scene'").await;
    assert_eq!(js(&c, "return window.loupe.state.tradeoffs.points;").await, 0, "not plotted");
    let empty = js(&c, "return document.querySelector('#tradeoffs-empty').textContent;").await;
    assert!(empty.as_str().is_some_and(|t| t.starts_with("These results are for scenes/showcase.toml, not this one")), "{empty}");
    c.close().await.unwrap();
}
