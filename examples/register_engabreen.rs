//! `register` on Engabreen (docs/registration.md): IMG_8902's fitted camera moved by a few
//! metres and turned by up to ±2° in yaw and ±1° in pitch and roll (N deterministic starts),
//! registered against the Engabreen store without GCPs; the 28 GCPs are held out and give
//! the result's RMSE (the GCP fit's own level is 3.04 px).
//!
//! ```text
//! cargo run --release --example register_engabreen -- [STORE_DIR] [--starts N] [--free LIST]
//!     [--position-scale S]
//! ```
//! `--position-scale` scales the position offsets (0: the fitted position kept).
//! `--textures best`: the terrain samples labelled by the store's photo textures where it
//! has them (`LabelTexture::Best`; docs/registration.md, "Registering against projected
//! photos"). `--label-8937`: IMG_8937's own pixels label the terrain it shows
//! (`LabelledTerrain::set_label_photos`).
//! `--resect-render [--max-slope DEG]` (an experiment, docs/registration.md "Position"): after
//! the terrain search the photo is resected (`register::resect_photo`, position free) against
//! the store rendered from the camera found, the glacier masked out.
//! `--position-search H` (an experiment, docs/registration.md "Position by the score at full
//! resolution"): after the angle search, the position searched by the score itself, steps
//! H and H/2 metres (as `cliffmap register --position-search-m H`).
//! `--focal-scale S`: the rough camera's focal length S times the fitted one.
//! `--gcp-on-dem`: also every GCP moved vertically onto the store's DEM (bilinear at its
//! x, y), the surface the terrain search aligns the photo with: the fitted camera's and each
//! result's RMSE on those points, and the GCP fit (yaw, pitch, roll, fx, fy, k1, position
//! fixed, as ImGRAFT's) to them, so a result can be compared with the best any camera does
//! on the DEM's surface (docs/registration.md, "Where issue #17's goals stand").
//! `--overlay PNG`: for the first start, the photo blended with the store rendered from the
//! rough and from the registered camera, side by side, GCPs marked (docs/registration.md).
//! STORE_DIR is built (default build + reparam) when it holds no store.

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::path::PathBuf;

use cliffmap::pipeline::{ReparamOptions, reparam_store};
use cliffmap::register::{
    CameraParams, LabelTexture, LabelledTerrain, ResectOptions, TerrainOptions, parse_free,
    register_to_terrain, resect_photo,
};
use glam::DVec3;

