//! `cliffmap fit-camera`: a photo's camera from ground control points.

use std::path::PathBuf;

use anyhow::Context;
use cliffmap::camera::{
    CameraModel, camera_from_json_file, camera_to_imgraft_json, rotation_from_yaw_pitch_roll,
};
use cliffmap::fsutil::write_atomic;
use cliffmap::register::{
    CameraFit, FitOptions, GcpColumns, PixelOrigin, fit_camera, parse_free, read_gcps_for_image,
    start_from_position,
};
use glam::DVec3;
use serde_json::json;

/// Flags of `cliffmap fit-camera`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// GCP file: ImGRAFT text (`X Y Z U V`, 1-based pixels, `1951+9` sums) or CSV with a
    /// header `x,y,z,u,v[,name][,weight]` (0-based pixels).
    #[arg(long)]
    gcps: PathBuf,
    /// Start camera (Camera JSON, e.g. ImGRAFT-style): position, view direction, focal
    /// length and image size. Without it: --position and the size (--size or --image), or the
    /// size alone (a start from the GCPs by P3P + RANSAC, at least 4 GCPs, and with 6 or more
    /// also by DLT + RANSAC, the better kept; the focal length from --focal-px or EXIF, else
    /// searched).
    #[arg(long)]
    camera: Option<PathBuf>,
    /// Camera position "X,Y,Z" (world metres) for a start without --camera (or to replace
    /// the start camera's).
    #[arg(long, allow_hyphen_values = true)]
    position: Option<String>,
    /// Start yaw, degrees (azimuth of the optical axis counter-clockwise from east); with
    /// --focal-px. Without it the orientation is solved from the GCPs' bearings.
    #[arg(long, allow_hyphen_values = true)]
    yaw: Option<f64>,
    /// Start pitch, degrees (positive looking down; with --yaw, default 0).
    #[arg(long, allow_hyphen_values = true)]
    pitch: Option<f64>,
    /// Start roll, degrees (with --yaw, default 0).
    #[arg(long, allow_hyphen_values = true)]
    roll: Option<f64>,
    /// Start focal length, pixels (without it and without --camera it is searched).
    #[arg(long)]
    focal_px: Option<f64>,
    /// Image size "WxH" in pixels (without --camera).
    #[arg(long)]
    size: Option<String>,
    /// The photo: its size (without --camera and --size) and, without --focal-px, its EXIF
    /// focal length.
    #[arg(long)]
    image: Option<PathBuf>,
    /// CRS of the GCPs' world coordinates (EPSG:CODE or a PROJ string): with --image and
    /// neither --position nor --camera, the photo's EXIF GPS fix (WGS 84, altitude above sea
    /// level) in this CRS is the start position.
    #[arg(long)]
    crs: Option<String>,
    /// Sensor width in mm, for photos whose EXIF gives the focal length in mm alone.
    #[arg(long)]
    sensor_width_mm: Option<f64>,
    /// Free parameters: yaw, pitch, roll (angles), x, y, z (position), f (fx and fy together),
    /// fx, fy, cx, cy (c), k1, k2.
    #[arg(long, default_value = "yaw,pitch,roll,f,k1")]
    free: String,
    /// Pixel convention of the GCP file: "format" (ImGRAFT text 1-based, CSV 0-based), 0 or 1.
    #[arg(long, default_value = "format")]
    pixel_origin: String,
    /// Plain least squares instead of the Huber-weighted fit.
    #[arg(long)]
    no_robust: bool,
    /// Fixed Huber threshold in pixels (default: 2.45 times the robust residual scale, at
    /// least 0.5 px).
    #[arg(long)]
    huber_px: Option<f64>,
    /// Output camera (ImGRAFT-style Camera JSON, read directly by `project`).
    #[arg(long)]
    out: PathBuf,
    /// Print the fit as JSON on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// A store of the terrain the photo shows: the GCPs' heights are compared with its
    /// surface and the fitted camera is checked against it (a warning when it ends up below
    /// the ground; "terrain" in the JSON).
    #[arg(long)]
    store: Option<PathBuf>,
}

