//! `cliffmap export-glb`: the GLB read back with the `gltf` crate gives the store's cells,
//! triangle counts, texture coordinates and texture bytes; bad selections fail cleanly.

mod cli_util;
mod common;

use std::path::Path;

use cli_util::{fails_naming, ok};
use cliffmap::store::{Store, texcoord};

fn small_store(dir: &Path) {
    common::small_demo_store(dir, true);
}

#[test]
fn glb_round_trip_gives_the_store_cells() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    small_store(&dir);
    let out = tmp.path().join("t.glb");
    ok(&[
        "export-glb",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    cli_util::validate_gltf(&[&out]);
    let store = Store::open(&dir).unwrap();
    let finest = store.manifest.quadtree.levels - 1;
    let recs: Vec<_> = store
        .manifest
        .cells
        .iter()
        .filter(|c| c.level == finest)
        .collect();
    assert!(
        recs.iter().any(|r| r.reparam.is_some()),
        "the test wants reparameterized cells"
    );
    let bytes = std::fs::read(&out).unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let blob = g.blob.as_deref().unwrap();
    let extras: serde_json::Value =
        serde_json::from_str(g.document.as_json().extras.as_ref().unwrap().get()).unwrap();
    let o = &extras["cliffmap"]["origin"];
    let origin = [
        o[0].as_f64().unwrap(),
        o[1].as_f64().unwrap(),
        o[2].as_f64().unwrap(),
    ];
    let nodes: Vec<_> = g.document.nodes().collect();
    assert_eq!(nodes.len(), recs.len());
    for (node, rec) in nodes.iter().zip(&recs) {
        assert_eq!(node.name(), Some(rec.id.as_str()));
        let mesh = node.mesh().unwrap();
        let store_mesh = store.read_active_mesh(rec).unwrap();
        let prims: Vec<_> = mesh.primitives().collect();
        let count = |p: &gltf::Primitive| p.indices().unwrap().count() / 3;
        assert_eq!(count(&prims[0]), rec.triangles as usize, "{}", rec.id);
        assert_eq!(
            prims.iter().map(count).sum::<usize>(),
            store_mesh.triangles.len()
        );
        let read = |a: gltf::Accessor| -> Vec<f32> {
            let v = a.view().unwrap();
            let s = &blob[v.offset() + a.offset()..v.offset() + a.offset() + a.count() * a.size()];
            s.chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        };
        let uv = read(prims[0].get(&gltf::Semantic::TexCoords(0)).unwrap());
        let pos = read(prims[0].get(&gltf::Semantic::Positions).unwrap());
        for i in 0..store_mesh.positions.len() {
            let want = texcoord(rec, &store_mesh, i);
            assert!(
                (uv[2 * i] - want[0]).abs() <= 1e-6 && (uv[2 * i + 1] - want[1]).abs() <= 1e-6,
                "{} uv {i}",
                rec.id
            );
            // x east, y up, z south around the origin
            let p = store_mesh.positions[i];
            let world = [
                rec.origin[0] + p[0] as f64,
                rec.origin[1] + p[1] as f64,
                rec.origin[2] + p[2] as f64,
            ];
            let back = [
                origin[0] + pos[3 * i] as f64,
                origin[1] - pos[3 * i + 2] as f64,
                origin[2] + pos[3 * i + 1] as f64,
            ];
            for k in 0..3 {
                assert!(
                    (back[k] - world[k]).abs() < 1e-3,
                    "{} vertex {i}: {back:?} vs {world:?}",
                    rec.id
                );
            }
        }
        // The texture is the store's file, byte for byte.
        let tex = prims[0]
            .material()
            .pbr_metallic_roughness()
            .base_color_texture()
            .unwrap()
            .texture();
        let gltf::image::Source::View { view, mime_type } = tex.source().source() else {
            panic!("image not embedded")
        };
        assert_eq!(mime_type, "image/png");
        let file = rec
            .reparam
            .as_ref()
            .map_or(&rec.files.texture, |r| &r.files.texture);
        assert_eq!(
            &blob[view.offset()..view.offset() + view.length()],
            store.read_file(file).unwrap().as_slice(),
            "{}",
            rec.id
        );
        assert!(prims[0].material().unlit());
    }
}

#[test]
fn export_glb_refuses_bad_selections() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("store");
    small_store(&dir);
    let out = tmp.path().join("t.glb");
    let d = dir.to_str().unwrap();
    let o = out.to_str().unwrap();
    fails_naming(&["export-glb", d, "--out", o, "--level", "40"], "level 40");
    fails_naming(
        &["export-glb", d, "--out", o, "--region", "0,0,1,1"],
        "region",
    );
    fails_naming(
        &["export-glb", d, "--out", o, "--region", "5,0,1,1"],
        "X0 < X1",
    );
    fails_naming(
        &["export-glb", d, "--out", o, "--max-error", "-1"],
        "max-error",
    );
    fails_naming(
        &[
            "export-glb",
            tmp.path().join("none").to_str().unwrap(),
            "--out",
            o,
        ],
        "none",
    );
    assert!(!out.exists());
}
