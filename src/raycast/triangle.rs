//! The ray–triangle test shared by the view grid, the BVH and the brute-force reference.

use glam::Vec3A;
use obvhs::triangle::Triangle;

/// A triangle prepared for rays from one origin: the terms of
/// [`obvhs::triangle::Triangle::intersect`] that do not depend on the ray direction,
/// computed with the same operations, so the hit distance is bit-identical to obvhs's.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PreTri {
    /// `v0 − origin`.
    pub(crate) c: Vec3A,
    /// `v0 − v1`.
    pub(crate) e1: Vec3A,
    /// `v2 − v0`.
    pub(crate) e2: Vec3A,
    /// `e1 × e2`.
    pub(crate) n: Vec3A,
    /// `n · c`.
    pub(crate) nc: f32,
}

impl PreTri {
    pub(crate) fn new(t: &Triangle, origin: Vec3A) -> PreTri {
        let e1 = t.v0 - t.v1;
        let e2 = t.v2 - t.v0;
        let n = e1.cross(e2);
        let c = t.v0 - origin;
        PreTri {
            c,
            e1,
            e2,
            n,
            nc: n.dot(c),
        }
    }

    /// Distance along `d` to the hit in `[0, tmax]` and its barycentric `(u, v)` (weights of
    /// `v1`, `v2`), or `(∞, _)` (Möller–Trumbore as obvhs).
    #[inline(always)]
    pub(crate) fn intersect(&self, d: Vec3A, tmax: f32) -> (f32, [f32; 2]) {
        let r = d.cross(self.c);
        let det = self.n.dot(d);
        let (a, b) = (r.dot(self.e2), r.dot(self.e1));
        // u = a / det and v = b / det have the sign bits of a ^ det and b ^ det (for a NaN-free
        // ray), so a negative one is known before the division: the same decision as below.
        if ((a.to_bits() ^ det.to_bits()) | (b.to_bits() ^ det.to_bits())) & 0x8000_0000 != 0 {
            return (f32::INFINITY, [0.0; 2]);
        }
        let inv_det = 1.0 / det;
        let u = a * inv_det;
        let v = b * inv_det;
        let w = 1.0 - u - v;
        let signs = u.to_bits() | v.to_bits() | w.to_bits();
        if inv_det != 0.0 && signs & 0x8000_0000 == 0 {
            let t = self.nc * inv_det;
            if t >= 0.0 && t <= tmax {
                return (t, [u, v]);
            }
        }
        (f32::INFINITY, [0.0; 2])
    }

    /// Barycentric weights `[w, u, v]` of `v0, v1, v2` from [`PreTri::intersect`]'s `(u, v)`:
    /// each in [0, 1], sum 1 up to rounding (the hit test accepted only non-negative ones).
    #[inline]
    pub(crate) fn barycentric(uv: [f32; 2]) -> [f32; 3] {
        [(1.0 - uv[0] - uv[1]).max(0.0), uv[0], uv[1]]
    }
}
