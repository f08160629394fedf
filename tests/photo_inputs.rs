//! Photo inputs: photos.json (cliffmap and ImGRAFT cameras, rotation deltas), COLMAP text
//! models with a similarity to the world frame, and the errors for bad input.

mod common;

use std::path::{Path, PathBuf};

use cliffmap::camera::{CameraModel, camera_from_json_file, camera_to_json, rotation_look_at};
use cliffmap::camera::{apply_rotation_delta, validate_camera};
use cliffmap::photo::{read_colmap, read_colmap_specs, read_photo_list, read_photo_specs};
use glam::{DMat3, DQuat, DVec3};

fn write(path: &Path, text: &str) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

fn write_png(path: &Path, w: u32, h: u32) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    image::RgbImage::from_fn(w, h, |x, y| {
        image::Rgb([(x % 256) as u8, (y % 256) as u8, 7])
    })
    .save(path)
    .unwrap();
}

fn test_camera(w: u32, h: u32) -> CameraModel {
    let pos = DVec3::new(431_500.0, 6_877_400.0, 612.0);
    let rot = rotation_look_at(pos, DVec3::new(431_300.0, 6_877_600.0, 640.0)).unwrap();
    let mut c = CameraModel::with_fov(pos, rot, w, h, 0.7);
    c.k1 = -0.05;
    c.k2 = 0.01;
    c.cx += 2.25;
    c
}

fn err_of<T: std::fmt::Debug>(r: cliffmap::Result<T>) -> String {
    r.unwrap_err().to_string()
}

#[test]
fn photo_list_with_cliffmap_and_imgraft_cameras() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("set");
    write_png(&dir.join("img/a.png"), 64, 48);
    let cam = test_camera(128, 96); // twice the image size: same aspect, resized on read
    write(&dir.join("cams/a.json"), &camera_to_json(&cam).to_string());
    let eng_img = common::real_data("engabreen/IMG_8902.jpg");
    let eng_cam = common::real_data("engabreen/engabreen_camera_IMG_8902.json");
    let list = serde_json::json!({"photos": [
        {"image": "img/a.png", "camera": "cams/a.json"},
        {"image": eng_img, "imgraft": eng_cam},
        {"image": eng_img, "imgraft": eng_cam, "rotation_delta_deg": [0.12633, 0.017584, 0.015242]},
    ]});
    write(&dir.join("photos.json"), &list.to_string());
    let specs = read_photo_specs(&dir.join("photos.json")).unwrap();
    assert_eq!(specs.len(), 3);
    assert_eq!(specs[0].name, "a.png");
    assert_eq!(specs[0].image_path, dir.join("img/a.png"));
    let a = specs[0].camera;
    assert_eq!((a.width, a.height), (64, 48));
    assert!((a.fov_y() - cam.fov_y()).abs() < 1e-12);
    assert!(
        (a.fx - cam.fx / 2.0).abs() < 1e-9 && (a.cx - ((cam.cx + 0.5) / 2.0 - 0.5)).abs() < 1e-9
    );
    let direct = camera_from_json_file(&eng_cam, (1, 1)).unwrap();
    assert_eq!(specs[1].camera, direct);
    // The delta is ImGRAFT's camB.viewdir = camA.viewdir + delta.
    let b = specs[2].camera;
    assert_eq!(
        b,
        apply_rotation_delta(&direct, [0.12633, 0.017584, 0.015242])
    );
    assert_eq!(
        (b.position, b.fx, b.k1),
        (direct.position, direct.fx, direct.k1)
    );
    let angle = (b.forward().dot(direct.forward()))
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees();
    assert!(
        (angle - 0.12633f64.hypot(0.017584) * 0.995).abs() < 0.01,
        "axis turned {angle}°"
    );
    // Decoding: only the small photo (the Engabreen one is decoded by the GCP test).
    write(
        &dir.join("one.json"),
        r#"{"photos": [{"image": "img/a.png", "camera": "cams/a.json"}]}"#,
    );
    let photos = read_photo_list(&dir.join("one.json")).unwrap();
    assert_eq!(photos[0].image.dimensions(), (64, 48));
    assert_eq!(photos[0].image.get_pixel(5, 9).0, [5, 9, 7]);
    assert_eq!(photos[0].camera, a);
}

