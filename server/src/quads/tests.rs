//! Every figure here is derived independently of the model: by hand (the
//! arithmetic in the comments), or by `reference`, a deliberately naive
//! rasterizer written for these tests: every pixel centre of the target
//! tested against every triangle in f64, the top-left rule in D3D's words,
//! quads collected in a set per primitive.

use std::collections::HashSet;

use super::*;

// ---- helpers ---------------------------------------------------------

/// Clip-space position of a framebuffer point (pixels, y down) in a
/// `width` × `height` target, at depth `z`, with w = 1.
fn at(width: u32, height: u32, [x, y]: [f64; 2], z: f32) -> [f32; 4] {
    [(x / f64::from(width) * 2.0 - 1.0) as f32, (1.0 - y / f64::from(height) * 2.0) as f32, z, 1.0]
}

/// The fullscreen triangle at depth `z`.
fn fullscreen(z: f32) -> [[f32; 4]; 3] {
    [[-1.0, -1.0, z, 1.0], [3.0, -1.0, z, 1.0], [-1.0, 3.0, z, 1.0]]
}

/// The target as two triangles, (-1,-1),(1,-1),(-1,1) then (-1,1),(1,-1),(1,1).
fn two_triangles(z: f32) -> [[f32; 4]; 6] {
    let c = |x: f32, y: f32| [x, y, z, 1.0];
    [c(-1.0, -1.0), c(1.0, -1.0), c(-1.0, 1.0), c(-1.0, 1.0), c(1.0, -1.0), c(1.0, 1.0)]
}

fn draw(positions: &[[f32; 4]]) -> Draw<'_> {
    Draw { positions, ..Draw::default() }
}

fn one_draw(width: u32, height: u32, d: &Draw) -> DrawStats {
    Pass::new(width, height).unwrap().draw(d).unwrap()
}

fn stats(triangles: u64, culled_triangles: u64, pixels: u64, quads: u64) -> QuadStats {
    QuadStats { triangles, culled_triangles, pixels, quads }
}

/// A small deterministic generator (xorshift64*), for meshes and jitter.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

// ---- the reference -----------------------------------------------------

/// A triangle in framebuffer pixels (y down).
type Tri = [[f64; 2]; 3];

struct Reference {
    pixels: u64,
    quads: u64,
    overdraw: Vec<u32>,
    helpers: Vec<u32>,
}

impl Reference {
    fn helper_lanes(&self) -> u64 {
        4 * self.quads - self.pixels
    }
}

