//! Success rate of `register` (terrain registration without GCPs) on a generated scene
//! with exact cameras (docs/registration.md, "`cliffmap register`"): builds the scene's
//! store, renders its ground photos with the exact cameras, perturbs each camera N times
//! inside the issue's ranges (yaw ±3°, pitch and roll ±1.5°, focal ±3 %, position ±5 m
//! horizontally and ±2 m vertically, kept at least 0.5 m above the ground), registers, and
//! prints per start the remaining errors, and a table of success rates and times.
//!
//! ```text
//! cargo run --release --example register_synthetic -- OUT [--scene demo|tall] [--starts N]
//!     [--photo-width W] [--free LIST] [--reuse] [--position-error M] [--max-error M] [--finest F]
//!     [--position-search H]
//! ```

#[path = "bench_util/mod.rs"]
mod bench_util;

use bench_util::scene_args::{
    Rng, SceneArgs, angle_diff, build_scene_store, keep_above_ground, reparam_quietly, rough_start,
    write_scene_photos,
};
use std::time::Instant;

use cliffmap::camera::CameraModel;
use cliffmap::register::{
    CameraParams, LabelledTerrain, TerrainOptions, parse_free, register_to_terrain,
};

fn main() -> anyhow::Result<()> {
    let a = SceneArgs::from_env("register_synthetic OUT [options]")?;
    let (out, flag, has) = (a.out.clone(), |n: &str| a.flag(n), |n: &str| a.has(n));
    let scene = a.scene()?;
    let starts: usize = flag("--starts").unwrap_or("5").parse()?;
    let width: u32 = flag("--photo-width").unwrap_or("1600").parse()?;
    let pos_err: f64 = flag("--position-error").unwrap_or("5").parse()?;
    let mut opts = TerrainOptions::default();
    if let Some(f) = flag("--finest") {
        opts.finest_factor = f.parse()?;
    }
    if let Some(f) = flag("--free") {
        opts.free = parse_free(f)?;
        // (x, y, z: the silhouette-edge stage, which the command does not offer)
        opts.experimental_position = true;
    }
    // --position-search H: the position searched by the score at full resolution (an
    // experiment, docs/registration.md "Position by the score at full resolution")
    if let Some(h) = flag("--position-search") {
        opts.position_search_m = Some(h.parse()?);
    }
    let (dem, ortho) = scene.generate()?;
    let store_dir = out.join("store");
    let list = out.join("photos").join("photos.json");
    if !(has("--reuse") && store_dir.join("manifest.json").exists() && list.exists()) {
        let t = Instant::now();
        let max_error: f64 = flag("--max-error").unwrap_or("0.5").parse()?;
        build_scene_store(
            &scene,
            &dem,
            &ortho,
            max_error,
            &store_dir,
            "register_synthetic",
        )?;
        reparam_quietly(&store_dir)?;
        write_scene_photos(&scene, &dem, &out.join("photos"), width)?;
        eprintln!("store and photos: {:.1} s", t.elapsed().as_secs_f64());
    }
    let store = cliffmap::store::Store::open(&store_dir)?;
    let photos = cliffmap::photo::read_photo_list(&list)?;
    let mut rng = Rng(0x5EED_2026);
    println!(
        "| photo | start | yaw/pitch/roll error start (°) | after (°) | position error start / after (m) | focal error start / after (%) | repeat (px) | verdict | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut rows: Vec<(String, bool, bool, f64)> = Vec::new(); // photo, converged, within goal, seconds
    for p in &photos {
        let truth = CameraParams::from_camera(&p.camera);
        let terrain = LabelledTerrain::new(&store, p.camera.position)?;
        for s in 0..starts {
            let mut c = rough_start(truth, &mut rng, pos_err, true);
            keep_above_ground(&mut c, &terrain);
            let rough: CameraModel = c.camera();
            let fit = register_to_terrain(&terrain, &p.image, &rough, &opts)?;
            let got = CameraParams::from_camera(&fit.found);
            let err = |q: &CameraParams| {
                let a = [0, 1, 2].map(|k| angle_diff(q.angles[k], truth.angles[k]).to_degrees());
                (
                    a,
                    (q.position - truth.position).length(),
                    100.0 * (q.focal[0] / truth.focal[0] - 1.0),
                )
            };
            if let Some(e) = &fit.edges {
                eprintln!(
                    "{} {s}: edges {} matched, median {:.2} px, restart {:.2} m, sigma {:?}",
                    p.name, e.matched, e.median_px, e.position_repeat_m, e.sigma
                );
            }
            let (a0, p0, f0) = err(&c);
            let (a1, p1, f1) = err(&got);
            let goal = a1.iter().all(|&e| e <= 0.02) && p1 <= 0.3;
            println!(
                "| {} | {s} | {:.2} / {:.2} / {:.2} | {:.3} / {:.3} / {:.3} | {:.1} / {:.2} | {:+.1} / {:+.2} | {:.2} | {} | {:.1} |",
                p.name,
                a0[0],
                a0[1],
                a0[2],
                a1[0],
                a1[1],
                a1[2],
                p0,
                p1,
                f0,
                f1,
                fit.repeat_px,
                if fit.converged {
                    "converged"
                } else {
                    "not converged"
                },
                fit.seconds
            );
            rows.push((p.name.clone(), fit.converged, goal, fit.seconds));
        }
    }
    println!();
    println!(
        "| photo | starts | registered | registered within 0.02° and 0.3 m | registered outside the goal | refused, found camera within the goal | refused, outside | median s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut names: Vec<String> = rows.iter().map(|r| r.0.clone()).collect();
    names.dedup();
    for n in names.iter().chain(std::iter::once(&"all".to_string())) {
        let sel: Vec<&(String, bool, bool, f64)> =
            rows.iter().filter(|r| n == "all" || &r.0 == n).collect();
        if sel.is_empty() {
            continue; // --starts 0: the scene is only built
        }
        let mut t: Vec<f64> = sel.iter().map(|r| r.3).collect();
        t.sort_by(f64::total_cmp);
        let count = |f: &dyn Fn(bool, bool) -> bool| sel.iter().filter(|r| f(r.1, r.2)).count();
        println!(
            "| {n} | {} | {} | {} | {} | {} | {} | {:.1} |",
            sel.len(),
            count(&|c, _| c),
            count(&|c, g| c && g),
            count(&|c, g| c && !g),
            count(&|c, g| !c && g),
            count(&|c, g| !c && !g),
            t[t.len() / 2]
        );
    }
    Ok(())
}
