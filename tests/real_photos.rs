//! Issue #52, "Real photos on real terrain": projection works on stores without an ortho and
//! with a coarse one, says what each photo supplied, refuses a camera below the terrain,
//! and DEMs with undeclared no-data markers load without pits.

mod cli_util;
mod common;

use std::path::Path;

use cliffmap::demo_scene::{DemoPhotoOptions, DemoScene};
use cliffmap::photo::{PhotoInput, read_photo_list};
use cliffmap::pipeline::{BuildInputs, BuildOptions, ProjectOptions, build_store, project_store};
use cliffmap::store::{PhotoReport, Store};
use cliffmap::{Dem, Ortho};

/// The demo scene at 129 × 129 samples of 4 m (the terrain of `common::small_demo_store`).
fn scene() -> DemoScene {
    DemoScene {
        samples: 129,
        spacing: 4.0,
        ..DemoScene::default()
    }
}

/// Builds a store of `dem` with `ortho` (or none) into `dir`.
fn build(dir: &Path, dem: &Dem, ortho: Option<&Ortho>) {
    let inputs = BuildInputs {
        dem,
        ortho,
        dem_source: "demo".into(),
        ortho_source: ortho.map(|_| "demo".to_string()),
        fingerprint: format!("real-photos-{}", ortho.map_or(0, |o| o.image.width())),
    };
    let opts = BuildOptions {
        max_error: 0.5,
        cell_intervals: 32,
        cell_texels: 64,
        force: true,
        ..BuildOptions::default()
    };
    build_store(&inputs, &opts, dir).unwrap();
}

/// The demo's ground photos at 320 × 240, written into `dir`.
fn photos(scene: &DemoScene, dem: &Dem, dir: &Path) -> Vec<PhotoInput> {
    let opts = DemoPhotoOptions {
        width: 320,
        height: 240,
        supersample: 1,
    };
    let list = scene.write_demo_photos(dem, dir, &opts).unwrap();
    read_photo_list(&list).unwrap()
}

fn project(dir: &Path, photos: &[PhotoInput]) -> Vec<PhotoReport> {
    project_store(dir, photos, &ProjectOptions::default())
        .unwrap()
        .settings
        .photos
}

#[test]
fn a_store_without_an_ortho_takes_the_colour_of_every_photo_that_sees_it() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene();
    let (dem, ortho) = scene.generate().unwrap();
    let ps = photos(&scene, &dem, &tmp.path().join("photos"));
    let (bare, with_ortho) = (tmp.path().join("bare"), tmp.path().join("ortho"));
    build(&bare, &dem, None);
    build(&with_ortho, &dem, Some(&ortho));
    let bare_reports = project(&bare, &ps);
    let ortho_reports = project(&with_ortho, &ps);
    for (b, o) in bare_reports.iter().zip(&ortho_reports) {
        assert!(
            b.pixels_hit > 10_000,
            "{}: {} pixels hit",
            b.name,
            b.pixels_hit
        );
        // the counts account for every terrain pixel
        assert_eq!(
            b.pixels_supplying
                + b.pixels_outweighed
                + b.pixels_masked
                + b.pixels_near
                + b.rejected_silhouette
                + b.pixels_dropped,
            b.pixels_hit,
            "{}",
            b.name
        );
        // a DEM-derived texture holds no image: every terrain pixel but those on silhouette
        // edges or off a chart supplies it
        assert!(
            b.supplying_share() >= 0.9,
            "{}: {:.3} of the terrain pixels supplied",
            b.name,
            b.supplying_share()
        );
        assert!(b.warnings.is_empty(), "{}: {:?}", b.name, b.warnings);
        // ... and more texels than against the (sharper) ortho
        assert!(
            b.texels_supplied > o.texels_supplied && b.pixels_supplying > o.pixels_supplying,
            "{}: {} / {} texels, {} / {} pixels",
            b.name,
            b.texels_supplied,
            o.texels_supplied,
            b.pixels_supplying,
            o.pixels_supplying
        );
    }
    // no leveling towards a hypsometric tint
    let m = Store::open(&bare).unwrap().manifest;
    let settings = m.photos.unwrap();
    assert!(!settings.level_colours);
    assert!(settings.photos.iter().all(|p| p.colour_gain == [1.0; 3]));
}

