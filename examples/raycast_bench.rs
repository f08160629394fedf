//! Ray-casting benchmark for the photo stage (docs/projection.md, "Ray casting").
//!
//! 1. Rays/s of `TriangleBvh::nearest` against `nearest_brute_force` on a small heightfield
//!    mesh (same rays; the hits must agree).
//! 2. On the finest level of an Engabreen store (built here, into STORE_DIR if given and
//!    it holds no store yet), for every `BvhQuality`: scene + BVH build time, corner rays/s for the
//!    IMG_8902 camera (4290 × 2856, 12.26 M corner rays) and the full `photo_footprints` time.
//!
//! Medians of `RUNS` runs (default 3). Run with:
//! ```sh
//! cargo run --release --example raycast_bench -- [STORE_DIR] [RUNS] [SHRINK] [METHODS] [LEVEL]
//! ```

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::time::Instant;

use bench_util::{cpu_seconds, median, shared_data};
use cliffmap::camera::CameraModel;
use cliffmap::camera::camera_from_json_file;
use cliffmap::photo::{FootprintOptions, photo_footprints};
use cliffmap::raycast::{
    BvhQuality, LevelScene, RayAccel, TriangleBvh, ViewGrid, nearest_brute_force,
};
use cliffmap::store::Store;
use glam::Vec3;
use rayon::prelude::*;

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

fn time<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let r = f();
    (r, t.elapsed().as_secs_f64())
}

fn small_mesh_table() {
    let n = 48;
    let z = |i: i32, j: i32| {
        (i as f32 * 0.37).sin() * 3.0 + (j as f32 * 0.23).cos() * 2.0 + ((i * j) % 7) as f32 * 0.2
    };
    let p = |i: i32, j: i32| Vec3::new(i as f32, j as f32, z(i, j));
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    let mut rng = Lcg(7);
    let rays: Vec<(Vec3, Vec3)> = (0..20_000)
        .map(|_| {
            let o = Vec3::new(
                rng.next() * 60.0 - 6.0,
                rng.next() * 60.0 - 6.0,
                20.0 + rng.next() * 10.0,
            );
            let target = Vec3::new(rng.next() * n as f32, rng.next() * n as f32, 0.0);
            (o, target - o)
        })
        .collect();
    let bvh = TriangleBvh::build(&tris, BvhQuality::default());
    let mut bf_s = Vec::new();
    let mut bvh_s = Vec::new();
    let mut bvh2_s = Vec::new();
    let mut agree = 0;
    let mut hits = 0;
    for _ in 0..3 {
        let (a, t) = time(|| {
            rays.iter()
                .map(|(o, d)| bvh.nearest(*o, *d, 0.0, f32::INFINITY))
                .collect::<Vec<_>>()
        });
        bvh_s.push(t);
        let (_, t2) = time(|| {
            rays.par_iter()
                .map(|(o, d)| bvh.nearest(*o, *d, 0.0, f32::INFINITY))
                .collect::<Vec<_>>()
        });
        bvh2_s.push(t2);
        let (b, t) = time(|| {
            rays.iter()
                .map(|(o, d)| nearest_brute_force(&tris, *o, *d, 0.0, f32::INFINITY))
                .collect::<Vec<_>>()
        });
        bf_s.push(t);
        agree = a
            .iter()
            .zip(&b)
            .filter(|(x, y)| x.map(|h| h.triangle) == y.map(|h| h.triangle))
            .count();
        hits = a.iter().filter(|h| h.is_some()).count();
    }
    let nr = rays.len() as f64;
    let (bf, bv, bv2) = (median(bf_s), median(bvh_s), median(bvh2_s));
    println!(
        "Small mesh: {} triangles, {} rays ({} hit), hits agree on {}/{} rays\n",
        tris.len(),
        rays.len(),
        hits,
        agree,
        rays.len()
    );
    println!("| method | threads | rays/s | speed-up vs brute force |");
    println!("|---|---|---|---|");
    println!("| nearest_brute_force | 1 | {:.3} M | 1.0 |", nr / bf / 1e6);
    println!(
        "| TriangleBvh::nearest ({}) | 1 | {:.2} M | {:.0} |",
        BvhQuality::default().name(),
        nr / bv / 1e6,
        bf / bv
    );
    println!(
        "| TriangleBvh::nearest ({}) | {} | {:.2} M | {:.0} |\n",
        BvhQuality::default().name(),
        rayon::current_num_threads(),
        nr / bv2 / 1e6,
        bf / bv2
    );
    assert_eq!(agree, rays.len(), "BVH and brute force disagree");
}

