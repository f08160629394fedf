//! Golden images: fixed views of a small generated store rendered unlit and lit (320×180),
//! compared with the PNGs in fixtures/golden/ with a tolerance (software rasterizers differ
//! slightly across Mesa/LLVM versions): a pixel differs when a channel is off by more than
//! `PIXEL_TOL` levels, and at most `MAX_DIFFERING` of the pixels may differ.
//!
//! Regenerate after an intended rendering change with
//! `CLIFFMAP_UPDATE_GOLDEN=1 cargo test --release --test render_golden` (and look at them).

use std::path::{Path, PathBuf};

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::demo_scene::DemoScene;
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
use cliffmap::render::accuracy::image_difference;
use cliffmap::render::{FrameOptions, SceneOptions, StoreRenderer};
use glam::DVec3;

const W: u32 = 320;
const H: u32 = 180;
/// Per-channel tolerance, 8-bit levels.
const PIXEL_TOL: u8 = 12;
/// Largest fraction of pixels allowed over the tolerance.
const MAX_DIFFERING: f64 = 0.01;

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/golden")
}

fn small_store(out: &Path) {
    let scene = DemoScene {
        samples: 129,
        ..DemoScene::default()
    };
    let (dem, ortho) = scene.generate().unwrap();
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "demo:129".into(),
        ortho_source: Some("demo".into()),
        fingerprint: "render-golden".into(),
    };
    let opts = BuildOptions {
        max_error: 0.5,
        cell_intervals: 32,
        cell_texels: 64,
        force: true,
        ..BuildOptions::default()
    };
    build_store(&inputs, &opts, out).unwrap();
}

/// Fixed views in the scene's own coordinates: an oblique overview and a low view into the
/// terrain (positions relative to the root bounding box, so they follow the generator's extent).
fn views(scene: &StoreRenderer) -> Vec<(&'static str, CameraModel)> {
    let m = &scene.store().manifest;
    let root = m.cells.iter().find(|c| c.level == 0).unwrap();
    let (lo, hi) = (DVec3::from(root.bbox_min), DVec3::from(root.bbox_max));
    let c = (lo + hi) / 2.0;
    let s = hi.x - lo.x;
    let over = c + DVec3::new(-0.6 * s, -0.7 * s, 0.6 * s);
    let low = DVec3::new(lo.x + 0.1 * s, c.y, hi.z + 0.02 * s);
    let low_at = DVec3::new(hi.x, c.y + 0.1 * s, lo.z);
    [("overview", over, c, 55.0), ("low", low, low_at, 60.0)]
        .into_iter()
        .map(|(n, p, t, fov)| {
            (
                n,
                CameraModel::with_fov(
                    p,
                    rotation_look_at(p, t).unwrap(),
                    W,
                    H,
                    f64::to_radians(fov),
                ),
            )
        })
        .collect()
}

#[test]
fn fixed_views_match_the_golden_images() {
    let t = tempfile::tempdir().unwrap();
    small_store(t.path());
    let update = std::env::var_os("CLIFFMAP_UPDATE_GOLDEN").is_some_and(|v| v == "1");
    let mut failures = Vec::new();
    for lit in [false, true] {
        let opts = SceneOptions {
            frame: FrameOptions {
                lit,
                ..Default::default()
            },
            ..Default::default()
        };
        let mut scene = StoreRenderer::open(t.path(), W, H, opts).unwrap_or_else(|e| {
            panic!("cannot open a headless GPU scene: {e}\n(install Mesa: apt-get install mesa-vulkan-drivers)")
        });
        for (name, cam) in views(&scene) {
            scene.frame(&cam, true).unwrap();
            let img = scene.read_rgba().unwrap();
            let file =
                golden_dir().join(format!("{name}_{}.png", if lit { "lit" } else { "unlit" }));
            if update {
                std::fs::create_dir_all(golden_dir()).unwrap();
                img.save(&file).unwrap();
                eprintln!("wrote {}", file.display());
                continue;
            }
            let want = image::open(&file)
                .unwrap_or_else(|e| panic!("golden image {} unreadable ({e}); regenerate with CLIFFMAP_UPDATE_GOLDEN=1", file.display()))
                .to_rgba8();
            let d = image_difference(&img, &want, PIXEL_TOL)
                .unwrap_or_else(|| panic!("{}: size differs from {W}x{H}", file.display()));
            eprintln!(
                "{}: mean {:.3} levels, max {}, {:.3} % over {PIXEL_TOL}",
                file.display(),
                d.mean_abs,
                d.max_abs,
                100.0 * d.frac_over
            );
            if d.frac_over > MAX_DIFFERING {
                let got = std::env::temp_dir().join(format!("cliffmap_golden_{name}_{lit}.png"));
                let _ = img.save(&got);
                failures.push(format!(
                    "{}: {:.2} % of pixels differ by more than {PIXEL_TOL} (got {})",
                    file.display(),
                    100.0 * d.frac_over,
                    got.display()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
