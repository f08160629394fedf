//! `cliffmap export-tiles`: tileset structure (explicit quadtree, REPLACE, errors, boxes
//! that hold their content), georeferencing through ECEF (a store corner back to the CRS
//! within a millimetre), content GLBs re-read; bad input refused.

mod cli_util;
mod common;

use std::path::Path;

use cli_util::{fails_naming, ok};
use cliffmap::export::{ToEcef, ecef_to_enu};
use cliffmap::store::Store;
use glam::{DMat3, DVec3};

fn small_store(dir: &Path) {
    common::small_demo_store(dir, false);
}

fn walk<'a>(t: &'a serde_json::Value, depth: usize, out: &mut Vec<(&'a serde_json::Value, usize)>) {
    out.push((t, depth));
    for c in t["children"].as_array().into_iter().flatten() {
        walk(c, depth + 1, out);
    }
}

#[test]
fn tileset_is_an_explicit_quadtree_placed_in_ecef() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    small_store(&dir);
    let out = tmp.path().join("tiles");
    ok(&[
        "export-tiles",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--crs",
        "EPSG:32633",
        "--geoid-offset",
        "35",
        "--quiet",
    ]);
    let store = Store::open(&dir).unwrap();
    let ts: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("tileset.json")).unwrap()).unwrap();
    assert_eq!(ts["asset"]["version"], "1.1");
    assert_eq!(ts["root"]["refine"], "REPLACE");
    assert!(
        ts["asset"]["extras"]["cliffmap"]["heights"]
            .as_str()
            .unwrap()
            .contains("35")
    );
    let m: Vec<f64> = ts["root"]["transform"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let rot_t = DMat3::from_cols(
        DVec3::new(m[0], m[1], m[2]),
        DVec3::new(m[4], m[5], m[6]),
        DVec3::new(m[8], m[9], m[10]),
    );
    let centre = DVec3::new(m[12], m[13], m[14]);
    let mut tiles = Vec::new();
    walk(&ts["root"], 0, &mut tiles);
    let with_content: Vec<_> = tiles
        .iter()
        .filter(|(t, _)| t.get("content").is_some())
        .collect();
    assert_eq!(
        with_content.len(),
        store.manifest.cells.len(),
        "every cell is a tile (the demo's children cover their parents)"
    );
    let to_ecef = ToEcef::new("EPSG:32633", 35.0).unwrap();
    for (t, depth) in &with_content {
        let uri = t["content"]["uri"].as_str().unwrap();
        let id = uri
            .trim_start_matches("tiles/")
            .trim_end_matches(".glb")
            .replace(['/', '-'], "-");
        let rec = store.cell(&id).unwrap();
        assert_eq!(*depth, rec.level as usize + 1);
        assert_eq!(t["geometricError"].as_f64().unwrap(), rec.max_error);
        for c in t["children"].as_array().into_iter().flatten() {
            assert!(c["geometricError"].as_f64().unwrap() <= rec.max_error + 1e-12);
        }
        // Content re-read: triangle count, and every vertex inside the tile's box.
        if rec.level == 0 {
            cli_util::validate_gltf(&[&out.join(uri)]);
        }
        let bytes = std::fs::read(out.join(uri)).unwrap();
        let g = gltf::Gltf::from_slice(&bytes).unwrap();
        let prim = g
            .document
            .meshes()
            .next()
            .unwrap()
            .primitives()
            .next()
            .unwrap();
        assert_eq!(prim.indices().unwrap().count() / 3, rec.triangles as usize);
        let b: Vec<f64> = t["boundingVolume"]["box"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let pos = prim.get(&gltf::Semantic::Positions).unwrap();
        let (lo, hi) = (pos.min().unwrap(), pos.max().unwrap());
        // glTF y-up → tile z-up: (x, y, z) → (x, −z, y).
        let lo_t = [
            lo[0].as_f64().unwrap(),
            -hi[2].as_f64().unwrap(),
            lo[1].as_f64().unwrap(),
        ];
        let hi_t = [
            hi[0].as_f64().unwrap(),
            -lo[2].as_f64().unwrap(),
            hi[1].as_f64().unwrap(),
        ];
        for k in 0..3 {
            let h = [b[3], b[7], b[11]][k];
            assert!(
                lo_t[k] >= b[k] - h - 1e-3 && hi_t[k] <= b[k] + h + 1e-3,
                "{id} axis {k}"
            );
        }
    }
    // A store corner: through ECEF into the root frame and back to the CRS within 1 mm.
    let rec = &store.manifest.cells[0];
    let corner = DVec3::new(rec.extent.min_x, rec.extent.min_y, rec.bbox_min[2]);
    let q = to_ecef.to_ecef(corner).unwrap();
    let enu = rot_t.transpose() * (q - centre);
    let back = to_ecef.from_ecef(centre + rot_t * enu).unwrap();
    assert!((back - corner).length() < 1e-3, "{back} vs {corner}");
    // The root frame is the ellipsoid's east-north-up frame at its origin.
    assert!(
        (ecef_to_enu(centre).transpose() - rot_t)
            .abs()
            .to_cols_array()
            .iter()
            .all(|v| *v < 1e-9)
    );
}

#[test]
fn export_tiles_refuses_a_store_without_crs_and_bad_crs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    small_store(&dir);
    let out = tmp.path().join("tiles");
    let (d, o) = (dir.to_str().unwrap(), out.to_str().unwrap());
    fails_naming(&["export-tiles", d, "--out", o], "--crs");
    fails_naming(
        &["export-tiles", d, "--out", o, "--crs", "EPSG:1"],
        "EPSG:1",
    );
    fails_naming(
        &[
            "export-tiles",
            d,
            "--out",
            o,
            "--crs",
            "EPSG:32633",
            "--geoid-offset",
            "1e9",
        ],
        "geoid-offset",
    );
    assert!(!out.join("tileset.json").exists());
}

