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
