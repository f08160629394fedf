//! The render-space evaluation (docs/evaluation.md): its reference images on a case whose
//! answer is known, the scores of known images, and the photo gain as the photo texture
//! budget grows.

use std::path::Path;

use cliffmap::demo_scene::{DemTracer, DemoScene};
use cliffmap::eval::{
    BASELINE, Class, EvalOptions, ORACLE, ReferenceSources, evaluate_views, reference_images,
    score_view,
};
use cliffmap::photo::PhotoInput;
use cliffmap::pipeline::{
    BuildInputs, BuildOptions, PhotoTextureOptions, ProjectOptions, ReparamOptions, build_store,
    project_store, reparam_store,
};

fn tracer_origin(dem: &cliffmap::Dem) -> glam::DVec3 {
    let (x, y) = dem
        .georef
        .world(dem.height as f64 / 2.0, dem.width as f64 / 2.0);
    let (lo, hi) = dem.height_range();
    glam::DVec3::new(x, y, 0.5 * (lo + hi) as f64)
}

#[test]
fn the_oracle_of_a_photo_taken_from_the_view_is_the_truth() {
    // A photo taken from the view's own camera, one ray per pixel: ideal projective
    // texturing from it reproduces the truth wherever the photo sees the surface.
    let scene = DemoScene {
        samples: 129,
        spacing: 4.0,
        ..DemoScene::default()
    };
    let (dem, ortho) = scene.generate().unwrap();
    let view = scene
        .novel_views(160, 90)
        .into_iter()
        .next()
        .expect("a view");
    let photo = scene.render_truth_photo(&dem, &view.camera, 1).unwrap();
    let photos = [PhotoInput {
        name: "self".into(),
        image_path: "self.png".into(),
        image: photo,
        camera: view.camera,
        mask: None,
    }];
    let tracer = DemTracer::new(&dem, tracer_origin(&dem)).unwrap();
    let src = ReferenceSources {
        scene: &scene,
        tracer: &tracer,
        ortho: &ortho,
        photos: &photos,
    };
    let r = reference_images(&src, &view.camera, 1).unwrap();
    // the truth of the view is the photo (same rays, same colours)
    // (the two casts use BVHs in different f32 frames: hit points agree to micrometres)
    let diff = r
        .truth
        .pixels()
        .zip(photos[0].image.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) > 1))
        .count();
    assert!(diff * 1000 < r.truth.len() / 3, "{diff} pixels differ");
    let rep = score_view("self", &r, &[], 2.0).unwrap();
    let oracle = rep.method(ORACLE).unwrap();
    // the photo covers nearly all terrain: all but the pixels along its own silhouettes,
    // where a sample would mix in sky or the occluder (the oracle takes the ortho there)
    let (terrain, covered) = (
        oracle.terrain.pixels,
        r.classes
            .iter()
            .filter(|c| **c & cliffmap::eval::COVERED != 0)
            .count() as u64,
    );
    assert!(
        terrain > 5000 && covered * 100 > terrain * 95,
        "{covered} of {terrain} covered"
    );
    // on the covered walls the oracle is the truth (8-bit rounding only) and far better than
    // the ortho
    let steep = oracle.steep_covered;
    assert!(steep.pixels > 200, "{}", steep.pixels);
    assert!(steep.psnr > 45.0, "oracle {} dB", steep.psnr);
    assert!(
        rep.gain(ORACLE, Class::SteepCovered).unwrap()[0] > 10.0,
        "{:?}",
        rep.gain(ORACLE, Class::SteepCovered)
    );
}

#[test]
fn known_images_get_known_scores() {
    let scene = DemoScene {
        samples: 129,
        spacing: 4.0,
        ..DemoScene::default()
    };
    let (dem, ortho) = scene.generate().unwrap();
    let view = scene
        .novel_views(120, 68)
        .into_iter()
        .nth(1)
        .expect("a view");
    let tracer = DemTracer::new(&dem, tracer_origin(&dem)).unwrap();
    let src = ReferenceSources {
        scene: &scene,
        tracer: &tracer,
        ortho: &ortho,
        photos: &[],
    };
    let r = reference_images(&src, &view.camera, 2).unwrap();
    // without photos the oracle is the baseline; the truth itself scores infinitely
    assert_eq!(r.oracle, r.baseline);
    let methods = vec![
        ("truth".to_string(), r.truth.clone()),
        ("same_as_baseline".to_string(), r.baseline.clone()),
    ];
    let rep = score_view("v", &r, &methods, 2.0).unwrap();
    assert_eq!(rep.method("truth").unwrap().terrain.psnr, f64::INFINITY);
    assert_eq!(
        rep.gain("same_as_baseline", Class::Terrain).unwrap(),
        [0.0, 0.0]
    );
    assert!(rep.method(BASELINE).unwrap().terrain.psnr.is_finite());
    // no photo covers anything
    assert_eq!(rep.method(BASELINE).unwrap().steep_covered.pixels, 0);
    // a wrong size is an error
    let small = image::RgbImage::new(10, 10);
    assert!(score_view("v", &r, &[("small".into(), small)], 2.0).is_err());
}

