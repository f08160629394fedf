//! Test meshes for the parameterization tests: height grids to disc meshes.
#![allow(dead_code)]

use cliffmap::ParamMesh;

/// A mesh of `cols` x `rows` samples; sample (r, c) is at (xs[c], ys[r], z(r, c)) plus
/// `offset`. Two triangles per quad, counter-clockwise seen from +z (ys increasing).
pub fn grid_mesh(
    xs: &[f64],
    ys: &[f64],
    z: impl Fn(usize, usize) -> f64,
    offset: [f64; 3],
) -> ParamMesh {
    let (cols, rows) = (xs.len(), ys.len());
    let mut positions = Vec::with_capacity(cols * rows);
    for (r, &y) in ys.iter().enumerate() {
        for (c, &x) in xs.iter().enumerate() {
            positions.push([x + offset[0], y + offset[1], z(r, c) + offset[2]]);
        }
    }
    let mut triangles = Vec::new();
    for r in 0..rows - 1 {
        for c in 0..cols - 1 {
            let a = (r * cols + c) as u32;
            let b = a + 1;
            let d = a + cols as u32;
            let e = d + 1;
            // Alternate the diagonal for a less anisotropic triangulation.
            if (r + c) % 2 == 0 {
                triangles.push([a, b, e]);
                triangles.push([a, e, d]);
            } else {
                triangles.push([a, b, d]);
                triangles.push([b, e, d]);
            }
        }
    }
    ParamMesh {
        positions,
        triangles,
    }
}

/// A square `n` x `n` grid with unit spacing and heights `z(r, c)`.
pub fn height_grid(n: usize, z: impl Fn(usize, usize) -> f64) -> ParamMesh {
    let xs: Vec<f64> = (0..n).map(|i| i as f64).collect();
    grid_mesh(&xs, &xs, z, [0.0; 3])
}

/// A straight wall of slope `deg` degrees across the columns between `c0` and `c0 + 2`
/// (unit spacing), flat on both sides.
pub fn wall(n: usize, deg: f64) -> ParamMesh {
    let h = deg.to_radians().tan();
    let c0 = n / 2 - 1;
    height_grid(n, move |_, c| h * (c.saturating_sub(c0).min(2)) as f64)
}

/// A square plateau raised by tan(`deg`)·1 over one grid interval on all four sides.
pub fn box_plateau(n: usize, deg: f64) -> ParamMesh {
    let h = deg.to_radians().tan();
    let (lo, hi) = (n / 3, n - 1 - n / 3);
    height_grid(n, move |r, c| {
        if (lo..=hi).contains(&r) && (lo..=hi).contains(&c) {
            h
        } else {
            0.0
        }
    })
}
