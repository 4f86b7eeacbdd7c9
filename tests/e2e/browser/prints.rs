//! The inspector's prints (client/prints.js): pinning a pixel selects it
//! on the server, and its `debugPrintf` lines show under the readout,
//! grouped by pass and call with the call's source line, following an
//! edit to the print.

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
    c.close().await.unwrap();
}