fn cross(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> f64 {
    (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
}

/// D3D's rule: a top edge is exactly horizontal with the rest of the
/// triangle below it; a left edge is not horizontal and has the rest of the
/// triangle to its right.
fn top_or_left(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> bool {
    if p[1] == q[1] {
        return r[1] > p[1];
    }
    let edge_x = p[0] + (r[1] - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
    r[0] > edge_x
}

/// Whether the pixel centre `c` is inside `t` (already snapped), either winding.
fn covers(t: &Tri, c: [f64; 2]) -> bool {
    if cross(t[0], t[1], t[2]) == 0.0 {
        return false;
    }
    (0..3).all(|i| {
        let (p, q, r) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
        let side = cross(p, q, c);
        if side == 0.0 { top_or_left(p, q, r) } else { (side > 0.0) == (cross(p, q, r) > 0.0) }
    })
}

/// Coverage of `primitives` (each a list of triangles rasterized as one
/// primitive) inside the pixel rectangle `[x0, y0, x1, y1)` of a
/// `width` × `height` target, with vertices snapped to 1/256 pixel.
fn reference(width: u32, height: u32, rect: [u32; 4], primitives: &[Vec<Tri>]) -> Reference {
    let (qw, qh) = (width.div_ceil(2), height.div_ceil(2));
    let mut r = Reference { pixels: 0, quads: 0, overdraw: vec![0; (qw * qh) as usize], helpers: vec![0; (width * height) as usize] };
    for primitive in primitives {
        let mut covered = HashSet::new();
        for t in primitive {
            let t = t.map(|p| p.map(|c| (c * 256.0).round() / 256.0));
            for y in rect[1]..rect[3] {
                for x in rect[0]..rect[2] {
                    if covers(&t, [f64::from(x) + 0.5, f64::from(y) + 0.5]) {
                        covered.insert((x, y));
                    }
                }
            }
        }
        let blocks: HashSet<(u32, u32)> = covered.iter().map(|&(x, y)| (x / 2, y / 2)).collect();
        r.pixels += covered.len() as u64;
        r.quads += blocks.len() as u64;
        for (bx, by) in blocks {
            r.overdraw[(by * qw + bx) as usize] += 1;
            for (x, y) in [(2 * bx, 2 * by), (2 * bx + 1, 2 * by), (2 * bx, 2 * by + 1), (2 * bx + 1, 2 * by + 1)] {
                if x < width && y < height && !covered.contains(&(x, y)) {
                    r.helpers[(y * width + x) as usize] += 1;
                }
            }
        }
    }
    r
}

/// The model against the reference: each triangle of `tris` one primitive,
/// drawn unculled in one draw.
fn check_against_reference(width: u32, height: u32, tris: &[Tri]) {
    let positions: Vec<[f32; 4]> = tris.iter().flatten().map(|&p| at(width, height, p, 0.5)).collect();
    let mut pass = Pass::new(width, height).unwrap();
    let got = pass.draw(&draw(&positions)).unwrap().rasterized;
    let primitives: Vec<Vec<Tri>> = tris.iter().map(|&t| vec![t]).collect();
    let want = reference(width, height, [0, 0, width, height], &primitives);
    assert_eq!((got.pixels, got.quads, got.helper_lanes()), (want.pixels, want.quads, want.helper_lanes()));
    assert_eq!(pass.maps().quads(), &want.overdraw[..]);
    assert_eq!(pass.maps().helper_lanes(), &want.helpers[..]);
}

// ---- full-target draws -----------------------------------------------

#[test]
fn one_fullscreen_triangle_launches_every_quad_once() {
    // 512×512 pixels in 256×256 = 65,536 quads, every lane covered.
    let s = one_draw(512, 512, &draw(&fullscreen(0.0)));
    assert_eq!(s.rasterized, stats(1, 0, 262_144, 65_536));
    assert_eq!(s.rasterized.helper_lanes(), 0);
    assert_eq!(s.rasterized.quad_efficiency(), Some(1.0));
    assert_eq!(s.shaded, None);
}

#[test]
fn two_triangles_pay_the_diagonal() {
    // The diagonal from (0,0) to (512,512) passes through the 256 blocks
    // (b, b): each holds a pixel on either side of it ((2b+1, 2b) and
    // (2b, 2b+1)), so both triangles launch it: 65,536 + 256 = 65,792
    // quads for 512² = 262,144 pixels, 4·65,792 - 262,144 = 1,024 helper
    // lanes (4 per diagonal block: 8 lanes run, 4 pixels covered).
    let positions = two_triangles(0.0);
    let mut pass = Pass::new(512, 512).unwrap();
    let s = pass.draw(&draw(&positions)).unwrap();
    assert_eq!(s.rasterized, stats(2, 0, 262_144, 65_792));
    assert_eq!(s.rasterized.helper_lanes(), 1_024);

    // The 512 centres on the diagonal go to the upper-right triangle, whose
    // left edge it is: the lower-left one covers the 512·511/2 = 130,816
    // centres strictly below, the other 130,816 + 512 = 131,328.
    let lower = one_draw(512, 512, &draw(&positions[..3])).rasterized;
    let upper = one_draw(512, 512, &draw(&positions[3..])).rasterized;
    assert_eq!((lower.pixels, upper.pixels), (130_816, 131_328));

    // Overdraw 2 on the diagonal blocks, 1 elsewhere; each pixel of a
    // diagonal block is a helper once (the lower triangle covers one of its
    // four pixels, the upper three).
    let maps = pass.maps();
    assert_eq!(maps.blocks(), (256, 256));
    for by in 0..256 {
        for bx in 0..256 {
            assert_eq!(maps.quads()[by * 256 + bx], 1 + u32::from(bx == by), "block ({bx}, {by})");
        }
    }
    for y in 0..512 {
        for x in 0..512 {
            assert_eq!(maps.helper_lanes()[y * 512 + x], u32::from(x / 2 == y / 2), "pixel ({x}, {y})");
        }
    }
}

#[test]
fn odd_sizes_count_lanes_outside_the_target_as_helpers() {
    // 333×211: ceil(333/2)·ceil(211/2) = 167·106 = 17,702 quads for 70,263
    // pixels: 70,808 - 70,263 = 545 helper lanes, all outside the target:
    // x = 333 in the last block column (106 blocks × 2 lanes), y = 211 in
    // the last block row (167 × 2), the corner lane counted in both:
    // 212 + 334 - 1 = 545.
    let mut pass = Pass::new(333, 211).unwrap();
    let s = pass.draw(&draw(&fullscreen(0.0))).unwrap().rasterized;
    assert_eq!(s, stats(1, 0, 70_263, 17_702));
    assert_eq!(s.helper_lanes(), 545);
    assert_eq!(pass.maps().blocks(), (167, 106));
    assert!(pass.maps().helper_lanes().iter().all(|&h| h == 0));

    // Two triangles tile the target, so each pixel is covered once; the
    // quads on the (not 45°) diagonal come from the reference.
    let s = one_draw(333, 211, &draw(&two_triangles(0.0))).rasterized;
    assert_eq!(s.pixels, 70_263);
    let corners = [[0.0, 211.0], [333.0, 211.0], [0.0, 0.0], [333.0, 0.0]];
    let halves = [vec![[corners[0], corners[1], corners[2]]], vec![[corners[2], corners[1], corners[3]]]];
    let want = reference(333, 211, [0, 0, 333, 211], &halves);
    assert_eq!((s.pixels, s.quads, s.helper_lanes()), (want.pixels, want.quads, want.helper_lanes()));
}

#[test]
fn scissor_and_viewport_bound_coverage() {
    // Scissor x 3..103, y 5..55: 100·50 = 5,000 pixels in block columns
    // 1..=51 (pixels 2..=103: 51) and block rows 2..=27 (pixels 4..=55:
    // 26): 1,326 quads, 5,304 - 5,000 = 304 helper lanes: the columns
    // x = 2 and 103 and rows y = 4 and 55 just outside it, 2·52 + 2·102 - 4.
    let scissor = Scissor { x: 3, y: 5, width: 100, height: 50 };
    let positions = fullscreen(0.0);
    let s = one_draw(512, 512, &Draw { scissor: Some(scissor), ..draw(&positions) }).rasterized;
    assert_eq!(s, stats(1, 0, 5_000, 1_326));
    assert_eq!(s.helper_lanes(), 304);

    // A viewport maps NDC onto its rectangle: the fullscreen triangle covers
    // exactly it. 100×50 at (10, 20): blocks 5..=54 × 10..=34, 50·25 =
    // 1,250 quads, no helpers.
    let viewport = Viewport { x: 10.0, y: 20.0, width: 100.0, height: 50.0, min_depth: 0.0, max_depth: 1.0 };
    let s = one_draw(512, 512, &Draw { viewport: Some(viewport), ..draw(&positions) }).rasterized;
    assert_eq!(s, stats(1, 0, 5_000, 1_250));

    // Both: the intersection, x 10..103, y 20..55: 93·35 = 3,255 pixels in
    // blocks 5..=51 (47) × 10..=27 (18) = 846 quads.
    let both = Draw { viewport: Some(viewport), scissor: Some(scissor), ..draw(&positions) };
    assert_eq!(one_draw(512, 512, &both).rasterized, stats(1, 0, 3_255, 846));

    // A quarter of the target through the viewport, the same triangle: a
    // viewport at half-pixel offsets takes the centres on its left and top
    // edges, not those on its right and bottom ones. x from 0.5 to 2.5
    // holds centres 0.5, 1.5 (2.5 excluded); y likewise.
    let half = Viewport { x: 0.5, y: 0.5, width: 2.0, height: 2.0, min_depth: 0.0, max_depth: 1.0 };
    assert_eq!(one_draw(8, 8, &Draw { viewport: Some(half), ..draw(&positions) }).rasterized, stats(1, 0, 4, 1));
}

// ---- the fill rule and snapping, against the reference ---------------

#[test]
fn a_mesh_of_sub_pixel_triangles_covers_like_the_reference() {
    // A 64×32 grid of cells 3/4 px square from (0.5, 0.5), so unmoved
    // vertices fall on pixel centres (every 4th), on pixel edges and
    // between, and unmoved rows make horizontal edges through centres; half
    // the vertices jittered on the sub-pixel grid (by less than a sixth of
    // a cell, so no triangle folds over); each cell split along a random
    // diagonal.
    let (width, height) = (64, 32);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (cols, rows) = (64, 32);
    let mut grid = vec![[0.0; 2]; (cols + 1) * (rows + 1)];
    for (i, p) in grid.iter_mut().enumerate() {
        let (c, r) = ((i % (cols + 1)) as f64, (i / (cols + 1)) as f64);
        *p = [0.5 + c * 0.75, 0.5 + r * 0.75];
        if rng.next() < 0.5 {
            for coordinate in p.iter_mut() {
                *coordinate += ((rng.next() * 49.0).floor() - 24.0) / 256.0;
            }
        }
    }
    let mut tris = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let v = |dc: usize, dr: usize| grid[(r + dr) * (cols + 1) + c + dc];
            if rng.next() < 0.5 {
                tris.push([v(0, 0), v(1, 0), v(1, 1)]);
                tris.push([v(0, 0), v(1, 1), v(0, 1)]);
            } else {
                tris.push([v(0, 0), v(1, 0), v(0, 1)]);
                tris.push([v(1, 0), v(1, 1), v(0, 1)]);
            }
        }
    }
    check_against_reference(width, height, &tris);

    // A mesh covers each centre inside it exactly once: the sum over its
    // triangles is the size of the union.
    let one_primitive = reference(width, height, [0, 0, width, height], &[tris.clone()]);
    let positions: Vec<[f32; 4]> = tris.iter().flatten().map(|&p| at(width, height, p, 0.5)).collect();
    assert_eq!(one_draw(width, height, &draw(&positions)).rasterized.pixels, one_primitive.pixels);
}

#[test]
fn random_small_triangles_off_the_sub_pixel_grid_cover_like_the_reference() {
    // Overlapping triangles from 0.1 to 6 pixels, either winding, vertices
    // anywhere: snapping rounds them as the reference does.
    let mut rng = Rng(42);
    let tris: Vec<Tri> = (0..600)
        .map(|_| {
            let centre = [rng.next() * 40.0 - 2.0, rng.next() * 26.0 - 2.0];
            let size = 0.1 + rng.next() * 6.0;
            std::array::from_fn(|_| [centre[0] + (rng.next() - 0.5) * size, centre[1] + (rng.next() - 0.5) * size])
        })
        .collect();
    check_against_reference(37, 23, &tris);
}

#[test]
fn thin_nearly_horizontal_slivers_cover_like_the_reference() {
    // Rows of a block pair can cover spans blocks apart.
    let tris: Vec<Tri> = (0..40)
        .map(|i| {
            let y = 1.0 + f64::from(i) * 0.37;
            [[0.3, y], [31.7, y + 1.9], [0.3, y + 0.05 + f64::from(i % 7) * 0.02]]
        })
        .collect();
    check_against_reference(32, 20, &tris);
}

// ---- culling, clipping, off screen -----------------------------------

#[test]
fn face_culling_follows_wgpus_winding() {
    // Counter-clockwise in NDC (y up): lower-left, lower-right, upper-left.
    let ccw = [[-1.0, -1.0, 0.5, 1.0], [1.0, -1.0, 0.5, 1.0], [-1.0, 1.0, 0.5, 1.0]];
    let cw = [ccw[0], ccw[2], ccw[1]];
    let culled = |positions: &[[f32; 4]], cull: Option<Face>, front_face: FrontFace| {
        let s = one_draw(64, 64, &Draw { cull, front_face, ..draw(positions) }).rasterized;
        assert_eq!(s.triangles, 1);
        // Half the target when drawn, the centres below its diagonal (the
        // diagonal is its right edge): 64·63/2 = 2,016, either winding.
        assert_eq!(s.pixels, if s.culled_triangles == 1 { 0 } else { 2_016 });
        s.culled_triangles == 1
    };
    for (positions, ccw_winding) in [(&ccw, true), (&cw, false)] {
        for front_face in [FrontFace::Ccw, FrontFace::Cw] {
            let front = ccw_winding == (front_face == FrontFace::Ccw);
            assert!(!culled(positions, None, front_face));
            assert_eq!(culled(positions, Some(Face::Back), front_face), !front, "{ccw_winding} {front_face:?}");
            assert_eq!(culled(positions, Some(Face::Front), front_face), front, "{ccw_winding} {front_face:?}");
        }
    }
}

#[test]
fn a_draw_off_screen_counts_only_its_triangles() {
    // Right of the target, inside the guard band: drawn, covering nothing.
    let mut positions = Vec::new();
    for i in 0..10 {
        let x = 1.5 + i as f32 * 0.1;
        positions.extend([[x, -0.5, 0.5, 1.0], [x + 1.0, -0.5, 0.5, 1.0], [x, 0.5, 0.5, 1.0]]);
    }
    let s = one_draw(128, 128, &Draw { cull: Some(Face::Back), ..draw(&positions) });
    assert_eq!(s.rasterized, stats(10, 0, 0, 0));
    assert_eq!(s.rasterized.quad_efficiency(), None);

    // Far beyond the guard band (x/w = 10^7): the same.
    let far = [[1.0e7, 0.0, 0.5, 1.0], [2.0e7, 0.0, 0.5, 1.0], [1.0e7, 1.0e7, 0.5, 1.0]];
    assert_eq!(one_draw(128, 128, &draw(&far)).rasterized, stats(1, 0, 0, 0));

    // Behind the near plane, beyond the far one, behind the eye: culled.
    let clipped = [
        [-1.0, -1.0, -0.1, 1.0],
        [3.0, -1.0, -0.1, 1.0],
        [-1.0, 3.0, -0.1, 1.0],
        [-1.0, -1.0, 1.1, 1.0],
        [3.0, -1.0, 1.1, 1.0],
        [-1.0, 3.0, 1.1, 1.0],
        [-1.0, -1.0, -0.5, -1.0],
        [3.0, -1.0, -0.5, -1.0],
        [-1.0, 3.0, -0.5, -1.0],
    ];
    assert_eq!(one_draw(128, 128, &draw(&clipped)).rasterized, stats(3, 3, 0, 0));
}

#[test]
fn degenerate_and_non_finite_triangles_are_culled() {
    let nan = f32::NAN;
    let positions = [
        // Zero area: collinear.
        [-1.0, -1.0, 0.5, 1.0],
        [0.0, 0.0, 0.5, 1.0],
        [1.0, 1.0, 0.5, 1.0],
        // Zero area once snapped: 1/1024 pixel tall.
        [-1.0, 0.0, 0.5, 1.0],
        [1.0, 0.0, 0.5, 1.0],
        [0.0, 1.0 / 65_536.0, 0.5, 1.0],
        // A NaN coordinate.
        [-1.0, -1.0, 0.5, 1.0],
        [3.0, nan, 0.5, 1.0],
        [-1.0, 3.0, 0.5, 1.0],
    ];
    assert_eq!(one_draw(128, 128, &draw(&positions)).rasterized, stats(3, 3, 0, 0));
}

#[test]
fn the_near_plane_clips_to_the_analytic_polygon() {
    // z = 0.5 - 0.5·(y + 1) (w = 1) is 0 at y = 0: the near plane keeps the
    // lower half of the 512×512 target, a 4-sided polygon rasterized as two
    // fan pieces. 512·256 = 131,072 pixels in 256·128 = 32,768 quads, no
    // helper lanes: the blocks along the fan's diagonal are launched once.
    let positions = [[-1.0, -1.0, 0.5, 1.0], [3.0, -1.0, 0.5, 1.0], [-1.0, 3.0, -1.5, 1.0]];
    assert_eq!(one_draw(512, 512, &draw(&positions)).rasterized, stats(1, 0, 131_072, 32_768));

    // z = 0.5 - 0.5·(x + 1) - 0.5·(y + 1): the clipped triangle is
    // (-1,-1),(0,-1),(-1,0), exactly as if drawn directly.
    let clipped = [[-1.0, -1.0, 0.5, 1.0], [3.0, -1.0, -1.5, 1.0], [-1.0, 3.0, -1.5, 1.0]];
    let direct = [[-1.0, -1.0, 0.5, 1.0], [0.0, -1.0, 0.0, 1.0], [-1.0, 0.0, 0.0, 1.0]];
    let got = one_draw(512, 512, &draw(&clipped)).rasterized;
    assert_eq!(got, one_draw(512, 512, &draw(&direct)).rasterized);
    assert_eq!(got.pixels, 256 * 255 / 2);

    // Perspective, one vertex behind the eye (w = -1): the near plane cuts
    // A→C and B→C at t = 0.5 / 2, at clip (∓0.375, 0, 0, 0.5), NDC
    // (∓0.75, 0). The visible part is the trapezoid (-0.5,-0.5),
    // (0.5,-0.5), (0.75,0), (-0.75,0), wider away from the eye: in pixels
    // (128,384), (384,384), (448,256), (64,256).
    let behind = [[-0.5, -0.5, 0.5, 1.0], [0.5, -0.5, 0.5, 1.0], [0.0, 1.5, -1.5, -1.0]];
    let got = one_draw(512, 512, &draw(&behind)).rasterized;
    let (a, b, q, p) = ([128.0, 384.0], [384.0, 384.0], [448.0, 256.0], [64.0, 256.0]);
    let want = reference(512, 512, [0, 0, 512, 512], &[vec![[a, b, q], [a, q, p]]]);
    assert_eq!((got.culled_triangles, got.pixels, got.quads), (0, want.pixels, want.quads));

    // Its facing is that of the visible trapezoid: A, B, Q, P runs
    // counter-clockwise on screen, front-facing for wgpu's default.
    let back = Some(Face::Back);
    assert_eq!(one_draw(512, 512, &Draw { cull: back, ..draw(&behind) }).rasterized, got);
    let reversed = [behind[0], behind[2], behind[1]];
    assert_eq!(one_draw(512, 512, &Draw { cull: back, ..draw(&reversed) }).rasterized, stats(1, 1, 0, 0));
}

// ---- depth -----------------------------------------------------------

fn depth_pass(width: u32, height: u32, depth: f32) -> Pass {
    Pass::new(width, height).unwrap().with_depth(vec![depth; (width * height) as usize]).unwrap()
}

fn with_depth<'a>(positions: &'a [[f32; 4]], state: DepthState) -> Draw<'a> {
    Draw { depth: Some(state), ..draw(positions) }
}