/// Runs `fit-camera`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let origin = match a.pixel_origin.as_str() {
        "format" => PixelOrigin::Format,
        "0" => PixelOrigin::Zero,
        "1" => PixelOrigin::One,
        o => anyhow::bail!("--pixel-origin must be format, 0 or 1, got {o}"),
    };
    let size = match &a.camera {
        Some(path) => {
            let c = camera_from_json_file(path, (0, 0))?;
            (c.width, c.height)
        }
        None => image_size(&a)?,
    };
    let (gcps, columns) = read_gcps_for_image(&a.gcps, origin, size)?;
    if columns == GcpColumns::PixelThenWorld {
        eprintln!(
            "note: {}: read as U V X Y Z (its pixel columns come first: in the documented order \
             X Y Z U V they fall outside the {}x{} image)",
            a.gcps.display(),
            size.0,
            size.1
        );
    }
    let free = parse_free(&a.free)?;
    let position = a.position.as_deref().map(parse_position).transpose()?;
    if let Some(f) = a.focal_px {
        anyhow::ensure!(
            f.is_finite() && f > 0.0,
            "--focal-px must be a positive number of pixels, got {f}"
        );
    }
    if let Some(d) = a.huber_px {
        anyhow::ensure!(
            d.is_finite() && d > 0.0,
            "--huber-px must be a positive number of pixels, got {d}"
        );
    }
    if let Some(s) = a.sensor_width_mm {
        anyhow::ensure!(
            s.is_finite() && s > 0.0,
            "--sensor-width-mm must be positive, got {s}"
        );
    }
    let start = start_camera(&a, position, &gcps)?;
    if let Some(problem) = start.problem() {
        anyhow::bail!("the start camera is unusable: {problem}");
    }
    let opts = FitOptions {
        free,
        robust: !a.no_robust,
        huber_px: a.huber_px,
        ..FitOptions::default()
    };
    let fit = fit_camera(&start, &gcps, &opts).with_context(|| format!("{}", a.gcps.display()))?;
    if let Some(problem) = fit.camera.problem() {
        anyhow::bail!(
            "{}: the fitted camera is unusable: {problem} (nothing written; fit with fewer \
             distortion terms free, e.g. without k2, or more GCPs towards the image corners)",
            a.gcps.display()
        );
    }
    let rayless = fit.camera.rayless_share();
    if rayless > 0.0 {
        eprintln!(
            "warning: the fitted distortion (k1 {:.4}, k2 {:.4}) folds inside the image: {:.1} % \
             of its pixels (the corners beyond {:.0} px from the principal point) have no ray \
             in this model; every command accepts the camera (projection leaves those pixels \
             out, renders show sky there)",
            fit.camera.k1,
            fit.camera.k2,
            100.0 * rayless,
            fit.camera.fold_radius() * fit.camera.fx
        );
    }
    let mut report = fit_json(&fit, &a.gcps.display().to_string());
    if let Some(obj) = report.as_object_mut() {
        obj.insert("rayless_share".into(), json!(rayless));
    }
    if let Some(dir) = &a.store {
        let terrain = check_against_terrain(dir, &fit.camera, &gcps)?;
        if let Some(obj) = report.as_object_mut() {
            obj.insert("terrain".into(), terrain);
        }
    }
    let mut doc = camera_to_imgraft_json(&fit.camera);
    if let Some(obj) = doc.as_object_mut() {
        obj.insert("fit".into(), report.clone());
        obj.insert("rmse_px".into(), json!(fit.rmse_px));
    }
    let text = serde_json::to_string_pretty(&doc)?;
    write_atomic(&a.out, text.as_bytes())?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&fit);
        println!("camera written to {}", a.out.display());
    }
    Ok(())
}

