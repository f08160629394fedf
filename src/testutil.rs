//! Test-only helpers shared by unit tests.

use crate::cells::{SampleRect, Tin};

/// A full grid triangulation of `rect` using every `stride`-th sample (plus the last row and
/// column): two triangles per quad, split NW–SE, counter-clockwise seen from above in world
/// coordinates (rows run south).
pub(crate) fn grid_tin(rect: SampleRect, stride: u32) -> Tin {
    let axis = |a: u32, b: u32| {
        let mut v: Vec<u32> = (a..b).step_by(stride as usize).collect();
        v.push(b);
        v
    };
    let (cols, rows) = (axis(rect.c0, rect.c1), axis(rect.r0, rect.r1));
    let nc = cols.len() as u32;
    let vertices = rows.iter().flat_map(|&r| cols.iter().map(move |&c| [c, r])).collect();
    let mut triangles = Vec::new();
    for j in 0..rows.len() as u32 - 1 {
        for i in 0..nc - 1 {
            let (nw, ne, sw, se) = (j * nc + i, j * nc + i + 1, (j + 1) * nc + i, (j + 1) * nc + i + 1);
            triangles.push([nw, sw, se]);
            triangles.push([nw, se, ne]);
        }
    }
    Tin { vertices, triangles, max_error: 0.0 }
}

#[test]
fn grid_tin_is_ccw_in_world() {
    let t = grid_tin(SampleRect { c0: 2, r0: 3, c1: 9, r1: 7 }, 2);
    assert_eq!(t.vertices.len(), 5 * 3);
    assert_eq!(t.triangles.len(), 2 * 4 * 2);
    for tri in &t.triangles {
        // world (x, y) = (col, -row)
        let p = tri.map(|k| {
            let v = t.vertices[k as usize];
            (v[0] as f64, -(v[1] as f64))
        });
        let twice = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0);
        assert!(twice > 0.0);
    }
}