#[test]
fn nearer_draws_shade_and_farther_ones_only_rasterize() {
    let less = DepthState::new(Compare::Less, true);
    let full = stats(1, 0, 262_144, 65_536);
    let (near, far) = (fullscreen(0.25), fullscreen(0.5));

    // Far then near: both pass everywhere.
    let mut pass = depth_pass(512, 512, 1.0);
    assert_eq!(pass.draw(&with_depth(&far, less)).unwrap().shaded, Some(full));
    assert_eq!(pass.draw(&with_depth(&near, less)).unwrap().shaded, Some(full));
    assert!(pass.depth().unwrap().iter().all(|&d| d == 0.25));

    // Near then far: the second rasterizes every quad and shades none.
    let mut pass = depth_pass(512, 512, 1.0);
    pass.draw(&with_depth(&near, less)).unwrap();
    let s = pass.draw(&with_depth(&far, less)).unwrap();
    assert_eq!((s.rasterized, s.shaded), (full, Some(stats(1, 0, 0, 0))));
    let totals = pass.totals();
    assert_eq!((totals.rasterized.quads, totals.shaded.unwrap().quads), (131_072, 65_536));
    assert!(pass.maps().quads().iter().all(|&q| q == 1));
}

#[test]
fn an_occluder_edge_inside_a_quad_makes_helper_lanes() {
    // The left 255 columns at depth 0.25 (x from -1 to -2/512 in NDC),
    // then the full target at 0.5: columns 255..512 shade, 257·512 =
    // 131,584 pixels in block columns 127..=255 (129) × 256 rows = 33,024
    // quads, 132,096 - 131,584 = 512 helper lanes (column 254).
    let less = DepthState::new(Compare::Less, true);
    let edge = -2.0 / 512.0;
    let c = |x: f32, y: f32| [x, y, 0.25, 1.0];
    let occluder = [c(-1.0, -1.0), c(edge, -1.0), c(-1.0, 1.0), c(-1.0, 1.0), c(edge, -1.0), c(edge, 1.0)];
    let mut pass = depth_pass(512, 512, 1.0);
    pass.draw(&with_depth(&occluder, less)).unwrap();
    let s = pass.draw(&with_depth(&fullscreen(0.5), less)).unwrap().shaded.unwrap();
    assert_eq!(s, stats(1, 0, 131_584, 33_024));
    assert_eq!(s.helper_lanes(), 512);
}

