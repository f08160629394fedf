//! The ImGRAFT camera of the Engabreen photo parses to the pose and model stored with it.

mod common;

use cliffmap::camera::camera_from_json_file;
use glam::DVec3;

#[test]
fn engabreen_camera_matches_its_rotation_and_gcps() {
    let path = common::real_data("engabreen/engabreen_camera_IMG_8902.json");
    let cam = camera_from_json_file(&path, (640, 480)).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let rows = v["R_world_to_camera_rows"].as_array().unwrap();
    for (i, row) in rows.iter().enumerate() {
        let want: Vec<f64> = row
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let got = cam.world_to_camera.row(i);
        assert!(
            (got - DVec3::new(want[0], want[1], want[2])).length() < 1e-9,
            "row {i}: {got} vs {want:?}"
        );
    }
    assert_eq!((cam.width, cam.height), (4290, 2856));
    assert_eq!(cam.position, DVec3::new(446722.0, 7396671.0, 770.0));
    // Reprojection of the ground control points (X Y Z U V, MATLAB 1-based pixels; "a+b"
    // tokens are sums) with the ImGRAFT model: RMSE as published in the file (3.04 px).
    let gcp = std::fs::read_to_string(common::real_data("engabreen/gcp8902.txt")).unwrap();
    let mut sq = Vec::new();
    for line in gcp
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('%'))
    {
        let t: Vec<f64> = line
            .split_whitespace()
            .map(|tok| tok.split('+').map(|p| p.parse::<f64>().unwrap()).sum())
            .collect();
        let p = cam.project(DVec3::new(t[0], t[1], t[2])).unwrap();
        sq.push((p[0] + 1.0 - t[3]).powi(2) + (p[1] + 1.0 - t[4]).powi(2));
    }
    let rmse = (sq.iter().sum::<f64>() / sq.len() as f64).sqrt();
    let want = v["rmse_px"].as_f64().unwrap();
    assert_eq!(sq.len(), 28);
    assert!(
        (rmse - want).abs() < 0.05,
        "GCP RMSE {rmse:.3} px, file says {want:.3}"
    );
    // Rendering at a quarter of the size keeps the field of view.
    let small = cam.resized(1072, 714);
    assert!((small.fov_y() - cam.fov_y()).abs() < 1e-3);
}

/// The 28 GCPs of gcp8902.txt: world point and MATLAB 1-based pixel ("a+b" tokens are sums).
fn gcps() -> Vec<(DVec3, [f64; 2])> {
    let gcp = std::fs::read_to_string(common::real_data("engabreen/gcp8902.txt")).unwrap();
    gcp.lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('%'))
        .map(|line| {
            let t: Vec<f64> = line
                .split_whitespace()
                .map(|tok| tok.split('+').map(|p| p.parse::<f64>().unwrap()).sum())
                .collect();
            (DVec3::new(t[0], t[1], t[2]), [t[3], t[4]])
        })
        .collect()
}

/// Engabreen's two photos through `photos.json` (the pipeline's reader): IMG_8902 with the
/// fitted ImGRAFT camera, IMG_8937 with ImGRAFT's reported view-direction delta.
fn engabreen_specs(dir: &std::path::Path) -> Vec<cliffmap::photo::PhotoSpec> {
    let list = serde_json::json!({"photos": [
        {"image": common::real_data("engabreen/IMG_8902.jpg"),
         "imgraft": common::real_data("engabreen/engabreen_camera_IMG_8902.json")},
        {"image": common::real_data("engabreen/IMG_8937.jpg"),
         "imgraft": common::real_data("engabreen/engabreen_camera_IMG_8902.json"),
         "rotation_delta_deg": [0.12633, 0.017584, 0.015242]},
    ]});
    let path = dir.join("photos.json");
    std::fs::write(&path, list.to_string()).unwrap();
    cliffmap::photo::read_photo_specs(&path).unwrap()
}

