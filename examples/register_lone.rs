//! A lone photo's position from the store alone (no placed photo nearby), on a generated
//! scene with exact cameras: the terrain search turns the rough camera (position kept), the
//! store is rendered from that camera (headless, unlit), and the photo is resected against
//! the render as against a placed photo (`register::resect_photo`), matching only points on
//! surfaces no steeper than `--max-slope` (the ortho smears walls). Prints per start the
//! errors left (docs/registration.md, "Position").
//!
//! ```text
//! cargo run --release --example register_lone -- OUT [--scene demo|tall] [--starts N]
//!     [--position-error M] [--max-slope DEG] [--mode ortho|mixed] [--max-error M]
//!     [--photo-width W] [--reuse]
//! ```

#[path = "bench_util/mod.rs"]
mod bench_util;

use bench_util::scene_args::{
    Rng, SceneArgs, angle_diff, build_scene_store, keep_above_ground, rough_start,
    write_scene_photos,
};
use std::time::Instant;

use cliffmap::camera::CameraModel;
use cliffmap::register::{
    CameraParams, LabelledTerrain, ResectOptions, TerrainOptions, register_to_terrain, resect_photo,
};
use cliffmap::render::UvMode;

fn main() -> anyhow::Result<()> {
    let a = SceneArgs::from_env("register_lone OUT [options]")?;
    let (out, flag, has) = (a.out.clone(), |n: &str| a.flag(n), |n: &str| a.has(n));
    let scene = a.scene()?;
    let starts: usize = flag("--starts").unwrap_or("3").parse()?;
    let width: u32 = flag("--photo-width").unwrap_or("1600").parse()?;
    let pos_err: f64 = flag("--position-error").unwrap_or("5").parse()?;
    let max_error: f64 = flag("--max-error").unwrap_or("0.2").parse()?;
    let mode = match flag("--mode").unwrap_or("ortho") {
        "mixed" => UvMode::Mixed,
        _ => UvMode::Ortho,
    };
    let (dem, ortho) = scene.generate()?;
    let store_dir = out.join("store");
    let list = out.join("photos").join("photos.json");
    if !(has("--reuse") && store_dir.join("manifest.json").exists() && list.exists()) {
        build_scene_store(&scene, &dem, &ortho, max_error, &store_dir, "register_lone")?;
        write_scene_photos(&scene, &dem, &out.join("photos"), width)?;
    }
    let store = cliffmap::store::Store::open(&store_dir)?;
    let photos = cliffmap::photo::read_photo_list(&list)?;
    let mut rng = Rng(0x5EED_2026);
    let opts = ResectOptions {
        surface_error_m: max_error,
        max_slope_deg: flag("--max-slope").unwrap_or("35").parse()?,
        search_deg: flag("--search-deg").unwrap_or("3").parse()?,
        ..ResectOptions::default()
    };
    println!(
        "| photo | start | start: angle ° / position m | terrain search: angle ° / position m | resected: angles ° (yaw, pitch, roll) / position m / focal % | points / coarse / fine / inliers | RMSE px | σ position m | accepted | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for p in &photos {
        let truth = p.camera;
        let tp = CameraParams::from_camera(&truth);
        let terrain = LabelledTerrain::new(&store, truth.position)?;
        let errs = |cam: &CameraModel| {
            let q = CameraParams::from_camera(cam);
            let each = [0, 1, 2].map(|k| angle_diff(q.angles[k], tp.angles[k]).to_degrees());
            (
                each,
                each.iter().fold(0.0f64, |m, e| m.max(e.abs())),
                cam.position.distance(truth.position),
                100.0 * (cam.fx / truth.fx - 1.0),
            )
        };
        for s in 0..starts {
            let mut c = rough_start(tp, &mut rng, pos_err, true);
            keep_above_ground(&mut c, &terrain);
            let rough: CameraModel = c.camera();
            let t = Instant::now();
            let turned =
                register_to_terrain(&terrain, &p.image, &rough, &TerrainOptions::default())?;
            let c1 = turned.found;
            let render = cliffmap::eval::render_views(&store_dir, &[c1], &[mode], 0.5, 1)?;
            let anchor = &render[0][0];
            if s == 0 {
                anchor.save(out.join(format!("anchor_{}.png", p.name.trim_end_matches(".jpg"))))?;
            }
            let fit = resect_photo(
                &c1,
                anchor,
                &p.image,
                &c1,
                |o, d| terrain.hit(o, d),
                |_| true,
                &opts,
            )?;
            let secs = t.elapsed().as_secs_f64();
            let (_, a0, p0, _) = errs(&rough);
            let (_, a1, p1, _) = errs(&c1);
            let (each, _, p2, f2) = errs(&fit.found);
            println!(
                "| {} | {s} | {a0:.2} / {p0:.2} | {a1:.3} / {p1:.2} | {:.3}, {:.3}, {:.3} / {p2:.2} / {f2:+.2} | {} | {secs:.1} |",
                p.name,
                each[0],
                each[1],
                each[2],
                bench_util::resect_cells(&fit),
            );
        }
    }
    Ok(())
}
