//! Render-space evaluation of photo fidelity (docs/evaluation.md): builds a generated scene's
//! store, projects its ray-traced ground photos, renders novel views with cliffmap (ortho,
//! reparam and photo modes, unlit) and scores them against the exact ground truth, the
//! oracle (ideal projective texturing from the same photos) and the baseline (the ortho
//! draped at the exact hit points).
//!
//! ```text
//! cargo run --release --example render_eval -- OUT [--scene demo|tall] [--seed N]
//!     [--relief PLATEAU,CANYON,ESCARPMENT] [--photo-distance F] [--max-error M]
//!     [--cell-texels T] [--mixed-resolution] [--photo-width W] [--photo-supersample N]
//!     [--view-size WxH] [--supersample N] [--sigma S] [--reuse] [--colour-space srgb]
//!     [--fixed-photo-texels] [--max-photo-texels N] [--texels-per-pixel K]
//!     [--photo-texture-budget-mb MB] [--texels-per-delivered N] [--feather F] [--resolution-ramp LO,HI] [--best]
//!     [--render-supersample N] [--no-relief-mapping] [--project-onto-tin] [--perturb-yaw DEG] [--perturb-position DX,DY,DZ]
//!     [--occlusion-margin PX] [--rough SEED [--rough-position M] [--known-focal]
//!     [--register [--include-unregistered] [--textures active|best] [--position-search-m M]]]
//!     [--second-photos TURN_DEG,DISTANCE_RATIO]
//! ```
//! `--seed`, `--relief` (wall heights, m) and `--photo-distance` (factor on the cameras'
//! distances) change the chosen scene into one no one has tuned on (docs/evaluation.md,
//! "Scenes no one tuned on").
//! `--second-photos` projects and scores second photos of the demo photos' targets taken
//! elsewhere (`DemoScene::second_shots`) instead of the demo photos; with `--register` the
//! demo photos (exact) are `--known` anchors the second photos are resected against.
//! `--rough-position M` also moves each rough camera by up to ±M m horizontally and ±0.4 M
//! vertically.
//! `--rough SEED` projects with every camera turned and zoomed at random inside what a phone's
//! compass and EXIF give (yaw ±3°, pitch and roll ±1.5°, focal length ±3 %; seeded;
//! `--known-focal`: the focal length exact and held by `register`, the angles the same);
//! `--register` first refines those cameras with `cliffmap register` (prints the errors
//! before and after) and projects the registered ones (photos it could not confirm are left
//! out, as `cliffmap project` does, unless `--include-unregistered`; `--position-search-m M`
//! searches the position too, as `cliffmap register --position-search-m M`).
//! ```text
//! ```
//! `--perturb-*` project the photos with every camera's yaw turned by DEG degrees or its
//! position moved by (DX, DY, DZ) metres (docs/registration.md, "Sensitivity"); the oracle
//! and the truth keep the exact cameras.
//! Writes OUT/store, OUT/photos, OUT/views/VIEW_{baseline,oracle,truth,ortho,reparam,photo}.png,
//! OUT/views/VIEW_classes.png (red steep, green flat, blue covered by a photo),
//! OUT/views/VIEW_side_by_side.png (ortho | reparam | photo | truth) and OUT/eval.json, and
//! prints the table of gains. `--reuse` keeps an existing OUT/store and OUT/photos.

#[path = "bench_util/mod.rs"]
mod bench_util;

use bench_util::scene_args::SceneArgs;
use std::path::PathBuf;
use std::time::Instant;

use cliffmap::demo_scene::{DemTracer, DemoPhotoOptions};
use cliffmap::eval::{
    EvalOptions, ReferenceSources, evaluate_views, gains_table, write_view_images,
};
use cliffmap::pipeline::{
    BuildInputs, BuildOptions, ProjectOptions, ReparamOptions, build_store, project_store,
    reparam_store,
};