#[test]
fn pixels_failing_depth_in_a_shaded_quad_are_helpers() {
    // A checkerboard of depth 0 and 1: half of every quad passes.
    let (w, h) = (512, 512);
    let initial = (0..w * h).map(|i| if (i % w + i / w) % 2 == 0 { 0.0 } else { 1.0 }).collect();
    let mut pass = Pass::new(w, h).unwrap().with_depth(initial).unwrap();
    let s = pass.draw(&with_depth(&fullscreen(0.5), DepthState::new(Compare::Less, false))).unwrap();
    assert_eq!(s.rasterized, stats(1, 0, 262_144, 65_536));
    assert_eq!(s.shaded, Some(stats(1, 0, 131_072, 65_536)));
    assert_eq!(s.shaded.unwrap().helper_lanes(), 131_072);
    assert_eq!(s.shaded.unwrap().quad_efficiency(), Some(0.5));
    for (i, &helper) in pass.maps().helper_lanes().iter().enumerate() {
        assert_eq!(helper, u32::from((i as u32 % w + i as u32 / w).is_multiple_of(2)));
    }
}

#[test]
fn equal_depth_tests_pass_within_the_tolerance() {
    let equal = DepthState::new(Compare::Equal, false);
    let full = Some(stats(1, 0, 262_144, 65_536));
    let none = Some(stats(1, 0, 0, 0));

    // A sloped triangle after a prepass of itself.
    let sloped = [[-1.0, -1.0, 0.2, 1.0], [3.0, -1.0, 0.6, 1.0], [-1.0, 3.0, 0.9, 1.0]];
    let mut pass = depth_pass(512, 512, 1.0);
    pass.draw(&with_depth(&sloped, DepthState::new(Compare::Less, true))).unwrap();
    assert_eq!(pass.draw(&with_depth(&sloped, equal)).unwrap().shaded, full);

    // The same after a prepass the way a GPU might compute it: barycentric
    // interpolation in f32, a few ULPs from the model's plane.
    let initial = (0..512 * 512)
        .map(|i| {
            let (x, y) = ((i % 512) as f32 + 0.5, (i / 512) as f32 + 0.5);
            // Pixels (0,512), (1024,512), (0,-512): b1 grows with x, b2 upward.
            let (b1, b2) = (x / 1024.0, (512.0 - y) / 1024.0);
            (1.0 - b1 - b2) * 0.2 + b1 * 0.6 + b2 * 0.9
        })
        .collect();
    let mut pass = Pass::new(512, 512).unwrap().with_depth(initial).unwrap();
    assert_eq!(pass.draw(&with_depth(&sloped, equal)).unwrap().shaded, full);

    // Flat at 0.5 against 0.5 + 2^-21 (within 2^-20) and 0.5 + 2^-19 (not).
    let flat = fullscreen(0.5);
    let within = 0.5 + 1.0 / (1 << 21) as f32;
    let beyond = 0.5 + 1.0 / (1 << 19) as f32;
    let shaded = |stored: f32, compare: Compare| {
        depth_pass(512, 512, stored).draw(&with_depth(&flat, DepthState::new(compare, false))).unwrap().shaded
    };
    assert_eq!(shaded(within, Compare::Equal), full);
    assert_eq!(shaded(beyond, Compare::Equal), none);
    assert_eq!(shaded(within, Compare::LessEqual), full);
    assert_eq!(shaded(within, Compare::GreaterEqual), full);
    // Equal within the tolerance is not less.
    assert_eq!(shaded(within, Compare::Less), none);
    assert_eq!(shaded(beyond, Compare::Less), full);
    assert_eq!(shaded(within, Compare::NotEqual), none);
    assert_eq!(shaded(beyond, Compare::Greater), none);
}

