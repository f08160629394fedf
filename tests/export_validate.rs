//! Exports checked by independent validators (issue #18, "Validation"):
//! `tools/validate/validate.mjs` runs the Khronos glTF validator (npm `gltf-validator`) on
//! every GLB and validates every tileset JSON against the official 3D Tiles 1.1 JSON schemas
//! (Ajv), following external tilesets and checking that every content file exists and every
//! GLB is referenced. CesiumGS' `3d-tiles-validator` is not on the npm registry CI uses
//! (docs/export.md, "Validation"). Node and the packages are installed by `.ci/run`
//! (`npm ci --prefix tools/validate`).
//!
//! Exported: the demo scene (small store, reparameterized, four ray-traced demo photos
//! projected: photo, reparameterized and ortho textures) as `export-glb` and as
//! `export-tiles` with every texture mode, external child tilesets and JPEG textures; and
//! Engabreen (the CLI tests' 1 m build, reparameterized) as `export-tiles` (UTM 33N, geoid
//! offset, a view) and `export-glb`. Then broken copies show that the validators do fail.

mod cli_util;
mod common;

use std::path::{Path, PathBuf};

use cli_util::{ok, s, validate_export};

/// Issue codes (any severity below error) that the exports may report without failing the
/// test, with the reason. None: on 2026-12-04 the exports gave 0 errors, 0 warnings, 0 infos
/// and 0 hints from both validators, so any new message is a regression to look at.
const ACCEPTED: &[(&str, &str)] = &[];

/// Fails unless the validator exited 0 and reported nothing but [`ACCEPTED`] codes; returns
/// the totals (`gltf` files, `tilesets`).
fn assert_clean(code: i32, summary: &serde_json::Value) -> (u64, u64) {
    let mut bad = Vec::new();
    for f in summary["files"].as_array().expect("files") {
        for (issue, v) in f["issues"].as_object().expect("issues") {
            if v["severity"] == 0 || !ACCEPTED.iter().any(|(c, _)| c == issue) {
                bad.push(format!(
                    "{} {issue} ×{} {}",
                    f["file"], v["count"], f["messages"]
                ));
            }
        }
    }
    assert!(
        code == 0 && bad.is_empty(),
        "validation (exit {code}) reported:\n{}\ntotals {}",
        bad.join("\n"),
        summary["totals"]
    );
    let t = &summary["totals"];
    eprintln!(
        "validated: {t} (gltf-validator {}, ajv {})",
        summary["tools"]["gltf-validator"], summary["tools"]["ajv"]
    );
    (t["gltf"].as_u64().unwrap(), t["tilesets"].as_u64().unwrap())
}

/// The codes of every issue the summary reports for `file` (a path ending), sorted.
fn codes_of(summary: &serde_json::Value, file: &str) -> Vec<String> {
    let f = summary["files"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["file"].as_str().unwrap().ends_with(file))
        .unwrap_or_else(|| panic!("{file} not in the summary"));
    let mut c: Vec<String> = f["issues"].as_object().unwrap().keys().cloned().collect();
    c.sort();
    c
}

/// The small demo store with the demo's ground photos projected, so that the exports carry
/// all three texture sources.
fn demo_store_with_photos(tmp: &Path) -> PathBuf {
    use cliffmap::pipeline::{ProjectOptions, project_store};
    let store = tmp.join("store");
    common::small_demo_store(&store, true);
    // the scene of small_demo_store; its photos from the usual aims at 320 × 240
    let scene = cliffmap::scene::DemoScene {
        samples: 129,
        spacing: 4.0,
        ..cliffmap::scene::DemoScene::default()
    };
    let (dem, _) = scene.generate().unwrap();
    let opts = cliffmap::scene::DemoPhotoOptions {
        width: 320,
        height: 240,
        supersample: 1,
    };
    let list = scene
        .write_demo_photos(&dem, &tmp.join("photos"), &opts)
        .unwrap();
    let photos = cliffmap::photo::read_photo_list(&list).unwrap();
    project_store(
        &store,
        &photos,
        &ProjectOptions {
            quiet: true,
            ..ProjectOptions::default()
        },
    )
    .unwrap();
    store
}

