//! The Materials panel's budget rows (client/materials.js `budgetRows`)
//! on a one-material scene at 64×36: the car paint (56 B per pixel)
//! simplified to `quality.material_bytes = 24`, then whole again when an
//! override raises the budget to 80; the simplification preview (full
//! against the budget, and their difference) while it is simplified, and
//! the frame and its tile classes, which change with the budget.

use serde_json::json;

use super::{LIMIT, Project, Server, browser, until, until_within};

const SCENE: &str = "scenes/budget.toml";

/// The car paint on a torus knot at 64×36, at `budget` bytes per pixel.
fn car_paint(budget: u32) -> String {
    format!(
        "[output]\nwidth = 64\nheight = 36\n\n[quality]\nmaterial_bytes = {budget}\n\n[camera]\nposition = [0.0, 1.0, 3.2]\ntarget = [0.0, 0.0, 0.0]\n\n\
         [[materials]]\nname = \"car paint\"\nfile = \"materials/car_paint.mat\"\n\n\
         [[objects]]\nmesh = \"meshes/torus_knot.gltf\"\nmaterial = \"car paint\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = [1.5, 2.5, 2.0]\nintensity = 12.0\n"
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_materials_panel_shows_what_the_budget_did_and_follows_it() {
    let p = Project::copy_of_repo("browser-budget");
    p.write(SCENE, car_paint(24));
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", SCENE]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "the material listed", "document.querySelectorAll('#materials-list [data-index]').length === 1").await;
    c.execute("document.querySelector('#materials-list [data-index=\"0\"]').click(); return true;", vec![]).await.unwrap();
    let row = |key: &str| format!("document.querySelector('#material-report [data-key=\"{key}\"]')?.textContent");
    // The mix (node 3) first, the deepest, then the coat's layer (node 4)
    // into a haze lobe, which the smallest budget drops too.
    until(&c, &s, "the simplified car paint", &format!("{} === '56 → 16 B/px of 24 (complex → simple)'", row("budget"))).await;
    let rules = until(&c, &s, "its rules", &row("simplified")).await;
    assert_eq!(rules, "yes: mix #3 → 40 B, layer #4 → 28 B, drop haze #4 → 16 B");
    assert_eq!(until(&c, &s, "the closures kept", &row("closures_kept")).await, "1");
    // One slab of 16 B: its tiles are simple, none complex.
    let tiles = |class: &str| format!("Number(document.querySelector('#tiles-info [data-class=\"{class}\"]')?.dataset.tiles ?? -1)");
    until(&c, &s, "simple tiles and no complex one", &format!("{} > 0 && {} === 0", tiles("simple"), tiles("complex"))).await;

    // Simplified, so the preview compares by itself: the raster's full car
    // paint against 24 B differ (the coat's reflection is gone). Its
    // pipelines compile while the frame's do, on the same two cores.
    let diff = "document.querySelector('#material-budget [data-variant=\"difference\"][data-of=\"raster\"]')";
    let max = until_within(
        &c,
        &s,
        "the raster's full-against-budget difference",
        &format!("{diff}?.dataset.state === 'ready' && {diff}.dataset.key === '0:24' && [Number({diff}.dataset.max)]"),
        2 * LIMIT,
    )
    .await;
    assert!(max[0].as_f64() > Some(8.0), "full and 24 B differ by at most {max} levels");
    let frame_at_24 = s.get("/api/captures/tonemap/color.png").1;

    let mut ws = s.ws();
    ws.event("hello", LIMIT, |_| true);
    ws.send(json!({ "type": "set_override", "path": "quality.material_bytes", "value": 80 }));
    s.wait_for("the server's budget 80", LIMIT, || {
        (s.get_json("/api/materials")["definitions"][0]["budget"]["budget"] == 80).then_some(())
    });
    until(&c, &s, "the whole car paint", &format!("{} === '56 → 56 B/px of 80 (complex → complex)'", row("budget"))).await;
    assert_eq!(until(&c, &s, "not simplified", &row("simplified")).await, "no (fits)");
    assert_eq!(until(&c, &s, "its three closures", &row("closures_kept")).await, "3");
    // Whole again: the preview no longer compares by itself, and the frame
    // shows the coat.
    until(&c, &s, "the comparison off", "!document.querySelector('#material-budget-compare').checked").await;
    until(&c, &s, "complex tiles (three closures)", &format!("{} > 0", tiles("complex"))).await;
    s.wait_for("a frame at 80 B", LIMIT, || (s.get("/api/captures/tonemap/color.png").1 != frame_at_24).then_some(()));
    c.close().await.unwrap();
}

/// `loupe bench tradeoffs` sweeps the budget where it simplifies a material
/// (against the path tracer with the full material: the car paint at one
/// slab is further from it than whole), and the Pareto panel plots that
/// series from the run's results.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_budget_series_is_measured_and_plotted() {
    let p = Project::copy_of_repo("browser-budget-series");
    p.write(SCENE, car_paint(80));
    let args = ["bench", "tradeoffs", "--scene", SCENE, "--size", "32x18", "--repeats", "1", "--reference-spp", "64", "--out", "tradeoffs"];
    p.run(&args).code(0).stdout_has("## material_bytes");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(p.path("tradeoffs/tradeoffs.json")).unwrap()).unwrap();
    let series = json["series"].as_array().unwrap();
    let k = series.iter().position(|s| s["setting"] == "quality.material_bytes").expect("a material_bytes series");
    let points = series[k]["points"].as_array().unwrap();
    let budgets: Vec<u64> = points.iter().map(|p| p["value"].as_u64().unwrap()).collect();
    assert_eq!(budgets.first(), Some(&24), "{budgets:?}");
    assert!(budgets.windows(2).all(|w| w[0] < w[1]), "{budgets:?}");
    let error = |i: usize| points[i]["relative_mse"].as_f64().unwrap();
    assert!(error(0) > error(points.len() - 1), "one slab is further from the full car paint than the whole: {points:?}");
    // The same points against the raster at the last budget (nothing
    // simplified): that point is its reference exactly, each smaller
    // budget simplifies the car paint and is not, by a fraction of the
    // image (rendered through the last budget's pipelines, a point read
    // its words in another layout: relative MSE 1.9e10).
    let own = &series[k + 1];
    assert_eq!(own["setting"], "quality.material_bytes");
    let own: Vec<f64> = own["points"].as_array().unwrap().iter().map(|p| p["relative_mse"].as_f64().unwrap()).collect();
    assert!(own[..own.len() - 1].iter().all(|e| *e > 0.0 && *e < 0.1) && own[own.len() - 1] == 0.0, "{budgets:?}: {own:?}");

    let s = Server::start(&p.root, &["--render", "on-change", "--scene", SCENE]);
    let (_driver, c) = browser().await;
    c.goto(&s.url("/")).await.unwrap();
    until(&c, &s, "the results, current", "window.loupe.state.tradeoffs.state === 'current'").await;
    let plotted = format!("document.querySelectorAll('#tradeoffs-chart circle[data-series=\"{k}\"]').length");
    assert_eq!(until(&c, &s, "the budget's points plotted", &plotted).await, points.len());
    c.close().await.unwrap();
}