#[test]
fn depth_bias_moves_fragments() {
    let flat = fullscreen(0.5);
    let full = Some(stats(1, 0, 262_144, 65_536));
    let none = Some(stats(1, 0, 0, 0));
    let shaded = |positions: &[[f32; 4]], stored: f32, bias: DepthBias| {
        let state = DepthState { bias, ..DepthState::new(Compare::Less, false) };
        depth_pass(512, 512, stored).draw(&with_depth(positions, state)).unwrap().shaded
    };
    // Constant: units of 2^(e - 23) with e = -1 at depth 0.5, so 2^20 units
    // are 2^-4 = 0.0625: 0.5625 is not less than 0.55.
    let constant = DepthBias { constant: 1 << 20, ..DepthBias::default() };
    assert_eq!(shaded(&flat, 0.55, DepthBias::default()), full);
    assert_eq!(shaded(&flat, 0.55, constant), none);
    // Clamped to 0.01: 0.51 is.
    assert_eq!(shaded(&flat, 0.55, DepthBias { clamp: 0.01, ..constant }), full);
    // Slope: z rises 0.125 per NDC unit in x, 256 pixels, so 2^-11 per
    // pixel; slope_scale 1024 adds 0.5, lifting 0.25..0.5 above 0.7.
    let sloped = [[-1.0, -1.0, 0.25, 1.0], [3.0, -1.0, 0.75, 1.0], [-1.0, 3.0, 0.25, 1.0]];
    assert_eq!(shaded(&sloped, 0.7, DepthBias::default()), full);
    assert_eq!(shaded(&sloped, 0.7, DepthBias { slope_scale: 1024.0, ..DepthBias::default() }), none);
}

// ---- sums, serialization, refusals -------------------------------------

#[test]
fn a_pass_sums_its_draws_and_maps() {
    let mut pass = depth_pass(64, 64, 1.0);
    let a = pass.draw(&draw(&two_triangles(0.5))).unwrap();
    let b = pass.draw(&with_depth(&fullscreen(0.25), DepthState::new(Compare::Less, true))).unwrap();
    let c = pass.draw(&with_depth(&fullscreen(0.75), DepthState::new(Compare::Less, true))).unwrap();
    let totals = pass.totals();
    assert_eq!(totals, [a, b, c].into_iter().sum());
    // A draw without a depth test adds its rasterized figure to the shaded sum.
    let shaded = totals.shaded.unwrap();
    assert_eq!(shaded, a.rasterized + b.shaded.unwrap() + c.shaded.unwrap());
    assert_eq!((shaded.quads, shaded.pixels), (1_024 + 32 + 1_024, 4_096 + 4_096));
    let maps = pass.maps();
    assert_eq!(maps.quads().iter().map(|&q| u64::from(q)).sum::<u64>(), shaded.quads);
    assert_eq!(maps.helper_lanes().iter().map(|&h| u64::from(h)).sum::<u64>(), shaded.helper_lanes());
}

