//! Registering a photo against the store's photo textures instead of its ortho
//! (`LabelledTerrain::with_labels`, `LabelTexture::Best`; docs/registration.md, "Registering
//! against projected photos"), on a generated scene with exact cameras.
//!
//! The demo photos (the anchors, exact cameras) are projected into the scene's store; per
//! anchor a second photo of the same target is taken elsewhere (`DemoScene::second_shots`)
//! and rendered from the ground truth. Its camera is turned and zoomed `--starts` times
//! inside the issue's ranges (yaw ±3°, pitch and roll ±1.5°, focal ±3 %; position exact)
//! and registered against the terrain three times from each start: labels from the active
//! (ortho / reparameterized) textures, from the photo textures, and from the anchor photo's
//! own pixels (`LabelledTerrain::set_label_photos`). Prints per start the
//! angle errors and the pixel error of the found camera on the terrain the photo shows.
//!
//! ```text
//! cargo run --release --example register_labels -- OUT [--scene demo|tall] [--starts N]
//!     [--turn-deg D] [--distance-ratio R] [--max-error M] [--photo-width W] [--reuse]
//! ```

#[path = "bench_util/mod.rs"]
mod bench_util;

use bench_util::scene_args::{
    PairScene, Rng, SceneArgs, angle_diff, photo_height, pixel_errors, reparam_quietly,
    rough_start, shown_points,
};

use cliffmap::camera::CameraModel;
use cliffmap::pipeline::{ProjectOptions, project_store};
use cliffmap::register::{
    CameraParams, LabelTexture, LabelledTerrain, TerrainOptions, register_to_terrain,
};

fn main() -> anyhow::Result<()> {
    let a = SceneArgs::from_env("register_labels OUT [options]")?;
    let store_dir = a.out.join("store");
    let ps = PairScene::from_args(&a, "register_labels")?;
    if ps.built {
        reparam_quietly(&store_dir)?;
        project_store(
            &store_dir,
            &ps.anchors,
            &ProjectOptions {
                ..ProjectOptions::default()
            },
        )?;
    }
    let store = cliffmap::store::Store::open(&store_dir)?;
    let (scene, dem, width) = (&ps.scene, &ps.dem, ps.width);
    let mut rng = Rng(0x1ABE_2026);
    let opts = TerrainOptions::default();
    println!(
        "| second photo | start | start: yaw / pitch / roll ° | labels | after: yaw / pitch / roll ° | focal % | px median / 90 % | verdict | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut summary: Vec<(String, &str, f64, bool)> = Vec::new();
    for anchor in &ps.anchors {
        let Some(second) = ps.second_of(anchor) else {
            continue;
        };
        let truth = second.camera.resized(width, photo_height(width));
        let img = scene.render_truth_photo(dem, &truth, 2)?;
        let tp = CameraParams::from_camera(&truth);
        let active = LabelledTerrain::new(&store, truth.position)?;
        let best = LabelledTerrain::with_labels(&store, truth.position, LabelTexture::Best)?;
        // the anchor's own pixels as labels (what `register --textures best --known ANCHOR`
        // does within one run, no projection needed)
        let mut photos = LabelledTerrain::new(&store, truth.position)?;
        photos.set_label_photos(&[(anchor.camera, &anchor.image)]);
        // terrain points the photo shows, to score a camera by where it puts them
        let shown = shown_points(&truth, |o, d| active.hit(o, d));
        let px_err = |cam: &CameraModel| pixel_errors(cam, &shown);
        let angles = |cam: &CameraModel| {
            let p = CameraParams::from_camera(cam);
            [0, 1, 2].map(|i| angle_diff(p.angles[i], tp.angles[i]).to_degrees())
        };
        for s in 0..ps.starts {
            let rough = rough_start(tp, &mut rng, 0.0, true).camera();
            let a0 = angles(&rough);
            for (label, terrain) in [
                ("active", &active),
                ("photo textures", &best),
                ("anchor photo", &photos),
            ] {
                let fit = register_to_terrain(terrain, &img, &rough, &opts)?;
                let a1 = angles(&fit.found);
                let (m, p90) = px_err(&fit.found);
                println!(
                    "| {} | {s} | {:.2} / {:.2} / {:.2} | {} | {:.3} / {:.3} / {:.3} | {:+.2} | {:.2} / {:.2} | {} | {:.1} |",
                    second.name,
                    a0[0],
                    a0[1],
                    a0[2],
                    label,
                    a1[0],
                    a1[1],
                    a1[2],
                    100.0 * (fit.found.fx / truth.fx - 1.0),
                    m,
                    p90,
                    if fit.converged {
                        "registered"
                    } else {
                        "refused"
                    },
                    fit.seconds
                );
                summary.push((second.name.clone(), label, m, fit.converged));
            }
        }
    }
    println!("\n| labels | registered | median of the median px errors (registered) | largest |");
    println!("|---|---|---|---|");
    for label in ["active", "photo textures", "anchor photo"] {
        let mut e: Vec<f64> = summary
            .iter()
            .filter(|r| r.1 == label && r.3)
            .map(|r| r.2)
            .collect();
        let n = summary.iter().filter(|r| r.1 == label).count();
        e.sort_by(f64::total_cmp);
        println!(
            "| {label} | {} / {n} | {:.2} | {:.2} |",
            e.len(),
            e.get(e.len() / 2).copied().unwrap_or(f64::NAN),
            e.last().copied().unwrap_or(f64::NAN)
        );
    }
    Ok(())
}
