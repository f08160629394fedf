//! How well the terrain search's score locates a photo's position (docs/registration.md,
//! "Position"): IMG_8902's fitted camera moved along x (east), y (north) and z, the angles
//! re-fitted by `register_to_terrain` at each position (search ±0.6°, finest scale 1/F);
//! prints the final score and the held-out GCPs' RMSE per position. A score that peaks
//! where the GCP RMSE is lowest would let a search over the position find it.
//!
//! ```text
//! cargo run --release --example register_position_profile -- STORE [F]
//! ```
//! STORE: an Engabreen store (e.g. the one `register_engabreen` builds); F default 4.
#[path = "bench_util/mod.rs"]
mod bench_util;
use cliffmap::register::{CameraParams, LabelledTerrain, TerrainOptions, register_to_terrain};
use glam::DVec3;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let store_dir = a
        .first()
        .ok_or_else(|| anyhow::anyhow!("usage: register_position_profile STORE [F]"))?;
    let factor: u32 = a.get(1).map_or(Ok(4), |s| s.parse())?;
    let (photo, fitted, gcps) = bench_util::engabreen_8902()?;
    let store = cliffmap::store::Store::open(std::path::Path::new(store_dir))?;
    let terrain = LabelledTerrain::new(&store, fitted.position)?;
    let opts = TerrainOptions {
        search_deg: [0.6, 0.6, 0.6],
        finest_factor: factor,
        ..TerrainOptions::default()
    };
    for (name, axis, ds) in [
        ("x", DVec3::X, vec![-6.0, -3.0, -1.5, 0.0, 1.5, 3.0, 6.0]),
        ("y", DVec3::Y, vec![-6.0, -3.0, -1.5, 0.0, 1.5, 3.0, 6.0]),
        ("z", DVec3::Z, vec![-3.0, -1.5, 0.0, 1.5, 3.0]),
    ] {
        for d in ds {
            let mut c = CameraParams::from_camera(&fitted);
            c.position += axis * d;
            let fit = register_to_terrain(&terrain, &photo, &c.camera(), &opts)?;
            println!(
                "{name} {d:+.1} m: score {:.5} (start {:.5}), GCP RMSE {:.2} px, repeat {:.2}, {:.0} s",
                fit.score_final,
                fit.score_start,
                bench_util::gcp_rmse(&fit.found, &gcps),
                fit.repeat_px,
                fit.seconds
            );
        }
    }
    Ok(())
}