#[test]
fn a_reset_pass_starts_over_with_the_depth_it_is_given() {
    let less = DepthState::new(Compare::Less, true);
    let mut pass = depth_pass(64, 64, 1.0);
    pass.draw(&with_depth(&fullscreen(0.25), less)).unwrap();
    let half = vec![0.5; 64 * 64];
    pass.reset(Some(&half)).unwrap();
    assert_eq!(pass.totals(), DrawStats::default());
    assert!(pass.maps().quads().iter().chain(pass.maps().helper_lanes()).all(|&n| n == 0));
    assert_eq!(pass.depth(), Some(&half[..]));
    // 0.75 is behind what it was given, not behind 1.0 or 0.25.
    let s = pass.draw(&with_depth(&fullscreen(0.75), less)).unwrap();
    assert_eq!(s.shaded, Some(stats(1, 0, 0, 0)));
    assert_eq!(pass.reset(Some(&half[1..])).unwrap_err(), QuadError::DepthSize { got: 4_095, width: 64, height: 64 });
    pass.reset(None).unwrap();
    assert_eq!(pass.draw(&with_depth(&fullscreen(0.75), less)).unwrap_err(), QuadError::NoDepthBuffer);
    // Cleared, with or without a buffer before.
    pass.reset_cleared(0.5).unwrap();
    assert_eq!(pass.depth(), Some(&half[..]));
    pass.draw(&with_depth(&fullscreen(0.25), less)).unwrap();
    pass.reset_cleared(0.5).unwrap();
    assert_eq!((pass.depth(), pass.totals()), (Some(&half[..]), DrawStats::default()));
    assert!(matches!(pass.reset_cleared(f32::NAN), Err(QuadError::DepthValue { .. })));
}

#[test]
fn any_number_of_threads_draws_the_same_pass() {
    // Bands of rows, one a thread: overlapping depth-tested draws, a
    // clipped primitive and an odd height, in pools of 1 and 5 threads
    // (5 bands of 22 or fewer block rows over 107).
    let (width, height) = (96, 213);
    let mut rng = Rng(7);
    let tris: Vec<[f32; 4]> = (0..3_000)
        .flat_map(|_| {
            let centre = [rng.next() * 100.0 - 2.0, rng.next() * 220.0 - 4.0];
            let size = 0.5 + rng.next() * 30.0;
            let z = rng.next() as f32;
            let mut corner = || [centre[0] + (rng.next() - 0.5) * size, centre[1] + (rng.next() - 0.5) * size];
            [corner(), corner(), corner()].map(|p| at(width, height, p, z))
        })
        .chain([[-1.0, -1.0, 0.5, 1.0], [3.0, -1.0, 0.5, 1.0], [-1.0, 3.0, -1.5, 1.0]])
        .collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut pass = depth_pass(width, height, 1.0);
            let less = DepthState::new(Compare::LessEqual, true);
            let first = pass.draw(&with_depth(&tris, less)).unwrap();
            let second = pass.draw(&Draw { cull: Some(Face::Back), ..with_depth(&tris, less) }).unwrap();
            // Scissored to the lower half: the bands above it skip the draw,
            // another counts its primitives.
            let scissor = Some(Scissor { x: 10, y: 150, width: 60, height: 50 });
            let third = pass.draw(&Draw { scissor, ..with_depth(&tris, less) }).unwrap();
            assert_eq!(third.rasterized.triangles, 3_001);
            ((first, second, third), pass.maps().clone(), pass.depth().unwrap().to_vec())
        })
    };
    let (one, five) = (run(1), run(5));
    assert_eq!(one.0, five.0);
    assert!(one.1 == five.1, "the maps differ");
    assert!(one.2 == five.2, "the depth buffers differ");
    // The second draw, behind or equal to the first everywhere, shades.
    assert!(one.0.1.shaded.unwrap().quads > 0);
}

#[test]
fn stats_serialize_with_the_report_keys() {
    let json = serde_json::to_value(stats(3, 1, 6, 2)).unwrap();
    assert_eq!(
        json,
        serde_json::json!({
            "triangles": 3, "culled_triangles": 1, "pixels": 6, "quads": 2,
            "helper_lanes": 2, "quad_efficiency": 0.75
        })
    );
    assert_eq!(serde_json::to_value(stats(1, 1, 0, 0)).unwrap()["quad_efficiency"], serde_json::Value::Null);
}

#[test]
fn bad_input_is_refused_with_a_reason() {
    assert_eq!(Pass::new(0, 4).unwrap_err(), QuadError::TargetSize { width: 0, height: 4 });
    assert!(Pass::new(MAX_TARGET_SIZE + 1, 4).is_err());
    assert_eq!(Pass::new(4, 4).unwrap().with_depth(vec![1.0; 15]).unwrap_err(), QuadError::DepthSize { got: 15, width: 4, height: 4 });
    let mut bad = vec![1.0; 16];
    bad[6] = f32::NAN;
    assert!(matches!(Pass::new(4, 4).unwrap().with_depth(bad), Err(QuadError::DepthValue { x: 2, y: 1, .. })));

    let positions = fullscreen(0.5);
    let mut pass = Pass::new(4, 4).unwrap();
    let indices = [0, 1, 3];
    let err = pass.draw(&Draw { indices: Some(&indices), ..draw(&positions) }).unwrap_err();
    assert_eq!(err, QuadError::Index { at: 2, value: 3, vertices: 3 });
    let test = DepthState::new(Compare::Less, true);
    assert_eq!(pass.draw(&with_depth(&positions, test)).unwrap_err(), QuadError::NoDepthBuffer);
    let viewport = Viewport { x: 1.0, ..Viewport::whole(4, 4) };
    assert!(matches!(pass.draw(&Draw { viewport: Some(viewport), ..draw(&positions) }), Err(QuadError::Viewport(..))));
    let scissor = Scissor { x: 2, y: 0, width: 3, height: 1 };
    assert!(matches!(pass.draw(&Draw { scissor: Some(scissor), ..draw(&positions) }), Err(QuadError::Scissor(..))));
    let nan_tolerance = DepthState { tolerance: f32::NAN, ..test };
    let mut depth = depth_pass(4, 4, 1.0);
    assert!(matches!(depth.draw(&with_depth(&positions, nan_tolerance)), Err(QuadError::DepthState(_))));
    // Refused draws leave the pass as it was.
    assert_eq!(pass.totals(), DrawStats::default());

    // Indexed draws read their triangles through the indices; a last
    // incomplete triangle is ignored.
    let indices = [2, 1, 0, 0];
    let s = pass.draw(&Draw { indices: Some(&indices), ..draw(&positions) }).unwrap();
    assert_eq!(s.rasterized, stats(1, 0, 16, 4));
}

// ---- the probe: one pixel's fragments ----------------------------------

