//! Helpers shared by the benchmarks (included with `#[path]`).
#![allow(dead_code)]

pub mod overlay;
pub mod scene_args;

use std::io::Write;
use std::path::{Path, PathBuf};

use cliffmap::ParamMesh;

/// Path of a file in the shared real-data folder: `$CLIFFMAP_SHARED_DATA/rel`, else
/// `<repo>/../shared/data/real/rel`, else `/work/shared/data/real/rel`.
pub fn shared_data(rel: &str) -> PathBuf {
    if let Some(d) = std::env::var_os("CLIFFMAP_SHARED_DATA") {
        return PathBuf::from(d).join(rel);
    }
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real")).join(rel);
    if p.exists() {
        p
    } else {
        PathBuf::from("/work/shared/data/real").join(rel)
    }
}

/// Writes `m` with texture coordinates `uvs` as OBJ (`v`, `vt`, `f v/vt`).
pub fn write_obj(path: &Path, m: &ParamMesh, uvs: &[[f64; 2]]) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    for p in &m.positions {
        writeln!(f, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2])?;
    }
    for uv in uvs {
        writeln!(f, "vt {:.9} {:.9}", uv[0], uv[1])?;
    }
    for t in &m.triangles {
        writeln!(
            f,
            "f {}/{} {}/{} {}/{}",
            t[0] + 1,
            t[0] + 1,
            t[1] + 1,
            t[1] + 1,
            t[2] + 1,
            t[2] + 1
        )?;
    }
    f.flush()
}

/// Median of `v` (mean of the two middle values for an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// CPU seconds (user + system, all threads) this process has used so far (Linux
/// `/proc/self/stat`, 100 Hz ticks; NaN elsewhere).
pub fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = s.rsplit_once(')')?.1.split_whitespace().collect::<Vec<_>>();
            // Fields after the command: state is index 0, utime 11, stime 12.
            let u: f64 = rest.get(11)?.parse().ok()?;
            let k: f64 = rest.get(12)?.parse().ok()?;
            Some((u + k) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

/// Builds the Engabreen store (3 m lidar DEM + ortho from the shared data, default build
/// options) into `dir`; returns the build's wall-clock seconds.
pub fn build_engabreen_store(dir: &Path, fingerprint: &str) -> anyhow::Result<f64> {
    use cliffmap::OrthoPlacement;
    use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
    let dem = engabreen_dem()?;
    let ortho = cliffmap::load_ortho(
        &shared_data("engabreen/engabreen_ortho_3m_507x590.png"),
        OrthoPlacement::SameGridAsDem,
        &dem,
        1 << 30,
    )?;
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "engabreen".into(),
        ortho_source: None,
        fingerprint: fingerprint.into(),
    };
    let t = std::time::Instant::now();
    build_store(
        &inputs,
        &BuildOptions {
            ..BuildOptions::default()
        },
        dir,
    )?;
    Ok(t.elapsed().as_secs_f64())
}

/// Engabreen's 3-m DEM (507 × 590 samples, UTM 33N) as the stores of the benchmarks use it.
pub fn engabreen_dem() -> anyhow::Result<cliffmap::Dem> {
    let dem_opts = cliffmap::DemLoadOptions {
        width: Some(507),
        height: Some(590),
        spacing: Some(3.0),
        origin: Some((445302.17, 7396769.45)),
        ..Default::default()
    };
    Ok(cliffmap::load_dem(
        &shared_data("engabreen/engabreen_dem_3m_507x590.f32"),
        &dem_opts,
    )?)
}

/// Fractal DEM (diamond-square) of `(2^k + 1)^2` samples whose displacement depends only on
/// the absolute step in samples, so every size has the same local roughness.
pub fn fractal(n: usize, seed: u64) -> cliffmap::Dem {
    let mut s = seed | 1;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut h = vec![0f64; n * n];
    let amp = |step: usize| 0.4 * (step as f64).powf(0.9);
    let mut step = n - 1;
    while step > 1 {
        let half = step / 2;
        let a = amp(step);
        for y in (half..n).step_by(step) {
            for x in (half..n).step_by(step) {
                let m = (h[(y - half) * n + x - half]
                    + h[(y - half) * n + x + half]
                    + h[(y + half) * n + x - half]
                    + h[(y + half) * n + x + half])
                    / 4.0;
                h[y * n + x] = m + a * rnd();
            }
        }
        for y in (0..n).step_by(half) {
            let x0 = if (y / half).is_multiple_of(2) {
                half
            } else {
                0
            };
            for x in (x0..n).step_by(step) {
                let mut sum = 0.0;
                let mut cnt = 0.0;
                if y >= half {
                    sum += h[(y - half) * n + x];
                    cnt += 1.0;
                }
                if y + half < n {
                    sum += h[(y + half) * n + x];
                    cnt += 1.0;
                }
                if x >= half {
                    sum += h[y * n + x - half];
                    cnt += 1.0;
                }
                if x + half < n {
                    sum += h[y * n + x + half];
                    cnt += 1.0;
                }
                h[y * n + x] = sum / cnt + a * rnd();
            }
        }
        step = half;
    }
    let hs = h.iter().map(|&v| v as f32).collect();
    cliffmap::Dem::from_heights(n, n, hs, cliffmap::GridGeoref::new(0.0, 0.0, 10.0))
        .expect("fractal DEM")
}