#[test]
fn bad_photo_lists_are_clear_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write_png(&d.join("a.png"), 64, 48);
    write(
        &d.join("a.json"),
        &camera_to_json(&test_camera(64, 48)).to_string(),
    );
    write(
        &d.join("wide.json"),
        &camera_to_json(&test_camera(64, 32)).to_string(),
    );
    write(
        &d.join("zero_f.json"),
        r#"{"position":[0,0,0],"yaw_deg":0,"pitch_deg":0,"fx":0,"width":64,"height":48}"#,
    );
    write(
        &d.join("neg_f.json"),
        r#"{"position":[0,0,0],"yaw_deg":0,"pitch_deg":0,"fx":-10,"width":64,"height":48}"#,
    );
    write(
        &d.join("nan.json"),
        r#"{"position":[0,NaN,0],"yaw_deg":0,"pitch_deg":0,"fov_y_deg":40}"#,
    );
    write(&d.join("garbage.jpg"), "not a jpeg");
    // a JPEG cut short (issue #20: its missing part used to be projected as grey)
    let noise = image::RgbImage::from_fn(64, 48, |x, y| {
        image::Rgb([
            (x * 37 % 251) as u8,
            (y * 91 % 241) as u8,
            ((x * y) % 256) as u8,
        ])
    });
    noise.save(d.join("full.jpg")).unwrap();
    let bytes = std::fs::read(d.join("full.jpg")).unwrap();
    std::fs::write(d.join("cut.jpg"), &bytes[..bytes.len() * 3 / 5]).unwrap();
    assert_eq!(
        cliffmap::fsutil::decode_rgb8(&d.join("full.jpg")).unwrap(),
        image::open(d.join("full.jpg")).unwrap().to_rgb8()
    );
    let cases: &[(&str, &str, &str)] = &[
        (
            r#"{"photos": [{"image": "cut.jpg", "camera": "a.json"}]}"#,
            "cut.jpg",
            "truncated",
        ),
        (
            r#"{"photos": [{"image": "missing.jpg", "camera": "a.json"}]}"#,
            "missing.jpg",
            "No such file",
        ),
        (
            r#"{"photos": [{"image": "garbage.jpg", "camera": "a.json"}]}"#,
            "garbage.jpg",
            "cannot read image",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camera": "nope.json"}]}"#,
            "nope.json",
            "No such file",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camera": "zero_f.json"}]}"#,
            "zero_f.json",
            "focal",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camera": "neg_f.json"}]}"#,
            "neg_f.json",
            "focal",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camera": "nan.json"}]}"#,
            "nan.json",
            "invalid JSON",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camera": "wide.json"}]}"#,
            "wide.json",
            "aspect",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camera": "a.json", "imgraft": "a.json"}]}"#,
            "photos.json",
            "exactly one",
        ),
        (
            r#"{"photos": [{"image": "a.png"}]}"#,
            "photos.json",
            "exactly one",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camera": "a.json", "rotation_delta_deg": [1, 2]}]}"#,
            "photos.json",
            "invalid photo list",
        ),
        (
            r#"{"photos": [{"image": "a.png", "camrea": "a.json"}]}"#,
            "photos.json",
            "unknown field",
        ),
        (r#"{"photos": []}"#, "photos.json", "empty"),
        (r#"{"pictures": []}"#, "photos.json", "invalid photo list"),
    ];
    for (text, names, says) in cases {
        write(&d.join("photos.json"), text);
        let e = err_of(read_photo_list(&d.join("photos.json")));
        assert!(e.contains(names) && e.contains(says), "{text}: {e}");
    }
    assert!(err_of(read_photo_list(&d.join("absent.json"))).contains("absent.json"));
    // validate_camera catches what a hand-made or converted camera can get wrong.
    let good = test_camera(64, 48);
    assert!(validate_camera(&good, Path::new("x.json")).is_ok());
    let mut bad = good;
    bad.position.y = f64::NAN;
    assert!(err_of(validate_camera(&bad, Path::new("x.json"))).contains("x.json"));
    bad = good;
    bad.world_to_camera = DMat3::from_cols(DVec3::X, DVec3::X, DVec3::Z);
    assert!(err_of(validate_camera(&bad, Path::new("x.json"))).contains("orthonormal"));
    bad = good;
    bad.width = 0;
    assert!(err_of(validate_camera(&bad, Path::new("x.json"))).contains("size"));
    bad = good;
    bad.fy = 0.0;
    assert!(err_of(validate_camera(&bad, Path::new("x.json"))).contains("focal"));
}

/// Similarity used by the COLMAP tests: world = s·R·colmap + t.
fn similarity() -> (f64, DMat3, DVec3) {
    let r = DMat3::from_quat(DQuat::from_axis_angle(
        DVec3::new(0.3, -0.5, 0.8).normalize(),
        1.1,
    ));
    (37.5, r, DVec3::new(431_000.0, 6_877_000.0, 500.0))
}

/// Writes a COLMAP model of `cams` (one COLMAP camera each, `model` line built by `line`)
/// into `dir` with `transform.json`, with images of the cameras' sizes in `dir/images`.
fn write_colmap(dir: &Path, cams: &[CameraModel], line: impl Fn(&CameraModel) -> String) {
    let (s, rt, t) = similarity();
    let mut cameras = String::from(
        "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n",
    );
    let mut images = String::from(
        "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n",
    );
    for (i, c) in cams.iter().enumerate() {
        cameras += &format!("{} {}\n", i + 1, line(c));
        // COLMAP frame: colmap = Rtᵀ(world − t)/s; rotation R_c = R_w·Rt; centre C_c.
        let rc = c.world_to_camera * rt;
        let centre = rt.transpose() * (c.position - t) / s;
        let tc = -(rc * centre);
        let q = DQuat::from_mat3(&rc);
        let q = if i % 2 == 1 { -q } else { q }; // both signs are the same rotation
        let name = format!("photo {i}.png");
        images += &format!(
            "{} {} {} {} {} {} {} {} {} {}\n",
            i + 1,
            q.w,
            q.x,
            q.y,
            q.z,
            tc.x,
            tc.y,
            tc.z,
            i + 1,
            name
        );
        images += if i == 0 {
            "\n"
        } else {
            "12.5 30.25 -1 40.0 50.0 7\n"
        };
        write_png(&dir.join("images").join(&name), c.width, c.height);
    }
    write(&dir.join("cameras.txt"), &cameras);
    write(&dir.join("images.txt"), &images);
    let r: Vec<[f64; 3]> = (0..3).map(|i| rt.row(i).to_array()).collect();
    write(
        &dir.join("transform.json"),
        &serde_json::json!({"scale": s, "rotation": r, "translation": t.to_array()}).to_string(),
    );
}

fn assert_same_projection(a: &CameraModel, b: &CameraModel) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert!(
        (a.position - b.position).length() < 1e-6,
        "{} vs {}",
        a.position,
        b.position
    );
    let mut n = 0;
    for i in 0..400 {
        let (fi, fj) = ((i % 20) as f64 / 19.0, (i / 20) as f64 / 19.0);
        let Some(d) = a.pixel_ray(fi * (a.width - 1) as f64, fj * (a.height - 1) as f64) else {
            continue;
        };
        let x = a.position + (50.0 + 7.0 * i as f64) * d;
        let (p, q) = (a.project(x).unwrap(), b.project(x).unwrap());
        assert!(
            (p[0] - q[0]).abs() < 1e-6 && (p[1] - q[1]).abs() < 1e-6,
            "{p:?} vs {q:?}"
        );
        n += 1;
    }
    assert_eq!(n, 400);
}