fn main() -> anyhow::Result<()> {
    let a = SceneArgs::from_env("render_eval OUT [options]")?;
    let (out, flag, has) = (a.out.clone(), |n: &str| a.flag(n), |n: &str| a.has(n));
    let scene = a.scene()?;
    let max_error: f64 = flag("--max-error").unwrap_or("0.5").parse()?;
    let cell_texels: u32 = flag("--cell-texels").unwrap_or("256").parse()?;
    let photo_width: u32 = flag("--photo-width").unwrap_or("1600").parse()?;
    let photo_ss: u32 = flag("--photo-supersample").unwrap_or("2").parse()?;
    let ss: u32 = flag("--supersample").unwrap_or("2").parse()?;
    let sigma: f64 = flag("--sigma").unwrap_or("2").parse()?;
    let (vw, vh) = match flag("--view-size") {
        Some(s) => {
            let (a, b) = s
                .split_once('x')
                .ok_or_else(|| anyhow::anyhow!("--view-size WxH"))?;
            (a.parse()?, b.parse()?)
        }
        None => (1280u32, 720u32),
    };
    let t0 = Instant::now();
    let (dem, ortho) = scene.generate()?;
    let store = out.join("store");
    let photos_dir = out.join("photos");
    // with --second-photos, the photos projected and scored are second photos of the demo
    // photos' targets from elsewhere; the demo photos are then anchors for `register`
    let second = a.pair("--second-photos", "TURN_DEG,DISTANCE_RATIO")?;
    let anchors = photos_dir.join("photos.json");
    let list = match second {
        Some(_) => photos_dir.join("seconds.json"),
        None => anchors.clone(),
    };
    if !(has("--reuse") && store.join("manifest.json").exists() && list.exists()) {
        let inputs = BuildInputs {
            dem: &dem,
            ortho: Some(&ortho),
            dem_source: format!("eval:{:?}", scene.seed),
            ortho_source: Some("eval".into()),
            fingerprint: format!("render_eval:{scene:?}"),
        };
        let opts = BuildOptions {
            max_error,
            cell_texels,
            force: true,
            ..BuildOptions::default()
        };
        build_store(&inputs, &opts, &store)?;
        reparam_store(
            &store,
            &ReparamOptions {
                mixed_resolution: has("--mixed-resolution"),
                ..ReparamOptions::default()
            },
        )?;
        let popts = DemoPhotoOptions {
            width: photo_width,
            height: photo_width / 4 * 3,
            supersample: photo_ss,
        };
        scene.write_demo_photos(&dem, &photos_dir, &popts)?;
        if let Some((turn, ratio)) = second {
            let mut entries = Vec::new();
            for shot in scene.second_shots(turn, ratio) {
                let cam = shot.camera.resized(popts.width, popts.height);
                let img = scene.render_truth_photo(&dem, &cam, photo_ss)?;
                img.save(photos_dir.join(format!("{}.jpg", shot.name)))?;
                std::fs::write(
                    photos_dir.join(format!("{}.json", shot.name)),
                    cliffmap::camera::camera_to_json(&cam).to_string(),
                )?;
                entries.push(serde_json::json!({
                    "image": format!("{}.jpg", shot.name),
                    "camera": format!("{}.json", shot.name),
                }));
            }
            std::fs::write(&list, serde_json::json!({ "photos": entries }).to_string())?;
        }
        eprintln!("store and photos: {:.1} s", t0.elapsed().as_secs_f64());
        // projection with perturbed poses (the truth, the oracle and the scores keep the exact ones)
        let mut project_list =
            perturbed_list(&list, flag("--perturb-yaw"), flag("--perturb-position"))?;
        if let Some(seed) = flag("--rough") {
            let position: f64 = flag("--rough-position").unwrap_or("0").parse()?;
            project_list =
                rough_list(&project_list, seed.parse()?, position, has("--known-focal"))?;
        }
        if has("--register") {
            let mut specs = cliffmap::photo::read_photo_specs(&project_list)?;
            let mut ties = cliffmap::pipeline::TieSettings::default();
            if second.is_some() {
                // the demo photos, exact, are the known anchors the second photos are
                // resected against
                let known = cliffmap::photo::read_photo_specs(&anchors)?;
                ties.known = known.iter().map(|k| k.name.clone()).collect();
                specs.splice(0..0, known);
            }
            let out = project_list.with_file_name("photos_registered.json");
            let t = Instant::now();
            let all = cliffmap::pipeline::register_photos_with(
                &store,
                &specs,
                &out,
                &cliffmap::register::TerrainOptions {
                    free: if has("--known-focal") {
                        cliffmap::register::parse_free("yaw,pitch,roll")?
                    } else {
                        cliffmap::register::TerrainOptions::default().free
                    },
                    labels: match flag("--textures") {
                        None | Some("active") => cliffmap::register::LabelTexture::Active,
                        Some("best") => cliffmap::register::LabelTexture::Best,
                        Some(t) => anyhow::bail!("--textures active|best, not {t:?}"),
                    },
                    position_search_m: flag("--position-search-m").map(str::parse).transpose()?,
                    ..cliffmap::register::TerrainOptions::default()
                },
                &ties,
                &mut |w| eprintln!("warning: {w}"),
            )?;
            let regs: Vec<_> = all
                .into_iter()
                .filter(|r| !ties.known.contains(&r.name))
                .collect();
            if second.is_some() {
                // project the second photos alone, with their registered cameras
                let dir = out.parent().unwrap_or(std::path::Path::new("."));
                let entries: Vec<serde_json::Value> = regs
                    .iter()
                    .map(|r| {
                        serde_json::json!({
                            "image": r.name,
                            "camera": r.camera_file.file_name().map(|n| n.to_string_lossy().into_owned()),
                        })
                    })
                    .collect();
                std::fs::write(
                    dir.join("photos_registered_seconds.json"),
                    serde_json::json!({ "photos": entries }).to_string(),
                )?;
            }
            let exact = cliffmap::photo::read_photo_specs(&list)?;
            for (r, e) in regs.iter().zip(&exact) {
                eprintln!(
                    "register {}: {} ({}), position error before {:.2} m, after {:.2} m",
                    r.name,
                    r.method,
                    r.fit.converged,
                    r.rough.position.distance(e.camera.position),
                    r.fit.camera.position.distance(e.camera.position)
                );
                let (ya, pa, ra) =
                    cliffmap::camera::yaw_pitch_roll_from_rotation(&r.fit.camera.world_to_camera);
                let (yb, pb, rb) =
                    cliffmap::camera::yaw_pitch_roll_from_rotation(&e.camera.world_to_camera);
                let (y0, p0, r0) =
                    cliffmap::camera::yaw_pitch_roll_from_rotation(&r.rough.world_to_camera);
                let d = |a: f64, b: f64| {
                    let d = (a - b).rem_euclid(std::f64::consts::TAU);
                    d.min(std::f64::consts::TAU - d).to_degrees()
                };
                eprintln!(
                    "register {}: converged {}; error before yaw/pitch/roll {:.3}/{:.3}/{:.3} deg, f {:+.2} %; after {:.4}/{:.4}/{:.4} deg, f {:+.3} %",
                    r.name,
                    r.fit.converged,
                    d(y0, yb),
                    d(p0, pb),
                    d(r0, rb),
                    (r.rough.fx / e.camera.fx - 1.0) * 100.0,
                    d(ya, yb),
                    d(pa, pb),
                    d(ra, rb),
                    (r.fit.camera.fx / e.camera.fx - 1.0) * 100.0,
                );
            }
            eprintln!("register: {:.1} s", t.elapsed().as_secs_f64());
            project_list = match second {
                Some(_) => out.with_file_name("photos_registered_seconds.json"),
                None => out,
            };
        }
        // as `cliffmap project` does: photos `register` could not confirm are left out unless
        // `--include-unregistered`
        let photos = cliffmap::photo::read_photo_specs(&project_list)?
            .iter()
            .filter(|s| {
                let keep = s.unregistered.is_none() || has("--include-unregistered");
                if !keep {
                    eprintln!(
                        "left out {}: {}",
                        s.name,
                        s.unregistered.as_deref().unwrap_or("")
                    );
                }
                keep
            })
            .map(cliffmap::photo::PhotoSpec::load)
            .collect::<Result<Vec<_>, _>>()?;
        let t = Instant::now();
        let mut popts = ProjectOptions {
            onto_relief: !has("--project-onto-tin"),
            ..ProjectOptions::default()
        };
        if flag("--colour-space") == Some("srgb") {
            popts.colour_space = cliffmap::colour::ColourSpace::Srgb;
        }
        if has("--fixed-photo-texels") {
            popts.texture.photo_driven = false;
        }
        if let Some(m) = flag("--max-photo-texels") {
            popts.texture.max_texels = m.parse()?;
        }
        if let Some(m) = flag("--photo-texture-budget-mb") {
            popts.texture.budget_bytes = m.parse::<u64>()? << 20;
        }
        if let Some(m) = flag("--texels-per-delivered") {
            popts.texture.texels_per_delivered = m.parse()?;
        }
        if let Some(m) = flag("--texels-per-pixel") {
            popts.texture.texels_per_pixel = m.parse()?;
        }
        if let Some(m) = flag("--feather") {
            popts.confidence.feather = m.parse()?;
        }
        if let Some((lo, hi)) = a.pair("--resolution-ramp", "LO,HI")? {
            popts.confidence.resolution_ramp = [lo, hi];
        }
        if let Some(m) = flag("--occlusion-margin") {
            popts.confidence.occlusion_margin_px = m.parse()?;
        }
        if has("--best") {
            popts.blend = cliffmap::photo::BlendMode::Best;
        }
        let r = project_store(&store, &photos, &popts)?;
        let bytes: u64 = r
            .settings
            .levels
            .iter()
            .map(|l| l.photo_texture_bytes)
            .sum();
        eprintln!(
            "photo textures: {:.1} MB (GPU, with mips)",
            bytes as f64 / 1e6
        );
        eprintln!(
            "project: {} cells in {:.1} s",
            r.cells_written,
            t.elapsed().as_secs_f64()
        );
    }
    let photos = cliffmap::photo::read_photo_list(&list)?;
    let views = scene.novel_views(vw, vh);
    let centre = dem
        .georef
        .world(dem.height as f64 / 2.0, dem.width as f64 / 2.0);
    let mid = 0.5 * (dem.height_range().0 + dem.height_range().1) as f64;
    let tracer = DemTracer::new(&dem, glam::DVec3::new(centre.0, centre.1, mid))?;
    let src = ReferenceSources {
        scene: &scene,
        tracer: &tracer,
        ortho: &ortho,
        photos: &photos,
    };
    let eopts = EvalOptions {
        supersample: ss,
        render_supersample: flag("--render-supersample").unwrap_or("2").parse()?,
        sigma_px: sigma,
        relief: !has("--no-relief-mapping"),
        ..EvalOptions::default()
    };
    let t = Instant::now();
    let (reports, images) = evaluate_views(&store, &src, &views, &eopts)?;
    eprintln!(
        "evaluation of {} views: {:.1} s",
        views.len(),
        t.elapsed().as_secs_f64()
    );
    let vdir = out.join("views");
    std::fs::create_dir_all(&vdir)?;
    for v in &images {
        write_view_images(&vdir, v)?;
    }
    // The views' cameras, so that `cliffmap render STORE --camera VIEW.camera.json` redraws one.
    for v in &views {
        std::fs::write(
            vdir.join(format!("{}.camera.json", v.name)),
            cliffmap::camera::camera_to_json(&v.camera).to_string(),
        )?;
    }
    println!("{}", gains_table(&reports));
    std::fs::write(
        out.join("eval.json"),
        serde_json::to_string_pretty(&reports)?,
    )?;
    eprintln!("total {:.1} s", t0.elapsed().as_secs_f64());
    Ok(())
}

