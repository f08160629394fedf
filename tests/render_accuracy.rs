//! The screen-space error bound, checked on rendered depth buffers: frames drawn with the LOD
//! selection (threshold 0.5 px and 2 px) against frames of the finest level everywhere, on the
//! Engabreen store and on a generated demo store. Prints the measured table (docs/rendering.md).

mod common;

use std::path::Path;

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::demo_scene::DemoScene;
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
use cliffmap::render::accuracy::{image_difference, surface_displacement};
use cliffmap::render::{
    CellIndex, FlightPath, FrameOptions, SceneOptions, StoreRenderer, screen_space_error,
    select_cells,
};
use glam::DVec3;

const W: u32 = 480;
const H: u32 = 270;
/// Counterpart search radius, pixels (displacements beyond it count as window + 1).
const WINDOW: usize = 8;
/// Rasterization tolerance, pixels: sub-pixel coverage and depth interpolation at triangle
/// edges, plus the pixel-grid quantisation of counterparts matched to a single sample.
const RASTER_TOL: f64 = 1.0;
/// Threshold of the "finest everywhere" reference (every visible cell refines to a leaf).
const FINEST: f64 = 1e-9;

fn engabreen_store(out: &Path) {
    let dem = common::engabreen_dem();
    let ortho = common::engabreen_ortho(&dem);
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "engabreen".into(),
        ortho_source: Some("engabreen".into()),
        fingerprint: "render-accuracy-engabreen".into(),
    };
    let opts = BuildOptions {
        max_error: 1.0,
        cell_texels: 64,
        force: true,
        ..Default::default()
    };
    build_store(&inputs, &opts, out).unwrap();
}

fn demo_store(out: &Path) {
    let scene = DemoScene {
        samples: 257,
        ..DemoScene::default()
    };
    let (dem, ortho) = scene.generate().unwrap();
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "demo:257".into(),
        ortho_source: Some("demo".into()),
        fingerprint: "render-accuracy-demo".into(),
    };
    let opts = BuildOptions {
        max_error: 0.5,
        cell_texels: 256,
        force: true,
        ..Default::default()
    };
    build_store(&inputs, &opts, out).unwrap();
}

/// Views: three cameras of the default (low, steep) flight and an oblique overview.
fn views(scene: &StoreRenderer) -> Vec<CameraModel> {
    let m = &scene.store().manifest;
    let cams = FlightPath::default_for(m).unwrap().cameras(7, W, H);
    let mut out = vec![cams[1], cams[3], cams[5]];
    let root = m.cells.iter().find(|c| c.level == 0).unwrap();
    let (lo, hi) = (DVec3::from(root.bbox_min), DVec3::from(root.bbox_max));
    let c = (lo + hi) / 2.0;
    let span = (hi - lo).truncate().length();
    let pos = DVec3::new(lo.x - 0.2 * span, lo.y - 0.2 * span, hi.z + 0.4 * span);
    out.push(CameraModel::with_fov(
        pos,
        rotation_look_at(pos, c).unwrap(),
        W,
        H,
        50f64.to_radians(),
    ));
    // Far enough that 0.5 px keeps coarse levels.
    let far = c + DVec3::new(-1.5, -1.0, 1.2) * span;
    out.push(CameraModel::with_fov(
        far,
        rotation_look_at(far, c).unwrap(),
        W,
        H,
        25f64.to_radians(),
    ));
    out
}

struct Frame {
    depth: Vec<f32>,
    rgba: image::RgbaImage,
    cells: Vec<usize>,
}

fn render(scene: &mut StoreRenderer, cam: &CameraModel, sse: f64) -> Frame {
    scene.set_sse(sse).unwrap();
    let r = scene.frame(cam, true).unwrap();
    assert_eq!(
        (r.holes, r.substituted),
        (0, 0),
        "a complete frame draws what it selected"
    );
    let rc = scene.render_camera(cam);
    let cells = &scene.store().manifest.cells;
    let sel = select_cells(cells, &CellIndex::new(cells), &rc, sse);
    Frame {
        depth: scene.read_depth().unwrap(),
        rgba: scene.read_rgba().unwrap(),
        cells: sel.cells,
    }
}

