//! Exports checked by independent validators (issue #18, "Validation"):
//! - `tools/validate/validate.mjs` runs the Khronos glTF validator (npm `gltf-validator`) on
//!   every GLB and validates every tileset JSON against the official 3D Tiles 1.1 JSON
//!   schemas (Ajv), following external tilesets and checking that every content file exists
//!   and every GLB is referenced.
//! - CesiumGS' `3d-tiles-validator` 0.6.1, vendored as source in `tools/3d-tiles-validator`
//!   (it is not on the npm registry CI uses; README.md there says what was changed), runs on
//!   every exported `tileset*.json` with a report file. Its CLI exits 0 even with errors,
//!   so the test reads `numErrors`, `numWarnings` and `numInfos` from the report.
//!
//! Node and the packages are installed by `.ci/run` (`npm ci --prefix tools/validate`;
//! `npm ci --prefix tools/3d-tiles-validator` and its `tsc` build); a missing install fails
//! the tests, saying how to install it.
//!
//! Exported: the demo scene (small store, reparameterized, four ray-traced demo photos
//! projected: photo, reparameterized and ortho textures) as `export-glb` and as
//! `export-tiles` with every texture mode, external child tilesets and JPEG textures; and
//! Engabreen (the CLI tests' 1 m build, reparameterized) as `export-tiles` (UTM 33N, geoid
//! offset, a view) and `export-glb`. Then broken copies show that the validators do fail.

mod cli_util;
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use cli_util::{ok, s, validate_export};

/// Issue codes (any severity below error) that the exports may report without failing the
/// test, with the reason. None: on 2026-12-04 the exports gave 0 errors, 0 warnings, 0 infos
/// and 0 hints from both validators, so any new message is a regression to look at.
const ACCEPTED: &[(&str, &str)] = &[];

/// Whether every message of code `issue` in file summary `f` is what the Khronos glTF
/// validator says of a GLB with `EXT_structural_metadata`, which it does not support: the
/// extension named as unsupported, and the property textures (referenced only from the
/// extension) as possibly unused. The extension itself is validated by 3d-tiles-validator.
fn metadata_only(f: &serde_json::Value, issue: &str) -> bool {
    let msgs: Vec<&serde_json::Value> = f["messages"]
        .as_array()
        .map(|m| m.iter().filter(|m| m["code"] == issue).collect())
        .unwrap_or_default();
    !msgs.is_empty()
        && msgs.iter().all(|m| match issue {
            "UNSUPPORTED_EXTENSION" => m["message"]
                .as_str()
                .is_some_and(|t| t.contains("'EXT_structural_metadata'")),
            "UNUSED_OBJECT" => m["pointer"]
                .as_str()
                .is_some_and(|p| p.starts_with("/textures/")),
            _ => false,
        })
}

