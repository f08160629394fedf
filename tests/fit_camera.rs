//! `cliffmap fit-camera` on Engabreen's 28 GCPs (ImGRAFT's fit: yaw, pitch, roll, fx, fy, k1
//! with the position fixed, 3.04 px RMSE with the `+` tokens summed) and on bad input.

mod cli_util;
mod common;

use cli_util::{cliffmap, ok};
use cliffmap::camera::camera_from_json_file;
use cliffmap::register::{PixelOrigin, gcp_rmse_px, read_gcps};
use common::exif::{ascii, exif_field, jpeg_with_exif, rationals};

fn path(rel: &str) -> String {
    common::real_data(rel).display().to_string()
}

/// GCP RMSE (px) of a camera file over the Engabreen GCPs.
fn rmse_of(camera: &std::path::Path) -> f64 {
    let cam = camera_from_json_file(camera, (0, 0)).unwrap();
    let gcps = read_gcps(
        &common::real_data("engabreen/gcp8902.txt"),
        PixelOrigin::Format,
    )
    .unwrap();
    let (rmse, n) = gcp_rmse_px(&cam, &gcps);
    assert_eq!(n, gcps.len());
    rmse
}

#[test]
fn engabreen_fit_matches_imgraft_from_its_camera_and_from_the_position_alone() {
    let dir = tempfile::tempdir().unwrap();
    let gcps = path("engabreen/gcp8902.txt");
    let free = "yaw,pitch,roll,fx,fy,k1";
    // from a start 2° / 1° / 3 % off ImGRAFT's camera
    let start = dir.path().join("start.json");
    let mut doc: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(common::real_data(
            "engabreen/engabreen_camera_IMG_8902.json",
        ))
        .unwrap(),
    )
    .unwrap();
    let ypr = doc["viewdir_yaw_pitch_roll_deg"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect::<Vec<_>>();
    doc.as_object_mut()
        .unwrap()
        .remove("viewdir_yaw_pitch_roll_rad");
    doc["viewdir_yaw_pitch_roll_deg"] =
        serde_json::json!([ypr[0] + 2.0, ypr[1] - 1.0, ypr[2] + 1.0]);
    doc["f_px"] = serde_json::json!([5830.0, 5840.0]);
    doc["k1"] = serde_json::json!(0.0);
    std::fs::write(&start, doc.to_string()).unwrap();
    let out = dir.path().join("fit.json");
    let o = ok(&[
        "fit-camera",
        "--gcps",
        &gcps,
        "--camera",
        start.to_str().unwrap(),
        "--free",
        free,
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rmse = report["rmse_px"].as_f64().unwrap();
    assert!(
        (rmse - 3.044).abs() < 0.01,
        "RMSE {rmse} px, ImGRAFT's fit 3.04 px"
    );
    assert!(
        (rmse_of(&out) - rmse).abs() < 1e-6,
        "the written camera reproduces the fit"
    );
    assert!(
        (report["params"]["yaw"].as_f64().unwrap() - 219.2258).abs() < 0.01,
        "{}",
        report["params"]
    );
    assert!((report["params"]["k1"].as_f64().unwrap() + 0.1145).abs() < 0.002);
    assert_eq!(report["residuals"].as_array().unwrap().len(), 28);
    for k in ["yaw", "pitch", "roll", "fx", "fy", "k1"] {
        let s = report["sigma"][k].as_f64().unwrap();
        assert!(s > 0.0 && s.is_finite(), "sigma {k} = {s}");
    }
    assert!(report["aic"].as_f64().unwrap().is_finite());
    // from the position alone (orientation from the GCP bearings, focal length searched)
    let out2 = dir.path().join("fit2.json");
    ok(&[
        "fit-camera",
        "--gcps",
        &gcps,
        "--position",
        "446722,7396671,770",
        "--size",
        "4290x2856",
        "--free",
        free,
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert!((rmse_of(&out2) - 3.044).abs() < 0.01, "{}", rmse_of(&out2));
    // from the GCPs alone (DLT + RANSAC start), the position free too
    let out3 = dir.path().join("fit3.json");
    let o = ok(&[
        "fit-camera",
        "--gcps",
        &gcps,
        "--size",
        "4290x2856",
        "--free",
        "angles,position,f,k1",
        "--out",
        out3.to_str().unwrap(),
    ]);
    // (P3P + RANSAC over the focal length search wins over the DLT here: 2026-12-04, a
    // start 3.2 m from the surveyed position, the fit 0.77 m from it at 2.49 px)
    assert!(String::from_utf8_lossy(&o.stderr).contains("P3P + RANSAC"));
    let cam = camera_from_json_file(&out3, (0, 0)).unwrap();
    let off = cam.position - glam::DVec3::new(446722.0, 7396671.0, 770.0);
    assert!(off.length() < 2.0, "{off:?} from the surveyed position");
    assert!(rmse_of(&out3) < 2.6, "{}", rmse_of(&out3));
    // four GCPs are enough for a start (P3P on three, the fourth to choose), the focal
    // length searched
    let text = std::fs::read_to_string(&gcps).unwrap();
    let four: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with('%') && !l.trim().is_empty())
        .take(4)
        .collect();
    let gcp4 = dir.path().join("gcp4.txt");
    std::fs::write(&gcp4, four.join("\n")).unwrap();
    let out4 = dir.path().join("fit4.json");
    let o = ok(&[
        "fit-camera",
        "--gcps",
        gcp4.to_str().unwrap(),
        "--size",
        "4290x2856",
        "--free",
        "angles,f",
        "--out",
        out4.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("P3P + RANSAC"));
    let cam = camera_from_json_file(&out4, (0, 0)).unwrap();
    let off = cam.position - glam::DVec3::new(446722.0, 7396671.0, 770.0);
    assert!(off.length() < 5.0, "{off:?} from the surveyed position");
}

#[test]
fn exif_focal_length_of_img_8902() {
    // Canon EOS Rebel T3, FocalLength 30 mm, no focal-plane resolution in the file: the
    // sensor width (22.0 mm) gives 5850 px, 2.7 % below the GCP fit's 6014 px
    let img = common::real_data("engabreen/IMG_8902.jpg");
    let f = cliffmap::camera::exif_focal_px(&img, 4290, 2856, Some(22.0))
        .unwrap()
        .unwrap();
    assert!((f.focal_px - 5850.0).abs() < 0.5, "{f:?}");
    assert_eq!(
        cliffmap::camera::exif_focal_px(&img, 4290, 2856, None).unwrap(),
        None
    );
    // the command starts from it
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cam.json");
    let o = ok(&[
        "fit-camera",
        "--gcps",
        &path("engabreen/gcp8902.txt"),
        "--position",
        "446722,7396671,770",
        "--image",
        img.to_str().unwrap(),
        "--sensor-width-mm",
        "22.0",
        "--free",
        "yaw,pitch,roll,fx,fy,k1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("from EXIF"));
    assert!((rmse_of(&out) - 3.044).abs() < 0.01);
}

#[test]
fn bad_gcp_input_fails_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "446238 7396055 586.4 816+9\n").unwrap();
    let out = dir.path().join("cam.json");
    let cam = path("engabreen/engabreen_camera_IMG_8902.json");
    for (gcps, want) in [
        (bad.to_str().unwrap(), "bad.txt"),
        ("/nonexistent/g.txt", "/nonexistent/g.txt"),
    ] {
        let o = cliffmap(&[
            "fit-camera",
            "--gcps",
            gcps,
            "--camera",
            &cam,
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want), "{err}");
    }
    let o = cliffmap(&[
        "fit-camera",
        "--gcps",
        &path("engabreen/gcp8902.txt"),
        "--camera",
        &cam,
        "--free",
        "zoom",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("zoom"));
    for bad in [["--focal-px", "0"], ["--huber-px", "0"]] {
        let o = cliffmap(&[
            "fit-camera",
            "--gcps",
            &path("engabreen/gcp8902.txt"),
            "--camera",
            &cam,
            bad[0],
            bad[1],
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            !o.status.success() && String::from_utf8_lossy(&o.stderr).contains(bad[0]),
            "{bad:?}"
        );
    }
    assert!(!out.exists(), "nothing written on failure");
}

#[test]
fn img_8937_registers_to_img_8902_on_stable_ground() {
    // ImGRAFT: viewdir change +0.12633°, +0.017584°, +0.015242° from rock features, 0.41 px
    let a = image::open(common::real_data("engabreen/IMG_8902.jpg"))
        .unwrap()
        .to_rgb8();
    let b = image::open(common::real_data("engabreen/IMG_8937.jpg"))
        .unwrap()
        .to_rgb8();
    let cam = camera_from_json_file(
        &common::real_data("engabreen/engabreen_camera_IMG_8902.json"),
        (0, 0),
    )
    .unwrap();
    let matches =
        cliffmap::register::match_photos(&a, &b, &cliffmap::register::MatchOptions::default())
            .unwrap();
    let dem = common::engabreen_dem();
    let mask = image::open(common::real_data(
        "engabreen/engabreen_glacier_mask_507x590.png",
    ))
    .unwrap()
    .to_luma8();
    let tracer = cliffmap::demo_scene::DemTracer::new(&dem, cam.position).unwrap();
    let rock = |p: glam::DVec3| {
        let (r, c) = dem.georef.grid(p.x, p.y);
        r >= -0.5
            && c >= -0.5
            && mask
                .get_pixel_checked(c.round() as u32, r.round() as u32)
                .is_some_and(|m| m.0[0] < 128)
    };
    let stable = cliffmap::register::stable_matches(
        &cam,
        &matches,
        |o, d| tracer.nearest(o, d, f64::INFINITY).map(|h| h.point),
        rock,
    );
    assert!(
        stable.len() >= 200,
        "{} stable matches of {}",
        stable.len(),
        matches.len()
    );
    let fit = cliffmap::register::fit_rotation(&cam, &stable).unwrap();
    assert!(
        fit.rmse_inliers_px < 0.5,
        "match residual {} px",
        fit.rmse_inliers_px
    );
    let (ya, pa, _) = cliffmap::camera::yaw_pitch_roll_from_rotation(&cam.world_to_camera);
    let (yb, pb, _) = cliffmap::camera::yaw_pitch_roll_from_rotation(&fit.camera.world_to_camera);
    let (dy, dp) = ((yb - ya).to_degrees(), (pb - pa).to_degrees());
    assert!(
        (dy - 0.12633).abs() < 0.005 && (dp - 0.017584).abs() < 0.005,
        "{dy} {dp}"
    );
}

#[test]
fn gps_position_altitude_and_heading_are_read_with_their_references() {
    use cliffmap::camera::exif_gps;
    use exif::Tag;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("gps.jpg");
    jpeg_with_exif(
        &p,
        &[
            exif_field(Tag::GPSLatitudeRef, ascii("S")),
            exif_field(
                Tag::GPSLatitude,
                rationals(&[(66, 1), (41, 1), (1230, 100)]),
            ),
            exif_field(Tag::GPSLongitudeRef, ascii("W")),
            exif_field(Tag::GPSLongitude, rationals(&[(13, 1), (30, 1), (0, 1)])),
            exif_field(Tag::GPSAltitudeRef, exif::Value::Byte(vec![1])),
            exif_field(Tag::GPSAltitude, rationals(&[(7705, 10)])),
            exif_field(Tag::GPSImgDirectionRef, ascii("M")),
            exif_field(Tag::GPSImgDirection, rationals(&[(21925, 100)])),
        ],
    );
    let g = exif_gps(&p).unwrap().unwrap();
    assert!(
        (g.lat_deg + (66.0 + 41.0 / 60.0 + 12.3 / 3600.0)).abs() < 1e-12,
        "{g:?}"
    );
    assert!((g.lon_deg + 13.5).abs() < 1e-12);
    assert_eq!(g.altitude_m, Some(-770.5));
    assert_eq!(g.direction_deg, Some(219.25));
    assert!(g.direction_magnetic);
    // a latitude beyond the pole is refused, naming the file
    let bad = dir.path().join("bad.jpg");
    jpeg_with_exif(
        &bad,
        &[
            exif_field(Tag::GPSLatitude, rationals(&[(95, 1)])),
            exif_field(Tag::GPSLongitude, rationals(&[(1, 1)])),
        ],
    );
    let e = exif_gps(&bad).unwrap_err().to_string();
    assert!(e.contains("bad.jpg") && e.contains("latitude"), "{e}");
    // no GPS fields, or no EXIF at all: none
    let none = dir.path().join("none.jpg");
    jpeg_with_exif(
        &none,
        &[exif_field(Tag::FocalLength, rationals(&[(30, 1)]))],
    );
    assert_eq!(exif_gps(&none).unwrap(), None);
    let plain = dir.path().join("plain.png");
    image::RgbImage::new(4, 3).save(&plain).unwrap();
    assert_eq!(exif_gps(&plain).unwrap(), None);
}

#[test]
fn exif_gps_fix_gives_the_start_position_in_the_crs() {
    // IMG_8902's surveyed position (446722, 7396671, 770) in UTM 33N is 66°41'2.4612" N,
    // 13°47'37.2190" E (pyproj), i.e. within 2 mm after rounding to 1e-4 seconds
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("gps.jpg");
    let dms = |v: [u32; 3]| rationals(&[(v[0], 1), (v[1], 1), (v[2], 10_000)]);
    jpeg_with_exif(
        &img,
        &[
            exif_field(exif::Tag::GPSLatitudeRef, ascii("N")),
            exif_field(exif::Tag::GPSLatitude, dms([66, 41, 24612])),
            exif_field(exif::Tag::GPSLongitudeRef, ascii("E")),
            exif_field(exif::Tag::GPSLongitude, dms([13, 47, 372190])),
            exif_field(exif::Tag::GPSAltitude, rationals(&[(7700, 10)])),
        ],
    );
    let out = dir.path().join("fit.json");
    let o = ok(&[
        "fit-camera",
        "--gcps",
        &path("engabreen/gcp8902.txt"),
        "--image",
        img.to_str().unwrap(),
        "--crs",
        "EPSG:32633",
        "--size",
        "4290x2856",
        "--free",
        "yaw,pitch,roll,fx,fy,k1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("start position from EXIF GPS"), "{err}");
    assert!(err.contains("m from the GPS fix"), "{err}");
    let cam = camera_from_json_file(&out, (0, 0)).unwrap();
    let off = cam.position - glam::DVec3::new(446722.0, 7396671.0, 770.0);
    assert!(off.length() < 0.01, "{off:?}");
    // the same fit as from the surveyed position (ImGRAFT's 3.04 px)
    assert!((rmse_of(&out) - 3.044).abs() < 0.01, "{}", rmse_of(&out));
    // a wrong CRS code is an error, not a silent position
    cli_util::fails_naming(
        &[
            "fit-camera",
            "--gcps",
            &path("engabreen/gcp8902.txt"),
            "--image",
            img.to_str().unwrap(),
            "--crs",
            "EPSG:1",
            "--size",
            "4290x2856",
            "--out",
            out.to_str().unwrap(),
        ],
        "EPSG:1",
    );
}

/// `fit-camera --store` (issue #52): the GCPs' heights against the terrain, the fitted camera
/// placed above it; the same GCPs in `U V X Y Z` order give the same camera, with a note.
#[test]
fn fit_camera_checks_against_the_store_and_reads_pixel_first_gcps() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("store");
    let dem = common::real_data("engabreen/engabreen_dem_3m_507x590.f32");
    cli_util::ok(&[
        "build",
        "--dem",
        dem.to_str().unwrap(),
        "--width",
        "507",
        "--height",
        "590",
        "--spacing",
        "3",
        "--origin",
        "445302.17,7396769.45",
        "--max-error",
        "2",
        "--cell-texels",
        "32",
        "--out",
        store.to_str().unwrap(),
        "--quiet",
    ]);
    let gcps = path("engabreen/gcp8902.txt");
    let cam = path("engabreen/engabreen_camera_IMG_8902.json");
    let out = dir.path().join("cam.json");
    let fit = |gcps: &str, out: &std::path::Path| {
        cliffmap(&[
            "fit-camera",
            "--gcps",
            gcps,
            "--camera",
            &cam,
            "--store",
            store.to_str().unwrap(),
            "--json",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = fit(&gcps, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let t = &j["terrain"];
    // the fixed camera stands ~20-60 m above the valley side below it; the GCPs lie on the DEM
    let above = t["camera_height_above_ground_m"].as_f64().unwrap();
    assert!(
        above > 0.0 && !t["camera_underground"].as_bool().unwrap(),
        "{t}"
    );
    assert!(t["gcps_on_terrain"].as_u64().unwrap() >= 20, "{t}");
    assert!(
        t["gcp_height_minus_surface_median_abs_m"].as_f64().unwrap() < 5.0,
        "{t}"
    );
    // the same file with the pixel columns first
    let text = std::fs::read_to_string(&gcps).unwrap();
    let swapped: String = text
        .lines()
        .map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            if t.len() >= 5 && !l.trim_start().starts_with('%') {
                format!("{} {} {} {} {}\n", t[3], t[4], t[0], t[1], t[2])
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let p = dir.path().join("uvxyz.txt");
    std::fs::write(&p, swapped).unwrap();
    let out2 = dir.path().join("cam2.json");
    let o = fit(p.to_str().unwrap(), &out2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && err.contains("read as U V X Y Z"),
        "{err}"
    );
    assert!((rmse_of(&out2) - rmse_of(&out)).abs() < 1e-6);
}
