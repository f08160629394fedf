//! World rectangles of quadtree cells.

use crate::cells::{CellKey, Quadtree};
use crate::georef::{GridGeoref, WorldRect};

/// The cell's NOMINAL (unclipped) square in world units: its edges pass through the centres
/// of the cell's four corner samples, even where those samples lie in the virtual padding
/// beyond the DEM. This is the area a cell texture covers.
pub fn nominal_extent(tree: &Quadtree, georef: &GridGeoref, key: CellKey) -> WorldRect {
    let (c0, r0, n) = tree.nominal(key);
    let (x0, y0) = georef.world(r0 as f64, c0 as f64);
    let (x1, y1) = georef.world((r0 + n) as f64, (c0 + n) as f64);
    WorldRect {
        min_x: x0,
        min_y: y1,
        max_x: x1,
        max_y: y0,
    }
}

/// The cell's rectangle clipped to the DEM's data (sample-centre) rectangle, or `None` if
/// the cell has no area inside the DEM.
pub fn clipped_extent(tree: &Quadtree, georef: &GridGeoref, key: CellKey) -> Option<WorldRect> {
    let r = tree.clipped(key)?;
    let (x0, y0) = georef.world(r.r0 as f64, r.c0 as f64);
    let (x1, y1) = georef.world(r.r1 as f64, r.c1 as f64);
    Some(WorldRect {
        min_x: x0,
        min_y: y1,
        max_x: x1,
        max_y: y0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nominal_and_clipped_extents() {
        let q = Quadtree::new(101, 81, 32); // span 100 -> 32 * 4 = 128 -> 3 levels
        let g = GridGeoref::new(1000.0, 5000.0, 2.0);
        let k = CellKey {
            level: q.finest_level(),
            x: 3,
            y: 2,
        };
        let nom = nominal_extent(&q, &g, k);
        assert_eq!(
            nom,
            WorldRect {
                min_x: 1192.0,
                min_y: 4808.0,
                max_x: 1256.0,
                max_y: 4872.0
            }
        );
        let cl = clipped_extent(&q, &g, k).unwrap();
        // columns 96..=100, rows 64..=80
        assert_eq!(
            cl,
            WorldRect {
                min_x: 1192.0,
                min_y: 4840.0,
                max_x: 1200.0,
                max_y: 4872.0
            }
        );
    }
}