/// The start camera: --camera (position replaced by --position), else --yaw with
/// --focal-px, else the orientation from the GCP bearings at --position, else P3P or DLT of
/// the GCPs.
fn start_camera(
    a: &Args,
    position: Option<DVec3>,
    gcps: &[cliffmap::register::Gcp],
) -> anyhow::Result<CameraModel> {
    if let Some(path) = &a.camera {
        let mut cam = camera_from_json_file(path, (0, 0))?;
        if let Some(p) = position {
            cam.position = p;
        }
        if let Some(f) = a.focal_px {
            cam.fy *= f / cam.fx;
            cam.fx = f;
        }
        return Ok(cam);
    }
    let (w, h) = image_size(a)?;
    let mut focal = a.focal_px;
    if let (None, Some(img)) = (focal, &a.image)
        && let Some(e) = cliffmap::camera::exif_focal_px(img, w, h, a.sensor_width_mm)?
    {
        eprintln!(
            "start focal length {:.1} px from EXIF ({})",
            e.focal_px, e.source
        );
        focal = Some(e.focal_px);
    }
    let position = match (position, &a.crs, &a.image) {
        (None, Some(crs), Some(img)) => gps_position(img, crs, w, h, gcps, focal)?,
        (p, _, _) => p,
    };
    let Some(position) = position else {
        let (cam, how) = cliffmap::register::start_without_position(w, h, gcps, focal)?;
        eprintln!(
            "start from the GCPs alone ({how}): position {:.1}, {:.1}, {:.1}, focal {:.0} px",
            cam.position.x, cam.position.y, cam.position.z, cam.fx
        );
        return Ok(cam);
    };
    match (a.yaw, focal) {
        (Some(yaw), Some(f)) => {
            let r = rotation_from_yaw_pitch_roll(
                yaw.to_radians(),
                a.pitch.unwrap_or(0.0).to_radians(),
                a.roll.unwrap_or(0.0).to_radians(),
            );
            let mut cam = CameraModel::with_fov(position, r, w, h, 1.0);
            cam.fx = f;
            cam.fy = f;
            Ok(cam)
        }
        (Some(_), None) => anyhow::bail!(
            "--yaw needs --focal-px (or leave out --yaw to solve the orientation from the GCPs)"
        ),
        (None, f) => Ok(start_from_position(position, w, h, gcps, f)?),
    }
}

/// The photo's EXIF GPS fix in `crs` (`None`, with a note, without a fix or an altitude),
/// with how far it lies from the position the GCPs alone give (a wrong CRS or zone shows as
/// kilometres).
fn gps_position(
    img: &std::path::Path,
    crs: &str,
    w: u32,
    h: u32,
    gcps: &[cliffmap::register::Gcp],
    focal: Option<f64>,
) -> anyhow::Result<Option<DVec3>> {
    let Some(gps) = cliffmap::camera::exif_gps(img)? else {
        eprintln!(
            "{}: no EXIF GPS fix; the start comes from the GCPs",
            img.display()
        );
        return Ok(None);
    };
    let Some(alt) = gps.altitude_m else {
        eprintln!(
            "{}: the EXIF GPS fix has no altitude; the start comes from the GCPs",
            img.display()
        );
        return Ok(None);
    };
    let p = cliffmap::crs::from_lon_lat(crs, gps.lon_deg, gps.lat_deg, alt)?;
    eprintln!(
        "start position from EXIF GPS ({:.6}, {:.6}, {alt:.1} m): {:.1}, {:.1}, {:.1} in {crs}",
        gps.lat_deg, gps.lon_deg, p.x, p.y, p.z
    );
    if let Some(d) = gps.direction_deg {
        eprintln!(
            "EXIF image direction {d:.1}° from {} north (yaw {:.1}°)",
            if gps.direction_magnetic {
                "magnetic"
            } else {
                "true"
            },
            (90.0 - d).rem_euclid(360.0)
        );
    }
    if gcps.len() >= 4
        && let Ok((cam, how)) = cliffmap::register::start_without_position(w, h, gcps, focal)
    {
        eprintln!(
            "the GCPs alone ({how}) put the camera {:.1} m from the GPS fix",
            cam.position.distance(p)
        );
    }
    Ok(Some(p))
}

