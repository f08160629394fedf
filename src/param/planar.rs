//! Planar projections of a cell: alternative starting layouts for the finish.
//!
//! The hierarchy's layout can land in a worse basin than a plain projection on
//! jagged surfaces; [`projections`] offers the projection onto the horizontal plane
//! (the orthophoto's parameterization) and onto the plane orthogonal to the
//! area-weighted mean normal. Both keep the triangles' orientation seen from that
//! plane's normal; a projection where some triangle folds over is still returned (its
//! energy is +∞, so the caller skips it).

/// The projections onto the xy plane and onto the mean-normal plane (if that normal is
/// defined and differs from +z), in the mesh's own units.
pub(crate) fn projections(pos: &[[f64; 3]], tris: &[[u32; 3]]) -> Vec<Vec<[f64; 2]>> {
    let mut out = vec![pos.iter().map(|p| [p[0], p[1]]).collect::<Vec<_>>()];
    let mut n = [0.0f64; 3];
    for t in tris {
        let (a, b, c) = (pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]);
        let (u, v) = (sub(b, a), sub(c, a));
        let x = cross(u, v);
        for k in 0..3 {
            n[k] += x[k];
        }
    }
    let len = dot(n, n).sqrt();
    if !(len > 0.0) {
        return out;
    }
    let n = n.map(|x| x / len);
    if n[2] > 1.0 - 1e-9 {
        return out;
    }
    // e1 horizontal (along the slope's strike), e2 = n × e1 so (e1, e2, n) is right-handed.
    let h = (n[0] * n[0] + n[1] * n[1]).sqrt();
    let e1 = if h > 1e-12 {
        [-n[1] / h, n[0] / h, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let e2 = cross(n, e1);
    out.push(pos.iter().map(|p| [dot(*p, e1), dot(*p, e2)]).collect());
    out
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed area of a UV triangle.
    fn area(uv: &[[f64; 2]], t: [u32; 3]) -> f64 {
        let (a, b, c) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    }

    #[test]
    fn a_tilted_plane_projects_isometrically_onto_its_own_plane() {
        // A 60° ramp: the mean-normal projection keeps lengths, the xy one shortens y.
        let s = 60f64.to_radians();
        let pos = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, s.cos(), s.sin()],
            [0.0, s.cos(), s.sin()],
        ];
        let tris = [[0, 1, 2], [0, 2, 3]];
        let p = projections(&pos, &tris);
        assert_eq!(p.len(), 2);
        for t in tris {
            assert!((area(&p[0], t) - 0.5 * s.cos()).abs() < 1e-12);
            assert!(
                (area(&p[1], t) - 0.5).abs() < 1e-12,
                "same orientation, full area"
            );
        }
    }

    #[test]
    fn a_flat_cell_has_only_the_horizontal_projection() {
        let pos = [[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]];
        assert_eq!(projections(&pos, &[[0, 1, 2]]).len(), 1);
    }
}
