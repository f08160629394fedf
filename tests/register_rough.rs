//! Rough cameras for `cliffmap register` from a photo's EXIF data (GPS fix, compass
//! heading, focal length) and a `"rough"` entry of `photos.json` (`register::rough_camera`),
//! and the photo list's handling of such entries.

mod common;

use cliffmap::camera::RoughPose;
use cliffmap::camera::rough_camera;
use cliffmap::camera::yaw_pitch_roll_from_rotation;
use cliffmap::photo::{PhotoEntry, read_photo_entries, read_photo_specs};
use common::exif::{ascii, exif_field, jpeg_with_exif, rationals};
use exif::Tag;

/// IMG_8902's surveyed position (446722, 7396671) in UTM 33N as EXIF degrees, minutes and
/// 1e-4 seconds (pyproj; within 2 mm), with the altitude, a magnetic heading and the 35-mm
/// focal length.
fn gps_jpeg(path: &std::path::Path, with_direction: bool) {
    let dms = |v: [u32; 3]| rationals(&[(v[0], 1), (v[1], 1), (v[2], 10_000)]);
    let mut fields = vec![
        exif_field(Tag::GPSLatitudeRef, ascii("N")),
        exif_field(Tag::GPSLatitude, dms([66, 41, 24612])),
        exif_field(Tag::GPSLongitudeRef, ascii("E")),
        exif_field(Tag::GPSLongitude, dms([13, 47, 372190])),
        exif_field(Tag::GPSAltitude, rationals(&[(7800, 10)])),
        exif_field(Tag::FocalLengthIn35mmFilm, exif::Value::Short(vec![35])),
    ];
    if with_direction {
        fields.push(exif_field(Tag::GPSImgDirectionRef, ascii("M")));
        fields.push(exif_field(Tag::GPSImgDirection, rationals(&[(21925, 100)])));
    }
    jpeg_with_exif(path, &fields);
}

fn heading_of(cam: &cliffmap::camera::CameraModel) -> f64 {
    let (yaw, _, _) = yaw_pitch_roll_from_rotation(&cam.world_to_camera);
    (90.0 - yaw.to_degrees()).rem_euclid(360.0)
}

#[test]
fn exif_gps_heading_and_focal_length_give_the_rough_camera() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("gps.jpg");
    gps_jpeg(&img, true);
    let ground = |_x: f64, _y: f64| Some(700.0);
    let pose = RoughPose {
        declination_deg: Some(2.5),
        pitch_deg: 3.0,
        ..RoughPose::default()
    };
    let r = rough_camera(&img, (8, 8), &pose, Some("EPSG:32633"), &ground).unwrap();
    let c = r.camera;
    assert!((c.position.x - 446722.0).abs() < 0.01, "{:?}", c.position);
    assert!((c.position.y - 7396671.0).abs() < 0.01, "{:?}", c.position);
    // a photographer on the ground, not the GPS altitude (780 m)
    assert!((c.position.z - 701.6).abs() < 1e-9, "{:?}", c.position);
    assert!((heading_of(&c) - 221.75).abs() < 1e-9, "{}", heading_of(&c));
    let (_, pitch, roll) = yaw_pitch_roll_from_rotation(&c.world_to_camera);
    assert!((pitch.to_degrees() - 3.0).abs() < 1e-9 && roll.abs() < 1e-9);
    let f35 = 35.0 * (8f64 * 8.0 * 2.0).sqrt() / (36f64.hypot(24.0));
    assert!((c.fx - f35).abs() < 1e-6 && c.fx == c.fy, "{} {f35}", c.fx);
    let notes = r.notes.join("\n");
    assert!(
        notes.contains("EXIF GPS") && notes.contains("EPSG:32633"),
        "{notes}"
    );
    assert!(notes.contains("differs by +78.4 m"), "{notes}");
    assert!(notes.contains("declination +2.50"), "{notes}");

    // the entry's values win over EXIF; the store's CRS is not needed then
    let given = RoughPose {
        position: Some(vec![10.0, 20.0]),
        height_above_ground_m: Some(5.0),
        heading_deg: Some(90.0),
        focal_px: Some(1234.0),
        ..RoughPose::default()
    };
    let r = rough_camera(&img, (8, 8), &given, None, &ground).unwrap();
    assert_eq!(r.camera.position, glam::DVec3::new(10.0, 20.0, 705.0));
    assert!((heading_of(&r.camera) - 90.0).abs() < 1e-9);
    assert_eq!(r.camera.fx, 1234.0);
    // the GPS altitude when asked for; a full position as given
    let alt = RoughPose {
        use_gps_altitude: true,
        ..RoughPose::default()
    };
    let r = rough_camera(&img, (8, 8), &alt, Some("EPSG:32633"), &ground).unwrap();
    assert!((r.camera.position.z - 780.0).abs() < 1e-9);
    let full = RoughPose {
        position: Some(vec![1.0, 2.0, 3.0]),
        ..RoughPose::default()
    };
    let r = rough_camera(&img, (8, 8), &full, None, &|_, _| None).unwrap();
    assert_eq!(r.camera.position, glam::DVec3::new(1.0, 2.0, 3.0));
}

