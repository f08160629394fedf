//! End-to-end tests of `pipeline::project_store`: a small store with a west-facing wall,
//! synthetic photos from known cameras. These need the ray casts (`photo::photo_footprints`,
//! `photo::LevelScene::from_store`) from the raycast work.

use std::path::{Path, PathBuf};

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::photo::{BlendMode, PhotoInput};
use cliffmap::pipeline::{
    BuildInputs, BuildOptions, PhotoTextureOptions, ProjectOptions, ReparamOptions, build_store,
    project_store, reparam_store,
};
use cliffmap::store::Store;
use cliffmap::{Dem, GridGeoref};
use glam::DVec3;
use image::RgbImage;

const X0: f64 = 500_000.0;
const Y0: f64 = 7_000_000.0;
const N: usize = 65;

/// Flat ground at 100 m with a 20 m wall (≈ 84°) rising eastwards at x ≈ 31 m, plus a gentle
/// ripple so the TINs are not trivial.
fn dem() -> Dem {
    let heights: Vec<f32> = (0..N * N)
        .map(|i| {
            let (c, r) = ((i % N) as f64, (i / N) as f64);
            let t = ((c - 30.0) / 2.0).clamp(0.0, 1.0);
            (100.0 + 20.0 * t * t * (3.0 - 2.0 * t) + 0.3 * (0.4 * r).sin()) as f32
        })
        .collect();
    Dem::from_heights(N, N, heights, GridGeoref::new(X0, Y0, 1.0)).unwrap()
}

fn build(dir: &Path) {
    let d = dem();
    let inputs = BuildInputs {
        dem: &d,
        ortho: None,
        dem_source: "test:wall".into(),
        ortho_source: None,
        fingerprint: "wall-1".into(),
    };
    let opts = BuildOptions {
        max_error: 0.05,
        cell_intervals: 32,
        cell_texels: 64,
        force: false,
        ..BuildOptions::default()
    };
    build_store(&inputs, &opts, dir).unwrap();
}

fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cliffmap-photo-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A camera west of the wall looking at it, and a photo of one colour with a vertical
/// stripe pattern.
fn photo(position: DVec3, target: DVec3) -> PhotoInput {
    let r = rotation_look_at(position, target).unwrap();
    let camera = CameraModel::with_fov(position, r, 160, 120, 0.6);
    let image = RgbImage::from_fn(160, 120, |x, _| {
        if (x / 8) % 2 == 0 {
            image::Rgb([200, 60, 40])
        } else {
            image::Rgb([180, 70, 50])
        }
    });
    PhotoInput {
        name: "wall.png".into(),
        image_path: PathBuf::from("wall.png"),
        image,
        camera,
        mask: None,
    }
}

fn wall_photo() -> PhotoInput {
    photo(
        DVec3::new(X0 + 2.0, Y0 - 32.0, 115.0),
        DVec3::new(X0 + 31.0, Y0 - 32.0, 110.0),
    )
}

fn photo_files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let store = Store::open(dir).unwrap();
    let mut out = Vec::new();
    for c in &store.manifest.cells {
        if let Some(p) = &c.photo {
            for f in [&p.texture, &p.confidence] {
                out.push((f.path.clone(), store.read_file(f).unwrap()));
            }
        }
    }
    out
}

fn opts() -> ProjectOptions {
    ProjectOptions {
        level_colours: false,
        ..ProjectOptions::default()
    }
}

