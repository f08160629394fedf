//! `register::fit_camera` on generated scenes with exact cameras (docs/registration.md,
//! "Synthetic GCP fits"): per photo camera of the scene, N GCPs are ray cast through
//! random pixels onto the exact DEM, their pixels disturbed by Gaussian noise of SIGMA px
//! per axis (and a share of gross outliers), and the camera is fitted from STARTS random
//! starts (yaw ±3°, pitch and roll ±1.5°, focal length ±3 %, position ±5 m horizontally and
//! ±3 m vertically, as a phone's GPS and compass give) in two configurations: the position
//! known (fixed at the truth, angles + f + k1 free) and the position free (from the
//! disturbed start). Prints how many starts converge to the minimum the fit reaches from the
//! true camera (angles within 0.001°: the solver's part), the error of that minimum against
//! the truth (the GCPs' part: noise and geometry), and the worst start. Seeded,
//! deterministic.
//!
//! ```sh
//! cargo run --release --example fit_camera_synthetic -- [--scene demo|tall] [--gcps N] [--sigma PX] [--outliers FRACTION] [--starts N]
//! ```

use cliffmap::camera::CameraModel;
use cliffmap::demo_scene::{DemTracer, DemoScene};
use cliffmap::register::{CameraParams, FitOptions, Gcp, fit_camera, parse_free};
use glam::DVec3;

struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn symmetric(&mut self) -> f64 {
        2.0 * self.uniform() - 1.0
    }
    fn gauss(&mut self) -> f64 {
        (-2.0 * self.uniform().max(1e-300).ln()).sqrt()
            * (std::f64::consts::TAU * self.uniform()).cos()
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map(|s| s.as_str())
    };
    let scene = match flag("--scene").unwrap_or("demo") {
        "demo" => DemoScene::default(),
        "tall" => DemoScene::tall_walls(),
        s => anyhow::bail!("unknown scene {s}"),
    };
    let n_gcps: usize = flag("--gcps").unwrap_or("12").parse()?;
    let sigma: f64 = flag("--sigma").unwrap_or("1").parse()?;
    let outliers: f64 = flag("--outliers").unwrap_or("0").parse()?;
    let starts: usize = flag("--starts").unwrap_or("20").parse()?;
    let (dem, _) = scene.generate()?;
    let mut rng = Rng(0x1234_5678_9ABC_DEF1);
    println!(
        "{n_gcps} GCPs per photo, noise {sigma} px per axis, {:.0} % outliers (30–80 px), {starts} starts per photo\n",
        100.0 * outliers
    );
    println!(
        "| photo (distance to the GCPs) | configuration | starts converged | minimum's angle error ° | minimum's position error m | RMSE of the inliers px | worst start's angle error ° |"
    );
    println!("|---|---|---|---|---|---|---|");
    for truth in scene.photo_cameras() {
        let tracer = DemTracer::new(&dem, truth.position)?;
        let mut gcps = Vec::new();
        while gcps.len() < n_gcps {
            let (u, v) = (
                rng.uniform() * (truth.width as f64 - 1.0),
                rng.uniform() * (truth.height as f64 - 1.0),
            );
            let Some(dir) = truth.pixel_ray(u, v) else {
                continue;
            };
            let Some(hit) = tracer.nearest(truth.position, dir, f64::INFINITY) else {
                continue;
            };
            let Some(p) = truth.project(hit.point) else {
                continue;
            };
            let mut pixel = [p[0] + sigma * rng.gauss(), p[1] + sigma * rng.gauss()];
            if rng.uniform() < outliers {
                let (r, a) = (
                    30.0 + 50.0 * rng.uniform(),
                    std::f64::consts::TAU * rng.uniform(),
                );
                pixel = [pixel[0] + r * a.cos(), pixel[1] + r * a.sin()];
            }
            gcps.push(Gcp {
                name: format!("g{}", gcps.len()),
                world: hit.point,
                pixel,
                weight: 1.0,
            });
        }
        for (config, free, move_position) in [
            ("position known", "angles,f,k1", false),
            ("position free", "angles,position,f,k1", true),
        ] {
            let opts = FitOptions {
                free: parse_free(free)?,
                robust: !args.iter().any(|a| a == "--no-robust"),
                ..FitOptions::default()
            };
            let best = fit_camera(&truth, &gcps, &opts)?;
            let mut converged = 0;
            let mut worst = 0.0f64;
            for _ in 0..starts {
                let mut q = CameraParams::from_camera(&truth);
                q.angles[0] += (3.0 * rng.symmetric()).to_radians();
                q.angles[1] += (1.5 * rng.symmetric()).to_radians();
                q.angles[2] += (1.5 * rng.symmetric()).to_radians();
                let f = 1.0 + 0.03 * rng.symmetric();
                q.focal = [q.focal[0] * f, q.focal[1] * f];
                q.k = [0.0, 0.0];
                if move_position {
                    q.position += DVec3::new(
                        5.0 * rng.symmetric(),
                        5.0 * rng.symmetric(),
                        3.0 * rng.symmetric(),
                    );
                }
                let Ok(fit) = fit_camera(&q.camera(), &gcps, &opts) else {
                    continue;
                };
                converged += (angle_error(&fit.camera, &best.camera) <= 0.001) as usize;
                worst = worst.max(angle_error(&fit.camera, &truth));
            }
            println!(
                "| {:.0} m | {config} | {converged} / {starts} | {:.4} | {:.3} | {:.2} | {worst:.4} |",
                truth.position.distance(
                    gcps.iter().fold(DVec3::ZERO, |s, g| s + g.world) / gcps.len() as f64
                ),
                angle_error(&best.camera, &truth),
                (best.camera.position - truth.position).length(),
                best.rmse_inliers_px
            );
        }
    }
    Ok(())
}

/// The largest of the yaw, pitch and roll errors of `c` against `t`, degrees.
fn angle_error(c: &CameraModel, t: &CameraModel) -> f64 {
    let (a, b) = (CameraParams::from_camera(c), CameraParams::from_camera(t));
    (0..3)
        .map(|k| {
            let e = (a.angles[k] - b.angles[k]).to_degrees().rem_euclid(360.0);
            e.min(360.0 - e)
        })
        .fold(0.0, f64::max)
}
