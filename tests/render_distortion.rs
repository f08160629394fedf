//! Radial lens distortion in the renderer (lavapipe): markers on a textured plane land where
//! `CameraModel::project` (with k1, k2) puts them, and the resampling pass alone (a camera
//! without distortion, pass forced on) reproduces the direct frame.

mod render_support;

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::render::accuracy::image_difference;
use cliffmap::render::{DistortionMode, FrameOptions, SceneOptions, StoreRenderer};
use glam::DVec3;
use render_support::{Synth, X0, Y0, write_store_textured};

const W: u32 = 640;
const H: u32 = 480;
/// Side of the plane, metres, and of its texture, texels.
const SIDE: f64 = 100.0;
const TEXELS: u32 = 1024;
/// Plane height, metres.
const Z: f64 = 812.0;
/// Marker spacing and Gaussian radius (sigma), metres.
const SPACING: f64 = 8.0;
const SIGMA: f64 = 0.35;
/// Background grey of the plane (8-bit).
const BG: f64 = 250.0;

/// World x, y of the markers: a grid over the plane, away from its edges.
fn markers() -> Vec<DVec3> {
    let n = (SIDE / SPACING) as i32;
    let mut out = Vec::new();
    for j in 1..n {
        for i in 1..n {
            out.push(DVec3::new(
                X0 + i as f64 * SPACING,
                Y0 - j as f64 * SPACING,
                Z,
            ));
        }
    }
    out
}

/// The plane's texture: background grey with a dark Gaussian dot at every marker.
fn marker_texture() -> image::RgbaImage {
    let t = TEXELS as f64;
    let m = markers();
    image::RgbaImage::from_fn(TEXELS, TEXELS, |tx, ty| {
        let x = X0 + (tx as f64 + 0.5) / t * SIDE;
        let y = Y0 - (ty as f64 + 0.5) / t * SIDE;
        let i = ((x - X0) / SPACING).round();
        let j = ((Y0 - y) / SPACING).round();
        let (mx, my) = (X0 + i * SPACING, Y0 - j * SPACING);
        let dark = if m.iter().any(|p| p.x == mx && p.y == my) {
            (-((x - mx).powi(2) + (y - my).powi(2)) / (2.0 * SIGMA * SIGMA)).exp()
        } else {
            0.0
        };
        let g = (BG - 210.0 * dark).round() as u8;
        image::Rgba([g, g, g, 255])
    })
}

fn scene(dir: &std::path::Path, mode: DistortionMode) -> StoreRenderer {
    let opts = SceneOptions {
        frame: FrameOptions {
            lit: false,
            sky: [250, 250, 250],
            ..Default::default()
        },
        distortion: mode,
        ..Default::default()
    };
    StoreRenderer::open(dir, W, H, opts).unwrap_or_else(|e| {
        panic!("cannot open a headless GPU scene: {e}\n(install Mesa: apt-get install mesa-vulkan-drivers)")
    })
}

/// A camera 55 m above the plane looking down, slightly oblique, 50° vertical field of view.
fn camera(k1: f64, k2: f64) -> CameraModel {
    let c = DVec3::new(X0 + SIDE / 2.0, Y0 - SIDE / 2.0, Z);
    let pos = c + DVec3::new(-2.0, -3.0, 55.0);
    let r = rotation_look_at(pos, c + DVec3::new(1.0, 2.0, 0.0)).unwrap();
    let mut m = CameraModel::with_fov(pos, r, W, H, 50f64.to_radians());
    m.cx += 4.5;
    m.cy -= 2.0;
    m.k1 = k1;
    m.k2 = k2;
    m
}

/// Darkness-weighted centroid (pixel-centre convention) in a window of radius `r` around `p`.
fn centroid(img: &image::RgbaImage, p: [f64; 2], r: i64) -> Option<[f64; 2]> {
    let (cu, cv) = (p[0].round() as i64, p[1].round() as i64);
    let (mut sw, mut su, mut sv) = (0.0, 0.0, 0.0);
    for v in cv - r..=cv + r {
        for u in cu - r..=cu + r {
            if u < 0 || v < 0 || u >= W as i64 || v >= H as i64 {
                return None;
            }
            let w = (BG - 4.0 - img.get_pixel(u as u32, v as u32).0[0] as f64).max(0.0);
            sw += w;
            su += w * u as f64;
            sv += w * v as f64;
        }
    }
    (sw > 0.0).then(|| [su / sw, sv / sw])
}

