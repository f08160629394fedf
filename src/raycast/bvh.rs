//! Nearest-hit ray casting against a triangle soup with an `obvhs` compressed-wide BVH.
//!
//! Triangles are f32 in a caller-chosen local frame (subtract an f64 origin near the
//! camera before converting, so UTM-sized coordinates keep their precision).

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;

use super::triangle::PreTri;

/// BVH build quality: slower builds give faster traversal (see docs/projection.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhQuality {
    /// `obvhs` fastest preset.
    Fastest,
    /// `obvhs` fast preset (default: on the Engabreen scene the slower presets did not
    /// traverse measurably faster, see docs/projection.md "Ray casting").
    #[default]
    Fast,
    /// `obvhs` medium preset.
    Medium,
    /// `obvhs` slow preset.
    Slow,
    /// `obvhs` very slow preset (best traversal).
    VerySlow,
}

impl BvhQuality {
    /// All presets, fastest build first.
    pub const ALL: [BvhQuality; 5] = [
        BvhQuality::Fastest,
        BvhQuality::Fast,
        BvhQuality::Medium,
        BvhQuality::Slow,
        BvhQuality::VerySlow,
    ];

    /// Parses "fastest", "fast", "medium", "slow" or "very-slow".
    pub fn parse(s: &str) -> Option<BvhQuality> {
        Some(match s {
            "fastest" => BvhQuality::Fastest,
            "fast" => BvhQuality::Fast,
            "medium" => BvhQuality::Medium,
            "slow" => BvhQuality::Slow,
            "very-slow" | "veryslow" => BvhQuality::VerySlow,
            _ => return None,
        })
    }

    /// The name [`BvhQuality::parse`] accepts.
    pub fn name(self) -> &'static str {
        match self {
            BvhQuality::Fastest => "fastest",
            BvhQuality::Fast => "fast",
            BvhQuality::Medium => "medium",
            BvhQuality::Slow => "slow",
            BvhQuality::VerySlow => "very-slow",
        }
    }

    fn params(self) -> BvhBuildParams {
        match self {
            BvhQuality::Fastest => BvhBuildParams::fastest_build(),
            BvhQuality::Fast => BvhBuildParams::fast_build(),
            BvhQuality::Medium => BvhBuildParams::medium_build(),
            BvhQuality::Slow => BvhBuildParams::slow_build(),
            BvhQuality::VerySlow => BvhBuildParams::very_slow_build(),
        }
    }
}

/// The nearest intersection of a ray with the triangle soup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    /// Index of the triangle in the slice given to [`TriangleBvh::build`].
    pub triangle: u32,
    /// Ray parameter of the hit (distance if the direction is a unit vector).
    pub t: f32,
    /// Barycentric weights of the triangle's vertices 0, 1, 2 (sum 1, each in [0, 1] up to
    /// rounding).
    pub bary: [f32; 3],
}

/// A BVH over triangles in a local f32 frame. Both faces of a triangle are hit.
pub struct TriangleBvh {
    tris: Vec<Triangle>,
    bvh: Option<CwBvh>,
}

impl TriangleBvh {
    /// Builds the BVH over `triangles` (vertices in the local frame). Degenerate triangles
    /// are kept (they are simply never hit). Deterministic for the same input.
    pub fn build(triangles: &[[Vec3; 3]], quality: BvhQuality) -> TriangleBvh {
        let tris: Vec<Triangle> = triangles
            .iter()
            .map(|t| Triangle {
                v0: Vec3A::from(t[0]),
                v1: Vec3A::from(t[1]),
                v2: Vec3A::from(t[2]),
            })
            .collect();
        let bvh = if tris.is_empty() {
            None
        } else {
            let mut dt = Duration::ZERO;
            Some(build_cwbvh_from_tris(&tris, quality.params(), &mut dt))
        };
        TriangleBvh { tris, bvh }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// `true` if there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The nearest hit with `t` in `[t_min, t_max]` of the ray `origin + t·dir` (local
    /// frame; `dir` need not be normalized), or `None`.
    pub fn nearest(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<TriHit> {
        let bvh = self.bvh.as_ref()?;
        if !(origin.is_finite() && dir.is_finite()) || dir == Vec3::ZERO {
            return None;
        }
        let ray = make_ray(origin, dir, t_min, t_max);
        let mut hit = RayHit::none();
        let tris = &self.tris;
        if !bvh.ray_traverse(ray, &mut hit, |r, id| {
            tris[bvh.primitive_indices[id] as usize].intersect(r)
        }) {
            return None;
        }
        // `hit.primitive_id` indexes the BVH's primitive order; map it to the input order.
        let index = bvh.primitive_indices[hit.primitive_id as usize];
        Some(exact_hit(&tris[index as usize], index, origin, dir, hit.t))
    }

    /// `true` if nothing lies on the ray for `t` in `[t_min, t_max]` (early exit).
    pub fn unoccluded(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return true;
        };
        let ray = make_ray(origin, dir, t_min, t_max);
        let tris = &self.tris;
        bvh.ray_traverse_miss(ray, |r, id| {
            tris[bvh.primitive_indices[id] as usize].intersect(r)
        })
    }
}

/// An `obvhs` ray; negative zeros in the direction become positive zeros (the traversal's
/// octant logic misses hits for axis-parallel rays with -0.0 components).
pub(crate) fn make_ray(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Ray {
    Ray::new(
        Vec3A::from(origin),
        Vec3A::from(dir + Vec3::ZERO),
        t_min,
        t_max,
    )
}

/// Brute-force reference for [`TriangleBvh::nearest`]: tests every triangle (for tests and
/// benchmarks only).
pub fn nearest_brute_force(
    triangles: &[[Vec3; 3]],
    origin: Vec3,
    dir: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<TriHit> {
    let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), t_min, t_max);
    let mut best: Option<(f32, usize)> = None;
    for (i, t) in triangles.iter().enumerate() {
        let tri = Triangle {
            v0: Vec3A::from(t[0]),
            v1: Vec3A::from(t[1]),
            v2: Vec3A::from(t[2]),
        };
        let d = tri.intersect(&ray);
        if d.is_finite() && best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, i));
        }
    }
    let (t, i) = best?;
    let tri = &triangles[i];
    let tri = Triangle {
        v0: Vec3A::from(tri[0]),
        v1: Vec3A::from(tri[1]),
        v2: Vec3A::from(tri[2]),
    };
    Some(exact_hit(&tri, i as u32, origin, dir, t))
}