#[test]
fn a_rough_pose_missing_a_value_is_an_error_naming_the_image_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("gps.jpg");
    gps_jpeg(&img, false);
    let plain = dir.path().join("plain.png");
    image::RgbImage::new(8, 8).save(&plain).unwrap();
    let ground = |_x: f64, _y: f64| Some(0.0);
    let err = |path: &std::path::Path, pose: RoughPose, crs: Option<&str>, over: bool| {
        let g = move |x: f64, y: f64| if over { ground(x, y) } else { None };
        rough_camera(path, (8, 8), &pose, crs, &g)
            .unwrap_err()
            .to_string()
    };
    let heading = || RoughPose {
        heading_deg: Some(10.0),
        ..RoughPose::default()
    };
    let cases = [
        (
            err(&plain, heading(), Some("EPSG:32633"), true),
            "plain.png",
            "\"position\"",
        ),
        (err(&img, heading(), None, true), "gps.jpg", "\"crs\""),
        (
            err(&img, heading(), Some("EPSG:32633"), false),
            "gps.jpg",
            "[x, y, z]",
        ),
        (
            err(&img, RoughPose::default(), Some("EPSG:32633"), true),
            "gps.jpg",
            "\"heading_deg\"",
        ),
        (
            err(
                &plain,
                RoughPose {
                    position: Some(vec![0.0, 0.0]),
                    ..heading()
                },
                None,
                true,
            ),
            "plain.png",
            "\"focal_px\"",
        ),
        (
            err(
                &plain,
                RoughPose {
                    position: Some(vec![0.0, 0.0]),
                    use_gps_altitude: true,
                    focal_px: Some(100.0),
                    ..heading()
                },
                None,
                true,
            ),
            "plain.png",
            "altitude",
        ),
        (
            err(
                &img,
                RoughPose {
                    position: Some(vec![0.0]),
                    ..heading()
                },
                None,
                true,
            ),
            "gps.jpg",
            "\"position\"",
        ),
        (
            err(&img, heading(), Some("EPSG:1"), true),
            "EPSG:1",
            "EPSG:1",
        ),
    ];
    for (e, file, field) in cases {
        assert!(e.contains(file) && e.contains(field), "{file} {field}: {e}");
    }
}

#[test]
fn photo_lists_keep_rough_entries_for_register_and_refuse_them_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("gps.jpg");
    gps_jpeg(&img, true);
    let list = dir.path().join("photos.json");
    std::fs::write(
        &list,
        r#"{"photos": [{"image": "gps.jpg", "rough": {"pitch_deg": 2, "declination_deg": 1.5}}]}"#,
    )
    .unwrap();
    let entries = read_photo_entries(&list).unwrap();
    match &entries[..] {
        [
            PhotoEntry::Rough {
                name, size, pose, ..
            },
        ] => {
            assert_eq!((name.as_str(), *size), ("gps.jpg", (8, 8)));
            assert_eq!(pose.pitch_deg, 2.0);
            assert_eq!(pose.declination_deg, Some(1.5));
        }
        other => panic!("{other:?}"),
    }
    let e = read_photo_specs(&list).unwrap_err().to_string();
    assert!(
        e.contains("photos.json") && e.contains("cliffmap register"),
        "{e}"
    );
    for (body, says) in [
        (
            r#"{"photos": [{"image": "gps.jpg", "rough": {"pitch": 2}}]}"#,
            "pitch",
        ),
        (
            r#"{"photos": [{"image": "gps.jpg", "rough": {"heading_deg": 1e400}}]}"#,
            "photos.json",
        ),
        (
            r#"{"photos": [{"image": "gps.jpg", "rough": {"focal_px": -3}}]}"#,
            "focal_px",
        ),
        (
            r#"{"photos": [{"image": "gps.jpg", "rough": {}, "camera": "c.json"}]}"#,
            "exactly one",
        ),
        (
            r#"{"photos": [{"image": "gps.jpg", "rough": {}, "rotation_delta_deg": [1, 0, 0]}]}"#,
            "rotation_delta_deg",
        ),
        (
            r#"{"photos": [{"image": "absent.jpg", "rough": {}}]}"#,
            "absent.jpg",
        ),
    ] {
        std::fs::write(&list, body).unwrap();
        let e = read_photo_entries(&list).unwrap_err().to_string();
        assert!(e.contains(says), "{body}: {e}");
    }
}