#[test]
fn colmap_round_trip_through_a_similarity() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("colmap");
    let mut second = test_camera(80, 60);
    second.position += DVec3::new(40.0, -25.0, 3.0);
    second.world_to_camera =
        rotation_look_at(second.position, DVec3::new(431_350.0, 6_877_700.0, 600.0)).unwrap();
    second.fy = second.fx;
    let cams = [test_camera(96, 72), second];
    // RADIAL for both: f cx cy k1 k2 (COLMAP principal point: +0.5, corner origin).
    write_colmap(&dir, &cams, |c| {
        format!(
            "RADIAL {} {} {} {} {} {} {}",
            c.width,
            c.height,
            c.fx,
            c.cx + 0.5,
            c.cy + 0.5,
            c.k1,
            c.k2
        )
    });
    let specs = read_colmap_specs(&dir).unwrap();
    assert_eq!(specs.len(), 2);
    assert_eq!(specs[1].name, "photo 1.png");
    for (s, c) in specs.iter().zip(&cams) {
        assert_same_projection(c, &s.camera);
    }
    // Decoded photos come from DIR/images.
    let photos = read_colmap(&dir).unwrap();
    assert_eq!(photos[0].image.dimensions(), (96, 72));

    // Pinhole models, at half the COLMAP size of the image files (resized on read).
    for model in ["PINHOLE", "SIMPLE_PINHOLE", "SIMPLE_RADIAL", "OPENCV"] {
        let d = tmp.path().join(model);
        let mut c = test_camera(96, 72);
        c.fy = c.fx;
        c.k2 = 0.0;
        if model.contains("PINHOLE") {
            c.k1 = 0.0;
        }
        write_colmap(&d, &[c], |c| match model {
            "PINHOLE" => format!(
                "PINHOLE 48 36 {} {} {} {}",
                c.fx / 2.0,
                c.fy / 2.0,
                (c.cx + 0.5) / 2.0,
                (c.cy + 0.5) / 2.0
            ),
            "SIMPLE_PINHOLE" => format!(
                "SIMPLE_PINHOLE 48 36 {} {} {}",
                c.fx / 2.0,
                (c.cx + 0.5) / 2.0,
                (c.cy + 0.5) / 2.0
            ),
            "SIMPLE_RADIAL" => format!(
                "SIMPLE_RADIAL 48 36 {} {} {} {}",
                c.fx / 2.0,
                (c.cx + 0.5) / 2.0,
                (c.cy + 0.5) / 2.0,
                c.k1
            ),
            _ => format!(
                "OPENCV 48 36 {} {} {} {} {} 0 0 0",
                c.fx / 2.0,
                c.fy / 2.0,
                (c.cx + 0.5) / 2.0,
                (c.cy + 0.5) / 2.0,
                c.k1
            ),
        });
        let got = read_colmap_specs(&d).unwrap();
        assert_same_projection(&c, &got[0].camera);
    }
    // Without transform.json the COLMAP frame is the world frame; images may sit in DIR.
    let plain = tmp.path().join("plain");
    write(
        &plain.join("cameras.txt"),
        "1 SIMPLE_PINHOLE 40 30 50 20 15\n",
    );
    write(&plain.join("images.txt"), "1 1 0 0 0 0 0 0 1 p.png\n\n");
    write_png(&plain.join("p.png"), 40, 30);
    let c = read_colmap_specs(&plain).unwrap()[0].camera;
    assert_eq!(
        (c.position, c.world_to_camera, c.cx, c.cy),
        (DVec3::ZERO, DMat3::IDENTITY, 19.5, 14.5)
    );
    assert_eq!(c.project(DVec3::new(0.0, 0.0, 10.0)), Some([19.5, 14.5]));
}

