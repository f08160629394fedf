//! `register` on Engabreen (docs/registration.md): IMG_8902's fitted camera moved by a few
//! metres and turned by up to ±2° in yaw and ±1° in pitch and roll (N deterministic starts),
//! registered against the Engabreen store without GCPs; the 28 GCPs are held out and give
//! the result's RMSE (the GCP fit's own level is 3.04 px).
//!
//! ```text
//! cargo run --release --example register_engabreen -- [STORE_DIR] [--starts N] [--free LIST]
//! ```
//! STORE_DIR is built (default build + reparam) when it holds no store.

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::path::PathBuf;

use cliffmap::camera::{CameraModel, camera_from_json_file};
use cliffmap::pipeline::{ReparamOptions, reparam_store};
use cliffmap::register::{
    CameraParams, Gcp, PixelOrigin, TerrainOptions, TerrainScene, parse_free, read_gcps,
    register_to_terrain,
};
use glam::DVec3;

fn gcp_rmse(cam: &CameraModel, gcps: &[Gcp]) -> f64 {
    let mut s = 0.0;
    let mut n = 0;
    for g in gcps {
        if let Some(p) = cam.project(g.world) {
            s += (p[0] - g.pixel[0]).powi(2) + (p[1] - g.pixel[1]).powi(2);
            n += 1;
        }
    }
    (s / n.max(1) as f64).sqrt()
}

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
                quiet: true,
                ..ReparamOptions::default()
            },
        )?;
    }
    let starts: usize = flag("--starts").unwrap_or("6").parse()?;
    let mut opts = TerrainOptions::default();
    if let Some(f) = flag("--free") {
        opts.free = parse_free(f)?;
    }
    let data = bench_util::shared_data("engabreen");
    let photo = cliffmap::fsutil::decode_rgb8(&data.join("IMG_8902.jpg"))?;
    let fitted = camera_from_json_file(
        &data.join("engabreen_camera_IMG_8902.json"),
        photo.dimensions(),
    )?;
    let gcps = read_gcps(&data.join("gcp8902.txt"), PixelOrigin::Format)?;
    let store = cliffmap::store::Store::open(&dir)?;
    let terrain = TerrainScene::new(&store, fitted.position)?;
    println!(
        "fitted camera (ImGRAFT, from the GCPs): GCP RMSE {:.2} px\n",
        gcp_rmse(&fitted, &gcps)
    );
    println!(
        "| start | yaw/pitch/roll change (°) | position change (m) | GCP RMSE start (px) | after (px) | repeat (px) | verdict | s |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let base = CameraParams::from_camera(&fitted);
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
        let dp = DVec3::new(3.0 * t(3.1), 3.0 * t(3.7), 1.0 * t(4.3));
        c.position += dp;
        let rough = c.camera();
        let fit = register_to_terrain(&terrain, &photo, &rough, &opts)?;
        let after = gcp_rmse(&fit.found, &gcps);
        println!(
            "| {s} | {:+.2} / {:+.2} / {:+.2} | {:+.1}, {:+.1}, {:+.1} | {:.1} | {:.2} | {:.2} | {} | {:.0} |",
            d[0],
            d[1],
            d[2],
            dp.x,
            dp.y,
            dp.z,
            gcp_rmse(&rough, &gcps),
            after,
            fit.repeat_px,
            if fit.converged {
                "converged"
            } else {
                fit.reason.as_deref().unwrap_or("not converged")
            },
            fit.seconds
        );
        finals.push(after);
    }
    finals.sort_by(f64::total_cmp);
    println!(
        "\nmedian GCP RMSE after register: {:.2} px",
        finals[finals.len() / 2]
    );
    Ok(())
}
