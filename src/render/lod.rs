//! Level-of-detail selection over the store's quadtree: refine by screen-space error, cull by
//! frustum.

use std::collections::HashMap;

use glam::DVec3;

use super::camera::RenderCamera;
use crate::cells::CellKey;
use crate::store::CellRecord;

/// Finds cells of a manifest by quadtree key. Indices refer to the slice it was built from.
#[derive(Clone, Debug, Default)]
pub struct CellIndex {
    by_key: HashMap<CellKey, usize>,
    roots: Vec<usize>,
}

impl CellIndex {
    /// Indexes `cells` (a manifest's cell list). Roots are the level-0 cells.
    pub fn new(cells: &[CellRecord]) -> CellIndex {
        let by_key: HashMap<CellKey, usize> = cells
            .iter()
            .enumerate()
            .map(|(i, c)| (c.key(), i))
            .collect();
        let roots = cells
            .iter()
            .enumerate()
            .filter(|(_, c)| c.level == 0)
            .map(|(i, _)| i)
            .collect();
        CellIndex { by_key, roots }
    }

    /// Index of the cell with `key`, if the store has it.
    pub fn get(&self, key: CellKey) -> Option<usize> {
        self.by_key.get(&key).copied()
    }

    /// Indices of the level-0 cells.
    pub fn roots(&self) -> &[usize] {
        &self.roots
    }

    /// Indices of the existing children of `key` (NW, NE, SW, SE order, absent ones skipped).
    pub fn children(&self, key: CellKey) -> impl Iterator<Item = usize> + '_ {
        key.children().into_iter().filter_map(|k| self.get(k))
    }

    /// Index of the nearest ancestor of `key` that satisfies `pred`, if any.
    pub fn ancestor_where(
        &self,
        key: CellKey,
        mut pred: impl FnMut(usize) -> bool,
    ) -> Option<usize> {
        let mut k = key.parent();
        while let Some(p) = k {
            if let Some(i) = self.get(p).filter(|&i| pred(i)) {
                return Some(i);
            }
            k = p.parent();
        }
        None
    }
}

/// The error a cell makes, in world metres ([`CellRecord::error`]).
pub fn cell_error(rec: &CellRecord) -> f64 {
    rec.error()
}

/// A cell's geometric error in metres ([`CellRecord::geometric_error`]).
pub fn geometric_error(rec: &CellRecord) -> f64 {
    rec.geometric_error()
}

/// Distance (metres, ≥ 0) from `p` to the nearest point of the cell's world bounding box.
pub fn distance_to_bbox(rec: &CellRecord, p: DVec3) -> f64 {
    let (lo, hi) = (DVec3::from(rec.bbox_min), DVec3::from(rec.bbox_max));
    (p.clamp(lo, hi) - p).length()
}

/// Screen-space error in pixels: `cell_error · fy / distance`, i.e.
/// `error · viewport_height / (2 · distance · tan(fov_y / 2))`; infinite inside the box.
pub fn screen_space_error(rec: &CellRecord, cam: &RenderCamera) -> f64 {
    let d = distance_to_bbox(rec, cam.model.position);
    if d <= 0.0 {
        f64::INFINITY
    } else {
        cell_error(rec) * cam.pixels_per_metre(d)
    }
}

/// Result of one LOD traversal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LodSelection {
    /// Indices of the cells to draw, sorted ascending; they never overlap (no cell and its ancestor).
    pub cells: Vec<usize>,
    /// Cells rejected by the frustum test.
    pub culled: usize,
    /// Cells whose error was evaluated.
    pub visited: usize,
}

/// Traverses the quadtree from its roots: a visible cell whose screen-space error exceeds
/// `threshold_px` is replaced by its existing children; other visible cells are selected.
/// Cells whose bounding box (extended down by the skirt) is outside the frustum are dropped.
pub fn select_cells(
    cells: &[CellRecord],
    index: &CellIndex,
    cam: &RenderCamera,
    threshold_px: f64,
) -> LodSelection {
    select_cells_with_margin(cells, index, cam, threshold_px, |_| (0.0, 0.0))
}

/// [`select_cells`] with each cell's bounding box extended by `z_margin(cell index) = (up,
/// down)` metres (each ≥ 0; down in addition to the skirt) for the frustum test (e.g. the
/// height range a geomorphed cell can reach). The refinement test is unchanged.
pub fn select_cells_with_margin(
    cells: &[CellRecord],
    index: &CellIndex,
    cam: &RenderCamera,
    threshold_px: f64,
    z_margin: impl Fn(usize) -> (f64, f64),
) -> LodSelection {
    let frustum = cam.frustum();
    let eye = cam.model.position;
    let mut out = LodSelection::default();
    let mut stack: Vec<usize> = index.roots().iter().rev().copied().collect();
    while let Some(i) = stack.pop() {
        let rec = &cells[i];
        let clean = |m: f64| if m.is_finite() { m.max(0.0) } else { 0.0 };
        let (up, down) = z_margin(i);
        let (up, down) = (clean(up), clean(down));
        let lo =
            DVec3::from(rec.bbox_min) - DVec3::new(0.0, 0.0, rec.skirt_depth.max(0.0) + down) - eye;
        let hi = DVec3::from(rec.bbox_max) + DVec3::new(0.0, 0.0, up) - eye;
        if !frustum.intersects_aabb(lo, hi) {
            out.culled += 1;
            continue;
        }
        out.visited += 1;
        let before = stack.len();
        if screen_space_error(rec, cam) > threshold_px {
            stack.extend(
                index
                    .children(rec.key())
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev(),
            );
        }
        if stack.len() == before {
            out.cells.push(i);
        }
    }
    out.cells.sort_unstable();
    out
}