/// Copies the directory tree `from` into `to` (created).
pub fn copy_dir(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let e = e?;
        let dest = to.join(e.file_name());
        if e.file_type()?.is_dir() {
            copy_dir(&e.path(), &dest)?;
        } else {
            std::fs::copy(e.path(), dest)?;
        }
    }
    Ok(())
}

/// [`build_engabreen_store`] followed by `cliffmap reparam` with the default options.
pub fn build_engabreen_reparam_store(dir: &Path, fingerprint: &str) -> anyhow::Result<()> {
    build_engabreen_store(dir, fingerprint)?;
    cliffmap::pipeline::reparam_store(
        dir,
        &cliffmap::pipeline::ReparamOptions {
            ..Default::default()
        },
    )?;
    Ok(())
}

/// Argument `i` as the number of runs (at least 1), `default` when absent.
pub fn runs_arg(args: &[String], i: usize, default: usize) -> anyhow::Result<usize> {
    Ok(args
        .get(i)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(default)
        .max(1))
}

/// A `photos.json` in `dir` naming IMG_8902 with ImGRAFT's Engabreen camera (the shared
/// data), read and decoded.
pub fn img8902_photos(dir: &Path) -> anyhow::Result<Vec<cliffmap::photo::PhotoInput>> {
    let list = dir.join("photos.json");
    let data = shared_data("engabreen");
    std::fs::write(
        &list,
        serde_json::json!({"photos": [{"image": data.join("IMG_8902.jpg"), "imgraft": data.join("engabreen_camera_IMG_8902.json")}]})
            .to_string(),
    )?;
    Ok(cliffmap::photo::read_photo_list(&list)?)
}

/// Argument 1 as the store directory, else `tmp/store`.
pub fn store_arg(args: &[String], tmp: &Path) -> PathBuf {
    args.get(1).map_or_else(|| tmp.join("store"), PathBuf::from)
}

/// A resection's table cells: `points / coarse / fine / inliers | RMSE px | σ position m
/// | accepted` (markdown, no outer bars).
pub fn resect_cells(fit: &cliffmap::register::ResectFit) -> String {
    let [n0, n1, n2, n3] = fit.counts;
    let [sx, sy, sz] = fit.sigma_position_m;
    let verdict = if fit.accepted {
        "yes".to_string()
    } else {
        format!("no: {}", fit.reason.clone().unwrap_or_default())
    };
    format!(
        "{n0} / {n1} / {n2} / {n3} | {:.2} | {sx:.2}, {sy:.2}, {sz:.2} | {verdict}",
        fit.rmse_inliers_px
    )
}

/// Engabreen's IMG_8902 (decoded), ImGRAFT's camera fitted to it, and its 28 GCPs.
pub fn engabreen_8902() -> anyhow::Result<(
    image::RgbImage,
    cliffmap::camera::CameraModel,
    Vec<cliffmap::register::Gcp>,
)> {
    let data = shared_data("engabreen");
    let photo = cliffmap::fsutil::decode_rgb8(&data.join("IMG_8902.jpg"))?;
    let fitted = cliffmap::camera::camera_from_json_file(
        &data.join("engabreen_camera_IMG_8902.json"),
        photo.dimensions(),
    )?;
    let gcps = cliffmap::register::read_gcps(
        &data.join("gcp8902.txt"),
        cliffmap::register::PixelOrigin::Format,
    )?;
    Ok((photo, fitted, gcps))
}

/// RMS distance (pixels) between where `cam` projects the GCPs in front of it and their
/// pixels ([`cliffmap::register::gcp_rmse_px`]).
pub fn gcp_rmse(cam: &cliffmap::camera::CameraModel, gcps: &[cliffmap::register::Gcp]) -> f64 {
    cliffmap::register::gcp_rmse_px(cam, gcps).0
}