/// Issue #52: a rough entry can carry its lens: `focal_px` with `k1`/`k2`, or a `lens`
/// camera file (its intrinsics scaled to the photo, its pose ignored), the entry's values
/// over the file's; the photo list resolves `lens` against its folder.
#[test]
fn a_rough_entry_carries_its_lens() {
    let dir = tempfile::tempdir().unwrap();
    let img = dir.path().join("webcam.png");
    image::RgbImage::new(400, 300).save(&img).unwrap();
    let ground = |_x: f64, _y: f64| Some(100.0);
    let base = RoughPose {
        position: Some(vec![10.0, 20.0]),
        heading_deg: Some(45.0),
        ..RoughPose::default()
    };
    // focal length and distortion in the entry
    let given = RoughPose {
        focal_px: Some(350.0),
        k1: Some(-0.25),
        k2: Some(0.02),
        ..base.clone()
    };
    let c = rough_camera(&img, (400, 300), &given, None, &ground)
        .unwrap()
        .camera;
    assert_eq!((c.fx, c.fy, c.k1, c.k2), (350.0, 350.0, -0.25, 0.02));
    // a lens file for a camera of twice the size: intrinsics halved, pose ignored
    let lens = dir.path().join("lens.json");
    std::fs::write(
        &lens,
        r#"{"position": [0, 0, 0], "yaw_deg": 0, "pitch_deg": 0, "width": 800, "height": 600,
            "fx": 700, "fy": 710, "cx": 404, "cy": 296, "k1": -0.2, "k2": 0.01}"#,
    )
    .unwrap();
    let with_lens = RoughPose {
        lens: Some(lens.clone()),
        ..base.clone()
    };
    let r = rough_camera(&img, (400, 300), &with_lens, None, &ground).unwrap();
    let c = r.camera;
    assert!(
        (c.fx - 350.0).abs() < 1e-9 && (c.fy - 355.0).abs() < 1e-9,
        "{c:?}"
    );
    assert!(
        (c.cx - 201.75).abs() < 1e-9 && (c.cy - 147.75).abs() < 1e-9,
        "{c:?}"
    );
    assert_eq!((c.k1, c.k2), (-0.2, 0.01));
    assert_eq!(c.position, glam::DVec3::new(10.0, 20.0, 101.6));
    assert!(r.notes.join("\n").contains("lens from"), "{:?}", r.notes);
    // the entry's k1 over the file's
    let over = RoughPose {
        k1: Some(-0.1),
        ..with_lens
    };
    let c = rough_camera(&img, (400, 300), &over, None, &ground)
        .unwrap()
        .camera;
    assert_eq!((c.k1, c.k2), (-0.1, 0.01));
    // an implausible coefficient is refused by name
    let bad = RoughPose {
        k1: Some(f64::NAN),
        ..base
    };
    let e = rough_camera(&img, (400, 300), &bad, None, &ground)
        .unwrap_err()
        .to_string();
    assert!(e.contains("\"k1\"") && e.contains("webcam.png"), "{e}");
    // in a photo list, "lens" is relative to the list's folder
    let list = dir.path().join("photos.json");
    std::fs::write(
        &list,
        r#"{"photos": [{"image": "webcam.png", "rough": {"lens": "lens.json", "heading_deg": 45}}]}"#,
    )
    .unwrap();
    match &read_photo_entries(&list).unwrap()[0] {
        PhotoEntry::Rough { pose, .. } => assert_eq!(pose.lens.as_deref(), Some(lens.as_path())),
        other => panic!("{other:?}"),
    }
}