/// Fails unless the validator exited 0 and reported nothing but [`ACCEPTED`] codes (and, in
/// files under `metadata` — exported with `--metadata` — what [`metadata_only`] accepts);
/// returns the totals (`gltf` files, `tilesets`).
fn assert_clean(code: i32, summary: &serde_json::Value, metadata: &[&Path]) -> (u64, u64) {
    let mut bad = Vec::new();
    for f in summary["files"].as_array().expect("files") {
        let with_metadata = f["file"]
            .as_str()
            .is_some_and(|p| metadata.iter().any(|m| Path::new(p).starts_with(m)));
        for (issue, v) in f["issues"].as_object().expect("issues") {
            if with_metadata && v["severity"] != 0 && metadata_only(f, issue) {
                continue;
            }
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

/// Runs the vendored 3d-tiles-validator (`tools/3d-tiles-validator`, compiled to `build/` by
/// `.ci/run`) on one tileset JSON file and returns its report: `{"date", "numErrors",
/// "numWarnings", "numInfos", "issues": [{"type", "path", "message", "severity", "causes"}]}`
/// (`issues` absent when there is none; glTF content is validated by the Khronos glTF
/// validator, whose messages down to INFO come as `causes` of a `CONTENT_VALIDATION_*`
/// issue). Fails, saying how to install it, when it is not installed or built.
fn tiles_validator(tileset: &Path) -> serde_json::Value {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/3d-tiles-validator");
    let main = dir.join("build/main.js");
    assert!(
        dir.join("node_modules/3d-tiles-tools").exists() && main.exists(),
        "3d-tiles-validator is not installed: run `npm ci --prefix tools/3d-tiles-validator \
         --ignore-scripts && npm run --prefix tools/3d-tiles-validator build` (as .ci/run does)"
    );
    let report = tempfile::Builder::new()
        .prefix("3d-tiles-validator-report")
        .suffix(".json")
        .tempfile()
        .unwrap();
    let t0 = std::time::Instant::now();
    let o = Command::new("node")
        .arg(&main)
        .arg("--tilesetFile")
        .arg(tileset)
        .arg("--reportFile")
        .arg(report.path())
        .output()
        .expect("cannot start node (.ci/run installs it)");
    // The CLI exits 0 whatever it finds; anything else is a crash.
    let out = || {
        format!(
            "stdout: {}\nstderr: {}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    };
    assert!(
        o.status.success(),
        "3d-tiles-validator failed to run on {tileset:?}:\n{}",
        out()
    );
    let bytes = std::fs::read(report.path()).unwrap();
    let report: serde_json::Value = serde_json::from_slice(&bytes).unwrap_or_else(|e| {
        panic!(
            "no 3d-tiles-validator report for {tileset:?} ({e}):\n{}",
            out()
        )
    });
    for k in ["numErrors", "numWarnings", "numInfos"] {
        assert!(report[k].is_u64(), "report without {k}: {report:#}");
    }
    eprintln!(
        "3d-tiles-validator {}: {} errors, {} warnings, {} infos ({:.1} s)",
        tileset.display(),
        report["numErrors"],
        report["numWarnings"],
        report["numInfos"],
        t0.elapsed().as_secs_f64()
    );
    report
}

/// Every issue of a 3d-tiles-validator report, causes included (indented under their
/// issue), as `SEVERITY TYPE path: message` lines.
fn issue_lines(report: &serde_json::Value) -> Vec<String> {
    fn walk(issues: &serde_json::Value, depth: usize, out: &mut Vec<String>) {
        for i in issues.as_array().into_iter().flatten() {
            out.push(format!(
                "{}{} {} {}: {}",
                "  ".repeat(depth),
                i["severity"].as_str().unwrap_or("?"),
                i["type"].as_str().unwrap_or("?"),
                i["path"].as_str().unwrap_or("-"),
                i["message"].as_str().unwrap_or("")
            ));
            walk(&i["causes"], depth + 1, out);
        }
    }
    let mut out = Vec::new();
    walk(&report["issues"], 0, &mut out);
    out
}

/// The (severity, type) of every top-level issue of a report, sorted.
fn issue_types(report: &serde_json::Value) -> Vec<(String, String)> {
    let mut t: Vec<(String, String)> = report["issues"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|i| {
            (
                i["severity"].as_str().unwrap().into(),
                i["type"].as_str().unwrap().into(),
            )
        })
        .collect();
    t.sort();
    t
}

/// Runs 3d-tiles-validator on `tileset` and fails unless the report has no issue at all:
/// 0 errors (issue #18), and also 0 warnings and 0 infos. No warning is accepted: on
/// 2026-12-04 the demo and Engabreen tilesets gave 0 / 0 / 0, so any message is a
/// regression to look at (the same policy as [`ACCEPTED`] for the other validators).
/// With `metadata` (a tileset exported with `--metadata`), infos are accepted when every
/// one of their innermost causes is what the embedded Khronos glTF validator says of
/// `EXT_structural_metadata`, which it does not support (see [`metadata_only`]); the
/// extension itself is checked by 3d-tiles-validator's own `EXT_structural_metadata`
/// validator, whose findings would be errors or warnings.
fn assert_tiles_validator_clean(tileset: &Path, metadata: bool) {
    let r = tiles_validator(tileset);
    fn leaves<'a>(issues: &'a serde_json::Value, out: &mut Vec<&'a serde_json::Value>) {
        for i in issues.as_array().into_iter().flatten() {
            if i["causes"].as_array().is_some_and(|c| !c.is_empty()) {
                leaves(&i["causes"], out);
            } else {
                out.push(i);
            }
        }
    }
    let mut leaf = Vec::new();
    leaves(&r["issues"], &mut leaf);
    let metadata_infos = metadata
        && !leaf.is_empty()
        && leaf.iter().all(|i| {
            let (path, msg) = (
                i["path"].as_str().unwrap_or(""),
                i["message"].as_str().unwrap_or(""),
            );
            i["severity"] == "INFO"
                && (msg.contains("'EXT_structural_metadata'")
                    || (path.starts_with("/textures/") && msg == "This object may be unused."))
        });
    assert!(
        r["numErrors"] == 0
            && r["numWarnings"] == 0
            && ((r["numInfos"] == 0 && r["issues"].is_null()) || metadata_infos),
        "3d-tiles-validator on {tileset:?}: {} errors, {} warnings, {} infos\n{}",
        r["numErrors"],
        r["numWarnings"],
        r["numInfos"],
        issue_lines(&r).join("\n")
    );
}

/// `path` relative to `base`, with `/` separators (as tileset URIs have them).
fn rel_to(path: &Path, base: &Path) -> String {
    let r = path.strip_prefix(base).unwrap();
    r.components()
        .map(|c| c.as_os_str().to_str().unwrap())
        .collect::<Vec<_>>()
        .join("/")
}

/// Copies the directory `from` to `to` (recursively).
fn copy_dir(from: &Path, to: &Path) {
    for f in cli_util::files_under(from) {
        let dst = to.join(f.strip_prefix(from).unwrap());
        std::fs::create_dir_all(dst.parent().unwrap()).unwrap();
        std::fs::copy(&f, &dst).unwrap();
    }
}

/// The small demo store with the demo's ground photos projected, so that the exports carry
/// all three texture sources.
fn demo_store_with_photos(tmp: &Path) -> PathBuf {
    let store = tmp.join("store");
    common::small_demo_store(&store, true);
    // the scene of small_demo_store; its photos from the usual aims at 320 × 240
    let scene = cliffmap::demo_scene::DemoScene {
        samples: 129,
        spacing: 4.0,
        ..cliffmap::demo_scene::DemoScene::default()
    };
    let (dem, _) = scene.generate().unwrap();
    common::project_demo_photos(&store, &scene, &dem, &tmp.join("photos"), (320, 240));
    store
}

/// The level-0 GLB's `EXT_structural_metadata`: the `texel` class, and the cell's stretch
/// texture holding exactly the encoded per-texel stretch of its mesh's texture layout.
fn metadata_round_trips(st: &cliffmap::store::Store, glb: &Path) {
    use cliffmap::export::metadata::stretch_raw;
    let g = gltf::Gltf::from_slice(&std::fs::read(glb).unwrap()).unwrap();
    let ext = g
        .document
        .extensions()
        .and_then(|e| e.get("EXT_structural_metadata"))
        .expect("EXT_structural_metadata at the top level")
        .clone();
    assert!(ext["schema"]["classes"]["texel"]["properties"]["stretch"].is_object());
    let pt = &ext["propertyTextures"][0];
    assert_eq!(pt["class"], "texel");
    let tex = pt["properties"]["stretch"]["index"].as_u64().unwrap() as usize;
    let image = g.document.textures().nth(tex).unwrap().source();
    let gltf::image::Source::View { view, .. } = image.source() else {
        panic!("embedded image expected")
    };
    let blob = g.blob.as_deref().unwrap();
    let got = image::load_from_memory(&blob[view.offset()..view.offset() + view.length()])
        .unwrap()
        .to_rgb8();
    let rec = st.manifest.cells.iter().find(|c| c.level == 0).unwrap();
    let (mesh, texels) = match &rec.reparam {
        Some(r) => (st.read_mesh_file(&r.files.mesh).unwrap(), r.texels),
        None => (st.read_mesh(rec).unwrap(), rec.texels),
    };
    let uvs = rec.surface_texcoords(&mesh);
    let want = cliffmap::stats::cell_texel_stretch(&mesh, &uvs, rec.base_area(), texels);
    assert_eq!(got.dimensions(), (texels, texels));
    let mut on_surface = 0;
    for (i, p) in got.pixels().enumerate() {
        assert_eq!(
            u16::from_le_bytes([p.0[0], p.0[1]]),
            stretch_raw(want[i]),
            "texel {i}"
        );
        on_surface += usize::from(want[i] > 0.0);
    }
    assert!(on_surface > (texels * texels / 2) as usize);
    // the surface primitive names its property texture
    let prim = g
        .document
        .meshes()
        .next()
        .unwrap()
        .primitives()
        .next()
        .unwrap();
    assert_eq!(
        prim.extensions()
            .and_then(|e| e.get("EXT_structural_metadata"))
            .map(|v| v["propertyTextures"][0].clone()),
        Some(serde_json::json!(0))
    );
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
        "--lit",
        "--metadata",
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
    let lit = tmp.path().join("lit");
    ok(&[
        "export-tiles",
        s(&store),
        "--out",
        s(&lit),
        "--crs",
        "EPSG:32633",
        "--lit",
        "--metadata",
        "--quiet",
    ]);
    metadata_round_trips(&st, &glb0);
    // (`glb0` and `lit` are the lit variant: normal maps in tangent space, NORMAL and
    // TANGENT, which the glTF validator checks for unit length and handedness; with metadata)
    for f in [&glb0, &lit.join(cliffmap::export::tile_path(0, 0, 0))] {
        let doc = gltf::Gltf::from_slice(&std::fs::read(f).unwrap()).unwrap();
        for m in doc.materials() {
            assert!(m.normal_texture().is_some() && !m.unlit(), "{f:?}: not lit");
        }
        for m in doc.meshes() {
            for p in m.primitives() {
                assert!(
                    p.get(&gltf::Semantic::Normals).is_some()
                        && p.get(&gltf::Semantic::Tangents).is_some(),
                    "{f:?}: no NORMAL or TANGENT"
                );
            }
        }
    }
    let (code, summary) = validate_export(&[&glb, &glb0, &all, &jpeg]);
    let (gltf, tilesets) = assert_clean(code, &summary, &[&glb0]);
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
    // 3d-tiles-validator on every top-level tileset (it follows the external ones itself and
    // validates every GLB): the three modes of `all`, and `jpeg`.
    let mut entries: Vec<PathBuf> = [&all, &jpeg]
        .iter()
        .flat_map(|d| std::fs::read_dir(d).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_str().unwrap();
            n.starts_with("tileset") && n.ends_with(".json")
        })
        .collect();
    entries.sort();
    assert_eq!(entries.len(), 4, "{entries:?}");
    for t in &entries {
        assert_tiles_validator_clean(t, false);
    }
    // the lit tileset with metadata: every GLB through both validators
    let (code, summary) = validate_export(&[&lit]);
    assert_eq!(assert_clean(code, &summary, &[&lit]), (cells, 1));
    assert_tiles_validator_clean(&lit.join("tileset.json"), true);

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

    // 3d-tiles-validator on broken copies. It stops at the first structure error of a
    // tileset JSON: on this copy it names the 3-number box only, not the missing or truncated
    // GLBs nor the child's error, so these are checked one by one below. numErrors counts
    // top-level issues: the errors of one GLB or one external tileset count as one.
    let err = |sev: &str, ty: &str| (sev.to_string(), ty.to_string());
    let r = tiles_validator(&ts_path);
    let lines = issue_lines(&r).join("\n");
    assert_eq!(r["numErrors"], 1, "{lines}");
    assert_eq!(
        issue_types(&r),
        [err("ERROR", "ARRAY_LENGTH_MISMATCH")],
        "{lines}"
    );
    assert_eq!(
        r["issues"][0]["path"],
        "/root/children/0/boundingVolume/box"
    );

    // A missing GLB, alone.
    let missing = tmp.path().join("bad_missing");
    copy_dir(&jpeg, &missing);
    let gone = &cli_util::files_under(&missing.join("tiles"))[1];
    std::fs::remove_file(gone).unwrap();
    let r = tiles_validator(&missing.join("tileset.json"));
    let lines = issue_lines(&r).join("\n");
    assert!(r["numErrors"].as_u64().unwrap() > 0, "{lines}");
    assert_eq!(
        issue_types(&r),
        [err("ERROR", "CONTENT_VALIDATION_ERROR")],
        "{lines}"
    );
    assert!(
        lines.contains(&format!(
            "URI {}, which could not be resolved",
            rel_to(gone, &missing)
        )),
        "the missing GLB is named: {lines}"
    );

    // A truncated GLB of the finest level, referenced only from an external tileset: the
    // validator follows external tilesets and runs the glTF validator on their GLBs.
    let sub = tmp.path().join("bad_subtree");
    copy_dir(&all, &sub);
    let finest = &cli_util::files_under(&sub.join(format!("tiles/{}", levels - 1)))[0];
    let bytes = std::fs::read(finest).unwrap();
    std::fs::write(finest, &bytes[..bytes.len() / 2]).unwrap();
    let r = tiles_validator(&sub.join("tileset.json"));
    let lines = issue_lines(&r).join("\n");
    assert!(r["numErrors"].as_u64().unwrap() > 0, "{lines}");
    assert_eq!(
        issue_types(&r),
        [err("ERROR", "EXTERNAL_TILESET_VALIDATION_ERROR")],
        "{lines}"
    );
    assert!(
        r["issues"][0]["path"]
            .as_str()
            .unwrap()
            .starts_with("subtrees/")
            && lines.contains(&format!("../../{}", rel_to(finest, &sub)))
            && lines.contains("Unexpected end of chunk data."),
        "the external tileset, the GLB and the glTF validator's message are named: {lines}"
    );

    // A child whose geometric error exceeds its parent's, alone: 3d-tiles-validator calls that
    // a warning, not an error (0 errors), which is one reason why the clean checks above want
    // 0 warnings too.
    let ge = tmp.path().join("bad_error");
    copy_dir(&jpeg, &ge);
    let ge_ts = ge.join("tileset.json");
    let mut ts: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&ge_ts).unwrap()).unwrap();
    ts["root"]["children"][0]["geometricError"] = serde_json::json!(1e9);
    std::fs::write(&ge_ts, serde_json::to_vec(&ts).unwrap()).unwrap();
    let r = tiles_validator(&ge_ts);
    let lines = issue_lines(&r).join("\n");
    assert_eq!(
        (&r["numErrors"], &r["numWarnings"]),
        (&0.into(), &1.into()),
        "{lines}"
    );
    assert_eq!(
        issue_types(&r),
        [err("WARNING", "TILE_GEOMETRIC_ERRORS_INCONSISTENT")],
        "{lines}"
    );
    assert_eq!(r["issues"][0]["path"], "/root/children/0");
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
    assert_eq!(assert_clean(code, &summary, &[]), (cells + 1, 1));
    assert_tiles_validator_clean(&tiles.join("tileset.json"), false);
}