#[test]
fn a_coarse_ortho_yields_to_the_photos_where_they_resolve_more() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene();
    let (dem, fine) = scene.generate().unwrap();
    // the same terrain's ortho at 8x the spacing (17 x 17 pixels of 32 m), its georef
    // recorded: the cell textures are 8x finer than what the ortho holds
    let (_, coarse) = DemoScene {
        samples: 17,
        spacing: 32.0,
        ..scene
    }
    .generate()
    .unwrap();
    assert_eq!(coarse.georef.origin_x, fine.georef.origin_x);
    let ps = photos(&scene, &dem, &tmp.path().join("photos"));
    let (a, b) = (tmp.path().join("fine"), tmp.path().join("coarse"));
    build(&a, &dem, Some(&fine));
    build(&b, &dem, Some(&coarse));
    assert_eq!(Store::open(&b).unwrap().manifest.ortho_spacing, Some(32.0));
    let (fine_r, coarse_r) = (project(&a, &ps), project(&b, &ps));
    let total = |r: &[PhotoReport], f: fn(&PhotoReport) -> u64| r.iter().map(f).sum::<u64>();
    let (pf, pc) = (
        total(&fine_r, |p| p.pixels_supplying),
        total(&coarse_r, |p| p.pixels_supplying),
    );
    let (tf, tc) = (
        total(&fine_r, |p| p.texels_supplied),
        total(&coarse_r, |p| p.texels_supplied),
    );
    assert!(
        pc > pf && tc > tf,
        "pixels {pf} -> {pc}, texels {tf} -> {tc}"
    );
}

#[test]
fn a_camera_below_the_terrain_is_refused_and_the_store_is_left_as_it_was() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene();
    let (dem, _) = scene.generate().unwrap();
    let mut ps = photos(&scene, &dem, &tmp.path().join("photos"));
    let dir = tmp.path().join("store");
    build(&dir, &dem, None);
    let before = std::fs::read(dir.join("manifest.json")).unwrap();
    let store = Store::open(&dir).unwrap();
    let p = ps[0].camera.position;
    let ground = store.surface_at(p.x, p.y).unwrap().unwrap();
    ps[0].camera.position.z = ground.height - 5.0;
    let e = project_store(&dir, &ps, &ProjectOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&ps[0].name) && e.contains("5.0 m below the terrain surface"),
        "{e}"
    );
    assert_eq!(std::fs::read(dir.join("manifest.json")).unwrap(), before);
    // within the TIN's error below the surface is still accepted (the DEM may be above)
    ps[0].camera.position.z = ground.height - 0.5 * ground.max_error;
    assert!(project_store(&dir, &ps[..1], &ProjectOptions::default()).is_ok());
}

#[test]
fn a_photo_that_sees_no_terrain_is_reported_with_where_its_camera_stands() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene();
    let (dem, _) = scene.generate().unwrap();
    let mut ps = photos(&scene, &dem, &tmp.path().join("photos"));
    let dir = tmp.path().join("store");
    build(&dir, &dem, None);
    // looking straight up
    let c = &mut ps[0].camera;
    c.world_to_camera = cliffmap::camera::rotation_look_at(
        c.position,
        c.position + glam::DVec3::new(0.0, 0.001, 100.0),
    )
    .unwrap();
    let r = &project(&dir, &ps[..1])[0];
    assert_eq!(r.pixels_hit, 0);
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(
        r.warnings[0].contains("sees no terrain") && r.warnings[0].contains("above the terrain"),
        "{:?}",
        r.warnings
    );
}

/// A raw f32 DEM of `w × h` with `hole` written into a 3 × 3 block.
fn dem_with_hole(path: &Path, w: usize, h: usize, hole: f32) {
    let v: Vec<f32> = (0..w * h)
        .map(|i| {
            let (r, c) = (i / w, i % w);
            if (5..8).contains(&r) && (5..8).contains(&c) {
                hole
            } else {
                2000.0 + (r as f32 * 0.7).sin() * 5.0 + c as f32 * 0.5
            }
        })
        .collect();
    std::fs::write(
        path,
        v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>(),
    )
    .unwrap();
}

#[test]
fn undeclared_nodata_sentinels_are_voids_unless_turned_off() {
    use cliffmap::DemLoadOptions;
    let tmp = tempfile::tempdir().unwrap();
    for hole in [-9999.0, -32768.0, f32::MIN, -3.4e38, f32::NAN] {
        let p = tmp.path().join("d.f32");
        dem_with_hole(&p, 20, 16, hole);
        let opts = DemLoadOptions {
            width: Some(20),
            height: Some(16),
            spacing: Some(4.0),
            ..DemLoadOptions::default()
        };
        let d = cliffmap::load_dem(&p, &opts).unwrap();
        assert_eq!(d.void.iter().filter(|v| **v).count(), 9, "{hole}");
        assert!(d.heights.iter().all(|h| *h > 1900.0), "{hole}: filled");
        // off: the marker is a height (a plausible one) or an error naming the file
        let off = DemLoadOptions {
            nodata_sentinels: false,
            ..opts
        };
        match cliffmap::load_dem(&p, &off) {
            Ok(d) => {
                assert!(hole > -1e5, "{hole}");
                assert!(d.void.iter().all(|v| !v) && d.heights.contains(&hole));
            }
            Err(e) => assert!(
                (hole.is_nan() || hole < -1e5) && e.to_string().contains("d.f32"),
                "{hole}: {e}"
            ),
        }
    }
}

