//! Two photos from different places, **both** with rough cameras (GPS ±5 m, compass, EXIF),
//! placed together through the points they share and the terrain (`register::adjust_bundle`;
//! docs/registration.md, "Two rough photos together"), on a generated scene with exact cameras.
//!
//! Per demo photo (its exact camera is the truth of photo A), a second photo B of the same
//! target from elsewhere (`DemoScene::second_shots`), both rendered from the scene's ground
//! truth. Both cameras are perturbed `--starts` times inside the issue's ranges (position
//! ±5 m horizontally and ±2 m vertically, yaw ±3°, pitch and roll ±1.5°, focal ±3 % unless
//! `--same-body`). Then:
//! 1. *resection against the rough A*: B resected against A's rough camera (what
//!    `register` could do before: it treats one photo as known);
//! 2. *bundle*: ties of that resection, both cameras adjusted together, priors at the rough
//!    cameras; then `--rounds` − 1 times: B resected again against the adjusted A (better
//!    templates, more ties) and the bundle rerun.
//!
//! Prints per start the errors of A and B after each step, and per pair a summary.
//!
//! ```text
//! cargo run --release --example register_bundle -- OUT [--scene demo|tall] [--starts N]
//!     [--turn-deg D] [--distance-ratio R] [--max-error M] [--photo-width W] [--reuse]
//!     [--same-body] [--rounds N]
//! ```

#[path = "bench_util/mod.rs"]
mod bench_util;

use bench_util::scene_args::{
    PairScene, Rng, SceneArgs, angle_diff, keep_above_ground, photo_height, rough_start,
};
use std::time::Instant;

use cliffmap::camera::CameraModel;
use cliffmap::register::{
    BundleOptions, BundlePair, CameraParams, LabelledTerrain, Param, ResectOptions, adjust_bundle,
    resect_photo,
};

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Largest angle error (degrees) and position error (metres) of `cam` against `truth`.
fn errs(cam: &CameraModel, truth: &CameraModel) -> (f64, f64) {
    let (p, t) = (
        CameraParams::from_camera(cam),
        CameraParams::from_camera(truth),
    );
    let ang = (0..3)
        .map(|i| angle_diff(p.angles[i], t.angles[i]).to_degrees().abs())
        .fold(0.0, f64::max);
    (ang, cam.position.distance(truth.position))
}

