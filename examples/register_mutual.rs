//! Two rough photos of one target registered against the terrain, then each again against
//! the other's pixels (`LabelledTerrain::set_label_photos` with the other's camera found):
//! does a second, mutual pass make them agree, and does it move them towards the truth?
//! (docs/registration.md, "Registering against projected photos": a trial.)
//!
//! Per demo photo (A, exact camera known to the benchmark only) and its second shot (B,
//! `DemoScene::second_shots`), both cameras turned and zoomed inside the issue's ranges
//! (position exact). Pass 1: each against the active textures. Pass 2: each from its pass-1
//! camera (the given one if pass 1 refused it) against the other's pixels if the other is
//! placed, kept if it converges (a refused camera printed as it was given). Prints per start
//! the pixel errors of A and B against
//! the truth (median over a 40-px grid of the terrain each shows) and the ghost: on terrain
//! both see, how far apart (A's pixels) the two photos put the same texel's colour.
//!
//! ```text
//! cargo run --release --example register_mutual -- OUT [--scene demo|tall] [--starts N]
//!     [--max-error M] [--photo-width W] [--reuse] [--sequential] [--third T,R [--rounds N]]
//! ```
//! `--sequential`: in pass 2, B is registered against A's pass-2 camera (else both
//! against the other's pass-1 camera).
//!
//! `--third T,R`: a third rough photo C of each target, from the second place found at a
//! turn of `T`° and `R` times the distance (`DemoScene::second_shots(T, R)`; targets
//! without such a place, or whose place is B's, are skipped), its rough start drawn from
//! its own generator so that A's and B's starts are those of the run without it. Pass 1
//! registers C too; then, besides the two-photo pass 2 above (sequential), a three-photo
//! pass 2 in list order as `register --textures best` runs it: A against B's and C's
//! pass-1 cameras, B against A's new and C's pass-1 ones, C against A's and B's new ones
//! (only placed photos label); `--rounds N` repeats that pass N times (default 1), each
//! from the cameras of the one before. Printed per start: pass 1 A, B, C; pass 2 with two photos
//! A, B; pass 2 with three A, B, C; and the ghosts A–B of each.

#[path = "bench_util/mod.rs"]
mod bench_util;

use bench_util::scene_args::{
    PairScene, Rng, SceneArgs, photo_height, pixel_errors, reparam_quietly, rough_start,
    shown_points,
};

use cliffmap::camera::CameraModel;
use cliffmap::register::{
    CameraParams, LabelledTerrain, TerrainFit, TerrainOptions, register_to_terrain,
};

fn main() -> anyhow::Result<()> {
    let a = SceneArgs::from_env("register_mutual OUT [options]")?;
    let store_dir = a.out.join("store");
    let ps = PairScene::from_args(&a, "register_mutual")?;
    if ps.built {
        reparam_quietly(&store_dir)?;
    }
    let store = cliffmap::store::Store::open(&store_dir)?;
    let (scene, dem, width) = (&ps.scene, &ps.dem, ps.width);
    let mut rng = Rng(0x307A_2026);
    let opts = TerrainOptions::default();
    let third = a.pair("--third", "TURN_DEG,DISTANCE_RATIO")?;
    if let Some((turn, ratio)) = third {
        let rounds: usize = a.flag("--rounds").unwrap_or("1").parse()?;
        return run_triples(&ps, &store, turn, ratio, rounds);
    }
    println!(
        "| target | start | pass 1: A px, B px, ghost px | pass 2 (against each other): A px, B px, ghost px |"
    );
    println!("|---|---|---|---|");
    let mut rows = Vec::new();
    let mut registered = [0usize; 2];
    for anchor in &ps.anchors {
        let Some(second) = ps.second_of(anchor) else {
            continue;
        };
        let (ta, tb) = (
            anchor.camera,
            second.camera.resized(width, photo_height(width)),
        );
        let (img_a, img_b) = (&anchor.image, scene.render_truth_photo(dem, &tb, 2)?);
        let terrain = LabelledTerrain::new(&store, ta.position)?;
        let hit = |o, d| terrain.hit(o, d);
        let (shown_a, shown_b) = (shown_points(&ta, hit), shown_points(&tb, hit));
        let ghost =
            |fa: &CameraModel, fb: &CameraModel| ghost_px(&terrain, &shown_a, (&ta, &tb), (fa, fb));
        for s in 0..ps.starts {
            let ra = rough_start(CameraParams::from_camera(&ta), &mut rng, 0.0, true).camera();
            let rb = rough_start(CameraParams::from_camera(&tb), &mut rng, 0.0, true).camera();
            let fa1 = register_to_terrain(&terrain, img_a, &ra, &opts)?;
            let fb1 = register_to_terrain(&terrain, &img_b, &rb, &opts)?;
            // pass 2 as `register --textures best` runs it (`again`)
            let fa2 = again(&store, &opts, img_a, &fa1, &[(&fb1, &img_b)])?;
            // --sequential: B against A's pass-2 camera (Gauss-Seidel, what `register`
            // does), else against its pass-1 one
            let fa_for_b = if a.has("--sequential") { &fa2 } else { &fa1 };
            let fb2 = again(&store, &opts, &img_b, &fb1, &[(fa_for_b, img_a)])?;
            registered[0] += usize::from(fa1.converged) + usize::from(fb1.converged);
            registered[1] += usize::from(fa2.converged) + usize::from(fb2.converged);
            let (a1, b1, a2, b2) = (fa1.camera, fb1.camera, fa2.camera, fb2.camera);
            let e = |c: &CameraModel, sh| pixel_errors(c, sh).0;
            let r = [
                e(&a1, &shown_a),
                e(&b1, &shown_b),
                ghost(&a1, &b1),
                e(&a2, &shown_a),
                e(&b2, &shown_b),
                ghost(&a2, &b2),
            ];
            println!(
                "| {} | {s} | {:.2}, {:.2}, {:.2} | {:.2}, {:.2}, {:.2} |",
                anchor.name, r[0], r[1], r[2], r[3], r[4], r[5]
            );
            rows.push(r);
        }
    }
    let med = |k: usize| median(rows.iter().map(|r| r[k]).collect());
    println!(
        "\nmedians: pass 1 A {:.2}, B {:.2}, ghost {:.2} px; pass 2 A {:.2}, B {:.2}, ghost {:.2} px; registered (converged) pass 1 {} of {n}, pass 2 {} of {n}",
        med(0),
        med(1),
        med(2),
        med(3),
        med(4),
        med(5),
        registered[0],
        registered[1],
        n = 2 * rows.len()
    );
    Ok(())
}