/// Marker centroids in `img` around the positions `predict` gives; (max, rms) error in px and
/// the number of markers measured (those whose window lies inside the image).
fn marker_errors(
    img: &image::RgbaImage,
    predict: impl Fn(DVec3) -> Option<[f64; 2]>,
) -> (f64, f64, usize) {
    let r = 10;
    let (mut max, mut sq, mut n) = (0.0f64, 0.0, 0usize);
    for m in markers() {
        let Some(p) = predict(m) else { continue };
        if p[0] < r as f64 + 2.0
            || p[1] < r as f64 + 2.0
            || p[0] > W as f64 - r as f64 - 3.0
            || p[1] > H as f64 - r as f64 - 3.0
        {
            continue;
        }
        let Some(c) = centroid(img, p, r) else {
            continue;
        };
        let e = (c[0] - p[0]).hypot(c[1] - p[1]);
        max = max.max(e);
        sq += e * e;
        n += 1;
    }
    (max, (sq / n.max(1) as f64).sqrt(), n)
}

fn marker_store() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let s = Synth {
        levels: 1,
        size: SIDE,
        z: Z,
        finest_error: 0.01,
        texels: TEXELS,
    };
    let tex = marker_texture();
    write_store_textured(dir.path(), &s, |_| tex.clone(), |_| false);
    dir
}

#[test]
fn markers_land_on_the_distorted_projection() {
    let dir = marker_store();
    let mut on = scene(dir.path(), DistortionMode::Auto);
    let mut off = scene(dir.path(), DistortionMode::Off);
    // Barrel (the Engabreen photo's k1) and pincushion with a second coefficient.
    for (k1, k2) in [(-0.11454086509291705, 0.0), (0.06, 0.02)] {
        let cam = camera(k1, k2);
        let pinhole = CameraModel {
            k1: 0.0,
            k2: 0.0,
            ..cam
        };
        let r = on.frame(&cam, true).unwrap();
        assert!(
            r.distorted,
            "k1 {k1}: a distorted camera goes through the distortion pass"
        );
        let (pw, ph) = r.pinhole_size;
        assert!(
            pw > W && ph > H,
            "the pinhole view is wider than the frame: {pw}x{ph}"
        );
        let img = on.read_rgba().unwrap();
        assert!(on.read_depth().is_err(), "no depth for a distorted frame");
        let (max, rms, n) = marker_errors(&img, |p| cam.project(p));
        // The largest shift the distortion makes at the markers (what a pinhole render misses).
        let shift = markers()
            .iter()
            .filter_map(|&p| Some((cam.project(p)?, pinhole.project(p)?)))
            .filter(|(d, _)| {
                d[0] > 12.0 && d[1] > 12.0 && d[0] < W as f64 - 13.0 && d[1] < H as f64 - 13.0
            })
            .map(|(d, q)| (d[0] - q[0]).hypot(d[1] - q[1]))
            .fold(0.0, f64::max);
        eprintln!(
            "k1 {k1} k2 {k2}: {n} markers, max {max:.3} px, rms {rms:.3} px (distortion shifts them by up to {shift:.1} px; pinhole view {pw}x{ph})"
        );
        assert!(n >= 20, "only {n} markers in view");
        assert!(
            shift > 5.0,
            "the test camera should distort noticeably ({shift:.1} px)"
        );
        assert!(
            max <= 1.0 && rms <= 0.5,
            "k1 {k1} k2 {k2}: markers off the distorted projection by max {max:.3} px, rms {rms:.3} px"
        );
        // With distortion off the same camera renders the pinhole image: the markers sit on the
        // pinhole projection instead (which validates the centroids themselves).
        let r = off.frame(&cam, true).unwrap();
        assert!(!r.distorted);
        let img_off = off.read_rgba().unwrap();
        let (max_p, rms_p, n_p) = marker_errors(&img_off, |p| pinhole.project(p));
        eprintln!(
            "  --no-distortion: {n_p} markers on the pinhole projection, max {max_p:.3} px, rms {rms_p:.3} px"
        );
        assert!(max_p <= 1.0, "pinhole frame: max {max_p:.3} px");
    }
}