/// The hit of `tri` at distance `t` with barycentric weights from the same Möller–Trumbore
/// test the view grid uses (so every acceleration reports the same weights for a hit).
fn exact_hit(tri: &Triangle, index: u32, origin: Vec3, dir: Vec3, t: f32) -> TriHit {
    let (t2, uv) = PreTri::new(tri, Vec3A::from(origin))
        .intersect(Vec3A::from(dir + Vec3::ZERO), f32::INFINITY);
    let bary = if t2.is_finite() {
        PreTri::barycentric(uv)
    } else {
        barycentric(tri, origin + dir * t)
    };
    TriHit {
        triangle: index,
        t,
        bary,
    }
}

/// Barycentric weights of `p` (a point on the triangle's plane) clamped to the triangle
/// and normalized to sum 1; equal weights for a degenerate triangle.
pub(crate) fn barycentric(tri: &Triangle, p: Vec3) -> [f32; 3] {
    let (a, b, c) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1p, d2p) = (e1.dot(d), e2.dot(d));
    let den = d11 * d22 - d12 * d12;
    if !(den.abs() > f32::MIN_POSITIVE) || !den.is_finite() {
        return [1.0 / 3.0; 3];
    }
    let w1 = ((d22 * d1p - d12 * d2p) / den).clamp(0.0, 1.0);
    let w2 = ((d11 * d2p - d12 * d1p) / den).clamp(0.0, 1.0);
    let w0 = (1.0 - w1 - w2).max(0.0);
    let s = w0 + w1 + w2;
    [w0 / s, w1 / s, w2 / s]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bvh_matches_brute_force_on_a_grid() {
        let mut tris = Vec::new();
        for j in 0..20 {
            for i in 0..20 {
                let z = |a: i32, b: i32| ((a * 7 + b * 3) % 5) as f32 * 0.3;
                let p = |a: i32, b: i32| Vec3::new(a as f32, b as f32, z(a, b));
                tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        let bvh = TriangleBvh::build(&tris, BvhQuality::Medium);
        for k in 0..200 {
            let o = Vec3::new((k % 17) as f32 + 0.37, (k % 13) as f32 * 1.4 + 0.11, 10.0);
            let d = Vec3::new(
                0.3 * ((k % 5) as f32 - 2.0),
                0.2 * ((k % 3) as f32 - 1.0),
                -1.0,
            );
            let a = bvh.nearest(o, d, 0.0, f32::INFINITY);
            let b = nearest_brute_force(&tris, o, d, 0.0, f32::INFINITY);
            assert_eq!(a.map(|h| h.triangle), b.map(|h| h.triangle), "ray {k}");
            if let (Some(a), Some(b)) = (a, b) {
                assert!((a.t - b.t).abs() < 1e-4);
                // Barycentric weights reproduce the hit point.
                let t = tris[a.triangle as usize];
                let p = t[0] * a.bary[0] + t[1] * a.bary[1] + t[2] * a.bary[2];
                assert!(
                    (p - (o + d * a.t)).length() < 1e-3,
                    "{p} vs {}",
                    o + d * a.t
                );
            }
        }
        assert!(
            bvh.nearest(Vec3::new(5.0, 5.0, 10.0), Vec3::Z, 0.0, f32::INFINITY)
                .is_none()
        );
        let down = -Vec3::Z; // -0.0 components
        assert!(
            bvh.nearest(Vec3::new(5.5, 5.5, 10.0), down, 0.0, f32::INFINITY)
                .is_some()
        );
        assert!(!bvh.unoccluded(Vec3::new(5.5, 5.5, 10.0), down, 0.0, f32::INFINITY));
        assert!(bvh.unoccluded(Vec3::new(5.5, 5.5, 10.0), down, 0.0, 5.0));
        assert!(
            TriangleBvh::build(&[], BvhQuality::Fast)
                .nearest(Vec3::ZERO, Vec3::X, 0.0, 1.0)
                .is_none()
        );
    }
}
