//! Tile classification in the page: the counts under the pass list (one
//! chip per class, in the tile-class view's colours), which add up to the
//! frame's pixels and tiles and follow `quality.tile_classification` when
//! it is switched off live; and the tile-class debug view as the frame.

use fantoccini::Client;
use loupe_tests::{Project, Server};

use super::{browser, until};

/// Reads the chips' `data-tiles` and `data-pixels`, as "empty,simple,single,complex".
async fn chips(c: &Client, key: &str) -> Vec<u64> {
    let js = format!(
        "return ['empty', 'simple', 'single', 'complex'].map((k) => Number(document.querySelector(`#tiles-info [data-class=\"${{k}}\"]`).dataset.{key}));"
    );
    let v = c.execute(&js, vec![]).await.unwrap();
    v.as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_tile_counts_add_up_and_follow_the_setting_and_the_tile_class_view_shows() {
    let p = Project::copy_of_repo("browser-tiles");
    // The minimal scene, small: the knot's shorthand (simple) and the sky.
    let small = p.read("scenes/minimal.toml").replacen("width = 640", "width = 96", 1).replacen("height = 360", "height = 54", 1);
    assert!(small.contains("width = 96"), "minimal.toml's size moved: update this test");
    p.write("scenes/small.toml", small);
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", "scenes/small.toml"]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(
        &c,
        &s,
        "the tile counts",
        "!document.querySelector('#tiles-info').hidden && document.querySelector('#tiles-info [data-class=\"simple\"]')",
    )
    .await;
    let (tiles, pixels) = (chips(&c, "tiles").await, chips(&c, "pixels").await);
    // 96 × 54: 12 × 7 tiles; the shorthand makes only simple pixels.
    assert_eq!(tiles.iter().sum::<u64>(), 12 * 7, "{tiles:?}");
    assert_eq!(pixels.iter().sum::<u64>(), 96 * 54, "{pixels:?}");
    assert!(tiles[1] > 0 && tiles[0] > 0 && tiles[2] == 0 && tiles[3] == 0, "{tiles:?}");
    let bytes = c.execute("return Number(document.querySelector('#tiles-info').dataset.bytes);", vec![]).await.unwrap();
    assert_eq!(bytes.as_u64(), Some(pixels[1] * 16), "16 B per simple pixel");

    // Off: every tile through the complex pipeline; the pixels keep theirs.
    let toggle = "document.querySelector('#controls [data-path=\"quality.tile_classification\"]')";
    until(&c, &s, "the setting's control", toggle).await;
    c.execute(&format!("const i = {toggle}; i.checked = false; i.dispatchEvent(new Event('change')); return true;"), vec![]).await.unwrap();
    until(&c, &s, "every tile complex", "Number(document.querySelector('#tiles-info [data-class=\"complex\"]').dataset.tiles) === 84")
        .await;
    assert_eq!(chips(&c, "pixels").await, pixels, "the pixels keep their own classes");
    until(&c, &s, "the simple pass culled", "document.querySelector('#passes li[data-pass=\"lighting_simple\"][data-status=\"culled\"]')")
        .await;

    // The tile-class view is the frame.
    let view = "document.querySelector('#controls [data-path=\"post.debug_view\"]')";
    c.execute(&format!("const i = {view}; i.value = 'tile_class'; i.dispatchEvent(new Event('change')); return true;"), vec![])
        .await
        .unwrap();
    until(&c, &s, "the debug view live", "document.querySelector('#passes li[data-pass=\"debug_view\"][data-status=\"ok\"]')").await;
    c.close().await.unwrap();
}
