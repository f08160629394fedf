//! What a repair must redo, and how a rebuilt base is merged with the old manifest.

use std::collections::BTreeSet;

use super::{Layer, VerifyReport};
use crate::store::Manifest;

/// The cells to redo per layer (sorted, deduplicated ids).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RepairPlan {
    /// `manifest.json` cannot be trusted: every layer's records are lost with it.
    pub manifest: bool,
    /// Cells whose build output (mesh, texture, normal map) is damaged.
    pub base: Vec<String>,
    /// Cells whose reparameterized variant is damaged.
    pub reparam: Vec<String>,
    /// Cells whose photo texture is damaged.
    pub photo: Vec<String>,
}

impl RepairPlan {
    /// True if nothing needs repair.
    pub fn is_empty(&self) -> bool {
        !self.manifest && self.base.is_empty() && self.reparam.is_empty() && self.photo.is_empty()
    }
}

/// Groups the findings of `report` by layer.
pub fn repair_plan(report: &VerifyReport) -> RepairPlan {
    let mut sets = [BTreeSet::new(), BTreeSet::new(), BTreeSet::new()];
    let mut manifest = false;
    for f in &report.findings {
        match (f.layer, &f.cell) {
            (Layer::Manifest, _) | (_, None) => manifest = true,
            (Layer::Base, Some(c)) => {
                sets[0].insert(c.clone());
            }
            (Layer::Reparam, Some(c)) => {
                sets[1].insert(c.clone());
            }
            (Layer::Photo, Some(c)) => {
                sets[2].insert(c.clone());
            }
        }
    }
    let [b, r, p] = sets.map(|s| s.into_iter().collect::<Vec<_>>());
    RepairPlan {
        manifest,
        base: b,
        reparam: r,
        photo: p,
    }
}

/// After the base layer was rebuilt (`rebuilt`, a fresh build's manifest), carries over from
/// `old` the reparameterized and photo records of every cell whose rebuilt base files are
/// byte-identical to the old ones (a deterministic rebuild), and the stores' reparam/photo
/// settings. Returns the merged manifest and the ids of cells whose derived records had to
/// be dropped because their base changed.
pub fn merge_rebuilt(old: &Manifest, rebuilt: &Manifest) -> (Manifest, Vec<String>) {
    let mut out = rebuilt.clone();
    let mut dropped = Vec::new();
    for c in &mut out.cells {
        let Some(o) = old.cell(&c.id) else { continue };
        if o.reparam.is_none() && o.photo.is_none() {
            continue;
        }
        if o.files == c.files {
            c.reparam = o.reparam.clone();
            c.photo = o.photo.clone();
            c.parameterization = o.parameterization;
        } else {
            dropped.push(c.id.clone());
        }
    }
    out.reparam = old.reparam.clone();
    out.photos = old.photos.clone();
    (out, dropped)
}