/// One acceleration's corner hits: (triangle, t) per corner, row-major, `None` = miss.
type Hits = Vec<Option<(u32, f32)>>;

fn cast_all(
    cam: &CameraModel,
    w: u32,
    h: u32,
    nearest: &(dyn Fn(Vec3) -> Option<(u32, f32)> + Sync),
) -> Hits {
    (0..=h)
        .into_par_iter()
        .flat_map_iter(|j| {
            (0..=w).map(move |i| {
                cam.pixel_ray(i as f64 - 0.5, j as f64 - 0.5)
                    .and_then(|d| nearest(d.as_vec3()))
            })
        })
        .collect()
}

/// (same triangle %, same hit/miss %, max |Δt| / t where the triangle agrees).
fn agreement(a: &Hits, b: &Hits) -> (f64, f64, f64) {
    let (mut same_tri, mut same_hit, mut max_dt) = (0usize, 0usize, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        same_hit += usize::from(x.is_some() == y.is_some());
        match (x, y) {
            (Some((ta, da)), Some((tb, db))) if ta == tb => {
                same_tri += 1;
                max_dt = max_dt.max(((da - db).abs() / da.max(1e-6)) as f64);
            }
            (None, None) => same_tri += 1,
            _ => {}
        }
    }
    let n = a.len().max(1) as f64;
    (
        100.0 * same_tri as f64 / n,
        100.0 * same_hit as f64 / n,
        max_dt,
    )
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let runs = bench_util::runs_arg(&args, 2, 3)?;
    small_mesh_table();

    let tmp = tempfile::tempdir()?;
    // A given directory without a manifest gets the store built into it (kept for reruns).
    let dir = args
        .get(1)
        .map_or_else(|| tmp.path().to_path_buf(), std::path::PathBuf::from);
    if !dir.join("manifest.json").is_file() {
        let t = bench_util::build_engabreen_store(&dir, "raycast-bench")?;
        println!("Engabreen store built in {t:.1} s (default build options)");
    }
    let store = Store::open(&dir)?;
    // Optional fifth argument: the quadtree level (default the finest) and photo shrink.
    let level = match args.get(5) {
        Some(l) => l.parse()?,
        None => store.manifest.quadtree.levels - 1,
    };
    let cam = camera_from_json_file(
        &shared_data("engabreen/engabreen_camera_IMG_8902.json"),
        (4290, 2856),
    )?;
    // Optional third argument: shrink the photo by this factor (quick runs).
    let shrink: u32 = args
        .get(3)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(1)
        .max(1);
    // Optional fourth argument: comma-separated accelerations (RayAccel names).
    let methods: Vec<RayAccel> = match args.get(4) {
        Some(list) => list
            .split(',')
            .map(|m| RayAccel::parse(m).ok_or_else(|| anyhow::anyhow!("bad method {m}")))
            .collect::<anyhow::Result<_>>()?,
        None => ["grid:4", "grid:8", "grid:16", "grid:32"]
            .into_iter()
            .map(|m| RayAccel::parse(m).expect("valid"))
            .chain(BvhQuality::ALL.into_iter().map(RayAccel::Bvh))
            .collect(),
    };
    let cam = cam.resized(cam.width / shrink, cam.height / shrink);
    let (w, h) = (cam.width, cam.height);
    let base = LevelScene::from_store(&store, level, cam.position, BvhQuality::Fast)?;
    let cells = base.cells.clone();
    println!(
        "Finest level {level}: {} cells, {} triangles; camera {w} × {h} = {:.2} M corner rays; {} threads\n",
        cells.len(),
        base.triangle_count(),
        ((w + 1) * (h + 1)) as f64 / 1e6,
        rayon::current_num_threads()
    );
    let origin = Vec3::ZERO; // the frame is centred on the camera
    let bvh = base.bvh().expect("built with a BVH");
    let reference = cast_all(&cam, w, h, &|d| {
        bvh.nearest(origin, d, 0.0, f32::INFINITY)
            .map(|x| (x.triangle, x.t))
    });
    let rays = ((w + 1) * (h + 1)) as f64;
    let nhit = reference.iter().filter(|x| x.is_some()).count();
    println!(
        "Reference: BVH (fast) nearest hits, {:.1} % of the corner rays hit.\n",
        100.0 * nhit as f64 / rays
    );
    println!(
        "| method | scene + accel build s (CPU s) | grid entries / bins | corner rays/s | corner rays s (CPU s) | same triangle as BVH % | same hit/miss % | max rel Δt | photo_footprints s (CPU s) | footprints | silhouette | reconstructed | dropped |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for m in methods {
        let mut build = Vec::new();
        let mut build_cpu = Vec::new();
        let mut scene = None;
        let mut stats = None;
        for _ in 0..runs {
            let c0 = cpu_seconds();
            let (s, t) = time(|| {
                let s = LevelScene::new(cells.clone(), cam.position, m);
                if let RayAccel::ViewGrid(p) = m {
                    stats = Some(ViewGrid::for_camera(&s, &cam, p).stats());
                }
                s
            });
            build_cpu.push(cpu_seconds() - c0);
            build.push(t);
            scene = Some(s);
        }
        let scene = scene.expect("runs >= 1");
        let mut cast = Vec::new();
        let mut cast_cpu = Vec::new();
        let mut hits = Vec::new();
        for _ in 0..runs {
            let c0 = cpu_seconds();
            let (x, t) = time(|| match m {
                RayAccel::ViewGrid(p) => {
                    let g = ViewGrid::for_camera(&scene, &cam, p);
                    cast_all(&cam, w, h, &|d| {
                        g.nearest(origin, d).map(|x| (x.triangle, x.t))
                    })
                }
                RayAccel::Bvh(_) => {
                    let b = scene.bvh().expect("built with a BVH");
                    cast_all(&cam, w, h, &|d| {
                        b.nearest(origin, d, 0.0, f32::INFINITY)
                            .map(|x| (x.triangle, x.t))
                    })
                }
            });
            cast_cpu.push(cpu_seconds() - c0);
            cast.push(t);
            hits = x;
        }
        let (same_tri, same_hit, max_dt) = agreement(&hits, &reference);
        drop(hits);
        let mut full = Vec::new();
        let mut full_cpu = Vec::new();
        let mut set = None;
        for _ in 0..runs {
            let c0 = cpu_seconds();
            let (s, t) = time(|| photo_footprints(&scene, &cam, &FootprintOptions::default()));
            full_cpu.push(cpu_seconds() - c0);
            full.push(t);
            set = Some(s);
        }
        let set = set.expect("runs >= 1");
        let c = median(cast);
        let grid = stats.map_or("–".to_string(), |s| {
            format!(
                "{:.2} M / {}×{}",
                s.entries as f64 / 1e6,
                s.bins[0],
                s.bins[1]
            )
        });
        println!(
            "| {} | {:.2} ({:.2}) | {} | {:.2} M | {:.2} ({:.1}) | {:.4} | {:.4} | {:.1e} | {:.2} ({:.1}) | {} | {} | {} | {} |",
            m.name(),
            median(build),
            median(build_cpu),
            grid,
            rays / c / 1e6,
            c,
            median(cast_cpu),
            same_tri,
            same_hit,
            max_dt,
            median(full),
            median(full_cpu),
            set.len(),
            set.rejected_silhouette,
            set.reconstructed,
            set.dropped
        );
    }
    Ok(())
}