/// A copy of the photo list `list`, written beside it as `photos_{tag}.json`, whose every
/// camera is `change`d and written as `{camera stem}.{tag}.json`.
fn rewrite_cameras(
    list: &std::path::Path,
    tag: &str,
    mut change: impl FnMut(&mut cliffmap::camera::CameraModel),
) -> anyhow::Result<PathBuf> {
    let dir = list.parent().unwrap_or(std::path::Path::new("."));
    let mut doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(list)?)?;
    for entry in doc["photos"]
        .as_array_mut()
        .ok_or_else(|| anyhow::anyhow!("no photos"))?
    {
        let name = entry["camera"]
            .as_str()
            .ok_or_else(|| anyhow::anyhow!("photo without camera"))?
            .to_string();
        let mut cam = cliffmap::camera::camera_from_json_file(&dir.join(&name), (0, 0))?;
        change(&mut cam);
        let out = format!("{}.{tag}.json", name.trim_end_matches(".json"));
        std::fs::write(
            dir.join(&out),
            cliffmap::camera::camera_to_json(&cam).to_string(),
        )?;
        entry["camera"] = serde_json::json!(out);
    }
    let out = dir.join(format!("photos_{tag}.json"));
    std::fs::write(&out, doc.to_string())?;
    Ok(out)
}

