//! `verify`: check a store's integrity, and repair what can be rebuilt.
//!
//! Data types:
//! - [`VerifyReport`]: what was checked and every [`Finding`] (a damaged file or an
//!   inconsistency), each naming the file, the cell and which [`Layer`] it belongs to
//!   (the base build, the reparameterized variant or the photo texture).
//! - [`verify_store`] (read-only) and [`repair_plan`] (which cells must be redone per
//!   layer); [`repair_store`] redoes them from the store's build recipe
//!   ([`crate::pipeline::read_recipe`]) and recorded options (docs/reliability.md).
//!
//! Checks, per store: `manifest.json` parses, has the right format/version and (for stores
//! written since 2026-12-04) matches its content checksum; cell ids are unique and match
//! their level/x/y; every cell lies inside the quadtree. Per cell and layer: every recorded
//! file exists with the recorded size and CRC-32; meshes decode (magic, version, sizes,
//! indices in range, finite values), have the recorded surface vertex/triangle counts, no
//! repeated corner in a triangle, every surface vertex inside the cell's recorded bounding
//! box (the f32 cell-local frame, 1 cm tolerance plus f32 rounding) and UVs in [0, 1];
//! PNG textures decode to the recorded side.

mod checks;
mod plan;
mod repair;

pub use checks::verify_store;
pub use plan::{RepairPlan, merge_rebuilt, repair_plan};
pub use repair::repair_store;

use serde::Serialize;

/// Which stage wrote a file (and so which stage can rebuild it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Layer {
    /// `manifest.json` itself.
    Manifest,
    /// `cliffmap build`: the cell's mesh, texture and normal map.
    Base,
    /// `cliffmap reparam`: the reparameterized mesh, texture and normal map.
    Reparam,
    /// `cliffmap project`: the photo texture and its confidence map.
    Photo,
}

/// One problem found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    /// Cell id, if the problem belongs to a cell.
    pub cell: Option<String>,
    /// The file (relative to the store).
    pub file: String,
    /// The layer the file belongs to.
    pub layer: Layer,
    /// What is wrong.
    pub problem: String,
}

/// The result of [`verify_store`].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct VerifyReport {
    /// Cells in the manifest.
    pub cells: usize,
    /// Files whose checksum was verified.
    pub files_checked: usize,
    /// Every problem, in manifest order.
    pub findings: Vec<Finding>,
}

impl VerifyReport {
    /// True if nothing is wrong.
    pub fn is_intact(&self) -> bool {
        self.findings.is_empty()
    }
}