fn fragment(draw: usize, primitive: u32, depth: Option<f32>, verdict: Verdict, helper: bool) -> Fragment {
    Fragment { draw, primitive, depth, verdict, helper }
}

/// The probe's fragments of a random stack of draws against a naive
/// derivation: each triangle's coverage of the probed block's four pixel
/// centres by `covers` (either winding), its depth there by barycentric
/// interpolation in f64, a plain `<` against the stored depth (no ties
/// closer than 10^-5 occur), and the quad rule (a quad runs when one of
/// its pixels passes; its other lanes help). Vertices lie on the sub-pixel
/// grid and no edge passes within 1/20 pixel of a centre, so snapping and
/// the fill rule decide nothing.
#[test]
fn probed_fragments_match_a_naive_derivation() {
    let (width, height) = (24, 20);
    let (bx, by) = (5, 4);
    let centres: [[f64; 2]; 4] =
        std::array::from_fn(|k| [f64::from(2 * bx + (k as u32 & 1)) + 0.5, f64::from(2 * by + (k as u32 >> 1)) + 0.5]);
    let mut rng = Rng(0x5eed);
    let mut random_triangle = || loop {
        // Within 6 pixels of the block's centre (11, 9), on the sub-pixel
        // grid: edges cross the block often.
        let corner = |rng: &mut Rng| [11.0, 9.0].map(|c| c + ((rng.next() - 0.5) * 12.0 * 256.0).round() / 256.0);
        let t: Tri = [corner(&mut rng), corner(&mut rng), corner(&mut rng)];
        let z: [f32; 3] = std::array::from_fn(|_| (0.05 + 0.9 * rng.next()) as f32);
        let clear = centres.iter().all(|&c| {
            (0..3).all(|i| {
                let (p, q) = (t[i], t[(i + 1) % 3]);
                cross(p, q, c).abs() / ((q[0] - p[0]).hypot(q[1] - p[1])) > 0.05
            })
        });
        if cross(t[0], t[1], t[2]).abs() > 2.0 && clear {
            return (t, z);
        }
    };
    // Four draws: depth tested and written, then culling back faces, then
    // without a depth test, then tested again.
    let less = Some(DepthState::new(Compare::Less, true));
    let states = [(less, None), (less, Some(Face::Back)), (None, None), (less, None)];
    let draws: Vec<Vec<(Tri, [f32; 3])>> = states.iter().map(|_| (0..60).map(|_| random_triangle()).collect()).collect();

    let mut stored = [1.0f32; 4];
    let mut want = Vec::new();
    for (d, (tris, (depth, cull))) in draws.iter().zip(states).enumerate() {
        for (p, (t, z)) in tris.iter().enumerate() {
            let covered = centres.map(|c| covers(t, c));
            // Clockwise in framebuffer coordinates (y down) is clockwise on
            // screen: a back face for wgpu's default counter-clockwise front.
            if cull == Some(Face::Back) && cross(t[0], t[1], t[2]) > 0.0 {
                if covered[1] {
                    want.push(fragment(d, p as u32, None, Verdict::Culled, false));
                }
                continue;
            }
            let at = centres.map(|c| {
                let area = cross(t[0], t[1], t[2]);
                let b = [cross(t[1], t[2], c) / area, cross(t[2], t[0], c) / area, cross(t[0], t[1], c) / area];
                b[0] * f64::from(z[0]) + b[1] * f64::from(z[1]) + b[2] * f64::from(z[2])
            });
            let passed: [bool; 4] = std::array::from_fn(|k| {
                covered[k]
                    && depth.is_none_or(|_| {
                        let d = at[k] - f64::from(stored[k]);
                        assert!(d.abs() > 1e-5, "a near tie: pick another seed");
                        d < 0.0
                    })
            });
            if depth.is_some() {
                for k in (0..4).filter(|&k| passed[k]) {
                    stored[k] = at[k] as f32;
                }
            }
            let ran = passed.contains(&true);
            // The probed pixel is the block's top-right one, lane 1.
            match (covered[1], depth) {
                (true, Some(_)) => {
                    let verdict = if passed[1] { Verdict::Passed } else { Verdict::FailedDepth };
                    want.push(fragment(d, p as u32, Some(at[1] as f32), verdict, ran && !passed[1]));
                }
                (true, None) => want.push(fragment(d, p as u32, None, Verdict::NotTested, false)),
                (false, _) if ran => want.push(fragment(d, p as u32, None, Verdict::NotTested, true)),
                (false, _) => {}
            }
        }
    }

    // In bands of rows, one a thread: the probed row is in band 0 of 1,
    // band 2 of 7.
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut pass = depth_pass(width, height, 1.0);
            pass.probe(2 * bx + 1, 2 * by).unwrap();
            for (tris, (depth, cull)) in draws.iter().zip(states) {
                let positions: Vec<[f32; 4]> = tris.iter().flat_map(|(t, z)| [0, 1, 2].map(|k| at(width, height, t[k], z[k]))).collect();
                pass.draw(&Draw { depth, cull, ..draw(&positions) }).unwrap();
            }
            pass
        })
    };
    let pass = run(7);
    assert_eq!(pass.fragments(), run(1).fragments());
    let got = pass.fragments();
    assert_eq!(got.len(), want.len(), "{got:?}\n{want:?}");
    for (g, w) in got.iter().zip(&want) {
        let close = match (g.depth, w.depth) {
            (Some(a), Some(b)) => (a - b).abs() < 1e-6,
            (a, b) => a == b,
        };
        assert!(close && (g.draw, g.primitive, g.verdict, g.helper) == (w.draw, w.primitive, w.verdict, w.helper), "{g:?} != {w:?}");
    }
    // Every kind of fragment is in there.
    for (verdict, helper) in [
        (Verdict::Passed, false),
        (Verdict::FailedDepth, false),
        (Verdict::FailedDepth, true),
        (Verdict::NotTested, false),
        (Verdict::NotTested, true),
        (Verdict::Culled, false),
    ] {
        assert!(want.iter().any(|f| (f.verdict, f.helper) == (verdict, helper)), "no {verdict:?} fragment with helper {helper}");
    }
    assert_eq!(pass.depth().unwrap()[(2 * by * width + 2 * bx + 1) as usize], stored[1], "depth written as today");
}