/// A small demo scene's store with reparameterized cells in `dir`.
fn small_store(scene: &DemoScene, dem: &cliffmap::Dem, ortho: &cliffmap::Ortho, dir: &Path) {
    let inputs = BuildInputs {
        dem,
        ortho: Some(ortho),
        dem_source: "eval-test".into(),
        ortho_source: Some("eval-test".into()),
        fingerprint: format!("eval-test:{scene:?}"),
    };
    let opts = BuildOptions {
        max_error: 0.25,
        cell_intervals: 32,
        cell_texels: 64,
        force: true,
        ..BuildOptions::default()
    };
    build_store(&inputs, &opts, dir).unwrap();
    reparam_store(
        dir,
        &ReparamOptions {
            ..ReparamOptions::default()
        },
    )
    .unwrap();
}

#[test]
fn the_photo_gain_does_not_fall_as_the_texture_budget_grows() {
    let t = tempfile::tempdir().unwrap();
    let scene = DemoScene {
        samples: 257,
        spacing: 2.0,
        ..DemoScene::default()
    };
    let (dem, ortho) = scene.generate().unwrap();
    let store = t.path().join("store");
    small_store(&scene, &dem, &ortho, &store);
    let photo_dir = t.path().join("photos");
    let list = scene
        .write_demo_photos(
            &dem,
            &photo_dir,
            &cliffmap::demo_scene::DemoPhotoOptions {
                width: 480,
                height: 360,
                supersample: 1,
            },
        )
        .unwrap();
    let photos = cliffmap::photo::read_photo_list(&list).unwrap();
    let views: Vec<_> = scene.novel_views(240, 136).into_iter().take(2).collect();
    let tracer = DemTracer::new(&dem, tracer_origin(&dem)).unwrap();
    let src = ReferenceSources {
        scene: &scene,
        tracer: &tracer,
        ortho: &ortho,
        photos: &photos,
    };
    let eopts = EvalOptions {
        supersample: 1,
        tin_baseline: false,
        ..EvalOptions::default()
    };
    let budgets = [None, Some(1u64 << 20), Some(1u64 << 30)];
    let mut gains: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut bytes = Vec::new();
    for b in budgets {
        let texture = match b {
            None => PhotoTextureOptions {
                photo_driven: false,
                ..PhotoTextureOptions::default()
            },
            Some(budget_bytes) => PhotoTextureOptions {
                budget_bytes,
                ..PhotoTextureOptions::default()
            },
        };
        let r = project_store(
            &store,
            &photos,
            &ProjectOptions {
                texture,
                ..ProjectOptions::default()
            },
        )
        .unwrap();
        bytes.push(
            r.settings
                .levels
                .iter()
                .map(|l| l.photo_texture_bytes)
                .sum::<u64>(),
        );
        let (reports, _) = match evaluate_views(&store, &src, &views, &eopts) {
            Ok(x) => x,
            Err(e) => {
                panic!("cannot render (install Mesa: apt-get install mesa-vulkan-drivers): {e}")
            }
        };
        gains.push(
            reports
                .iter()
                .map(|r| r.gain("photo", Class::SteepCovered).unwrap())
                .collect(),
        );
    }
    // more texture memory is granted as the budget grows, and the photos' gain on the steep
    // covered pixels of every view, full-resolution and low-pass, does not fall (0.05 dB of
    // rasterization noise allowed)
    assert!(bytes[0] <= bytes[1] && bytes[1] < bytes[2], "{bytes:?}");
    for k in 1..gains.len() {
        for (v, (a, b)) in gains[k - 1].iter().zip(&gains[k]).enumerate() {
            for i in 0..2 {
                assert!(
                    b[i] >= a[i] - 0.05,
                    "budget step {k}, view {v}: gain {:?} -> {:?} ({gains:?})",
                    a,
                    b
                );
            }
        }
    }
    // and the photos do gain on the walls
    assert!(
        gains[2].iter().all(|g| g[0] > 3.0 && g[1] > 3.0),
        "{gains:?}"
    );
}