#[test]
fn the_command_line_names_sentinels_walls_and_accepts_nodata_none() {
    use cli_util::{cliffmap, ok, s};
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("d.f32");
    let args = |p: &Path, out: &Path, extra: &[&str]| -> Vec<String> {
        let mut a: Vec<String> = [
            "build",
            "--dem",
            s(p),
            "--dem-format",
            "f32",
            "--width",
            "20",
            "--height",
            "16",
            "--spacing",
            "4",
            "--origin",
            "1000,2000",
            "--out",
            s(out),
            "--quiet",
        ]
        .iter()
        .map(|x| x.to_string())
        .collect();
        a.extend(extra.iter().map(|x| x.to_string()));
        a
    };
    let run = |a: &[String]| {
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        cliffmap(&a)
    };
    // -9999 without --nodata: voids, named with their count
    dem_with_hole(&p, 20, 16, -9999.0);
    let o = run(&args(&p, &tmp.path().join("a"), &[]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("9 samples of -9999") && err.contains("--nodata none"),
        "{err}"
    );
    // --nodata none: the marker is a height, and the 2000-m walls around it are named
    let o = run(&args(&p, &tmp.path().join("b"), &["--nodata", "none"]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("12 pairs") && err.contains("--nodata -9999"),
        "{err}"
    );
    // 0 m for missing cells (a GeoTIFF habit): the wall warning proposes --nodata 0
    dem_with_hole(&p, 20, 16, 0.0);
    let o = run(&args(&p, &tmp.path().join("c"), &[]));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--nodata 0"), "{err}");
    // the contract's explicit form
    ok(&args(&p, &tmp.path().join("d"), &["--nodata", "-9999"])
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>());
}

/// Engabreen built without its ortho (a real DEM-only store) through the command-line
/// contract of issue #52: IMG_8902 supplies most of its terrain pixels, and a render from
/// its own camera shows the photo (against the photo, over the terrain the render shows).
#[test]
fn engabreen_without_its_ortho_takes_the_photo_and_renders_it_back() {
    use cli_util::{ok, s};
    use common::real_data;
    let tmp = tempfile::tempdir().unwrap();
    let store = tmp.path().join("store");
    let dem = real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let image = real_data("engabreen/IMG_8902.jpg");
    let camera = real_data("engabreen/engabreen_camera_IMG_8902.json");
    ok(&[
        "build",
        "--dem",
        s(&dem),
        "--dem-format",
        "f32",
        "--width",
        "507",
        "--height",
        "590",
        "--spacing",
        "3",
        "--origin",
        "445302.17,7396769.45",
        "--nodata",
        "-9999",
        "--max-error",
        "1",
        "--cell-texels",
        "64",
        "--out",
        s(&store),
        "--quiet",
    ]);
    let list = tmp.path().join("photos.json");
    std::fs::write(
        &list,
        serde_json::to_vec(&serde_json::json!({"photos": [
            {"image": image, "imgraft": camera}
        ]}))
        .unwrap(),
    )
    .unwrap();
    let o = ok(&["project", s(&store), "--photos", s(&list), "--json"]);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let p = &report["photos"][0];
    let (hit, supplying) = (
        p["pixels_hit"].as_u64().unwrap(),
        p["pixels_supplying"].as_u64().unwrap(),
    );
    assert!(hit > 8_000_000, "{p}");
    assert!(supplying as f64 >= 0.8 * hit as f64, "{p}");
    assert!(p["texels_supplied"].as_u64().unwrap() > 100_000, "{p}");
    assert!(p.get("warnings").is_none(), "{p}");
    // the photo's own view, a quarter of its size
    let out = tmp.path().join("view.png");
    ok(&[
        "render",
        s(&store),
        "--camera",
        s(&camera),
        "--size",
        "1072x714",
        "--unlit",
        "--out",
        s(&out),
    ]);
    let view = image::open(&out).unwrap().to_rgb8();
    let photo = image::imageops::resize(
        &image::open(&image).unwrap().to_rgb8(),
        1072,
        714,
        image::imageops::FilterType::Triangle,
    );
    // terrain pixels: not the renderer's sky colour
    let sky = cliffmap::render::FrameOptions::default().sky;
    let (mut n, mut diff) = (0u64, 0f64);
    for (a, b) in view.pixels().zip(photo.pixels()) {
        if a.0 != sky {
            n += 1;
            diff += (0..3)
                .map(|k| (a.0[k] as f64 - b.0[k] as f64).abs())
                .sum::<f64>()
                / 3.0;
        }
    }
    let mae = diff / n.max(1) as f64;
    eprintln!("{n} terrain pixels, MAE {mae:.2}");
    // (2026-12-07: 4.5 of 255; docs/projection.md, "Real photos on real terrain", has the
    // figures before and after)
    assert!(
        n > 400_000 && mae < 20.0,
        "{n} terrain pixels, MAE {mae:.1}"
    );
}

/// Texels of the store's photo textures that are near white (every channel > 245) where the
/// photo supplied most of the colour (share > 1/2).
fn white_photo_texels(dir: &Path) -> u64 {
    let store = Store::open(dir).unwrap();
    let mut n = 0;
    for c in &store.manifest.cells {
        if let Some(p) = &c.photo {
            let (tex, share) = store.read_photo_texture(c, p).unwrap();
            n += tex
                .pixels()
                .zip(share.pixels())
                .filter(|(t, s)| s.0[0] > 127 && t.0[..3].iter().all(|v| *v > 245))
                .count() as u64;
        }
    }
    n
}

/// The demo photos with a 12-px white frame (a scanned print) and a 16-px black banner
/// with white text at the bottom (a webcam's), written next to the originals; the new list.
fn framed_photos(photos: &[PhotoInput], dir: &Path) -> std::path::PathBuf {
    let mut entries = Vec::new();
    for (k, p) in photos.iter().enumerate() {
        let (w, h) = p.image.dimensions();
        let mut img = p.image.clone();
        for (x, y, px) in img.enumerate_pixels_mut() {
            if y >= h - 16 {
                let text = (30..200).contains(&x) && (h - 12..h - 4).contains(&y) && x % 4 < 2;
                *px = if text {
                    image::Rgb([255, 255, 255])
                } else {
                    image::Rgb([0, 0, 0])
                };
            } else if x < 12 || y < 12 || x >= w - 12 {
                *px = image::Rgb([252, 252, 250]);
            }
        }
        let image = dir.join(format!("framed{k}.png"));
        img.save(&image).unwrap();
        let camera = dir.join(format!("framed{k}.json"));
        std::fs::write(
            &camera,
            cliffmap::camera::camera_to_json(&p.camera).to_string(),
        )
        .unwrap();
        entries.push(serde_json::json!({"image": image, "camera": camera}));
    }
    let list = dir.join("framed.json");
    std::fs::write(&list, serde_json::json!({ "photos": entries }).to_string()).unwrap();
    list
}

#[test]
fn photo_frames_and_banners_stay_off_the_terrain() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene();
    let (dem, _) = scene.generate().unwrap();
    let ps = photos(&scene, &dem, &tmp.path().join("photos"));
    let framed = read_photo_list(&framed_photos(&ps, tmp.path())).unwrap();
    let (masked, unmasked) = (tmp.path().join("masked"), tmp.path().join("unmasked"));
    build(&masked, &dem, None);
    build(&unmasked, &dem, None);
    let with = project(&masked, &framed);
    let without = project_store(
        &unmasked,
        &framed,
        &ProjectOptions {
            mask_borders: false,
            ..ProjectOptions::default()
        },
    )
    .unwrap()
    .settings
    .photos;
    // the frame and the banner draped onto the terrain without the mask, not with it
    let (w_with, w_without) = (white_photo_texels(&masked), white_photo_texels(&unmasked));
    eprintln!("white photo texels: {w_with} with the border mask, {w_without} without");
    assert!(
        w_without > 200 && w_with == 0,
        "white texels {w_with} / {w_without}"
    );
    for (a, b) in with.iter().zip(&without) {
        // the bottom banner (and the frame where it meets terrain) is named and counted
        assert!(
            a.border_masked.iter().any(|s| s.starts_with("bottom")),
            "{}: {:?}",
            a.name,
            a.border_masked
        );
        assert!(a.pixels_masked > 0 && b.pixels_masked == 0, "{}", a.name);
        assert_eq!(a.pixels_hit, b.pixels_hit);
    }
}

#[test]
fn a_mask_file_and_a_minimum_distance_leave_pixels_out() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene();
    let (dem, _) = scene.generate().unwrap();
    let dir = tmp.path().join("photos");
    let ps = photos(&scene, &dem, &dir);
    let store = tmp.path().join("store");
    build(&store, &dem, None);
    // a mask leaving out the left half of the first photo
    let p = &ps[0];
    let (w, h) = p.image.dimensions();
    let mask =
        image::GrayImage::from_fn(w, h, |x, _| image::Luma([if x < w / 2 { 0 } else { 255 }]));
    let mask_path = dir.join("mask0.png");
    mask.save(&mask_path).unwrap();
    let camera = dir.join("cam0.json");
    std::fs::write(
        &camera,
        cliffmap::camera::camera_to_json(&p.camera).to_string(),
    )
    .unwrap();
    let list = dir.join("masked.json");
    let entry = |m: &Path| serde_json::json!({"photos": [{"image": p.image_path, "camera": camera, "mask": m}]});
    std::fs::write(&list, entry(&mask_path).to_string()).unwrap();
    let masked = read_photo_list(&list).unwrap();
    let r = &project(&store, &masked)[0];
    let full = &project(&store, &ps[..1])[0];
    assert_eq!(r.pixels_hit, full.pixels_hit);
    assert!(
        r.pixels_masked > full.pixels_hit / 5 && r.pixels_supplying < full.pixels_supplying,
        "{} masked of {}",
        r.pixels_masked,
        r.pixels_hit
    );
    // a mask of another size is refused, naming it
    let small = dir.join("small.png");
    image::GrayImage::new(w / 2, h).save(&small).unwrap();
    std::fs::write(&list, entry(&small).to_string()).unwrap();
    let e = read_photo_list(&list).unwrap_err().to_string();
    assert!(e.contains("small.png") && e.contains("its photo"), "{e}");
    // what is nearer than the median distance is left out
    let near = project_store(
        &store,
        &ps[..1],
        &ProjectOptions {
            min_distance_m: 60.0,
            ..ProjectOptions::default()
        },
    )
    .unwrap()
    .settings
    .photos;
    let n = &near[0];
    assert!(n.pixels_near > 0 && n.pixels_near < n.pixels_hit, "{n:?}");
    assert_eq!(
        n.pixels_supplying
            + n.pixels_outweighed
            + n.pixels_masked
            + n.pixels_near
            + n.rejected_silhouette
            + n.pixels_dropped,
        n.pixels_hit
    );
    // refused: a negative distance
    assert!(
        project_store(
            &store,
            &ps[..1],
            &ProjectOptions {
                min_distance_m: -1.0,
                ..ProjectOptions::default()
            },
        )
        .is_err_and(|e| e.to_string().contains("--min-distance"))
    );
}