#[test]
fn ecef_agrees_with_pyproj_within_5_cm() {
    // Points in three UTM zones (Engabreen 33N, St Helens 10N, a southern zone), heights
    // with a geoid offset; pyproj (installed by .ci/run) is the independent transform.
    let cases = [
        ("EPSG:32633", 446_722.0, 7_396_671.0, 770.0),
        ("EPSG:32610", 562_000.0, 5_118_000.0, 2_500.0),
        ("EPSG:32755", 330_000.0, 6_250_000.0, 12.0),
    ];
    for (crs, x, y, z) in cases {
        let ours = ToEcef::new(crs, 37.5)
            .unwrap()
            .to_ecef(DVec3::new(x, y, z))
            .unwrap();
        let script = format!(
            "import pyproj\nt = pyproj.Transformer.from_crs('{crs}', 'EPSG:4978', always_xy=True)\nprint(*t.transform({x}, {y}, {z} + 37.5))"
        );
        let o = std::process::Command::new("python3")
            .args(["-c", &script])
            .output()
            .expect("python3 is needed (.ci/run installs python3-pyproj)");
        assert!(
            o.status.success(),
            "pyproj failed (is python3-pyproj installed?): {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: Vec<f64> = String::from_utf8_lossy(&o.stdout)
            .split_whitespace()
            .map(|s| s.parse().unwrap())
            .collect();
        let theirs = DVec3::new(v[0], v[1], v[2]);
        assert!(
            (ours - theirs).length() < 0.05,
            "{crs}: {ours} vs pyproj {theirs} ({:.4} m)",
            (ours - theirs).length()
        );
    }
}

/// Writes a global 1° geoid grid (EPSG:4326, PixelIsPoint) with value `n(lon, lat)`.
fn write_geoid_grid(path: &Path, n: impl Fn(f64, f64) -> f64, lat_range: (f64, f64)) {
    use common::tiffgen::{Geo, write_strips};
    let (lat1, lat0) = lat_range;
    let (w, h) = (361u32, (lat1 - lat0) as u32 + 1);
    let v: Vec<f32> = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .map(|(c, r)| n(c as f64 - 180.0, lat1 - r as f64) as f32)
        .collect();
    let geo = Geo {
        scale: (1.0, 1.0),
        tie: (0.0, 0.0, -180.0, lat1),
        pixel_is_point: true,
        epsg: Some(4326),
        nodata: None,
    };
    write_strips::<tiff::encoder::colortype::Gray32Float>(
        path,
        w,
        h,
        &v,
        tiff::encoder::Compression::Uncompressed,
        tiff::tags::Predictor::None,
        Some(&geo),
    );
}

#[test]
fn a_geoid_grid_replaces_the_constant_offset() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    small_store(&dir);
    let d = dir.to_str().unwrap();
    let export = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let mut args = vec![
            "export-tiles",
            d,
            "--out",
            out.to_str().unwrap(),
            "--crs",
            "EPSG:32633",
            "--quiet",
        ];
        args.extend_from_slice(extra);
        ok(&args);
        out
    };
    // A constant grid gives exactly the constant offset's tileset and tiles.
    let constant = tmp.path().join("egm_constant.tif");
    write_geoid_grid(&constant, |_, _| 35.0, (90.0, -90.0));
    let a = export("offset", &["--geoid-offset", "35"]);
    let b = export("grid", &["--geoid", constant.to_str().unwrap()]);
    let files = cli_util::files_under(&a);
    assert!(files.len() > 3);
    for f in files {
        let rel = f.strip_prefix(&a).unwrap();
        if rel == Path::new(cliffmap::export::EXPORT_KEY_FILE) {
            continue; // (records the options, which differ)
        }
        if rel == Path::new("tileset.json") {
            let ta: serde_json::Value =
                serde_json::from_slice(&std::fs::read(&f).unwrap()).unwrap();
            let tb: serde_json::Value =
                serde_json::from_slice(&std::fs::read(b.join(rel)).unwrap()).unwrap();
            assert_eq!(ta["root"], tb["root"]);
            let h = tb["asset"]["extras"]["cliffmap"]["heights"]
                .as_str()
                .unwrap();
            assert!(
                h.contains("egm_constant.tif") && h.contains("35.00..35.00"),
                "{h}"
            );
        } else {
            assert!(
                std::fs::read(&f).unwrap() == std::fs::read(b.join(rel)).unwrap(),
                "{} differs",
                rel.display()
            );
        }
    }
    // A sloped grid moves each tile by its own N: the root frame's origin rises by N there.
    let sloped = tmp.path().join("egm_sloped.tif");
    write_geoid_grid(
        &sloped,
        |lon, lat| 10.0 + 0.5 * lon + 0.25 * lat,
        (90.0, -90.0),
    );
    let c = export("sloped", &["--geoid", sloped.to_str().unwrap()]);
    let root = |dir: &Path| -> DVec3 {
        let ts: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("tileset.json")).unwrap()).unwrap();
        let m = ts["root"]["transform"].as_array().unwrap();
        DVec3::new(
            m[12].as_f64().unwrap(),
            m[13].as_f64().unwrap(),
            m[14].as_f64().unwrap(),
        )
    };
    let (qa, qc) = (root(&a), root(&c));
    let up = ecef_to_enu(qa).row(2);
    let store = Store::open(&dir).unwrap();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for cell in &store.manifest.cells {
        lo = lo.min(DVec3::from_array(cell.bbox_min));
        hi = hi.max(DVec3::from_array(cell.bbox_max));
    }
    let n = ToEcef::with_geoid(
        "EPSG:32633",
        cliffmap::export::GeoidGrid::read(&sloped).unwrap(),
    )
    .unwrap()
    .geoid_height((lo + hi) * 0.5)
    .unwrap();
    assert!(
        ((qc - qa).dot(up) - (n - 35.0)).abs() < 1e-3,
        "{} vs {}",
        (qc - qa).dot(up),
        n - 35.0
    );
    // A grid that does not reach the store, and both flags at once, are refused.
    let south = tmp.path().join("egm_south.tif");
    write_geoid_grid(&south, |_, _| 20.0, (-60.0, -90.0));
    let o = tmp.path().join("refused");
    let os = o.to_str().unwrap();
    fails_naming(
        &[
            "export-tiles",
            d,
            "--out",
            os,
            "--crs",
            "EPSG:32633",
            "--geoid",
            south.to_str().unwrap(),
        ],
        "egm_south.tif",
    );
    fails_naming(
        &[
            "export-tiles",
            d,
            "--out",
            os,
            "--crs",
            "EPSG:32633",
            "--geoid",
            south.to_str().unwrap(),
            "--geoid-offset",
            "3",
        ],
        "--geoid",
    );
    assert!(!o.join("tileset.json").exists());
}

