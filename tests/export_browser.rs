//! `cliffmap export-tiles` opened in a real browser: the demo store with its ground photos
//! projected (so the walls carry photo textures), the generated CesiumJS page in headless
//! Chromium (SwiftShader WebGL, `tools/js/screenshot_tiles.mjs`) from a demo photo's camera,
//! compared with `cliffmap render --unlit` (best texture) of the same camera on terrain
//! pixels, and the page's ortho texture mode (`--modes all`, `?mode=ortho`) with
//! `render --mode ortho`; the tilesets are split into external child tilesets every 2
//! levels, which the page follows. Chromium,
//! CesiumJS and puppeteer-core are installed by `.ci/run`.

mod cli_util;
mod common;

use cli_util::ok;
use cliffmap::camera::camera_to_json;
use cliffmap::demo_scene::DemoScene;
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};

#[test]
fn cesium_page_shows_what_cliffmap_renders() {
    let tools = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/js");
    assert!(
        tools.join("node_modules/cesium").exists()
            && tools.join("node_modules/puppeteer-core").exists(),
        "CesiumJS / puppeteer-core are not installed: run `npm ci --prefix tools/js` (as .ci/run does)"
    );
    let tmp = tempfile::tempdir().unwrap();
    let scene = DemoScene::default();
    let (dem, ortho) = scene.generate().unwrap();
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "t".into(),
        ortho_source: Some("t".into()),
        fingerprint: "browser".into(),
    };
    let store = tmp.path().join("store");
    build_store(
        &inputs,
        &BuildOptions {
            force: true,
            ..BuildOptions::default()
        },
        &store,
    )
    .unwrap();
    common::project_demo_photos(&store, &scene, &dem, &tmp.path().join("photos"), (800, 600));
    let (w, h) = (640u32, 480u32);
    let cam = scene.photo_shots()[0].camera.resized(w, h);
    let cam_file = tmp.path().join("view.json");
    std::fs::write(
        &cam_file,
        serde_json::to_string(&camera_to_json(&cam)).unwrap(),
    )
    .unwrap();
    let out = tmp.path().join("tiles");
    let (s, o, c) = (
        store.to_str().unwrap(),
        out.to_str().unwrap(),
        cam_file.to_str().unwrap(),
    );
    ok(&[
        "export-tiles",
        s,
        "--out",
        o,
        "--crs",
        "EPSG:32633",
        "--view",
        c,
        "--modes",
        "all",
        // external child tilesets every 2 levels, so that CesiumJS follows them too (the
        // one-file layout is the default for stores this small)
        "--subtree-levels",
        "2",
        "--quiet",
    ]);
    assert!(out.join("subtrees").exists() && out.join("subtrees_ortho").exists());
    assert!(out.join("tileset_ortho.json").exists() && out.join("tileset_reparam.json").exists());
    assert!(out.join("index.html").exists() && out.join("views/view.json").exists());
    // The tiles carry the photo textures where the store has them.
    let m = cliffmap::store::Store::open(&store).unwrap();
    let with_photo: Vec<_> = m
        .manifest
        .cells
        .iter()
        .filter(|c| c.photo.is_some())
        .collect();
    assert!(!with_photo.is_empty());
    for c in &with_photo {
        let g = gltf::Gltf::from_slice(
            &std::fs::read(out.join(cliffmap::export::tile_path(c.level, c.x, c.y))).unwrap(),
        )
        .unwrap();
        assert!(
            g.document
                .images()
                .next()
                .unwrap()
                .name()
                .unwrap()
                .ends_with("photo"),
            "{}",
            c.id
        );
    }
    // The best texture (default page) against `cliffmap render`, then the ortho mode of the
    // page's toggle against `render --mode ortho`.
    for mode in [None, Some("ortho")] {
        let shot = tmp
            .path()
            .join(format!("cesium_{}.png", mode.unwrap_or("best")));
        let mut args = vec![
            o.to_string(),
            "views/view.json".into(),
            shot.to_str().unwrap().into(),
            w.to_string(),
            h.to_string(),
        ];
        args.extend(mode.map(String::from));
        let status = std::process::Command::new("node")
            .arg(tools.join("screenshot_tiles.mjs"))
            .args(&args)
            .status()
            .expect("cannot start node");
        assert!(status.success(), "the browser screenshot failed ({mode:?})");
        let ours = tmp
            .path()
            .join(format!("cliffmap_{}.png", mode.unwrap_or("best")));
        // `--camera` takes a pinhole view; the demo's first photo has no distortion.
        let size = format!("{w}x{h}");
        let mut r = vec![
            "render",
            s,
            "--camera",
            c,
            "--size",
            &size,
            "--unlit",
            "--out",
            ours.to_str().unwrap(),
        ];
        if let Some(m) = mode {
            r.extend(["--mode", m]);
        }
        ok(&r);
        let (psnr, share) = terrain_psnr(&shot, &ours, w, h);
        eprintln!(
            "Cesium vs cliffmap render ({mode:?}): {psnr:.1} dB on {:.0} % terrain pixels",
            100.0 * share
        );
        assert!(
            share > 0.3,
            "only {:.0} % of the pixels are terrain in both images ({mode:?})",
            100.0 * share
        );
        assert!(
            psnr >= 28.0,
            "Cesium's view differs from cliffmap's render ({mode:?}): {psnr:.1} dB"
        );
    }
    // The two modes show different textures (the photo detail is in the best one only).
    let (between, _) = terrain_psnr(
        &tmp.path().join("cesium_best.png"),
        &tmp.path().join("cesium_ortho.png"),
        w,
        h,
    );
    assert!(
        between < 40.0,
        "the ortho and photo modes look the same ({between:.1} dB)"
    );
}

/// PSNR (dB) of two renders on the pixels that are terrain in both (neither cliffmap's sky
/// nor Cesium's black background), and the share of such pixels.
fn terrain_psnr(a: &std::path::Path, b: &std::path::Path, w: u32, h: u32) -> (f64, f64) {
    let a = image::open(a).unwrap().to_rgb8();
    let b = image::open(b).unwrap().to_rgb8();
    assert_eq!(a.dimensions(), b.dimensions());
    let sky = [170i32, 200, 235];
    let (mut se, mut n) = (0.0f64, 0usize);
    for (pa, pb) in a.pixels().zip(b.pixels()) {
        let is_sky =
            |p: &image::Rgb<u8>| (0..3).map(|k| (p[k] as i32 - sky[k]).abs()).sum::<i32>() <= 6;
        let is_background = |p: &image::Rgb<u8>| p.0.iter().map(|&v| v as i32).sum::<i32>() <= 6;
        if !is_sky(pb) && !is_sky(pa) && !is_background(pa) && !is_background(pb) {
            se += (0..3)
                .map(|k| (pa[k] as f64 - pb[k] as f64).powi(2))
                .sum::<f64>()
                / 3.0;
            n += 1;
        }
    }
    (
        10.0 * (255.0f64.powi(2) / (se / n.max(1) as f64)).log10(),
        n as f64 / (w * h) as f64,
    )
}
