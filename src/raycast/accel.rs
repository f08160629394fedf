//! The choice of ray-casting acceleration for the photo stage, and the per-photo caster.
//!
//! Both accelerations give the nearest hit of every pixel-corner ray (the same triangle and
//! distance, up to ties between triangles hit at the same distance); they differ in cost
//! (docs/projection.md, "Ray casting").

use glam::Vec3;

use super::viewgrid::{ViewGrid, ViewGridParams};
use super::{BvhQuality, TriHit, TriangleBvh};

/// How a level's pixel-corner rays find their nearest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RayAccel {
    /// Triangles binned by their projection from the camera centre, per photo (default:
    /// several times faster than the BVH for the rays of one photo, see docs/projection.md).
    ViewGrid(ViewGridParams),
    /// An `obvhs` compressed-wide BVH over the level's triangles, built with this preset.
    Bvh(BvhQuality),
}

impl Default for RayAccel {
    fn default() -> Self {
        RayAccel::ViewGrid(ViewGridParams::default())
    }
}

impl From<BvhQuality> for RayAccel {
    fn from(q: BvhQuality) -> Self {
        RayAccel::Bvh(q)
    }
}

impl From<ViewGridParams> for RayAccel {
    fn from(p: ViewGridParams) -> Self {
        RayAccel::ViewGrid(p)
    }
}

impl RayAccel {
    /// Parses `grid`, `grid:BIN_PX` (bin side in pixels, > 0), `bvh` (default preset) or
    /// `bvh:PRESET` (a [`BvhQuality`] name).
    pub fn parse(s: &str) -> Option<RayAccel> {
        let (kind, arg) = match s.split_once(':') {
            Some((k, a)) => (k, Some(a)),
            None => (s, None),
        };
        match kind {
            "grid" => {
                let bin_px = match arg {
                    None => ViewGridParams::default().bin_px,
                    Some(a) => a
                        .parse::<f32>()
                        .ok()
                        .filter(|b| b.is_finite() && *b > 0.0 && *b <= 4096.0)?,
                };
                Some(RayAccel::ViewGrid(ViewGridParams { bin_px }))
            }
            "bvh" => Some(RayAccel::Bvh(match arg {
                None => BvhQuality::default(),
                Some(a) => BvhQuality::parse(a)?,
            })),
            _ => None,
        }
    }

    /// The name [`RayAccel::parse`] accepts for this value.
    pub fn name(&self) -> String {
        match self {
            RayAccel::ViewGrid(p) => format!("grid:{}", p.bin_px),
            RayAccel::Bvh(q) => format!("bvh:{}", q.name()),
        }
    }
}

/// Nearest-hit queries for the rays of one photo.
// one per photo, built and used in place: boxing the grid would only add an allocation
#[allow(clippy::large_enum_variant)]
pub(crate) enum Caster<'a> {
    Grid(ViewGrid),
    Bvh(&'a TriangleBvh),
}

impl Caster<'_> {
    /// Nearest hit (both faces) of the ray from `origin` (the camera centre, scene frame)
    /// along the unit vector `dir`, whose point on the undistorted image plane is `xy`.
    #[inline]
    pub(crate) fn nearest(&self, origin: Vec3, dir: Vec3, xy: [f64; 2]) -> Option<TriHit> {
        match self {
            Caster::Grid(g) => g.nearest_at(origin, dir, xy),
            Caster::Bvh(b) => b.nearest(origin, dir, 0.0, f32::INFINITY),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_round_trips() {
        for s in [
            "grid",
            "grid:4",
            "grid:2.5",
            "bvh",
            "bvh:fast",
            "bvh:very-slow",
        ] {
            let a = RayAccel::parse(s).unwrap();
            assert_eq!(RayAccel::parse(&a.name()), Some(a), "{s}");
        }
        assert_eq!(RayAccel::parse("grid"), Some(RayAccel::default()));
        for bad in [
            "",
            "grid:0",
            "grid:-1",
            "grid:nan",
            "grid:x",
            "bvh:quick",
            "octree",
        ] {
            assert_eq!(RayAccel::parse(bad), None, "{bad}");
        }
    }
}