/// `--modes all`: a tileset per texture mode, each GLB carrying exactly that mode's store
/// texture, and every tileset listing the modes for the page's toggle.
#[test]
fn every_texture_mode_gets_its_own_tileset() {
    use cliffmap::export::{TextureSource, tile_path_for, tileset_name};
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    common::small_demo_store(&dir, true);
    let out = tmp.path().join("tiles");
    ok(&[
        "export-tiles",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--crs",
        "EPSG:32633",
        "--modes",
        "ortho,reparam",
        "--quiet",
    ]);
    let store = Store::open(&dir).unwrap();
    let rec = store
        .manifest
        .cells
        .iter()
        .find(|c| c.reparam.is_some())
        .expect("a reparameterized cell");
    for (mode, file) in [
        (
            TextureSource::Photo,
            &rec.reparam.as_ref().unwrap().files.texture,
        ),
        (
            TextureSource::Reparam,
            &rec.reparam.as_ref().unwrap().files.texture,
        ),
        (TextureSource::Ortho, &rec.files.texture),
    ] {
        let ts: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(tileset_name(mode))).unwrap()).unwrap();
        let modes = ts["asset"]["extras"]["cliffmap"]["modes"]
            .as_array()
            .unwrap();
        assert_eq!(modes.len(), 3);
        assert_eq!(
            ts["asset"]["extras"]["cliffmap"]["texture_mode"],
            mode.name()
        );
        let glb = std::fs::read(out.join(tile_path_for(mode, rec.level, rec.x, rec.y))).unwrap();
        let g = gltf::Gltf::from_slice(&glb).unwrap();
        let blob = g.blob.as_deref().unwrap();
        let img = g.document.images().next().unwrap();
        let gltf::image::Source::View { view, .. } = img.source() else {
            panic!("embedded image expected")
        };
        let bytes = &blob[view.offset()..view.offset() + view.length()];
        assert!(
            bytes == std::fs::read(dir.join(&file.path)).unwrap().as_slice(),
            "{mode:?}"
        );
    }
    cli_util::fails_naming(
        &[
            "export-tiles",
            dir.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--modes",
            "sepia",
        ],
        "sepia",
    );
}