fn main() -> anyhow::Result<()> {
    let a = SceneArgs::from_env("register_bundle OUT [options]")?;
    let (flag, has) = (|n: &str| a.flag(n), |n: &str| a.has(n));
    let ps = PairScene::from_args(&a, "register_bundle")?;
    let (scene, dem, store) = (&ps.scene, &ps.dem, &ps.store);
    let (starts, width, max_error, same_body) = (ps.starts, ps.width, ps.max_error, ps.same_body);
    let (turn, ratio) = (ps.turn_deg, ps.distance_ratio);
    let rounds: usize = flag("--rounds").unwrap_or("2").parse()?;
    let mut rng = Rng(0xB0_4D1E);
    let mut ropts = ResectOptions {
        surface_error_m: max_error,
        ..ResectOptions::default()
    };
    let mut bopts = BundleOptions {
        surface_error_m: max_error,
        ..BundleOptions::default()
    };
    if same_body {
        ropts.free.retain(|p| *p != Param::F);
    } else {
        bopts.free.push(Param::F);
    }
    println!(
        "Scene {:?}, store --max-error {max_error}, photos {width} px wide, B turned {turn}° around A's target at {ratio} × the distance, {}\n",
        flag("--scene").unwrap_or("demo"),
        if same_body {
            "same body (focal lengths exact, not fitted)"
        } else {
            "focal lengths ±3 %, fitted"
        }
    );
    println!(
        "| A | start | rough: A ° / m, B ° / m | resection of B against rough A: B ° / m | bundle: A ° / m, B ° / m | σ position A, B m | ties (inlier residuals / all) | RMSE px | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut summary = Vec::new();
    for anchor in &ps.anchors {
        let terrain = LabelledTerrain::new(store, anchor.camera.position)?;
        let surface = |o, d| terrain.hit(o, d);
        let Some(second) = ps.second_of(anchor) else {
            eprintln!("{}: no second place with a clear view", anchor.name);
            continue;
        };
        let truth_a = anchor.camera;
        let truth_b = second.camera.resized(width, photo_height(width));
        let img_b = scene.render_truth_photo(dem, &truth_b, 2)?;
        let (mut res_b, mut bun_a, mut bun_b, mut times) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for s in 0..starts {
            let mut ca = rough_start(
                CameraParams::from_camera(&truth_a),
                &mut rng,
                5.0,
                !same_body,
            );
            let mut cb = rough_start(
                CameraParams::from_camera(&truth_b),
                &mut rng,
                5.0,
                !same_body,
            );
            keep_above_ground(&mut ca, &terrain);
            keep_above_ground(&mut cb, &terrain);
            let (rough_a, rough_b) = (ca.camera(), cb.camera());
            let t = Instant::now();
            let from_truth = has("--from-truth");
            let (res_a, res_b0) = if from_truth {
                (truth_a, truth_b)
            } else {
                (rough_a, rough_b)
            };
            let first = resect_photo(
                &res_a,
                &anchor.image,
                &img_b,
                &res_b0,
                surface,
                |_| true,
                &ropts,
            )?;
            let after_resection = first.found;
            let (mut cam_a, mut cam_b, mut ties) = (res_a, first.found, first.ties);
            let mut last = None;
            for round in 0..rounds.max(1) {
                if round > 0 {
                    let again = resect_photo(
                        &cam_a,
                        &anchor.image,
                        &img_b,
                        &cam_b,
                        surface,
                        |_| true,
                        &ropts,
                    )?;
                    if again.ties.len() >= ties.len() / 2 {
                        ties = again.ties;
                    }
                }
                if ties.len() < 10 {
                    break;
                }
                let pairs = [BundlePair {
                    a: 0,
                    b: 1,
                    ties: ties.clone(),
                }];
                match adjust_bundle(
                    &[cam_a, cam_b],
                    &[rough_a, rough_b],
                    &[false, false],
                    &pairs,
                    surface,
                    &bopts,
                ) {
                    Ok(fit) => {
                        cam_a = fit.cameras[0];
                        cam_b = fit.cameras[1];
                        last = Some(fit);
                    }
                    Err(e) => {
                        eprintln!("bundle failed: {e}");
                        break;
                    }
                }
            }
            let secs = t.elapsed().as_secs_f64();
            let (ra, rb) = (errs(&rough_a, &truth_a), errs(&rough_b, &truth_b));
            let r1 = errs(&after_resection, &truth_b);
            let (ba, bb) = (errs(&cam_a, &truth_a), errs(&cam_b, &truth_b));
            res_b.push(r1);
            bun_a.push(ba);
            bun_b.push(bb);
            times.push(secs);
            let (sig, inl, rmse) =
                last.as_ref()
                    .map_or(("–".to_string(), "–".to_string(), f64::NAN), |f| {
                        let m = |v: [f64; 3]| v.iter().copied().fold(0.0, f64::max);
                        (
                            format!(
                                "{:.2}, {:.2}",
                                m(f.sigma_position_m[0]),
                                m(f.sigma_position_m[1])
                            ),
                            format!("{} / {}", f.inliers[0].0, f.inliers[0].1),
                            f.rmse_px,
                        )
                    });
            println!(
                "| {} | {s} | {:.2} / {:.2}, {:.2} / {:.2} | {:.3} / {:.2} | {:.3} / {:.2}, {:.3} / {:.2} | {sig} | {inl} | {rmse:.2} | {secs:.1} |",
                anchor.name, ra.0, ra.1, rb.0, rb.1, r1.0, r1.1, ba.0, ba.1, bb.0, bb.1
            );
        }
        summary.push((anchor.name.clone(), res_b, bun_a, bun_b, times));
    }
    println!(
        "\n| A | starts | resection against rough A: B median ° / m | bundle: A median ° / m | bundle: B median ° / m | both within 0.02° and 0.3 m | median s |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (name, rb, ba, bb, mut t) in summary {
        let med = |v: &[(f64, f64)]| {
            let (mut x, mut y): (Vec<f64>, Vec<f64>) = v.iter().copied().unzip();
            (median(&mut x), median(&mut y))
        };
        let (r, a1, b1) = (med(&rb), med(&ba), med(&bb));
        let goal = ba
            .iter()
            .zip(&bb)
            .filter(|(a, b)| a.0 <= 0.02 && a.1 <= 0.3 && b.0 <= 0.02 && b.1 <= 0.3)
            .count();
        println!(
            "| {name} | {starts} | {:.3} / {:.2} | {:.3} / {:.2} | {:.3} / {:.2} | {goal} | {:.1} |",
            r.0,
            r.1,
            a1.0,
            a1.1,
            b1.0,
            b1.1,
            median(&mut t)
        );
    }
    Ok(())
}
