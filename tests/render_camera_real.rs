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
    assert!((2.5..=3.5).contains(&rmse), "GCP RMSE {rmse:.3} px, the fit says ~3.0 px");
    // Every GCP lies in front of the camera and inside the photo.
    for (x, _) in &pts {
        let p = cam.project(*x).unwrap();
        assert!(p[0] >= 0.0 && p[1] >= 0.0 && p[0] < 4290.0 && p[1] < 2856.0);
    }
}

/// Normalized cross-correlation of the `r`-radius patch of `a` at `(ua, va)` with that of
/// `b` at `(ua + du, va + dv)`.
fn ncc(a: &image::GrayImage, b: &image::GrayImage, ua: i64, va: i64, du: i64, dv: i64, r: i64) -> f64 {
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
    if va_ <= 0.0 || vb <= 0.0 { 0.0 } else { cov / (va_ * vb).sqrt() }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
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
            if den.abs() > 1e-12 { 0.5 * (cm - cp) / den } else { 0.0 }
        };
        let (c0, du, dv) = best;
        let fu = sub(ncc(&a, &b, ua, va, du - 1, dv, r), c0, ncc(&a, &b, ua, va, du + 1, dv, r));
        let fv = sub(ncc(&a, &b, ua, va, du, dv - 1, r), c0, ncc(&a, &b, ua, va, du, dv + 1, r));
        mu.push(du as f64 + fu);
        mv.push(dv as f64 + fv);
        pu.push(q[0] - p[0]);
        pv.push(q[1] - p[1]);
    }
    let n = mu.len();
    let (mu, mv, pu, pv) = (median(mu), median(mv), median(pu), median(pv));
    println!("IMG_8937 vs IMG_8902 at {n} GCP patches: measured shift ({mu:.2}, {mv:.2}) px, predicted by the delta ({pu:.2}, {pv:.2}) px");
    assert!(n >= 10, "only {n} reliable matches");
    assert!((mu - pu).abs() < 2.0 && (mv - pv).abs() < 2.0, "measured ({mu:.2}, {mv:.2}) vs predicted ({pu:.2}, {pv:.2})");
    // The shift is substantial, so applying the delta with the wrong sign would fail.
    assert!(pu > 10.0, "predicted du {pu}");
}
