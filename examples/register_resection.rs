//! Placing a photo, position included, from a placed photo taken elsewhere
//! (`register::resect_photo`; docs/registration.md, "Ties between different places"), on a
//! generated scene with exact cameras.
//!
//! Per demo photo (the anchor, exact camera), a second photo is taken of the same target
//! from elsewhere (`DemoScene::second_shots`: turned `--turn-deg` around it at
//! `--distance-ratio` times the anchor's distance, 1.7 m above the ground, aimed a little
//! off the target; in the canyon, farther up its floor); both are rendered from the scene's
//! ground truth. The
//! second camera is then perturbed `--starts` times inside the issue's ranges (position
//! ±5 m horizontally, ±2 m vertically, yaw ±3°, pitch and roll ±1.5°, focal ±3 %) and
//! resected against the anchor through the store's terrain. Prints per start the errors
//! left and per pair the success rate.
//!
//! ```text
//! cargo run --release --example register_resection -- OUT [--scene demo|tall] [--starts N]
//!     [--turn-deg D] [--distance-ratio R] [--max-error M] [--photo-width W] [--reuse]
//!     [--same-body]
//! ```
//! `--same-body`: the second photo is taken with the anchor's camera (the same focal length,
//! known), so the focal length is not fitted.

#[path = "bench_util/mod.rs"]
mod bench_util;

use bench_util::scene_args::{
    PairScene, Rng, SceneArgs, angle_diff, photo_height, pixel_errors, rough_start, shown_points,
};
use std::time::Instant;

use cliffmap::camera::CameraModel;
use cliffmap::register::{CameraParams, LabelledTerrain, Param, ResectOptions, resect_photo};

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let a = SceneArgs::from_env("register_resection OUT [options]")?;
    let flag = |n: &str| a.flag(n);
    let ps = PairScene::from_args(&a, "register_resection")?;
    let (scene, dem, store, anchors) = (&ps.scene, &ps.dem, &ps.store, &ps.anchors);
    let (starts, width, max_error, same_body) = (ps.starts, ps.width, ps.max_error, ps.same_body);
    let (turn, ratio) = (ps.turn_deg, ps.distance_ratio);
    let mut rng = Rng(0x2E5E_C710);
    let mut opts = ResectOptions {
        surface_error_m: max_error,
        ..ResectOptions::default()
    };
    if same_body {
        // the anchor's camera body: its focal length is known, not fitted
        opts.free.retain(|p| *p != Param::F);
    }
    println!(
        "Scene {:?}, store --max-error {max_error}, photos {width} px wide, second photo turned {turn}° around the target at {ratio} × the distance\n",
        flag("--scene").unwrap_or("demo")
    );
    println!(
        "| anchor | baseline m | start | start error: angles ° / position m / focal % / px median, 90 % | after: angles ° (yaw, pitch, roll) / position m / focal % / px median, 90 % | points / coarse / fine / inliers | RMSE px | σ position m | accepted | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut summary = Vec::new();
    for a in anchors {
        let terrain = LabelledTerrain::new(store, a.camera.position)?;
        let Some(second) = ps.second_of(a) else {
            eprintln!("{}: no second place with a clear view", a.name);
            continue;
        };
        let truth = second.camera.resized(width, photo_height(width));
        let img = scene.render_truth_photo(dem, &truth, 2)?;
        // terrain points the photo shows, to score a camera by where it puts them: RMS
        // pixel error, what the projection feels (median and 90th percentile; the near
        // ground at the image's foot moves most with the position)
        let shown = shown_points(&truth, |o, d| terrain.hit(o, d));
        let px_err = |cam: &CameraModel| pixel_errors(cam, &shown);
        let baseline = truth.position.distance(a.camera.position);
        let tp = CameraParams::from_camera(&truth);
        let (mut ok, mut goal, mut times, mut pos_errs, mut ang_errs, mut px_errs, mut px90_errs) = (
            0,
            0,
            Vec::new(),
            Vec::new(),
            Vec::new(),
            Vec::new(),
            Vec::new(),
        );
        for s in 0..starts {
            let c = rough_start(tp, &mut rng, 5.0, !same_body);
            let rough: CameraModel = c.camera();
            let t = Instant::now();
            let fit = resect_photo(
                &a.camera,
                &a.image,
                &img,
                &rough,
                |o, d| terrain.hit(o, d),
                |_| true,
                &opts,
            )?;
            let secs = t.elapsed().as_secs_f64();
            let errs = |cam: &CameraModel| {
                let p = CameraParams::from_camera(cam);
                let each: Vec<f64> = (0..3)
                    .map(|i| angle_diff(p.angles[i], tp.angles[i]).to_degrees())
                    .collect();
                let ang = each.iter().copied().fold(0.0, f64::max);
                (
                    ang,
                    cam.position.distance(truth.position),
                    100.0 * (cam.fx / truth.fx - 1.0),
                    each,
                )
            };
            let (a0, p0, f0, _) = errs(&rough);
            let (a1, p1, f1, each) = errs(&fit.found);
            let (px0, px1) = (px_err(&rough), px_err(&fit.found));
            if fit.accepted {
                ok += 1;
                px_errs.push(px1.0);
                px90_errs.push(px1.1);
                times.push(secs);
                pos_errs.push(p1);
                ang_errs.push(a1);
                if a1 <= 0.02 && p1 <= 0.3 {
                    goal += 1;
                }
            }
            println!(
                "| {} | {baseline:.0} | {s} | {a0:.2} / {p0:.2} / {f0:+.2} / {:.1}, {:.1} | {a1:.3} ({:.3}, {:.3}, {:.3}) / {p1:.2} / {f1:+.2} / {:.2}, {:.2} | {} | {secs:.1} |",
                a.name,
                px0.0,
                px0.1,
                each[0],
                each[1],
                each[2],
                px1.0,
                px1.1,
                bench_util::resect_cells(&fit),
            );
        }
        summary.push((
            a.name.clone(),
            baseline,
            ok,
            goal,
            median(&mut ang_errs),
            median(&mut pos_errs),
            median(&mut times),
            median(&mut px_errs),
            median(&mut px90_errs),
        ));
    }
    println!(
        "\n| anchor | baseline m | starts | accepted | within 0.02° and 0.3 m | median angle error ° | median position error m | px error on the terrain, median / 90 % (median of starts) | median s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, b, ok, goal, ang, pos, t, px, px90) in summary {
        println!(
            "| {name} | {b:.0} | {starts} | {ok} | {goal} | {ang:.3} | {pos:.2} | {px:.2} / {px90:.2} | {t:.1} |"
        );
    }
    Ok(())
}
