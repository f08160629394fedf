//! Shared helpers for integration tests.
#![allow(dead_code)]

pub mod exif;
pub mod tiffgen;

use std::path::PathBuf;

/// Path of a file in the shared real-data directory: `$CLIFFMAP_SHARED_DATA`, else
/// `$CARGO_MANIFEST_DIR/../shared/data/real`, else `/work/shared/data/real`. Panics (so the
/// test fails loudly) if the file does not exist.
pub fn real_data(rel: &str) -> PathBuf {
    let candidates = [
        std::env::var_os("CLIFFMAP_SHARED_DATA").map(PathBuf::from),
        Some(PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../shared/data/real"
        ))),
        Some(PathBuf::from("/work/shared/data/real")),
    ];
    for dir in candidates.into_iter().flatten() {
        if dir.is_dir() {
            let p = dir.join(rel);
            assert!(p.exists(), "real data file {} is missing", p.display());
            return p;
        }
    }
    panic!("real data directory not found (set CLIFFMAP_SHARED_DATA)");
}

use cliffmap::{Dem, DemLoadOptions, Ortho, OrthoPlacement};

#[allow(unused_imports)]
pub use cliffmap::cells::grid_tin;

/// The Engabreen DEM (507 x 590 at 3 m, UTM 33N) through the raw f32 reader.
pub fn engabreen_dem() -> Dem {
    let opts = DemLoadOptions {
        width: Some(507),
        height: Some(590),
        spacing: Some(3.0),
        origin: Some((445302.17, 7396769.45)),
        ..Default::default()
    };
    cliffmap::load_dem(&real_data("engabreen/engabreen_dem_3m_507x590.f32"), &opts).unwrap()
}

/// The Engabreen ortho on the DEM grid; pure black pixels (the wedge without image data)
/// get alpha 0, as `--ortho-nodata-colour 0,0,0` does on the command line.
pub fn engabreen_ortho(dem: &Dem) -> Ortho {
    let p = real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let mut o = cliffmap::load_ortho(&p, OrthoPlacement::SameGridAsDem, dem, 1 << 30).unwrap();
    for px in o.image.pixels_mut() {
        if px.0[..3] == [0, 0, 0] {
            px.0[3] = 0;
        }
    }
    o
}

/// Writes the ground photos of `scene` (over its DEM `dem`) at `w × h`, without
/// supersampling, into `dir`, and projects them into the store `store` with the default
/// options.
pub fn project_demo_photos(
    store: &std::path::Path,
    scene: &cliffmap::demo_scene::DemoScene,
    dem: &Dem,
    dir: &std::path::Path,
    (w, h): (u32, u32),
) {
    use cliffmap::pipeline::{ProjectOptions, project_store};
    let opts = cliffmap::demo_scene::DemoPhotoOptions {
        width: w,
        height: h,
        supersample: 1,
    };
    let list = scene.write_demo_photos(dem, dir, &opts).unwrap();
    let photos = cliffmap::photo::read_photo_list(&list).unwrap();
    project_store(
        store,
        &photos,
        &ProjectOptions {
            ..ProjectOptions::default()
        },
    )
    .unwrap();
}

/// A small store of the demo scene (129 × 129 samples at 4 m, max error 0.5 m, 32-interval
/// cells with 64² textures) in `dir`, reparameterized when `reparam`.
pub fn small_demo_store(dir: &std::path::Path, reparam: bool) {
    use cliffmap::pipeline::{
        BuildInputs, BuildOptions, ReparamOptions, build_store, reparam_store,
    };
    let scene = cliffmap::demo_scene::DemoScene {
        samples: 129,
        spacing: 4.0,
        ..cliffmap::demo_scene::DemoScene::default()
    };
    let (dem, ortho) = scene.generate().unwrap();
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "t".into(),
        ortho_source: Some("t".into()),
        fingerprint: "small-demo".into(),
    };
    let opts = BuildOptions {
        max_error: 0.5,
        cell_intervals: 32,
        cell_texels: 64,
        force: true,
        ..BuildOptions::default()
    };
    build_store(&inputs, &opts, dir).unwrap();
    if reparam {
        reparam_store(
            dir,
            &ReparamOptions {
                ..ReparamOptions::default()
            },
        )
        .unwrap();
    }
}

/// `build` arguments for the Engabreen DEM + ortho (1 m error, 64² textures) into `out`.
pub fn engabreen_build_args(
    dem: &std::path::Path,
    ortho: &std::path::Path,
    out: &std::path::Path,
) -> Vec<String> {
    let s = |p: &std::path::Path| p.to_str().expect("utf-8 path").to_string();
    [
        "build",
        "--dem",
        &s(dem),
        "--width",
        "507",
        "--height",
        "590",
        "--spacing",
        "3",
        "--origin",
        "445302.17,7396769.45",
        "--ortho",
        &s(ortho),
        "--ortho-same-grid",
        "--max-error",
        "1.0",
        "--cell-texels",
        "64",
        "--out",
        &s(out),
        "--quiet",
    ]
    .map(String::from)
    .to_vec()
}
