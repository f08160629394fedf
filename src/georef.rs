//! Georeferencing of regular north-up grids (DEMs and ortho images), in f64.
//!
//! Convention (everywhere in cliffmap): sample `(row, col)` has its **centre** at world
//! `x = origin_x + col * spacing_x`, `y = origin_y - row * spacing_y`. Row 0 is the
//! north edge, columns run west to east. Spacings are positive, in world units (metres).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Placement of a north-up grid in the world frame (f64, metres).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridGeoref {
    /// World x of the centre of sample (0, 0) (the north-west sample).
    pub origin_x: f64,
    /// World y of the centre of sample (0, 0).
    pub origin_y: f64,
    /// Distance between columns, > 0.
    pub spacing_x: f64,
    /// Distance between rows, > 0 (rows run north to south).
    pub spacing_y: f64,
}

impl GridGeoref {
    /// A grid with square spacing `spacing` whose sample (0,0) centre is at `(x, y)`.
    pub fn new(origin_x: f64, origin_y: f64, spacing: f64) -> Self {
        GridGeoref {
            origin_x,
            origin_y,
            spacing_x: spacing,
            spacing_y: spacing,
        }
    }

    /// Rejects non-finite origins and non-positive or non-finite spacings.
    pub fn validate(&self) -> Result<()> {
        if !(self.origin_x.is_finite() && self.origin_y.is_finite()) {
            return Err(Error::BadOption(format!(
                "grid origin ({}, {}) is not finite",
                self.origin_x, self.origin_y
            )));
        }
        for (name, s) in [("x", self.spacing_x), ("y", self.spacing_y)] {
            if !(s.is_finite() && s > 0.0) {
                return Err(Error::BadOption(format!(
                    "grid spacing in {name} must be a positive number, got {s}"
                )));
            }
        }
        Ok(())
    }

    /// World (x, y) of the fractional grid position (row, col).
    #[inline]
    pub fn world(&self, row: f64, col: f64) -> (f64, f64) {
        (
            self.origin_x + col * self.spacing_x,
            self.origin_y - row * self.spacing_y,
        )
    }

    /// Fractional grid position (row, col) of world (x, y); exact inverse of [`world`](Self::world).
    #[inline]
    pub fn grid(&self, x: f64, y: f64) -> (f64, f64) {
        (
            (self.origin_y - y) / self.spacing_y,
            (x - self.origin_x) / self.spacing_x,
        )
    }

    /// Whether `mask` (an image on this grid, one pixel per sample) is set (value ≥ 128) at
    /// the sample nearest world (x, y); false outside the mask.
    pub fn mask_covers(&self, mask: &image::GrayImage, x: f64, y: f64) -> bool {
        let (r, c) = self.grid(x, y);
        let (r, c) = (r.round(), c.round());
        r >= 0.0
            && c >= 0.0
            && (r as u32) < mask.height()
            && (c as u32) < mask.width()
            && mask.get_pixel(c as u32, r as u32).0[0] >= 128
    }
}

/// An axis-aligned world rectangle (f64, metres): `min` is south-west, `max` north-east.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldRect {
    /// West edge x.
    pub min_x: f64,
    /// South edge y.
    pub min_y: f64,
    /// East edge x.
    pub max_x: f64,
    /// North edge y.
    pub max_y: f64,
}

impl WorldRect {
    /// Width in x.
    pub fn width(&self) -> f64 {
        self.max_x - self.min_x
    }
    /// Height in y.
    pub fn height(&self) -> f64 {
        self.max_y - self.min_y
    }
    /// The overlap of two rectangles, or `None` if they do not overlap with positive area.
    pub fn intersect(&self, o: &WorldRect) -> Option<WorldRect> {
        let r = WorldRect {
            min_x: self.min_x.max(o.min_x),
            min_y: self.min_y.max(o.min_y),
            max_x: self.max_x.min(o.max_x),
            max_y: self.max_y.min(o.max_y),
        };
        (r.max_x > r.min_x && r.max_y > r.min_y).then_some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn world_grid_round_trip_at_utm_scale() {
        let g = GridGeoref {
            origin_x: 445302.17,
            origin_y: 7396769.45,
            spacing_x: 3.0,
            spacing_y: 3.0,
        };
        for &(r, c) in &[(0.0, 0.0), (589.0, 506.0), (12.25, 400.5)] {
            let (x, y) = g.world(r, c);
            let (r2, c2) = g.grid(x, y);
            assert!(
                (r - r2).abs() < 1e-9 && (c - c2).abs() < 1e-9,
                "{r},{c} -> {r2},{c2}"
            );
        }
        assert_eq!(g.world(0.0, 0.0), (445302.17, 7396769.45));
        assert!(GridGeoref::new(0.0, 0.0, -1.0).validate().is_err());
        assert!(GridGeoref::new(f64::NAN, 0.0, 1.0).validate().is_err());
    }
}
