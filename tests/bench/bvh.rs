//! `bench-bvh`: the path tracer's hierarchy on the CPU: build time over a
//! bundled scene's triangles, and closest-hit rays per second of the CPU
//! reference traversal, one ray per pixel of a 640×360 pinhole camera.
//!
//! ```sh
//! cargo run --release -p loupe-tests --bin bench-bvh [-- scenes/showcase.toml]
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use glam::{Mat4, Vec3};
use loupe::bvh::Bvh;
use loupe_tests::{machine, repo};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> ExitCode {
    let scenes: Vec<PathBuf> = match std::env::args().skip(1).map(PathBuf::from).collect::<Vec<_>>() {
        v if v.is_empty() => vec![repo().join("scenes/minimal.toml"), repo().join("scenes/showcase.toml")],
        v => v,
    };
    println!("bench-bvh on {}", machine());
    for path in scenes {
        let loaded = match loupe::scene::load(&path) {
            Ok(l) => l,
            Err(d) => {
                eprintln!("{}: {d}", path.display());
                return ExitCode::FAILURE;
            }
        };
        let tris = loupe::render::scene_gpu::world_triangles(&loaded.scene, &loaded.meshes);
        let builds: Vec<f64> = (0..11)
            .map(|_| {
                let start = Instant::now();
                std::hint::black_box(Bvh::build(&tris));
                start.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        let bvh = Bvh::build(&tris);
        let cam = &loaded.scene.camera;
        let (w, h) = (640u32, 360u32);
        // The raster's camera (`render::scene_gpu`'s view uniform).
        let view = Mat4::look_at_rh(Vec3::from(cam.position), Vec3::from(cam.target), Vec3::from(cam.up));
        let inv = (Mat4::perspective_rh(cam.fov_deg.to_radians(), w as f32 / h as f32, cam.near, cam.far) * view).inverse();
        let rays: Vec<(Vec3, Vec3)> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
                let ndc = |z: f32| inv.project_point3(Vec3::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0, z));
                let (near, far) = (ndc(0.0), ndc(1.0));
                (near, (far - near).normalize())
            })
            .collect();
        let mut hits = 0;
        let traces: Vec<f64> = (0..5)
            .map(|_| {
                let start = Instant::now();
                hits = rays.iter().filter(|(o, d)| bvh.intersect(*o, *d, 0.0, f32::INFINITY).is_some()).count();
                start.elapsed().as_secs_f64()
            })
            .collect();
        let s = &bvh.stats;
        println!(
            "{}: {} triangles, {} nodes, depth {}, largest leaf {}, SAH cost {:.1}; build {:.2} ms (median of 11); {:.2} M rays/s on one thread ({hits} of {} hit)",
            path.display(),
            s.triangles,
            s.nodes,
            s.max_depth,
            s.max_leaf,
            s.sah_cost,
            median(builds),
            rays.len() as f64 / median(traces) / 1e6,
            rays.len()
        );
    }
    ExitCode::SUCCESS
}