/// A camera found again against the pixels of the placed photos among `others` (found
/// cameras and images), from `first`'s camera, as `register --textures best`'s second
/// pass runs it: `first` kept when no other is placed or the search does not converge.
fn again(
    store: &cliffmap::store::Store,
    opts: &TerrainOptions,
    img: &image::RgbImage,
    first: &TerrainFit,
    others: &[(&TerrainFit, &image::RgbImage)],
) -> anyhow::Result<TerrainFit> {
    let labels: Vec<(CameraModel, &image::RgbImage)> = others
        .iter()
        .filter(|(f, _)| f.converged)
        .map(|(f, i)| (f.camera, *i))
        .collect();
    if labels.is_empty() {
        return Ok(first.clone());
    }
    let mut t = LabelledTerrain::new(store, first.camera.position)?;
    t.set_label_photos(&labels);
    let f = register_to_terrain(&t, img, &first.camera, opts)?;
    Ok(if f.converged { f } else { first.clone() })
}

/// `--third`: three rough photos per target (module docs).
fn run_triples(
    ps: &PairScene,
    store: &cliffmap::store::Store,
    turn: f64,
    ratio: f64,
    rounds: usize,
) -> anyhow::Result<()> {
    let (scene, dem, width) = (&ps.scene, &ps.dem, ps.width);
    let thirds = scene.second_shots(turn, ratio);
    let mut rng = Rng(0x307A_2026);
    let mut rng_c = Rng(0xC3_2026);
    let opts = TerrainOptions::default();
    println!(
        "| target | start | pass 1: A, B, C px | pass 2, two photos: A, B px, ghost A–B | pass 2, three photos: A, B, C px, ghost A–B |"
    );
    println!("|---|---|---|---|---|");
    let mut rows: Vec<[f64; 10]> = Vec::new();
    let mut registered = [0usize; 3];
    for anchor in &ps.anchors {
        let (Some(second), Some(third)) = (
            ps.second_of(anchor),
            thirds
                .iter()
                .find(|s| s.name == format!("{}_second", anchor.name.trim_end_matches(".jpg"))),
        ) else {
            println!(
                "| {} | – | no second or third place with a clear view; skipped | | |",
                anchor.name
            );
            continue;
        };
        if third.camera.position.distance(second.camera.position) < 1.0 {
            println!(
                "| {} | – | the third place is the second's; skipped | | |",
                anchor.name
            );
            continue;
        }
        let ta = anchor.camera;
        let tb = second.camera.resized(width, photo_height(width));
        let tc = third.camera.resized(width, photo_height(width));
        let img_a = &anchor.image;
        let img_b = scene.render_truth_photo(dem, &tb, 2)?;
        let img_c = scene.render_truth_photo(dem, &tc, 2)?;
        let terrain = LabelledTerrain::new(store, ta.position)?;
        let hit = |o, d| terrain.hit(o, d);
        let (sa, sb, sc) = (
            shown_points(&ta, hit),
            shown_points(&tb, hit),
            shown_points(&tc, hit),
        );
        let ghost =
            |fa: &CameraModel, fb: &CameraModel| ghost_px(&terrain, &sa, (&ta, &tb), (fa, fb));
        for s in 0..ps.starts {
            let ra = rough_start(CameraParams::from_camera(&ta), &mut rng, 0.0, true).camera();
            let rb = rough_start(CameraParams::from_camera(&tb), &mut rng, 0.0, true).camera();
            let rc = rough_start(CameraParams::from_camera(&tc), &mut rng_c, 0.0, true).camera();
            let fa1 = register_to_terrain(&terrain, img_a, &ra, &opts)?;
            let fb1 = register_to_terrain(&terrain, &img_b, &rb, &opts)?;
            let fc1 = register_to_terrain(&terrain, &img_c, &rc, &opts)?;
            // two photos, sequential (the run without --third)
            let fa2 = again(store, &opts, img_a, &fa1, &[(&fb1, &img_b)])?;
            let fb2 = again(store, &opts, &img_b, &fb1, &[(&fa2, img_a)])?;
            // three photos, in list order
            let (mut fa3, mut fb3, mut fc3) = (fa1.clone(), fb1.clone(), fc1.clone());
            for _ in 0..rounds {
                fa3 = again(store, &opts, img_a, &fa3, &[(&fb3, &img_b), (&fc3, &img_c)])?;
                fb3 = again(store, &opts, &img_b, &fb3, &[(&fa3, img_a), (&fc3, &img_c)])?;
                fc3 = again(store, &opts, &img_c, &fc3, &[(&fa3, img_a), (&fb3, &img_b)])?;
            }
            let conv = |fs: &[&TerrainFit]| fs.iter().filter(|f| f.converged).count();
            registered[0] += conv(&[&fa1, &fb1, &fc1]);
            registered[1] += conv(&[&fa2, &fb2]);
            registered[2] += conv(&[&fa3, &fb3, &fc3]);
            let e = |c: &CameraModel, sh| pixel_errors(c, sh).0;
            let r = [
                e(&fa1.camera, &sa),
                e(&fb1.camera, &sb),
                e(&fc1.camera, &sc),
                e(&fa2.camera, &sa),
                e(&fb2.camera, &sb),
                ghost(&fa2.camera, &fb2.camera),
                e(&fa3.camera, &sa),
                e(&fb3.camera, &sb),
                e(&fc3.camera, &sc),
                ghost(&fa3.camera, &fb3.camera),
            ];
            println!(
                "| {} | {s} | {:.2}, {:.2}, {:.2} | {:.2}, {:.2}, {:.2} | {:.2}, {:.2}, {:.2}, {:.2} |",
                anchor.name, r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9]
            );
            rows.push(r);
        }
    }
    let med = |k: usize| median(rows.iter().map(|r| r[k]).collect());
    let m: Vec<String> = (0..10).map(|k| format!("{:.2}", med(k))).collect();
    println!(
        "\nmedians: pass 1 A, B, C {}, {}, {}; two photos A, B {}, {} ghost {}; three photos A, B, C {}, {}, {} ghost {} px; registered pass 1 {} of {}, two photos {} of {}, three photos {} of {}",
        m[0],
        m[1],
        m[2],
        m[3],
        m[4],
        m[5],
        m[6],
        m[7],
        m[8],
        m[9],
        registered[0],
        3 * rows.len(),
        registered[1],
        2 * rows.len(),
        registered[2],
        3 * rows.len()
    );
    Ok(())
}