fn parse_position(s: &str) -> anyhow::Result<DVec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--position must be X,Y,Z metres, got {s}"))?;
    anyhow::ensure!(
        v.len() == 3 && v.iter().all(|x| x.is_finite()),
        "--position must be X,Y,Z metres, got {s}"
    );
    Ok(DVec3::new(v[0], v[1], v[2]))
}

fn image_size(a: &Args) -> anyhow::Result<(u32, u32)> {
    if let Some(s) = &a.size {
        let (w, h) = s
            .split_once(['x', 'X'])
            .with_context(|| format!("--size must be WxH, got {s}"))?;
        let (w, h): (u32, u32) = (
            w.trim().parse().with_context(|| format!("--size {s}"))?,
            h.trim().parse().with_context(|| format!("--size {s}"))?,
        );
        anyhow::ensure!(w > 0 && h > 0, "--size must be positive, got {s}");
        return Ok((w, h));
    }
    if let Some(p) = &a.image {
        // (as shown: turned by its EXIF orientation, as `project` decodes it)
        return Ok(cliffmap::fsutil::photo_dimensions(p)?);
    }
    anyhow::bail!("without --camera, give the image size: --size WxH or --image PHOTO")
}

/// GCP heights above the terrain of the store in `dir` differ from its surface by more
/// than this (median, metres): warned as a likely datum or column mix-up.
const GCP_HEIGHT_WARN_M: f64 = 5.0;

