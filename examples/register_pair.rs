//! Registering Engabreen's IMG_8937 to IMG_8902 (same camera position, the camera turned a
//! little; docs/registration.md): patch matches, then the rotation-only fit. Prints the
//! matches, the match residual (RMSE of all matches and of the inliers) and the rotation
//! against ImGRAFT's feature-tracking result (viewdir change +0.12633°, +0.017584°,
//! +0.015242°, 0.41 px), with the time of each step. As ImGRAFT, it matches stable ground
//! only: matches whose ray from IMG_8902's camera hits the glacier (the shared glacier mask
//! on the DEM grid) or no terrain (sky, clouds) are left out; the table also gives the fit
//! with every match.
//!
//! ```sh
//! cargo run --release --example register_pair
//! ```

use std::time::Instant;

use cliffmap::camera::{camera_from_json_file, yaw_pitch_roll_from_rotation};
use cliffmap::register::{
    GcpStatus, MatchOptions, fit_rotation, match_photos, rotation_consensus, stable_matches,
};

#[path = "bench_util/mod.rs"]
mod bench_util;

fn main() -> anyhow::Result<()> {
    let data = bench_util::shared_data("engabreen");
    let t = Instant::now();
    let a = image::open(data.join("IMG_8902.jpg"))?.to_rgb8();
    let b = image::open(data.join("IMG_8937.jpg"))?.to_rgb8();
    let decode = t.elapsed().as_secs_f64();
    let cam = camera_from_json_file(&data.join("engabreen_camera_IMG_8902.json"), (0, 0))?;
    let t = Instant::now();
    let matches = match_photos(&a, &b, &MatchOptions::default())?;
    let t_match = t.elapsed().as_secs_f64();
    // stable ground: the ray from A hits the DEM off the glacier
    let dem = bench_util::engabreen_dem()?;
    let mask = image::open(data.join("engabreen_glacier_mask_507x590.png"))?.to_luma8();
    let tracer = cliffmap::demo_scene::DemTracer::new(&dem, cam.position)?;
    let off_glacier = |p: glam::DVec3| {
        let (r, c) = dem.georef.grid(p.x, p.y);
        let (r, c) = (r.round(), c.round());
        r >= 0.0
            && c >= 0.0
            && (r as u32) < mask.height()
            && (c as u32) < mask.width()
            && mask.get_pixel(c as u32, r as u32).0[0] < 128
    };
    let stable = stable_matches(
        &cam,
        &matches,
        |o, d| tracer.nearest(o, d, f64::INFINITY).map(|h| h.point),
        off_glacier,
    );
    let all = fit_rotation(&cam, &matches)?;
    let t = Instant::now();
    let fit = fit_rotation(&cam, &stable)?;
    let t_fit = t.elapsed().as_secs_f64();
    let (ya, pa, ra) = yaw_pitch_roll_from_rotation(&cam.world_to_camera);
    let (yb, pb, rb) = yaw_pitch_roll_from_rotation(&fit.camera.world_to_camera);
    let d = [yb - ya, pb - pa, rb - ra].map(|v| v.to_degrees());
    let outliers = fit
        .gcps
        .iter()
        .filter(|g| g.status == GcpStatus::Outlier)
        .count();
    let mean_shift = stable.iter().fold([0.0, 0.0], |s, m| {
        [s[0] + m.b[0] - m.a[0], s[1] + m.b[1] - m.a[1]]
    });
    let n = stable.len().max(1) as f64;
    let (yc, pc, rc) = yaw_pitch_roll_from_rotation(&all.camera.world_to_camera);
    let dall = [yc - ya, pc - pa, rc - ra].map(|v| v.to_degrees());
    println!(
        "IMG_8937 against IMG_8902 (decoded in {decode:.2} s, not counted), {} threads\n",
        rayon::current_num_threads()
    );
    println!("| quantity | cliffmap | ImGRAFT |");
    println!("|---|---|---|");
    println!(
        "| matches (NCC ≥ 0.8) | {} on stable ground of {} ({outliers} flagged outliers) | rock features |",
        stable.len(),
        matches.len()
    );
    println!(
        "| mean shift du, dv (px) | {:+.2}, {:+.2} | ≈ +13.7, −1.2 |",
        mean_shift[0] / n,
        mean_shift[1] / n
    );
    println!(
        "| viewdir change yaw, pitch, roll (°) | {:+.5}, {:+.6}, {:+.6} | +0.12633, +0.017584, +0.015242 |",
        d[0], d[1], d[2]
    );
    println!(
        "| match residual RMSE, all / inliers (px) | {:.3} / {:.3} | 0.41 |",
        fit.rmse_px, fit.rmse_inliers_px
    );
    // ImGRAFT's camera B on the same inlier matches
    let mut imgraft_b = cam;
    imgraft_b.world_to_camera = cliffmap::camera::rotation_from_yaw_pitch_roll(
        ya + 0.12633f64.to_radians(),
        pa + 0.017584f64.to_radians(),
        ra + 0.015242f64.to_radians(),
    );
    let sq: Vec<f64> = fit
        .gcps
        .iter()
        .zip(&stable)
        .filter(|(g, _)| g.status == GcpStatus::Inlier)
        .filter_map(|(_, m)| {
            let p = imgraft_b.project(cam.position + cam.pixel_ray(m.a[0], m.a[1])? * 1e4)?;
            Some((p[0] - m.b[0]).powi(2) + (p[1] - m.b[1]).powi(2))
        })
        .collect();
    println!(
        "| RMSE on cliffmap's inlier matches (px) | {:.3} | {:.3} (ImGRAFT's rotation) |",
        fit.rmse_inliers_px,
        (sq.iter().sum::<f64>() / sq.len().max(1) as f64).sqrt()
    );
    println!(
        "| with every match: viewdir change (°), RMSE all / inliers (px) | {:+.5}, {:+.6}, {:+.6}; {:.3} / {:.3} | |",
        dall[0], dall[1], dall[2], all.rmse_px, all.rmse_inliers_px
    );
    // without the glacier mask: every match on terrain, the rotation consensus first (as
    // `tie_photo` does), then the fit on the matches it keeps
    let terrain = stable_matches(
        &cam,
        &matches,
        |o, d| tracer.nearest(o, d, f64::INFINITY).map(|h| h.point),
        |_| true,
    );
    for (label, set) in [("no glacier mask", &terrain), ("glacier mask", &stable)] {
        let t = Instant::now();
        let c = rotation_consensus(&cam, set, 1.0);
        let t_c = t.elapsed().as_secs_f64();
        let agreed: Vec<_> = c.inliers.iter().map(|&i| set[i]).collect();
        let on_rock = c
            .inliers
            .iter()
            .filter(|&&i| stable.iter().any(|m| m.a == set[i].a))
            .count();
        let f = fit_rotation(&cam, &agreed)?;
        let (y, p, r) = yaw_pitch_roll_from_rotation(&f.camera.world_to_camera);
        let dd = [y - ya, p - pa, r - ra].map(|v| v.to_degrees());
        println!(
            "| {label}, rotation consensus (1 px) of {} terrain matches: agreeing (off the glacier) / second motion; then the fit: viewdir change (°), RMSE inliers (px); consensus time | {} ({on_rock}) / {}; {:+.5}, {:+.6}, {:+.6}; {:.3}; {t_c:.3} s | |",
            set.len(),
            c.inliers.len(),
            c.second,
            dd[0],
            dd[1],
            dd[2],
            f.rmse_inliers_px
        );
    }
    println!("| time: matching / fit (s) | {t_match:.2} / {t_fit:.4} | |");
    Ok(())
}