/// The median of `v` (the upper one of an even count; NaN when empty).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The ghost between photos A and B (true cameras `ta`, `tb`; found ones `fa`, `fb`): on
/// the points A shows (`shown_a`) that B also sees, the median distance in A's true pixels
/// between what A and B paint there, where a photo paints a point with the true point its
/// found camera's pixel shows.
fn ghost_px(
    terrain: &LabelledTerrain,
    shown_a: &[(glam::DVec3, [f64; 2])],
    (ta, tb): (&CameraModel, &CameraModel),
    (fa, fb): (&CameraModel, &CameraModel),
) -> f64 {
    let painted = |fx: &CameraModel, tx: &CameraModel, p| {
        fx.project(p)
            .and_then(|q| tx.pixel_ray(q[0], q[1]))
            .and_then(|d| terrain.hit(tx.position, d))
    };
    let inside_b = |q: &[f64; 2]| {
        q[0] >= 0.0 && q[1] >= 0.0 && q[0] < tb.width as f64 && q[1] < tb.height as f64
    };
    median(
        shown_a
            .iter()
            .filter_map(|(p, _)| {
                let (pa, pb) = (painted(fa, ta, *p)?, painted(fb, tb, *p)?);
                let (qa, qb) = (ta.project(pa)?, ta.project(pb)?);
                tb.project(*p)
                    .filter(inside_b)
                    .map(|_| (qa[0] - qb[0]).hypot(qa[1] - qb[1]))
            })
            .collect(),
    )
}