#[test]
fn demo_exports_pass_the_gltf_validator_and_the_3d_tiles_schemas() {
    let tmp = tempfile::tempdir().unwrap();
    let store = demo_store_with_photos(tmp.path());
    let st = cliffmap::store::Store::open(&store).unwrap();
    let cells = st.manifest.cells.len() as u64;
    let sources = |f: fn(&cliffmap::store::CellRecord) -> bool| {
        st.manifest.cells.iter().filter(|c| f(c)).count()
    };
    assert!(
        sources(|c| c.photo.is_some()) > 0
            && sources(|c| c.photo.is_none() && c.reparam.is_some()) > 0,
        "the test wants photo and reparameterized textures"
    );
    let glb = tmp.path().join("demo.glb");
    let glb0 = tmp.path().join("demo_level0.glb");
    let all = tmp.path().join("all");
    let jpeg = tmp.path().join("jpeg");
    ok(&["export-glb", s(&store), "--out", s(&glb), "--quiet"]);
    ok(&[
        "export-glb",
        s(&store),
        "--out",
        s(&glb0),
        "--level",
        "0",
        "--quiet",
    ]);
    ok(&[
        "export-tiles",
        s(&store),
        "--out",
        s(&all),
        "--crs",
        "EPSG:32633",
        "--modes",
        "all",
        "--subtree-levels",
        "1",
        "--quiet",
    ]);
    ok(&[
        "export-tiles",
        s(&store),
        "--out",
        s(&jpeg),
        "--crs",
        "EPSG:32633",
        "--geoid-offset",
        "35",
        "--jpeg-quality",
        "85",
        "--quiet",
    ]);
    let (code, summary) = validate_export(&[&glb, &glb0, &all, &jpeg]);
    let (gltf, tilesets) = assert_clean(code, &summary);
    // Every tile of every tileset was reached and validated, plus the two GLBs.
    assert_eq!(gltf, 3 * cells + cells + 2);
    let levels = st.manifest.quadtree.levels;
    let external = st
        .manifest
        .cells
        .iter()
        .filter(|c| c.level >= 1 && c.level + 1 < levels)
        .count() as u64;
    assert_eq!(tilesets, 3 * (1 + external) + 1);

    // The same validators on broken copies: a truncated GLB, a missing one, a stray one, a
    // tileset with a 3-number box and a child whose error exceeds its parent's.
    let bad = tmp.path().join("bad");
    ok(&[
        "export-tiles",
        s(&store),
        "--out",
        s(&bad),
        "--crs",
        "EPSG:32633",
        "--quiet",
    ]);
    let tiles: Vec<PathBuf> = cli_util::files_under(&bad.join("tiles"));
    let truncated = &tiles[0];
    let bytes = std::fs::read(truncated).unwrap();
    std::fs::write(truncated, &bytes[..bytes.len() / 2]).unwrap();
    std::fs::remove_file(&tiles[1]).unwrap();
    std::fs::copy(&glb, bad.join("tiles/stray.glb")).unwrap();
    let ts_path = bad.join("tileset.json");
    let mut ts: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&ts_path).unwrap()).unwrap();
    ts["root"]["children"][0]["boundingVolume"]["box"] = serde_json::json!([0.0, 0.0, 0.0]);
    ts["root"]["children"][0]["geometricError"] = serde_json::json!(1e9);
    std::fs::write(&ts_path, serde_json::to_vec(&ts).unwrap()).unwrap();
    let (code, summary) = validate_export(&[&bad]);
    assert_eq!(code, 1, "broken exports must fail: {summary:#}");
    let rel = |p: &Path| p.strip_prefix(&bad).unwrap().to_str().unwrap().to_string();
    assert_eq!(
        codes_of(&summary, &rel(truncated)),
        ["GLB_UNEXPECTED_END_OF_CHUNK_DATA"]
    );
    assert_eq!(
        codes_of(&summary, "tiles/stray.glb"),
        ["UNREFERENCED_CONTENT"]
    );
    assert_eq!(
        codes_of(&summary, "tileset.json"),
        [
            "CONTENT_FILE_MISSING",
            "SCHEMA_VIOLATION",
            "TILE_GEOMETRIC_ERRORS_INCONSISTENT"
        ]
    );
    let messages = summary["files"].to_string();
    assert!(
        messages.contains(&rel(&tiles[1])),
        "the missing GLB is named"
    );
    assert!(
        messages.contains("/root/children/0/boundingVolume/box"),
        "the bad box is pointed at"
    );
}

#[test]
fn engabreen_exports_pass_the_gltf_validator_and_the_3d_tiles_schemas() {
    let tmp = tempfile::tempdir().unwrap();
    let store = tmp.path().join("eng.store");
    let dem = common::real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let ortho = common::real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let args = common::engabreen_build_args(&dem, &ortho, &store);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    ok(&["reparam", s(&store), "--threshold", "1.1", "--quiet"]);
    let cells = cliffmap::store::Store::open(&store)
        .unwrap()
        .manifest
        .cells
        .len() as u64;
    let tiles = tmp.path().join("tiles");
    let glb = tmp.path().join("engabreen.glb");
    let view = common::real_data("engabreen/engabreen_camera_IMG_8902.json");
    ok(&[
        "export-tiles",
        s(&store),
        "--out",
        s(&tiles),
        "--crs",
        "EPSG:32633",
        "--geoid-offset",
        "37.5",
        "--view",
        s(&view),
        "--quiet",
    ]);
    ok(&["export-glb", s(&store), "--out", s(&glb), "--quiet"]);
    let (code, summary) = validate_export(&[&tiles, &glb]);
    assert_eq!(assert_clean(code, &summary), (cells + 1, 1));
}
