//! Wavefront OBJ export of one cell's surface with texture coordinates.

use std::fmt::Write;

use super::manifest::CellRecord;
use crate::cells::CellMesh;

/// Renders the cell's surface (skirt excluded) as OBJ text: `v` positions (cell-local, or
/// world if `world`, printed with enough digits for UTM coordinates), `vt` texture
/// coordinates (stored UVs, or the orthographic map for ortho cells, v up as OBJ expects),
/// `f` triangles with `v/vt` indices, and `mtllib`-free comments naming the cell.
pub fn obj_text(record: &CellRecord, mesh: &CellMesh, world: bool) -> String {
    let n = mesh.surface_vertices as usize;
    let mut s = String::with_capacity(n * 64 + mesh.surface().len() * 32);
    let _ = writeln!(
        s,
        "# cliffmap cell {} (level {}), {} frame",
        record.id,
        record.level,
        if world { "world" } else { "cell-local" }
    );
    let _ = writeln!(
        s,
        "# origin {:.4} {:.4} {:.4}",
        record.origin[0], record.origin[1], record.origin[2]
    );
    let texture = match (&mesh.uvs, &record.reparam) {
        (Some(_), Some(r)) => &r.files.texture.path,
        _ => &record.files.texture.path,
    };
    let kind = if mesh.uvs.is_some() {
        "reparam"
    } else {
        "ortho"
    };
    let _ = writeln!(s, "# parameterization {kind}, texture {texture}");
    for p in &mesh.positions[..n] {
        if world {
            let w = [
                p[0] as f64 + record.origin[0],
                p[1] as f64 + record.origin[1],
                p[2] as f64 + record.origin[2],
            ];
            let _ = writeln!(s, "v {:.4} {:.4} {:.4}", w[0], w[1], w[2]);
        } else {
            let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
        }
    }
    for i in 0..n {
        let [u, v] = super::texcoord(record, mesh, i);
        let _ = writeln!(s, "vt {} {}", u, 1.0 - v);
    }
    for t in mesh.surface() {
        let _ = writeln!(s, "f {0}/{0} {1}/{1} {2}/{2}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}