/// Issue #52: a photo stored sideways with an EXIF orientation is decoded upright, and its
/// size (for the camera) is the upright one.
#[test]
fn exif_orientation_turns_a_photo_upright() {
    let dir = tempfile::tempdir().unwrap();
    // stored 32 x 16: left half dark, right half light; orientation 6 = turn 90° clockwise
    let stored = image::RgbImage::from_fn(32, 16, |x, _| {
        image::Rgb(if x < 16 {
            [10, 10, 10]
        } else {
            [240, 240, 240]
        })
    });
    let mut jpeg = Vec::new();
    stored
        .write_to(
            &mut std::io::Cursor::new(&mut jpeg),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
    let field = common::exif::exif_field(exif::Tag::Orientation, exif::Value::Short(vec![6]));
    let path = dir.path().join("portrait.jpg");
    std::fs::write(&path, common::exif::insert_exif(&jpeg, &[field])).unwrap();
    assert_eq!(cliffmap::fsutil::exif_orientation(&path), 6);
    assert_eq!(cliffmap::photo::image_size(&path).unwrap(), (16, 32));
    let up = cliffmap::fsutil::decode_photo_rgb8(&path).unwrap();
    assert_eq!(up.dimensions(), (16, 32));
    // turned clockwise: the stored left (dark) half is now the top
    assert!(up.get_pixel(8, 4).0[0] < 60 && up.get_pixel(8, 28).0[0] > 200);
    // without the tag: as stored
    let plain = dir.path().join("plain.jpg");
    std::fs::write(&plain, &jpeg).unwrap();
    assert_eq!(cliffmap::fsutil::exif_orientation(&plain), 1);
    assert_eq!(cliffmap::photo::image_size(&plain).unwrap(), (32, 16));
}