/// `--jpeg-quality Q`: every GLB embeds a JPEG (declared `image/jpeg`) of the same size as
/// the store texture it replaces, close to it in colour.
#[test]
fn jpeg_textures_replace_the_pngs_on_request() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    common::small_demo_store(&dir, true);
    let out = tmp.path().join("tiles");
    ok(&[
        "export-tiles",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--crs",
        "EPSG:32633",
        "--jpeg-quality",
        "90",
        "--quiet",
    ]);
    let store = Store::open(&dir).unwrap();
    let rec = store
        .manifest
        .cells
        .iter()
        .find(|c| c.reparam.is_some())
        .expect("a reparameterized cell");
    let glb = std::fs::read(out.join(cliffmap::export::tile_path_for(
        cliffmap::export::TextureSource::Photo,
        rec.level,
        rec.x,
        rec.y,
    )))
    .unwrap();
    let g = gltf::Gltf::from_slice(&glb).unwrap();
    let blob = g.blob.as_deref().unwrap();
    let img = g.document.images().next().unwrap();
    let gltf::image::Source::View { view, mime_type } = img.source() else {
        panic!("embedded image expected")
    };
    assert_eq!(mime_type, "image/jpeg");
    let jpeg = image::load_from_memory_with_format(
        &blob[view.offset()..view.offset() + view.length()],
        image::ImageFormat::Jpeg,
    )
    .unwrap()
    .to_rgb8();
    let png = image::open(dir.join(&rec.reparam.as_ref().unwrap().files.texture.path))
        .unwrap()
        .to_rgb8();
    assert_eq!(jpeg.dimensions(), png.dimensions());
    let mse = jpeg
        .as_raw()
        .iter()
        .zip(png.as_raw())
        .map(|(&a, &b)| (a as f64 - b as f64).powi(2))
        .sum::<f64>()
        / png.as_raw().len() as f64;
    let psnr = 10.0 * (255.0f64 * 255.0 / mse.max(1e-9)).log10();
    assert!(psnr > 30.0, "JPEG q90 against the PNG: {psnr:.1} dB");
    cli_util::fails_naming(
        &[
            "export-tiles",
            dir.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--jpeg-quality",
            "0",
        ],
        "jpeg-quality",
    );
}