#[test]
fn engabreen_gcps_reproject_through_the_photo_list_camera() {
    let tmp = tempfile::tempdir().unwrap();
    let specs = engabreen_specs(tmp.path());
    let cam = specs[0].camera;
    assert_eq!((cam.width, cam.height), (4290, 2856));
    let pts = gcps();
    assert_eq!(pts.len(), 28);
    let sq: Vec<f64> = pts
        .iter()
        .map(|(x, uv)| {
            let p = cam.project(*x).unwrap();
            (p[0] + 1.0 - uv[0]).powi(2) + (p[1] + 1.0 - uv[1]).powi(2)
        })
        .collect();
    let rmse = (sq.iter().sum::<f64>() / 28.0).sqrt();
    println!("Engabreen IMG_8902: GCP reprojection RMSE {rmse:.3} px over 28 points");
    assert!(
        (2.5..=3.5).contains(&rmse),
        "GCP RMSE {rmse:.3} px, the fit says ~3.0 px"
    );
    // Every GCP lies in front of the camera and inside the photo.
    for (x, _) in &pts {
        let p = cam.project(*x).unwrap();
        assert!(p[0] >= 0.0 && p[1] >= 0.0 && p[0] < 4290.0 && p[1] < 2856.0);
    }
}

/// Normalized cross-correlation of the `r`-radius patch of `a` at `(ua, va)` with that of
/// `b` at `(ua + du, va + dv)`.
fn ncc(
    a: &image::GrayImage,
    b: &image::GrayImage,
    ua: i64,
    va: i64,
    du: i64,
    dv: i64,
    r: i64,
) -> f64 {
    let (mut sa, mut sb, mut saa, mut sbb, mut sab, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for y in -r..=r {
        for x in -r..=r {
            let pa = a.get_pixel((ua + x) as u32, (va + y) as u32).0[0] as f64;
            let pb = b.get_pixel((ua + du + x) as u32, (va + dv + y) as u32).0[0] as f64;
            sa += pa;
            sb += pb;
            saa += pa * pa;
            sbb += pb * pb;
            sab += pa * pb;
            n += 1.0;
        }
    }
    let cov = sab - sa * sb / n;
    let va_ = saa - sa * sa / n;
    let vb = sbb - sb * sb / n;
    if va_ <= 0.0 || vb <= 0.0 {
        0.0
    } else {
        cov / (va_ * vb).sqrt()
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[test]
fn engabreen_img_8937_delta_matches_the_image_shift() {
    // IMG_8937's camera is IMG_8902's with ImGRAFT's view-direction delta. Validate it with
    // feature correspondence: template-match patches around the GCPs (rock features) from
    // IMG_8902 into IMG_8937 and compare the measured shift with the one the two cameras
    // predict at the same world points.
    let tmp = tempfile::tempdir().unwrap();
    let specs = engabreen_specs(tmp.path());
    let (ca, cb) = (specs[0].camera, specs[1].camera);
    let a = image::DynamicImage::ImageRgb8(specs[0].load().unwrap().image).to_luma8();
    let b = image::DynamicImage::ImageRgb8(specs[1].load().unwrap().image).to_luma8();
    let (r, search) = (20i64, 30i64);
    let (mut mu, mut mv, mut pu, mut pv) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (x, _) in gcps() {
        let (p, q) = (ca.project(x).unwrap(), cb.project(x).unwrap());
        let (ua, va) = (p[0].round() as i64, p[1].round() as i64);
        let m = r + search + 2;
        if ua < m || va < m || ua >= a.width() as i64 - m || va >= a.height() as i64 - m {
            continue;
        }
        let mut best = (f64::MIN, 0, 0);
        for dv in -search..=search {
            for du in -search..=search {
                let c = ncc(&a, &b, ua, va, du, dv, r);
                if c > best.0 {
                    best = (c, du, dv);
                }
            }
        }
        if best.0 < 0.8 || best.1.abs() == search || best.2.abs() == search {
            continue; // weak or ambiguous match (moving ice, changed light)
        }
        // Sub-pixel peak by parabola fits along each axis.
        let sub = |cm: f64, c0: f64, cp: f64| {
            let den = cm - 2.0 * c0 + cp;
            if den.abs() > 1e-12 {
                0.5 * (cm - cp) / den
            } else {
                0.0
            }
        };
        let (c0, du, dv) = best;
        let fu = sub(
            ncc(&a, &b, ua, va, du - 1, dv, r),
            c0,
            ncc(&a, &b, ua, va, du + 1, dv, r),
        );
        let fv = sub(
            ncc(&a, &b, ua, va, du, dv - 1, r),
            c0,
            ncc(&a, &b, ua, va, du, dv + 1, r),
        );
        mu.push(du as f64 + fu);
        mv.push(dv as f64 + fv);
        pu.push(q[0] - p[0]);
        pv.push(q[1] - p[1]);
    }
    let n = mu.len();
    let (mu, mv, pu, pv) = (median(mu), median(mv), median(pu), median(pv));
    println!(
        "IMG_8937 vs IMG_8902 at {n} GCP patches: measured shift ({mu:.2}, {mv:.2}) px, predicted by the delta ({pu:.2}, {pv:.2}) px"
    );
    assert!(n >= 10, "only {n} reliable matches");
    assert!(
        (mu - pu).abs() < 2.0 && (mv - pv).abs() < 2.0,
        "measured ({mu:.2}, {mv:.2}) vs predicted ({pu:.2}, {pv:.2})"
    );
    // The shift is substantial, so applying the delta with the wrong sign would fail.
    assert!(pu > 10.0, "predicted du {pu}");
}

/// Sobel gradient magnitude of a grey image.
fn gradient(img: &image::GrayImage) -> Vec<f64> {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let g = |i: i64, j: i64| {
        img.get_pixel(i.clamp(0, w - 1) as u32, j.clamp(0, h - 1) as u32)
            .0[0] as f64
    };
    let mut out = vec![0.0; (w * h) as usize];
    for j in 0..h {
        for i in 0..w {
            let gx = g(i + 1, j - 1) + 2.0 * g(i + 1, j) + g(i + 1, j + 1)
                - g(i - 1, j - 1)
                - 2.0 * g(i - 1, j)
                - g(i - 1, j + 1);
            let gy = g(i - 1, j + 1) + 2.0 * g(i, j + 1) + g(i + 1, j + 1)
                - g(i - 1, j - 1)
                - 2.0 * g(i, j - 1)
                - g(i + 1, j - 1);
            out[(j * w + i) as usize] = gx.hypot(gy);
        }
    }
    out
}

/// For each tile of the lower two thirds of a 4 × 3 grid: the integer shift (within ±`r` px)
/// of the photo's gradients that best matches the render's (NCC over non-sky render pixels),
/// as (tile column, tile row, du, dv, ncc).
fn tile_shifts(
    render: &image::RgbaImage,
    photo: &image::GrayImage,
    sky: [u8; 3],
    r: i64,
) -> Vec<(i64, i64, i64, i64, f64)> {
    let (w, h) = (render.width() as i64, render.height() as i64);
    let gr = gradient(&image::DynamicImage::ImageRgba8(render.clone()).to_luma8());
    let gp = gradient(photo);
    let is_sky = |i: i64, j: i64| {
        let p = render.get_pixel(i as u32, j as u32).0;
        (0..3).all(|k| (p[k] as i32 - sky[k] as i32).abs() <= 3)
    };
    let mut out = Vec::new();
    for tj in 1..3 {
        for ti in 0..4 {
            let (i0, i1) = ((ti * w / 4).max(r + 1), ((ti + 1) * w / 4).min(w - r - 1));
            let (j0, j1) = ((tj * h / 3).max(r + 1), ((tj + 1) * h / 3).min(h - r - 1));
            let mut best = (f64::MIN, 0, 0);
            for dv in -r..=r {
                for du in -r..=r {
                    let (mut sa, mut sb, mut saa, mut sbb, mut sab, mut n) =
                        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
                    for j in j0..j1 {
                        for i in i0..i1 {
                            if is_sky(i, j) {
                                continue;
                            }
                            let (p, q) = (
                                gr[(j * w + i) as usize],
                                gp[((j + dv) * w + i + du) as usize],
                            );
                            sa += p;
                            sb += q;
                            saa += p * p;
                            sbb += q * q;
                            sab += p * q;
                            n += 1.0;
                        }
                    }
                    let c =
                        (sab - sa * sb / n) / ((saa - sa * sa / n) * (sbb - sb * sb / n)).sqrt();
                    if n > 2000.0 && c > best.0 {
                        best = (c, du, dv);
                    }
                }
            }
            out.push((ti, tj, best.1, best.2, best.0));
        }
    }
    out
}

#[test]
fn engabreen_render_with_distortion_overlays_the_photo() {
    use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
    use cliffmap::render::{DistortionMode, FrameOptions, SceneOptions, StoreRenderer};
    // An Engabreen store (ortho textures) rendered from IMG_8902's camera at a quarter of the
    // photo's size, with and without the lens distortion, against the photo's edges.
    let t = tempfile::tempdir().unwrap();
    let dem = common::engabreen_dem();
    let ortho = common::engabreen_ortho(&dem);
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "engabreen".into(),
        ortho_source: Some("engabreen".into()),
        fingerprint: "render-distortion-engabreen".into(),
    };
    let opts = BuildOptions {
        max_error: 1.0,
        force: true,
        ..Default::default()
    };
    build_store(&inputs, &opts, t.path()).unwrap();
    let (w, h) = (1072, 714);
    let cam = camera_from_json_file(
        &common::real_data("engabreen/engabreen_camera_IMG_8902.json"),
        (w, h),
    )
    .unwrap()
    .resized(w, h);
    let photo = image::open(common::real_data("engabreen/IMG_8902.jpg"))
        .unwrap()
        .to_luma8();
    let photo = image::imageops::resize(&photo, w, h, image::imageops::FilterType::Triangle);
    let sky = [170, 200, 235];
    let mut shifts = Vec::new();
    for mode in [DistortionMode::Auto, DistortionMode::Off] {
        let opts = SceneOptions {
            frame: FrameOptions {
                lit: false,
                sky,
                ..Default::default()
            },
            distortion: mode,
            ..Default::default()
        };
        let mut scene = StoreRenderer::open(t.path(), w, h, opts).unwrap();
        assert_eq!(
            scene.frame(&cam, true).unwrap().distorted,
            mode == DistortionMode::Auto
        );
        let s = tile_shifts(&scene.read_rgba().unwrap(), &photo, sky, 6);
        println!("{mode:?}: per-tile (column, row, du, dv, ncc) {s:.2?}");
        shifts.push(s);
    }
    // Tiles whose edges match well in both renders (NCC ≥ 0.25; the right edge of the middle
    // row shows cliffs beyond the DEM crop).
    let reliable: Vec<usize> = (0..8)
        .filter(|&k| shifts[0][k].4 >= 0.25 && shifts[1][k].4 >= 0.25)
        .collect();
    assert!(
        reliable.len() >= 6,
        "only {} tiles match the photo",
        reliable.len()
    );
    let len = |s: &(i64, i64, i64, i64, f64)| s.2.abs().max(s.3.abs());
    for &k in &reliable {
        assert!(
            len(&shifts[0][k]) <= 1,
            "with distortion, tile {:?} is off the photo",
            shifts[0][k]
        );
    }
    // Without the distortion the image corners are off by 2–3 px (towards the centre: barrel).
    let corner_off = reliable
        .iter()
        .filter(|&&k| shifts[0][k].0 % 3 == 0)
        .map(|&k| len(&shifts[1][k]))
        .max()
        .unwrap_or(0);
    assert!(
        corner_off >= 2,
        "without distortion the corner tiles should be off: {:?}",
        shifts[1]
    );
}
