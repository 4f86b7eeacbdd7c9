//! The simplification preview over HTTP
//! (`GET /api/materials/{index}/preview?budget=full|N`) on a scene of two
//! materials at 64×36 and a 24 B budget: the car paint (56 B) simplified to
//! 24 B looks otherwise than in full, the plastic (24 B, it fits) the same;
//! the scene's own raster preview is the budget's; a budget outside the
//! setting's range is refused with the range.

use loupe_tests::{Project, Server};

use crate::materials_api::LIMIT;

const SCENE: &str = "scenes/budget_preview.toml";

/// A preview's status, its `X-Loupe-Material-Bytes` and its pixels.
fn preview(s: &Server, query: &str) -> (u16, Option<u32>, Vec<u8>) {
    let agent = ureq::Agent::config_builder().http_status_as_error(false).build().new_agent();
    let mut resp = agent.get(&s.url(&format!("/api/materials/{query}"))).call().unwrap_or_else(|e| panic!("{query}: {e}"));
    let status = resp.status().as_u16();
    let bytes = resp.headers().get("x-loupe-material-bytes").and_then(|v| v.to_str().ok()?.parse().ok());
    let body = resp.body_mut().read_to_vec().expect("body");
    if status != 200 {
        return (status, bytes, body);
    }
    let img = image::load_from_memory(&body).unwrap_or_else(|e| panic!("{query}: {e}\n{}", s.log())).to_rgb8();
    (status, bytes, img.into_raw())
}

/// Pixels whose channels differ by more than `levels` anywhere.
fn differing(a: &[u8], b: &[u8], levels: u8) -> usize {
    a.chunks(3).zip(b.chunks(3)).filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > levels)).count()
}

#[test]
fn the_budget_preview_differs_from_the_full_one_only_where_the_budget_simplified() {
    let p = Project::copy_of_repo("budget-preview");
    p.write(
        SCENE,
        "[output]\nwidth = 64\nheight = 36\n\n[quality]\nmaterial_bytes = 24\n\n\
         [[materials]]\nname = \"car paint\"\nfile = \"materials/car_paint.mat\"\n\n\
         [[materials]]\nname = \"plastic\"\nfile = \"materials/plastic.mat\"\n\n\
         [[objects]]\nshape = \"sphere\"\nmaterial = \"car paint\"\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, -0.4]\nintensity = 3.0\n",
    );
    let s = Server::start(&p.root, &["--render", "on-change", "--scene", SCENE]);
    s.wait_for("a first frame", LIMIT, || (s.get_json("/api/status")["frame"].as_u64() > Some(0)).then_some(()));

    let ok = |query: &str| {
        let (status, bytes, pixels) = preview(&s, query);
        assert_eq!(status, 200, "{query}: {}\n{}", String::from_utf8_lossy(&pixels), s.log());
        (bytes.expect("X-Loupe-Material-Bytes"), pixels)
    };
    let (full_bytes, full) = ok("0/preview?renderer=raster&budget=full");
    let (budget_bytes, budget) = ok("0/preview?renderer=raster&budget=24");
    assert!(full_bytes == 56 && budget_bytes <= 24, "{full_bytes} B → {budget_bytes} B");
    // The coat and the flakes gone: the sphere's highlights and colour move.
    let moved = differing(&full, &budget, 8);
    assert!(moved > 200, "{moved} pixels of the car paint differ by more than 8 levels");
    assert_eq!(ok("0/preview?renderer=raster").1, budget, "the scene's raster wears its budget");
    let (plastic_full, plastic_full_px) = ok("1/preview?renderer=raster&budget=full");
    let (plastic_budget, plastic_budget_px) = ok("1/preview?renderer=raster&budget=24");
    assert_eq!(plastic_full, plastic_budget);
    assert_eq!(differing(&plastic_full_px, &plastic_budget_px, 0), 0, "the plastic fits: one definition either way");
    // The path tracer wears either too.
    assert_eq!(ok("0/preview?renderer=path&budget=full").0, 56);
    assert_eq!(ok("0/preview?renderer=path&budget=24").0, budget_bytes);

    for (query, says) in
        [("0/preview?budget=7", "between 24 and 256, not 7"), ("0/preview?budget=lots", "expected `full` or bytes per pixel")]
    {
        let (status, _, body) = preview(&s, query);
        let body = String::from_utf8_lossy(&body);
        assert_eq!(status, 400, "{query}: {body}");
        assert!(body.contains(says) && body.contains("quality.material_bytes"), "{query}: {body}");
    }
}