/// Renders every view at each threshold and at the finest level, checks the displacement
/// bound and returns nothing; prints one table row per (view, threshold).
fn check_store(name: &str, dir: &Path) {
    let opts = SceneOptions {
        frame: FrameOptions {
            lit: false,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut scene = StoreRenderer::open(dir, W, H, opts).unwrap_or_else(|e| {
        panic!("cannot open a headless GPU scene: {e}\n(install Mesa: apt-get install mesa-vulkan-drivers)")
    });
    eprintln!("{name}: adapter {}", scene.gpu().describe());
    eprintln!(
        "| store | view | threshold px | cells LOD / finest | bound px | max on-axis px | max px | p99 px | mean px | point-matched % | silhouette-excluded % | image mean abs | pixels > 16 levels % |"
    );
    for (v, cam) in views(&scene).iter().enumerate() {
        let fine = render(&mut scene, cam, FINEST);
        assert!(
            fine.depth.iter().filter(|&&d| d > 0.0).count() > (W * H / 10) as usize,
            "view {v} sees terrain"
        );
        for thr in [0.5, 2.0] {
            let lod = render(&mut scene, cam, thr);
            let rc = scene.render_camera(cam);
            let cells = &scene.store().manifest.cells;
            // |LOD − finest| ≤ e_LOD + e_finest: the finest cells replaced by coarser LOD cells
            // contribute their own screen-space error.
            let fine_err = fine
                .cells
                .iter()
                .filter(|i| !lod.cells.contains(i))
                .map(|&i| screen_space_error(&cells[i], &rc))
                .fold(0.0, f64::max);
            // Bound on the on-axis displacement (see `Displacement::max_on_axis_px`).
            let bound = thr + fine_err + RASTER_TOL;
            // Silhouette neighbourhoods as wide as the displacement allowed there are left out.
            let d =
                surface_displacement(&rc, &lod.depth, &fine.depth, WINDOW, bound.ceil() as usize);
            let img = image_difference(&lod.rgba, &fine.rgba, 16).unwrap();
            eprintln!(
                "| {name} | {v} | {thr} | {} / {} | {bound:.2} | {:.2} | {:.2} | {:.2} | {:.3} | {:.1} | {:.1} | {:.2} | {:.2} |",
                lod.cells.len(),
                fine.cells.len(),
                d.max_on_axis_px,
                d.max_px,
                d.p99_px,
                d.mean_px,
                100.0 * d.point_matched as f64 / d.measured.max(1) as f64,
                100.0 * d.excluded as f64 / (d.measured + d.excluded).max(1) as f64,
                img.mean_abs,
                100.0 * img.frac_over
            );
            if let Some(dir) = std::env::var_os("CLIFFMAP_ACCURACY_DUMP") {
                let dir = Path::new(&dir);
                lod.rgba
                    .save(dir.join(format!("{name}_{v}_{thr}_lod.png")))
                    .unwrap();
                fine.rgba
                    .save(dir.join(format!("{name}_{v}_fine.png")))
                    .unwrap();
            }
            assert!(d.measured > 0);
            assert!(
                d.max_on_axis_px <= bound,
                "{name} view {v}, threshold {thr} px: surface moved {:.2} px (on-axis) > bound {bound:.2} ({d:?})",
                d.max_on_axis_px
            );
        }
    }
}

#[test]
fn lod_displacement_stays_within_the_threshold_on_engabreen() {
    let t = tempfile::tempdir().unwrap();
    engabreen_store(t.path());
    check_store("engabreen", t.path());
}

#[test]
fn lod_displacement_stays_within_the_threshold_on_a_generated_scene() {
    let t = tempfile::tempdir().unwrap();
    demo_store(t.path());
    check_store("demo", t.path());
}