#[test]
fn two_overlapping_draws_are_listed_in_order_with_the_far_one_failing() {
    let less = DepthState::new(Compare::Less, true);
    let mut pass = depth_pass(8, 8, 1.0);
    pass.probe(3, 5).unwrap();
    pass.draw(&with_depth(&fullscreen(0.25), less)).unwrap();
    pass.draw(&with_depth(&fullscreen(0.5), less)).unwrap();
    assert_eq!(
        pass.fragments(),
        [fragment(0, 0, Some(0.25), Verdict::Passed, false), fragment(1, 0, Some(0.5), Verdict::FailedDepth, false)]
    );
    // Without a depth test nothing is tested. Of two triangles, the first
    // covers the pixel's whole block (below the diagonal) and the second
    // none of it.
    pass.draw(&draw(&two_triangles(0.75))).unwrap();
    assert_eq!(pass.fragments()[2..], [fragment(2, 0, None, Verdict::NotTested, false)]);
    // Starting over forgets the fragments and counts draws from 0.
    pass.reset(Some(&[1.0; 64])).unwrap();
    assert_eq!(pass.fragments(), []);
    pass.draw(&with_depth(&fullscreen(0.5), less)).unwrap();
    assert_eq!(pass.fragments(), [fragment(0, 0, Some(0.5), Verdict::Passed, false)]);
}

#[test]
fn a_pixel_its_primitive_misses_runs_as_a_helper_lane() {
    // A triangle over pixel (0, 0) alone (centres (0.5, 0.5) in, the rest
    // out): its quad runs, and (1, 1) is a helper lane there.
    let tri = [at(8, 8, [0.0, 0.0], 0.5), at(8, 8, [1.2, 0.0], 0.5), at(8, 8, [0.0, 1.2], 0.5)];
    let mut pass = Pass::new(8, 8).unwrap();
    pass.probe(1, 1).unwrap();
    pass.draw(&draw(&tri)).unwrap();
    assert_eq!(pass.fragments(), [fragment(0, 0, None, Verdict::NotTested, true)]);
    // Behind the stored depth, its quad does not run: no helper lane.
    let mut pass = depth_pass(8, 8, 0.25);
    pass.probe(1, 1).unwrap();
    pass.draw(&with_depth(&tri, DepthState::new(Compare::Less, true))).unwrap();
    assert_eq!(pass.fragments(), []);
    // Outside the block: nothing at all.
    let mut pass = Pass::new(8, 8).unwrap();
    pass.probe(2, 0).unwrap();
    pass.draw(&draw(&tri)).unwrap();
    assert_eq!(pass.fragments(), []);
}

#[test]
fn a_covered_pixel_failing_depth_in_a_quad_that_runs_is_a_helper() {
    // Stored depth 0 at (0, 0) and 1 elsewhere: a fullscreen triangle at
    // 0.5 passes at (1, 0) and fails at (0, 0), which still runs.
    let mut initial = vec![1.0; 16];
    initial[0] = 0.0;
    let mut pass = Pass::new(4, 4).unwrap().with_depth(initial).unwrap();
    pass.probe(0, 0).unwrap();
    pass.draw(&with_depth(&fullscreen(0.5), DepthState::new(Compare::Less, false))).unwrap();
    assert_eq!(pass.fragments(), [fragment(0, 0, Some(0.5), Verdict::FailedDepth, true)]);
}

#[test]
fn a_culled_primitive_is_reported_where_it_would_cover() {
    // Clockwise on screen: a back face. It covers the lower-left half;
    // (1, 6) is under it, (6, 1) is not.
    let cw = [[-1.0, -1.0, 0.5, 1.0], [-1.0, 1.0, 0.5, 1.0], [1.0, -1.0, 0.5, 1.0]];
    let culled = |x: u32, y: u32| {
        let mut pass = Pass::new(8, 8).unwrap();
        pass.probe(x, y).unwrap();
        let s = pass.draw(&Draw { cull: Some(Face::Back), ..draw(&cw) }).unwrap();
        assert_eq!(s.rasterized.culled_triangles, 1);
        pass.fragments().to_vec()
    };
    assert_eq!(culled(1, 6), [fragment(0, 0, None, Verdict::Culled, false)]);
    assert_eq!(culled(6, 1), []);
    // Zero area: culled, never reported.
    let flat = [[-1.0, -1.0, 0.5, 1.0], [0.0, 0.0, 0.5, 1.0], [1.0, 1.0, 0.5, 1.0]];
    let mut pass = Pass::new(8, 8).unwrap();
    pass.probe(4, 3).unwrap();
    assert_eq!(pass.draw(&draw(&flat)).unwrap().rasterized.culled_triangles, 1);
    assert_eq!(pass.fragments(), []);
}

#[test]
fn a_clipped_primitive_is_probed_on_the_part_the_near_plane_keeps() {
    // z = 0.5 - 0.5·(y + 1) (w = 1) keeps the lower half of the 512×512
    // target, in two fan pieces. At pixel (100, 400), NDC y = 1 -
    // 400.5/256, z = 0.5 - 0.5·(2 - 400.5/256) = 0.2822265625.
    let positions = [[-1.0, -1.0, 0.5, 1.0], [3.0, -1.0, 0.5, 1.0], [-1.0, 3.0, -1.5, 1.0]];
    let less = DepthState::new(Compare::Less, true);
    let probed = |x: u32, y: u32, cull: Option<Face>| {
        let mut pass = depth_pass(512, 512, 1.0);
        pass.probe(x, y).unwrap();
        pass.draw(&Draw { cull, ..with_depth(&positions, less) }).unwrap();
        pass.fragments().to_vec()
    };
    assert_eq!(probed(100, 400, None), [fragment(0, 0, Some(0.282_226_56), Verdict::Passed, false)]);
    // The fan's diagonal runs from (0, 512) to (512, 256): (300, 360) lies
    // in the second piece.
    assert_eq!(probed(300, 360, None).len(), 1);
    assert_eq!(probed(100, 100, None), [], "clipped away");
    // Counter-clockwise on screen, so culling front faces removes it.
    assert_eq!(probed(100, 400, Some(Face::Front)), [fragment(0, 0, None, Verdict::Culled, false)]);
    assert_eq!(probed(100, 100, Some(Face::Front)), [], "culled, and clipped away there");
}

#[test]
fn a_probe_outside_the_target_is_refused() {
    let mut pass = Pass::new(4, 3).unwrap();
    assert_eq!(pass.probe(4, 0).unwrap_err(), QuadError::Pixel { x: 4, y: 0, width: 4, height: 3 });
    assert_eq!(pass.probe(0, 3).unwrap_err().to_string(), "pixel (0, 3) is outside the 4x3 target");
    assert!(pass.probe(3, 2).is_ok());
}