#[test]
fn e2e_wall_photo_colours_the_wall_and_reruns_identically() {
    let dir = tempdir("wall");
    build(&dir);
    let report = project_store(&dir, &[wall_photo()], &opts()).unwrap();
    assert!(report.cells_written > 0);
    let p = &report.settings.photos[0];
    assert!(p.texels_written > 0 && p.pixels_hit > 0, "{p:?}");
    let finest = report.settings.levels.last().unwrap();
    assert!(
        finest.steep_texels > 0 && finest.steep_photo_texels > 0,
        "{finest:?}"
    );
    // every level the wall is in got photo colour (coarser levels via the photo pyramid)
    assert!(
        report
            .settings
            .levels
            .iter()
            .all(|l| l.cells_with_photo > 0),
        "{:?}",
        report.settings.levels
    );

    // confident texels carry the photo's colours (red-dominant), which the derived ortho lacks
    let store = Store::open(&dir).unwrap();
    let mut confident = 0;
    for c in store.manifest.cells.iter().filter(|c| c.photo.is_some()) {
        let rec = c.photo.as_ref().unwrap();
        let (tex, conf) = store.read_photo_texture(c, rec).unwrap();
        for (t, s) in tex.pixels().zip(conf.pixels()) {
            if s.0[0] == 255 {
                confident += 1;
                assert!(
                    (170..=210).contains(&t.0[0]) && (55..=75).contains(&t.0[1]),
                    "{:?}",
                    t.0
                );
            }
        }
    }
    assert!(confident > 0);

    // stats summary gains the photo figures
    let json = cliffmap::pipeline::write_stats(&dir, &store.manifest, 1.1).unwrap();
    let f = json["summary"]["photo_improved_steep_fraction"]
        .as_f64()
        .unwrap();
    assert!(f > 0.0 && f <= 1.0, "{f}");
    assert_eq!(
        json["summary"]["photos"][0]["texels_written"].as_u64(),
        Some(p.texels_written)
    );

    // same photos again: byte-identical files and records
    let before = photo_files(&dir);
    let manifest_before = std::fs::read(dir.join("manifest.json")).unwrap();
    project_store(&dir, &[wall_photo()], &opts()).unwrap();
    assert_eq!(photo_files(&dir), before);
    assert_eq!(
        std::fs::read(dir.join("manifest.json")).unwrap(),
        manifest_before
    );

    // a lone photo competes with no other: the occlusion margin (which only weighs photos
    // against each other) changes no file
    let mut no_margin = opts();
    no_margin.confidence.occlusion_margin_px = 0.0;
    project_store(&dir, &[wall_photo()], &no_margin).unwrap();
    assert_eq!(photo_files(&dir), before);
    // nor does the rule that mixes photos: with one photo both give its colour
    let mut best = opts();
    best.blend = BlendMode::Best;
    project_store(&dir, &[wall_photo()], &best).unwrap();
    assert_eq!(photo_files(&dir), before);

    // a camera facing away: no photo textures, stale files removed, no error
    let away = photo(
        DVec3::new(X0 + 2.0, Y0 - 32.0, 115.0),
        DVec3::new(X0 - 50.0, Y0 - 32.0, 130.0),
    );
    let r = project_store(&dir, &[away], &opts()).unwrap();
    assert_eq!(
        (r.cells_written, r.settings.photos[0].texels_written),
        (0, 0)
    );
    for (path, _) in &before {
        assert!(!dir.join(path).exists(), "stale {path}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn e2e_output_does_not_depend_on_threads_and_blend_modes_differ() {
    let dir = tempdir("threads");
    build(&dir);
    let second = photo(
        DVec3::new(X0 + 5.0, Y0 - 10.0, 118.0),
        DVec3::new(X0 + 31.0, Y0 - 30.0, 110.0),
    );
    let photos = [
        wall_photo(),
        PhotoInput {
            image: RgbImage::from_pixel(160, 120, image::Rgb([40, 60, 200])),
            ..second
        },
    ];
    let run = |threads: usize, mode: BlendMode| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            project_store(
                &dir,
                &photos,
                &ProjectOptions {
                    blend: mode,
                    ..opts()
                },
            )
            .unwrap()
        });
        photo_files(&dir)
    };
    let one = run(1, BlendMode::Confidence);
    assert_eq!(run(2, BlendMode::Confidence), one);
    let best = run(2, BlendMode::Best);
    assert_ne!(best, one);
    // leveling on: still deterministic, and each photo reports its transform
    let lev = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let r = pool.install(|| {
            project_store(
                &dir,
                &photos,
                &ProjectOptions {
                    level_colours: true,
                    ..opts()
                },
            )
            .unwrap()
        });
        (r.settings, photo_files(&dir))
    };
    let (s1, f1) = lev(1);
    assert_eq!(lev(2), (s1.clone(), f1));
    assert!(
        s1.photos
            .iter()
            .all(|p| p.colour_gain.iter().all(|g| g.is_finite() && *g > 0.0))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn e2e_reparam_drops_photo_textures() {
    let dir = tempdir("reparam");
    build(&dir);
    project_store(&dir, &[wall_photo()], &opts()).unwrap();
    let files = photo_files(&dir);
    assert!(!files.is_empty());
    reparam_store(
        &dir,
        &ReparamOptions {
            ..ReparamOptions::default()
        },
    )
    .unwrap();
    let store = Store::open(&dir).unwrap();
    assert!(
        store.manifest.photos.is_none() && store.manifest.cells.iter().all(|c| c.photo.is_none())
    );
    for (path, _) in &files {
        assert!(!dir.join(path).exists(), "stale {path}");
    }
    // projecting into the reparameterized cells works and uses their texture layout, at
    // their size times a power of two (photo-driven sizes), or exactly their size with the
    // sizing off
    for photo_driven in [true, false] {
        let o = ProjectOptions {
            texture: PhotoTextureOptions {
                photo_driven,
                ..PhotoTextureOptions::default()
            },
            ..opts()
        };
        let r = project_store(&dir, &[wall_photo()], &o).unwrap();
        assert!(r.cells_written > 0);
        let store = Store::open(&dir).unwrap();
        for c in store.manifest.cells.iter().filter(|c| c.photo.is_some()) {
            let p = c.photo.as_ref().unwrap();
            let base = c.reparam.as_ref().map_or(c.texels, |r| r.texels);
            let k = p.texels / base;
            assert!(
                p.texels % base == 0 && k.is_power_of_two() && (photo_driven || k == 1),
                "{} {base}",
                p.texels
            );
            let (img, conf) = store.read_photo_texture(c, p).unwrap();
            assert_eq!((img.width(), img.height()), (p.texels, p.texels));
            assert_eq!(conf.dimensions(), img.dimensions());
            // the renderer's single read of the texture and the active one under it
            let (img2, conf2, active) = store.read_photo_texture_and_active(c, p).unwrap();
            assert!(img2 == img && conf2 == conf);
            assert!(active == store.read_active_texture(c).unwrap());
            // stored in blocks of photo colour: the atlas holds those blocks only
            let b = p
                .blocks
                .as_ref()
                .expect("project stores photo textures in blocks");
            let present = b.present(p.texels).unwrap();
            let stored = present.iter().filter(|&&v| v).count();
            assert!(stored > 0);
            let atlas = store.read_png(&p.texture).unwrap();
            let (cols, rows) = cliffmap::store::photo_texture::atlas_blocks(stored);
            assert_eq!(
                (atlas.width(), atlas.height()),
                (cols as u32 * b.side, rows as u32 * b.side)
            );
            // no block with photo colour is left out
            let g = cliffmap::store::PhotoBlocks::grid(b.side, p.texels);
            for (x, y, s) in conf.enumerate_pixels() {
                if s.0[0] > 0 {
                    assert!(present[((y / b.side) * g + x / b.side) as usize]);
                }
            }
            // the exporters embed the whole texture, pixel for pixel
            let e = cliffmap::export::read_export_cell(&store, c).unwrap();
            let embedded =
                image::load_from_memory_with_format(&e.texture_bytes, image::ImageFormat::Png)
                    .unwrap()
                    .to_rgba8();
            assert!(embedded == img, "{}: exported texture differs", c.id);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn e2e_photo_with_wrong_size_is_an_error() {
    let dir = tempdir("badsize");
    build(&dir);
    let mut p = wall_photo();
    p.image = RgbImage::new(10, 10);
    let e = project_store(&dir, &[p], &opts()).unwrap_err().to_string();
    assert!(e.contains("wall.png") && e.contains("10x10"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
