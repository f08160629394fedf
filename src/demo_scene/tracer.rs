//! Exact ray casting against a DEM's full-resolution grid: two triangles per quad of samples
//! in an `obvhs` BVH, in an f32 frame centred on a chosen origin (a camera, or the scene
//! centre for rays from several cameras). Hit points are interpolated from the f64 vertices.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::dem::Dem;
use crate::error::{Error, Result};
use crate::raycast::{BvhQuality, TriangleBvh};

/// A ray's nearest hit on the DEM surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DemHit {
    /// Distance along the (unit) ray from its origin, metres.
    pub t: f64,
    /// The hit point, world metres (f64, barycentric on the triangle's f64 vertices, relative
    /// to its first vertex).
    pub point: DVec3,
    /// Unit normal of the hit triangle, pointing up (z ≥ 0).
    pub normal: DVec3,
    /// Slope of the hit triangle, degrees from horizontal (0..=90).
    pub slope_deg: f64,
}

/// The DEM grid as triangles in a BVH (see the module docs (`src/scene/tracer.rs`)).
pub struct DemTracer<'a> {
    dem: &'a Dem,
    origin: DVec3,
    bvh: TriangleBvh,
}

impl<'a> DemTracer<'a> {
    /// Builds the BVH of `dem`'s grid (triangle `2q` = samples (r,c) (r+1,c) (r+1,c+1), `2q+1`
    /// = (r,c) (r+1,c+1) (r,c+1), `q = r·(w−1) + c`) in an f32 frame centred on `origin`.
    /// Errors for a DEM of fewer than 2 × 2 samples.
    pub fn new(dem: &'a Dem, origin: DVec3) -> Result<DemTracer<'a>> {
        if dem.width < 2 || dem.height < 2 {
            return Err(Error::BadOption(
                "ray casting needs a DEM of at least 2 x 2 samples".into(),
            ));
        }
        let (w, h) = (dem.width, dem.height);
        let tracer_tris: Vec<[Vec3; 3]> = (0..2 * (w - 1) * (h - 1))
            .into_par_iter()
            .map(|i| corners(w, i).map(|(r, c)| (world(dem, r, c) - origin).as_vec3()))
            .collect();
        let bvh = TriangleBvh::build(&tracer_tris, BvhQuality::Medium);
        Ok(DemTracer { dem, origin, bvh })
    }

    /// The origin of the BVH's f32 frame (world).
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// The nearest hit of the ray from `from` (world) along the unit direction `dir`, within
    /// `t_max` metres.
    pub fn nearest(&self, from: DVec3, dir: DVec3, t_max: f64) -> Option<DemHit> {
        let o = (from - self.origin).as_vec3();
        let hit = self.bvh.nearest(o, dir.as_vec3(), 0.0, t_max as f32)?;
        let p = corners(self.dem.width, hit.triangle as usize).map(|(r, c)| world(self.dem, r, c));
        Some(DemHit::on_triangle(hit.t as f64, p, hit.bary))
    }

    /// Whether the surface point `point` (world) is seen from `eye`: the nearest hit of the
    /// ray from `eye` towards it lies no more than `tolerance` metres before it.
    pub fn sees(&self, eye: DVec3, point: DVec3, tolerance: f64) -> bool {
        sees_with(eye, point, tolerance, |o, d, t| self.nearest(o, d, t))
    }
}

impl DemHit {
    /// The hit at distance `t` on the triangle `p` (world, f64) with barycentric weights
    /// `bary`: the point interpolated relative to the first vertex (barycentrics times
    /// absolute, UTM-sized coordinates would lose decimetres on the slivers of near-vertical
    /// walls), the upward unit normal and the slope.
    pub fn on_triangle(t: f64, p: [DVec3; 3], bary: [f32; 3]) -> DemHit {
        let b = bary.map(|x| x as f64);
        let point = p[0] + (p[1] - p[0]) * b[1] + (p[2] - p[0]) * b[2];
        let mut normal = (p[1] - p[0])
            .cross(p[2] - p[0])
            .try_normalize()
            .unwrap_or(DVec3::Z);
        if normal.z < 0.0 {
            normal = -normal;
        }
        let slope_deg = normal.z.clamp(0.0, 1.0).acos().to_degrees();
        DemHit {
            t,
            point,
            normal,
            slope_deg,
        }
    }
}

/// Whether `point` is seen from `eye` by a tracer's `nearest(origin, unit dir, t_max)`: the
/// nearest hit towards it lies no more than `tolerance` metres before it (false for `eye`
/// at the point or non-finite input).
pub(crate) fn sees_with(
    eye: DVec3,
    point: DVec3,
    tolerance: f64,
    nearest: impl Fn(DVec3, DVec3, f64) -> Option<DemHit>,
) -> bool {
    let d = point - eye;
    let len = d.length();
    if !(len > 0.0) || !len.is_finite() {
        return false;
    }
    nearest(eye, d / len, len + tolerance).is_none_or(|h| h.t >= len - tolerance)
}

/// The three samples `(row, col)` of triangle `i` of a grid `w` samples wide.
fn corners(w: usize, i: usize) -> [(usize, usize); 3] {
    let q = i / 2;
    let (r, c) = (q / (w - 1), q % (w - 1));
    if i.is_multiple_of(2) {
        [(r, c), (r + 1, c), (r + 1, c + 1)]
    } else {
        [(r, c), (r + 1, c + 1), (r, c + 1)]
    }
}

/// World position of sample `(r, c)`.
fn world(dem: &Dem, r: usize, c: usize) -> DVec3 {
    let (x, y) = dem.georef.world(r as f64, c as f64);
    DVec3::new(x, y, dem.at(r, c) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::georef::GridGeoref;

    #[test]
    fn hits_a_tilted_plane_exactly() {
        // z = 0.5 x (26.57° slope) on a 9 x 9 grid of 1-m spacing
        let georef = GridGeoref::new(1000.0, 2000.0, 1.0);
        let heights: Vec<f32> = (0..81).map(|i| 0.5 * (i % 9) as f32).collect();
        let dem = Dem::from_heights(9, 9, heights, georef).unwrap();
        let tr = DemTracer::new(&dem, DVec3::new(1004.0, 1996.0, 2.0)).unwrap();
        let eye = DVec3::new(1003.3, 1995.2, 50.0);
        let h = tr.nearest(eye, DVec3::new(0.0, 0.0, -1.0), 1e3).unwrap();
        assert!((h.point.z - 0.5 * 3.3).abs() < 1e-4, "{h:?}");
        assert!((h.slope_deg - 0.5f64.atan().to_degrees()).abs() < 1e-6);
        assert!((h.t - (50.0 - 1.65)).abs() < 1e-3);
        assert!(tr.sees(eye, h.point, 0.01));
        // a point below the surface is hidden
        assert!(!tr.sees(eye, h.point - DVec3::new(0.0, 0.0, 0.5), 0.01));
        assert!(tr.nearest(eye, DVec3::new(0.0, 0.0, 1.0), 1e3).is_none());
    }
}