/// `list` itself, or a copy next to it whose cameras have their yaw turned by `yaw` degrees
/// and their position moved by `position` ("DX,DY,DZ" metres).
fn perturbed_list(
    list: &std::path::Path,
    yaw: Option<&str>,
    position: Option<&str>,
) -> anyhow::Result<PathBuf> {
    if yaw.is_none() && position.is_none() {
        return Ok(list.to_path_buf());
    }
    let dyaw: f64 = yaw.map(str::parse).transpose()?.unwrap_or(0.0);
    let dpos: Vec<f64> =
        position.map_or(Ok(vec![0.0; 3]), |s| s.split(',').map(str::parse).collect())?;
    anyhow::ensure!(dpos.len() == 3, "--perturb-position DX,DY,DZ");
    rewrite_cameras(list, "perturbed", |cam| {
        let (y, p, r) = cliffmap::camera::yaw_pitch_roll_from_rotation(&cam.world_to_camera);
        cam.world_to_camera =
            cliffmap::camera::rotation_from_yaw_pitch_roll(y + dyaw.to_radians(), p, r);
        cam.position += glam::DVec3::new(dpos[0], dpos[1], dpos[2]);
    })
}

/// Every camera of `list` turned and zoomed at random (seed `seed`): yaw ±3°, pitch and roll
/// ±1.5°, focal length ±3 % (uniform), position kept; written beside it.
fn rough_list(
    list: &std::path::Path,
    seed: u64,
    position_m: f64,
    known_focal: bool,
) -> anyhow::Result<PathBuf> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x5_DEEC_E66D;
    let mut rnd = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    rewrite_cameras(list, "rough", |cam| {
        let (y, p, r) = cliffmap::camera::yaw_pitch_roll_from_rotation(&cam.world_to_camera);
        cam.world_to_camera = cliffmap::camera::rotation_from_yaw_pitch_roll(
            y + (3.0 * rnd()).to_radians(),
            p + (1.5 * rnd()).to_radians(),
            r + (1.5 * rnd()).to_radians(),
        );
        // the same random sequence whether or not the focal length is known
        let k = 1.0 + 0.03 * rnd();
        if !known_focal {
            cam.fx *= k;
            cam.fy *= k;
        }
        if position_m > 0.0 {
            cam.position += glam::DVec3::new(
                position_m * rnd(),
                position_m * rnd(),
                0.4 * position_m * rnd(),
            );
        }
    })
}