/// `--subtree-levels N`: the subtree under every cell at a positive multiple of N levels is
/// its own tileset, referenced from its parent; following the references reaches every
/// cell's GLB exactly once, at the right depth, with paths relative to each file.
#[test]
fn external_child_tilesets_hold_the_deeper_levels() {
    fn follow(
        file: &Path,
        t: &serde_json::Value,
        depth: usize,
        glbs: &mut Vec<(std::path::PathBuf, usize)>,
        files: &mut usize,
    ) {
        if let Some(uri) = t["content"]["uri"].as_str() {
            let target = file.parent().unwrap().join(uri);
            if uri.ends_with(".json") {
                *files += 1;
                let sub: serde_json::Value =
                    serde_json::from_slice(&std::fs::read(&target).unwrap()).unwrap();
                assert_eq!(sub["asset"]["version"], "1.1");
                assert_eq!(sub["root"]["refine"], "REPLACE");
                assert!(
                    sub["root"].get("transform").is_none(),
                    "one transform, at the root"
                );
                assert_eq!(sub["root"]["boundingVolume"], t["boundingVolume"]);
                assert_eq!(sub["root"]["geometricError"], t["geometricError"]);
                assert!(t.get("children").is_none());
                // the external root is the same tile: same depth
                follow(&target, &sub["root"], depth, glbs, files);
                return;
            }
            glbs.push((std::fs::canonicalize(&target).unwrap(), depth));
        }
        for c in t["children"].as_array().into_iter().flatten() {
            follow(file, c, depth + 1, glbs, files);
        }
    }
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    small_store(&dir);
    let store = Store::open(&dir).unwrap();
    let levels = store.manifest.quadtree.levels;
    assert!(levels >= 3, "the test needs a store of 3 levels or more");
    let out = tmp.path().join("tiles");
    let o = ok(&[
        "export-tiles",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--crs",
        "EPSG:32633",
        "--subtree-levels",
        "1",
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("external child tilesets"));
    let main = out.join("tileset.json");
    let ts: serde_json::Value = serde_json::from_slice(&std::fs::read(&main).unwrap()).unwrap();
    let (mut glbs, mut files) = (Vec::new(), 0);
    follow(&main, &ts["root"], 0, &mut glbs, &mut files);
    // every level below 0 with children starts a file: all cells of levels 1..levels-1
    let expected_files = store
        .manifest
        .cells
        .iter()
        .filter(|c| c.level >= 1 && c.level + 1 < levels)
        .count();
    assert_eq!(files, expected_files);
    assert_eq!(glbs.len(), store.manifest.cells.len());
    let mut seen = std::collections::HashSet::new();
    for (p, depth) in &glbs {
        assert!(seen.insert(p.clone()), "{p:?} listed twice");
        let rel = p
            .strip_prefix(std::fs::canonicalize(&out).unwrap())
            .unwrap();
        let level: usize = rel
            .iter()
            .nth(1)
            .unwrap()
            .to_str()
            .unwrap()
            .parse()
            .unwrap();
        assert_eq!(*depth, level + 1, "{rel:?}");
    }
    // the default for a store this small is one file; 0 forces one file
    for extra in [&[][..], &["--subtree-levels", "0"][..]] {
        let out2 = tmp.path().join(format!("one{}", extra.len()));
        let mut args = vec![
            "export-tiles",
            dir.to_str().unwrap(),
            "--out",
            out2.to_str().unwrap(),
            "--crs",
            "EPSG:32633",
            "--quiet",
        ];
        args.extend_from_slice(extra);
        ok(&args);
        assert!(!out2.join("subtrees").exists());
    }
}

/// An export interrupted after some GLBs (simulated by deleting the others and the tileset
/// files) resumes on the same command: the GLBs left are kept, the rest written, and every
/// file ends byte-identical to an uninterrupted export; another option starts afresh.
#[test]
fn an_interrupted_export_resumes_to_the_same_files() {
    use cliffmap::export::{EXPORT_KEY_FILE, TextureSource, TilesOptions, export_tiles};
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    common::small_demo_store(&dir, true);
    let out = tmp.path().join("tiles");
    let opts = TilesOptions {
        crs: Some("EPSG:32633".into()),
        extra_modes: vec![TextureSource::Ortho],
        subtree_levels: Some(1),
        ..TilesOptions::default()
    };
    let first = export_tiles(&dir, &out, &opts).unwrap();
    assert_eq!(first.resumed, 0);
    let files = |d: &Path| -> Vec<(std::path::PathBuf, Vec<u8>)> {
        let mut v: Vec<_> = cli_util::files_under(d)
            .into_iter()
            .map(|p| {
                (
                    p.strip_prefix(d).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                )
            })
            .collect();
        v.sort();
        v
    };
    let whole = files(&out);
    assert!(whole.iter().any(|(p, _)| p.ends_with(EXPORT_KEY_FILE)));
    // "interrupted": every other GLB and every tileset file gone
    let glbs: Vec<_> = whole
        .iter()
        .filter(|(p, _)| p.extension().is_some_and(|e| e == "glb"))
        .collect();
    let mut removed = 0;
    for (k, (p, _)) in glbs.iter().enumerate() {
        if k % 2 == 0 {
            std::fs::remove_file(out.join(p)).unwrap();
            removed += 1;
        }
    }
    for (p, _) in &whole {
        if p.extension().is_some_and(|e| e == "json")
            && !p.ends_with(EXPORT_KEY_FILE)
            && !p.starts_with("views")
        {
            std::fs::remove_file(out.join(p)).unwrap();
        }
    }
    let again = export_tiles(&dir, &out, &opts).unwrap();
    assert_eq!(again.resumed, glbs.len() - removed);
    assert_eq!(
        (again.tiles, again.bytes, again.textures),
        (first.tiles, first.bytes, first.textures)
    );
    assert!(
        files(&out) == whole,
        "the resumed export differs from the whole one"
    );
    // another option: nothing is kept, and no file of the earlier export is left over
    let lit = TilesOptions {
        lit: true,
        extra_modes: vec![],
        ..opts.clone()
    };
    let r = export_tiles(&dir, &out, &lit).unwrap();
    assert_eq!(r.resumed, 0);
    assert!(!out.join("tileset_ortho.json").exists() && !out.join("tiles_ortho").exists());
}
