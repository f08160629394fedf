//! Aggregates over many cells and the `stats.json` document.

use serde::{Deserialize, Serialize};

use crate::cells::{CellKey, Tin};
use crate::stats::stretch::stretch_bin_edges;
use crate::stats::{CellStats, Percentiles};

/// One cell's statistics with its address and TIN figures: one element of `stats.json`'s
/// `"cells"` array. Serialises flat: `id, level, x, y, triangles, max_error` followed by the
/// [`CellStats`] fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellStatsEntry {
    /// Cell id `"{level}-{x}-{y}"`.
    pub id: String,
    /// Quadtree level, 0 = root.
    pub level: u8,
    /// Column of the cell within its level.
    pub x: u32,
    /// Row of the cell within its level.
    pub y: u32,
    /// Number of TIN triangles.
    pub triangles: u32,
    /// The TIN's maximum vertical error (world units).
    pub max_error: f64,
    /// The cell's statistics.
    #[serde(flatten)]
    pub stats: CellStats,
}

impl CellStatsEntry {
    /// Entry for cell `key` with its TIN and statistics.
    pub fn new(key: CellKey, tin: &Tin, stats: CellStats) -> CellStatsEntry {
        CellStatsEntry {
            id: key.id(),
            level: key.level,
            x: key.x,
            y: key.y,
            triangles: tin.triangles.len().min(u32::MAX as usize) as u32,
            max_error: tin.max_error,
            stats,
        }
    }
}

/// Per-level aggregate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LevelSummary {
    /// Quadtree level.
    pub level: u8,
    /// Cells of this level.
    pub cells: usize,
    /// Cells with `rel_texel > threshold`.
    pub cells_above: usize,
    /// `cells_above / cells` (0 if no cells).
    pub fraction_above: f64,
    /// Distribution of `rel_texel` over this level's cells.
    pub rel_texel: Percentiles,
}

/// One bin of the overall per-texel stretch histogram.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistogramBin {
    /// Lower edge (inclusive) of the stretch values in the bin.
    pub lo: f64,
    /// Upper edge (exclusive); `None` for the open last bin.
    pub hi: Option<f64>,
    /// Texels in the bin, summed over all cells.
    pub texels: u64,
    /// `texels` / all covered texels (0 if none).
    pub fraction: f64,
}

/// Aggregate statistics over a set of cells (normally all cells of all levels).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StatsSummary {
    /// Number of cells.
    pub cells: usize,
    /// The `rel_texel` threshold above which a cell counts as stretched.
    pub threshold: f64,
    /// Cells with `rel_texel > threshold`.
    pub cells_above: usize,
    /// `100 * cells_above / cells` (0 if no cells).
    pub percent_above: f64,
    /// Distribution of `rel_texel` over all cells.
    pub rel_texel: Percentiles,
    /// Per-level counts, finest last.
    pub levels: Vec<LevelSummary>,
    /// Covered texels summed over all cells.
    pub covered_texels: u64,
    /// Per-texel stretch distribution over all cells, bins of
    /// [`stretch_bin_edges`](crate::stats::stretch_bin_edges).
    pub texel_stretch_histogram: Vec<HistogramBin>,
}

/// Aggregates `entries` (cells with `rel_texel > threshold` count as above). Deterministic
/// for a given order of entries; empty input gives zero counts.
pub fn summarize(entries: &[CellStatsEntry], threshold: f64) -> StatsSummary {
    let above = |e: &&&CellStatsEntry| e.stats.rel_texel > threshold;
    let rel = |es: &[&CellStatsEntry]| Percentiles::of(&mut es.iter().map(|e| e.stats.rel_texel).collect());
    let all: Vec<&CellStatsEntry> = entries.iter().collect();
    let cells_above = all.iter().filter(above).count();

    let mut level_ids: Vec<u8> = entries.iter().map(|e| e.level).collect();
    level_ids.sort_unstable();
    level_ids.dedup();
    let levels = level_ids
        .into_iter()
        .map(|level| {
            let es: Vec<&CellStatsEntry> = entries.iter().filter(|e| e.level == level).collect();
            let n_above = es.iter().filter(above).count();
            LevelSummary {
                level,
                cells: es.len(),
                cells_above: n_above,
                fraction_above: if es.is_empty() { 0.0 } else { n_above as f64 / es.len() as f64 },
                rel_texel: rel(&es),
            }
        })
        .collect();

    let edges = stretch_bin_edges();
    let mut counts = vec![0u64; edges.len()];
    for e in entries {
        for (c, &h) in counts.iter_mut().zip(&e.stats.stretch_histogram) {
            *c += h;
        }
    }
    let covered: u64 = counts.iter().sum();
    let texel_stretch_histogram = counts
        .iter()
        .enumerate()
        .map(|(k, &texels)| HistogramBin {
            lo: edges[k],
            hi: edges.get(k + 1).copied(),
            texels,
            fraction: if covered > 0 { texels as f64 / covered as f64 } else { 0.0 },
        })
        .collect();

    StatsSummary {
        cells: entries.len(),
        threshold,
        cells_above,
        percent_above: if entries.is_empty() { 0.0 } else { 100.0 * cells_above as f64 / entries.len() as f64 },
        rel_texel: rel(&all),
        levels,
        covered_texels: covered,
        texel_stretch_histogram,
    }
}

/// The `stats.json` document: `{"summary": StatsSummary, "cells": [CellStatsEntry...]}`, each
/// cell a flat object with `id, level, x, y, triangles, max_error, rel_texel, max_slope_deg`
/// and the other [`CellStats`] fields.
pub fn stats_json(entries: &[CellStatsEntry], threshold: f64) -> serde_json::Value {
    let summary = summarize(entries, threshold);
    serde_json::json!({
        "summary": serde_json::to_value(&summary).unwrap_or(serde_json::Value::Null),
        "cells": serde_json::to_value(entries).unwrap_or(serde_json::Value::Null),
    })
}
