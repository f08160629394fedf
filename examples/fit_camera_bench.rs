//! Camera fit from GCPs on Engabreen (docs/registration.md): `register::fit_camera` on the
//! 28 GCPs of IMG_8902 in two configurations, each from ImGRAFT's camera and from a
//! perturbed start, timed in-process (median of RUNS):
//! - A: yaw, pitch, roll, fx, fy, k1 free, position fixed (ImGRAFT's fit, 3.04 px);
//! - B: yaw, pitch, roll, x, y, z free, intrinsics fixed to ImGRAFT's (what OpenCV's
//!   `solvePnP` and pycolmap's absolute pose solve).
//!
//! Prints one JSON object per line (configuration, start, RMSE px, parameters, median
//! seconds), read by `benches/peers/fit_camera_peers.py`, which runs the peers.
//!
//! ```sh
//! cargo run --release --example fit_camera_bench -- [RUNS]
//! ```

use std::time::Instant;

use cliffmap::camera::camera_from_json_file;
use cliffmap::register::{
    CameraParams, FitOptions, PixelOrigin, fit_camera, parse_free, read_gcps,
};

#[path = "bench_util/mod.rs"]
mod bench_util;

fn main() -> anyhow::Result<()> {
    let runs: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(50)
        .max(1);
    let data = bench_util::shared_data("engabreen");
    let imgraft = camera_from_json_file(&data.join("engabreen_camera_IMG_8902.json"), (0, 0))?;
    let gcps = read_gcps(&data.join("gcp8902.txt"), PixelOrigin::Format)?;
    // the perturbed starts: angles +2° / −1° / +1°, focal −3 %, k1 0; position +5, −5, +3 m
    let mut p = CameraParams::from_camera(&imgraft);
    p.angles[0] += 2f64.to_radians();
    p.angles[1] -= 1f64.to_radians();
    p.angles[2] += 1f64.to_radians();
    let mut a_start = p;
    a_start.focal = [p.focal[0] * 0.97, p.focal[1] * 0.97];
    a_start.k = [0.0, 0.0];
    let mut b_start = p;
    b_start.position += glam::DVec3::new(5.0, -5.0, 3.0);
    for (config, free, perturbed) in [
        ("A", "yaw,pitch,roll,fx,fy,k1", a_start.camera()),
        ("B", "yaw,pitch,roll,x,y,z", b_start.camera()),
    ] {
        for robust in [false, true] {
            let opts = FitOptions {
                free: parse_free(free)?,
                robust,
                ..FitOptions::default()
            };
            for (start_name, start) in [("imgraft", imgraft), ("perturbed", perturbed)] {
                let mut times = Vec::new();
                let mut fit = None;
                for _ in 0..runs {
                    let t = Instant::now();
                    let f = fit_camera(&start, &gcps, &opts)?;
                    times.push(t.elapsed().as_secs_f64());
                    fit = Some(f);
                }
                let Some(fit) = fit else { continue };
                let q = CameraParams::from_camera(&fit.camera);
                let line = serde_json::json!({
                    "config": config,
                    "free": free,
                    "method": if robust { "cliffmap fit_camera (Huber IRLS)" } else { "cliffmap fit_camera (least squares)" },
                    "start": start_name,
                    "rmse_px": fit.rmse_px,
                    "yaw_deg": q.angles[0].to_degrees().rem_euclid(360.0),
                    "pitch_deg": q.angles[1].to_degrees(),
                    "roll_deg": q.angles[2].to_degrees(),
                    "position": [q.position.x, q.position.y, q.position.z],
                    "fx": q.focal[0], "fy": q.focal[1], "k1": q.k[0],
                    "seconds_median": bench_util::median(times),
                    "runs": runs,
                });
                println!("{line}");
            }
        }
    }
    Ok(())
}