#[test]
fn the_resampling_pass_alone_reproduces_the_direct_frame() {
    let dir = marker_store();
    let cam = camera(0.0, 0.0);
    let mut direct = scene(dir.path(), DistortionMode::Auto);
    let r = direct.frame(&cam, true).unwrap();
    assert!(!r.distorted, "Auto leaves a distortion-free camera alone");
    let a = direct.read_rgba().unwrap();
    let mut forced = scene(dir.path(), DistortionMode::Always);
    let r = forced.frame(&cam, true).unwrap();
    assert!(r.distorted);
    assert_eq!(
        r.pinhole_size,
        (W + 4, H + 4),
        "no distortion: the pinhole view is the frame plus a 2 px margin"
    );
    let b = forced.read_rgba().unwrap();
    let d0 = image_difference(&a, &b, 0).unwrap();
    let d1 = image_difference(&a, &b, 1).unwrap();
    eprintln!(
        "k = 0, pass forced on vs off: mean abs {:.5} levels, {:.4} % of pixels differ at all, {:.4} % by more than 1 level",
        d0.mean_abs,
        100.0 * d0.frac_over,
        100.0 * d1.frac_over
    );
    // Identical up to rounding: the pass samples the pinhole image at (f32-rounded) texel
    // centres, and the shifted principal point rasterizes a few edge pixels differently.
    assert!(d0.max_abs <= 2, "a pixel differs by {} levels", d0.max_abs);
    assert!(
        d0.frac_over <= 1e-3 && d1.frac_over <= 1e-4,
        "{d0:?} {d1:?}"
    );
    assert!(d0.mean_abs < 0.01, "{d0:?}");
}

/// Issue #52's one validity rule: a barrel model that folds in the image's corners (as
/// `fit-camera` can fit it) is accepted and rendered; the corners beyond the fold, which the
/// model gives no ray, show the sky, and the markers elsewhere land on the projection.
#[test]
fn a_model_folding_in_the_corners_renders_with_sky_beyond_the_fold() {
    let dir = marker_store();
    let opts = SceneOptions {
        frame: FrameOptions {
            lit: false,
            sky: [20, 200, 30],
            ..Default::default()
        },
        ..Default::default()
    };
    let mut on = StoreRenderer::open(dir.path(), W, H, opts).unwrap();
    let cam = camera(-0.5, 0.0);
    assert_eq!(cam.problem(), None);
    let share = cam.rayless_share();
    assert!(share > 0.01 && share < 0.3, "{share}");
    assert!(cam.pixel_ray(0.0, 0.0).is_none());
    let r = on.frame(&cam, true).unwrap();
    assert!(r.distorted);
    let img = on.read_rgba().unwrap();
    let sky = |u: u32, v: u32| img.get_pixel(u, v).0[..3] == [20, 200, 30];
    assert!(
        sky(0, 0) && sky(W - 1, H - 1),
        "corners beyond the fold are sky"
    );
    assert!(!sky(W / 2, H / 2) && !sky(W / 2, 5), "the rest is terrain");
    let (max, rms, n) = marker_errors(&img, |p| {
        let q = cam.project(p)?;
        // markers whose window lies within the fold
        let r = ((q[0] - cam.cx) / cam.fx).hypot((q[1] - cam.cy) / cam.fy);
        (r < 0.9 * cam.fold_radius()).then_some(q)
    });
    eprintln!(
        "k1 -0.5: {n} markers within the fold, max {max:.3} px, rms {rms:.3} px; {:.1} % of the pixels beyond it",
        100.0 * share
    );
    assert!(
        n >= 20 && max <= 1.0 && rms <= 0.5,
        "{n} markers, max {max}, rms {rms}"
    );
}