/// Compares the GCPs' heights with the store's surface and places the fitted camera
/// against it; warns (stderr) on a camera below the ground or GCPs far off the surface.
/// Returns the findings as JSON.
fn check_against_terrain(
    dir: &std::path::Path,
    camera: &cliffmap::camera::CameraModel,
    gcps: &[cliffmap::register::Gcp],
) -> anyhow::Result<serde_json::Value> {
    let store = cliffmap::store::Store::open(dir)?;
    let place = cliffmap::store::CameraPlacement::of(&store, camera)?;
    if place.is_underground() {
        eprintln!(
            "warning: the fitted camera is {}: it would see no terrain; check the GCPs' \
             heights and datum, or give the position (--position) and keep x, y, z fixed",
            place.describe()
        );
    }
    let mut dz: Vec<f64> = Vec::new();
    for g in gcps {
        if let Some(s) = store.surface_at(g.world.x, g.world.y)? {
            dz.push(g.world.z - s.height);
        }
    }
    let mut abs: Vec<f64> = dz.iter().map(|d| d.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let median = abs.get(abs.len() / 2).copied();
    if let Some(m) = median.filter(|m| *m > GCP_HEIGHT_WARN_M) {
        eprintln!(
            "warning: the GCPs' heights differ from the terrain's surface by {m:.1} m (median \
             of {} on the terrain): another vertical datum, or columns in another order?",
            abs.len()
        );
    }
    if abs.len() < gcps.len() {
        eprintln!(
            "note: {} of {} GCPs lie outside the store's terrain",
            gcps.len() - abs.len(),
            gcps.len()
        );
    }
    Ok(json!({
        "camera_height_above_ground_m": place.height_above_ground(),
        "camera_underground": place.is_underground(),
        "camera_placement": place.describe(),
        "gcps_on_terrain": abs.len(),
        "gcp_height_minus_surface_median_abs_m": median,
        "gcp_height_minus_surface_max_abs_m": abs.last(),
    }))
}

/// The fit as the JSON of `--json` (also stored under "fit" in the camera file).
fn fit_json(fit: &CameraFit, gcp_file: &str) -> serde_json::Value {
    let value = |p: cliffmap::register::Param, v: f64| match p {
        cliffmap::register::Param::Yaw => v.to_degrees().rem_euclid(360.0),
        _ if p.is_angle() => v.to_degrees(),
        _ => v,
    };
    let spread =
        |p: cliffmap::register::Param, v: f64| if p.is_angle() { v.to_degrees() } else { v };
    let params: serde_json::Map<String, serde_json::Value> = fit
        .params
        .iter()
        .map(|p| (p.param.name().to_string(), json!(value(p.param, p.value))))
        .collect();
    let start: serde_json::Map<String, serde_json::Value> = fit
        .params
        .iter()
        .map(|p| (p.param.name().to_string(), json!(value(p.param, p.start))))
        .collect();
    let sigma: serde_json::Map<String, serde_json::Value> = fit
        .params
        .iter()
        .map(|p| {
            (
                p.param.name().to_string(),
                if p.sigma.is_finite() {
                    json!(spread(p.param, p.sigma))
                } else {
                    serde_json::Value::Null
                },
            )
        })
        .collect();
    let residuals: Vec<serde_json::Value> = fit
        .gcps
        .iter()
        .map(|g| {
            json!({
                "name": g.name,
                "u": g.observed[0],
                "v": g.observed[1],
                "du": g.residual.map(|r| r[0]),
                "dv": g.residual.map(|r| r[1]),
                "px": g.residual.map(|r| r[0].hypot(r[1])),
                "robust_weight": g.robust_weight,
                "status": g.status.name(),
            })
        })
        .collect();
    let finite = |v: f64| {
        if v.is_finite() {
            json!(v)
        } else {
            serde_json::Value::Null
        }
    };
    json!({
        "gcp_file": gcp_file,
        "rmse_px": finite(fit.rmse_px),
        "rmse_inliers_px": finite(fit.rmse_inliers_px),
        "aic": finite(fit.aic),
        "robust_scale_px": finite(fit.sigma_px),
        "rounds": fit.rounds,
        "units": "angles in degrees (yaw, pitch, roll: ImGRAFT convention), position in metres, focal length and principal point in pixels (0-based)",
        "params": params,
        "start": start,
        "sigma": sigma,
        "residuals": residuals,
    })
}

fn print_table(fit: &CameraFit) {
    println!("| GCP | u | v | du | dv | px | status |");
    println!("|---|---|---|---|---|---|---|");
    for g in &fit.gcps {
        match g.residual {
            Some(r) => println!(
                "| {} | {:.1} | {:.1} | {:+.2} | {:+.2} | {:.2} | {} |",
                g.name,
                g.observed[0],
                g.observed[1],
                r[0],
                r[1],
                r[0].hypot(r[1]),
                g.status.name()
            ),
            None => println!(
                "| {} | {:.1} | {:.1} | | | | {} |",
                g.name,
                g.observed[0],
                g.observed[1],
                g.status.name()
            ),
        }
    }
    println!();
    println!("| parameter | start | fitted | σ |");
    println!("|---|---|---|---|");
    for p in &fit.params {
        let (k, unit) = if p.param.is_angle() {
            (180.0 / std::f64::consts::PI, "°")
        } else {
            (1.0, "")
        };
        let shown = |v: f64| {
            if p.param == cliffmap::register::Param::Yaw {
                (v * k).rem_euclid(360.0)
            } else {
                v * k
            }
        };
        println!(
            "| {} | {:.6}{unit} | {:.6}{unit} | {:.2e}{unit} |",
            p.param.name(),
            shown(p.start),
            shown(p.value),
            p.sigma * k
        );
    }
    let outliers = fit
        .gcps
        .iter()
        .filter(|g| g.status == cliffmap::register::GcpStatus::Outlier)
        .count();
    println!(
        "\nRMSE {:.3} px over the fitted GCPs ({:.3} px over the inliers, {outliers} outliers), AIC {:.2}, robust scale {:.3} px, {} rounds",
        fit.rmse_px, fit.rmse_inliers_px, fit.aic, fit.sigma_px, fit.rounds
    );
}