// indexed loops: each index serves more than one array or lookup
#[allow(clippy::needless_range_loop)]
fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map(|s| s.as_str())
    };
    let tmp = tempfile::tempdir()?;
    let dir = args
        .first()
        .filter(|a| !a.starts_with("--"))
        .map_or_else(|| tmp.path().join("store"), PathBuf::from);
    if !dir.join("manifest.json").exists() {
        bench_util::build_engabreen_store(&dir, "register-engabreen")?;
        reparam_store(
            &dir,
            &ReparamOptions {
                ..ReparamOptions::default()
            },
        )?;
    }
    let starts: usize = flag("--starts").unwrap_or("6").parse()?;
    // scales the position offsets (0: the fitted position, only the angles perturbed)
    let position_scale: f64 = flag("--position-scale").unwrap_or("1").parse()?;
    let resect_render = args.iter().any(|a| a == "--resect-render");
    let mask = image::open(
        bench_util::shared_data("engabreen").join("engabreen_glacier_mask_507x590.png"),
    )?
    .to_luma8();
    let mut opts = TerrainOptions::default();
    if let Some(f) = flag("--free") {
        opts.free = parse_free(f)?;
    }
    // --position-search H: the position searched by the score at full resolution
    if let Some(h) = flag("--position-search") {
        opts.position_search_m = Some(h.parse()?);
    }
    let (photo, fitted, gcps) = bench_util::engabreen_8902()?;
    let store = cliffmap::store::Store::open(&dir)?;
    // --textures best: labels from the store's photo textures where present
    let labels = if flag("--textures") == Some("best") {
        LabelTexture::Best
    } else {
        LabelTexture::Active
    };
    let mut terrain = LabelledTerrain::with_labels(&store, fitted.position, labels)?;
    // --label-8937: IMG_8937's pixels label the terrain it shows (its camera as in
    // fixtures/engabreen_photos.json: IMG_8902's ImGRAFT camera turned by ImGRAFT's tie)
    let label_photos = if args.iter().any(|a| a == "--label-8937") {
        let list = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fixtures")
            .join("engabreen_photos.json");
        cliffmap::photo::read_photo_list(&list)?
            .into_iter()
            .filter(|p| p.name == "IMG_8937.jpg")
            .collect()
    } else {
        Vec::new()
    };
    let refs: Vec<(cliffmap::camera::CameraModel, &image::RgbImage)> =
        label_photos.iter().map(|p| (p.camera, &p.image)).collect();
    terrain.set_label_photos(&refs);
    println!(
        "fitted camera (ImGRAFT, from the GCPs): GCP RMSE {:.2} px\n",
        bench_util::gcp_rmse(&fitted, &gcps)
    );
    // --gcp-on-dem: the GCPs moved onto the DEM's surface, and the best fit to them
    let gcps_dem = if args.iter().any(|a| a == "--gcp-on-dem") {
        let dem = bench_util::engabreen_dem()?;
        let moved: Vec<cliffmap::register::Gcp> = gcps
            .iter()
            .map(|g| {
                let (row, col) = dem.georef.grid(g.world.x, g.world.y);
                let mut m = g.clone();
                m.world.z = dem.bilinear(row, col);
                m
            })
            .collect();
        let mut dz: Vec<f64> = gcps
            .iter()
            .zip(&moved)
            .map(|(g, m)| g.world.z - m.world.z)
            .collect();
        dz.sort_by(f64::total_cmp);
        let mean = dz.iter().sum::<f64>() / dz.len() as f64;
        let sd = (dz.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / dz.len() as f64).sqrt();
        let refit = cliffmap::register::fit_camera(
            &fitted,
            &moved,
            &cliffmap::register::FitOptions {
                free: parse_free("yaw,pitch,roll,fx,fy,k1")?,
                robust: false,
                ..Default::default()
            },
        )?;
        println!(
            "GCP heights minus the DEM's: median {:+.2} m, mean {:+.2} m, sd {:.2} m, range {:+.2} .. {:+.2} m",
            dz[dz.len() / 2],
            mean,
            sd,
            dz[0],
            dz[dz.len() - 1]
        );
        println!(
            "GCPs on the DEM: fitted camera {:.2} px; refitted to them (yaw, pitch, roll, fx, fy, k1) {:.2} px\n",
            bench_util::gcp_rmse(&fitted, &moved),
            refit.rmse_px
        );
        Some(moved)
    } else {
        None
    };
    println!(
        "| start | yaw/pitch/roll change (°) | position change (m) | GCP RMSE start (px) | after (px) | position after, from the fitted (m) | repeat (px) | verdict | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let base = CameraParams::from_camera(&fitted);
    // --focal-scale S: the rough focal length S times the fitted one (an EXIF value off)
    let focal_scale: f64 = flag("--focal-scale").unwrap_or("1").parse()?;
    let mut finals = Vec::new();
    for s in 0..starts {
        // Deterministic spread of starts: signs alternate, sizes cycle.
        let k = s as f64;
        let t = |a: f64| (a * (k + 1.0) * 2.399_963).sin();
        let mut c = base;
        let d = [2.0 * t(1.0), 1.0 * t(1.7), 1.0 * t(2.3)];
        for i in 0..3 {
            c.angles[i] += d[i].to_radians();
        }
        let dp = position_scale * DVec3::new(3.0 * t(3.1), 3.0 * t(3.7), 1.0 * t(4.3));
        c.position += dp;
        c.focal = c.focal.map(|f| f * focal_scale);
        let rough = c.camera();
        let fit = register_to_terrain(&terrain, &photo, &rough, &opts)?;
        let after = bench_util::gcp_rmse(&fit.found, &gcps);
        if let (0, Some(path)) = (s, flag("--overlay")) {
            // photo over the render from the rough and from the registered camera
            let renders = cliffmap::eval::render_views(
                &dir,
                &[rough, fit.found],
                &[cliffmap::render::UvMode::Mixed],
                0.5,
                1,
            )?;
            let panels: Vec<image::RgbImage> = [rough, fit.found]
                .iter()
                .zip(&renders[0])
                .map(|(cam, r)| bench_util::overlay::photo_over_render(&photo, r, cam, &gcps, 4))
                .collect();
            bench_util::overlay::side_by_side(&panels, 8).save(path)?;
            println!("wrote {path}");
        }
        if resect_render {
            // experiment: the photo resected against the store rendered from the camera found
            let t = std::time::Instant::now();
            let c1 = fit.found;
            let render = cliffmap::eval::render_views(
                &dir,
                &[c1],
                &[cliffmap::render::UvMode::Mixed],
                0.5,
                1,
            )?;
            let georef = store.manifest.georef;
            let stable = |p: DVec3| !georef.mask_covers(&mask, p.x, p.y);
            let ropts = ResectOptions {
                surface_error_m: store.manifest.max_error,
                max_slope_deg: flag("--max-slope").unwrap_or("90").parse()?,
                search_deg: 1.0,
                ..ResectOptions::default()
            };
            let r = resect_photo(
                &c1,
                &render[0][0],
                &photo,
                &c1,
                |o, d| terrain.hit(o, d),
                stable,
                &ropts,
            )?;
            let truth = CameraParams::from_camera(&fitted);
            let got = CameraParams::from_camera(&r.found);
            println!(
                "  resected: GCP RMSE {:.2} px, position error {:.2} m, angles {:?}, counts {:?}, RMSE {:.2} px, sigma {:?}, accepted {} {:?}, {:.0} s",
                bench_util::gcp_rmse(&r.found, &gcps),
                r.found.position.distance(fitted.position),
                [0, 1, 2].map(|k| (got.angles[k] - truth.angles[k]).to_degrees()),
                r.counts,
                r.rmse_inliers_px,
                r.sigma_position_m,
                r.accepted,
                r.reason,
                t.elapsed().as_secs_f64()
            );
        }
        println!(
            "| {s} | {:+.2} / {:+.2} / {:+.2} | {:+.1}, {:+.1}, {:+.1} | {:.1} | {:.2} | {:+.2}, {:+.2}, {:+.2} | {:.2} | {} | {:.0} |",
            d[0],
            d[1],
            d[2],
            dp.x,
            dp.y,
            dp.z,
            bench_util::gcp_rmse(&rough, &gcps),
            after,
            fit.found.position.x - fitted.position.x,
            fit.found.position.y - fitted.position.y,
            fit.found.position.z - fitted.position.z,
            fit.repeat_px,
            if fit.converged {
                "converged"
            } else {
                fit.reason.as_deref().unwrap_or("not converged")
            },
            fit.seconds
        );
        if let Some(moved) = &gcps_dem {
            println!(
                "  start {s}: RMSE on the GCPs moved onto the DEM {:.2} px",
                bench_util::gcp_rmse(&fit.found, moved)
            );
        }
        finals.push(after);
    }
    finals.sort_by(f64::total_cmp);
    println!(
        "\nmedian GCP RMSE after register: {:.2} px",
        finals[finals.len() / 2]
    );
    Ok(())
}