#[test]
fn bad_colmap_models_are_clear_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let good_images = "1 1 0 0 0 0 0 0 1 p.png\n\n";
    let cases: &[(&str, &str, Option<&str>, &str, &str)] = &[
        (
            "1 SIMPLE_PINHOLE 40 30 0 20 15\n",
            good_images,
            None,
            "cameras.txt",
            "focal",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 -5 20 15\n",
            good_images,
            None,
            "cameras.txt",
            "focal",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 nan 20 15\n",
            good_images,
            None,
            "cameras.txt",
            "finite",
        ),
        (
            "1 SIMPLE_PINHOLE 0 30 50 20 15\n",
            good_images,
            None,
            "cameras.txt",
            "positive",
        ),
        (
            "1 FISHEYE 40 30 50 20 15 0.1\n",
            good_images,
            None,
            "cameras.txt",
            "not supported",
        ),
        (
            "1 OPENCV 40 30 50 50 20 15 0.1 0 0.01 0\n",
            good_images,
            None,
            "cameras.txt",
            "tangential",
        ),
        (
            "1 PINHOLE 40 30 50 20 15\n",
            good_images,
            None,
            "cameras.txt",
            "needs 4",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 50 20 15\n",
            "1 1 0 0 0 0 0 0 2 p.png\n\n",
            None,
            "images.txt",
            "camera 2",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 50 20 15\n",
            "1 0 0 0 0 0 0 0 1 p.png\n\n",
            None,
            "images.txt",
            "quaternion",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 50 20 15\n",
            "1 1 0 0 0 0 0 0 1 gone.png\n\n",
            None,
            "gone.png",
            "No such file",
        ),
        (
            "1 SIMPLE_PINHOLE 40 20 50 20 10\n",
            good_images,
            None,
            "cameras.txt",
            "aspect",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 50 20 15\n",
            good_images,
            Some(r#"{"scale": 1, "rotation": [[1,0,0],[0,1,0],[0,0,2]]}"#),
            "transform.json",
            "orthonormal",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 50 20 15\n",
            good_images,
            Some(r#"{"scale": 0}"#),
            "transform.json",
            "positive",
        ),
        (
            "1 SIMPLE_PINHOLE 40 30 50 20 15\n",
            good_images,
            Some(r#"{"scale": 1, "rotation": [[0,1,0],[1,0,0],[0,0,1]]}"#),
            "transform.json",
            "determinant",
        ),
    ];
    for (i, (cams, imgs, tf, names, says)) in cases.iter().enumerate() {
        let d: PathBuf = tmp.path().join(format!("case{i}"));
        write(&d.join("cameras.txt"), cams);
        write(&d.join("images.txt"), imgs);
        if let Some(tf) = tf {
            write(&d.join("transform.json"), tf);
        }
        write_png(&d.join("p.png"), 40, 30);
        let e = err_of(read_colmap_specs(&d));
        assert!(e.contains(names) && e.contains(says), "case {i}: {e}");
    }
    assert!(err_of(read_colmap_specs(&tmp.path().join("nothing"))).contains("cameras.txt"));
}
