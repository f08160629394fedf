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
    let rel = |es: &[&CellStatsEntry]| {
        Percentiles::of(&mut es.iter().map(|e| e.stats.rel_texel).collect())
    };
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
                fraction_above: if es.is_empty() {
                    0.0
                } else {
                    n_above as f64 / es.len() as f64
                },
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
            fraction: if covered > 0 {
                texels as f64 / covered as f64
            } else {
                0.0
            },
        })
        .collect();

    StatsSummary {
        cells: entries.len(),
        threshold,
        cells_above,
        percent_above: if entries.is_empty() {
            0.0
        } else {
            100.0 * cells_above as f64 / entries.len() as f64
        },
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::stretch::stretch_bin_edges;

    fn entry(level: u8, x: u32, rel: f64, hist_bin: usize) -> CellStatsEntry {
        let mut h = vec![0u64; stretch_bin_edges().len()];
        h[hist_bin] = 10;
        let stats = CellStats {
            rel_texel: rel,
            max_slope_deg: 10.0 * rel,
            covered_texels: 10,
            stretch_histogram: h,
            ..CellStats::default()
        };
        let tin = Tin {
            triangles: vec![[0, 1, 2]; 3],
            max_error: 0.25,
            ..Tin::default()
        };
        CellStatsEntry::new(CellKey { level, x, y: 0 }, &tin, stats)
    }

    #[test]
    fn summary_counts_and_levels() {
        let es = vec![
            entry(0, 0, 1.1, 2),
            entry(1, 0, 1.0, 2),
            entry(1, 1, 2.5, 8),
            entry(1, 2, 1.3, 4),
        ];
        let s = summarize(&es, 1.2);
        assert_eq!((s.cells, s.cells_above), (4, 2));
        assert_eq!(s.percent_above, 50.0);
        assert_eq!(s.rel_texel.max, 2.5);
        assert!((s.rel_texel.p50 - 1.2).abs() < 1e-12); // between 1.1 and 1.3
        assert_eq!(s.levels.len(), 2);
        assert_eq!(
            (
                s.levels[0].level,
                s.levels[0].cells,
                s.levels[0].cells_above
            ),
            (0, 1, 0)
        );
        assert_eq!(
            (
                s.levels[1].level,
                s.levels[1].cells,
                s.levels[1].cells_above
            ),
            (1, 3, 2)
        );
        assert!((s.levels[1].fraction_above - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(s.covered_texels, 40);
        assert_eq!(s.texel_stretch_histogram[2].texels, 20);
        assert_eq!(s.texel_stretch_histogram[2].fraction, 0.5);
        assert_eq!(s.texel_stretch_histogram.last().unwrap().hi, None);
        let empty = summarize(&[], 1.2);
        assert_eq!(
            (empty.cells, empty.percent_above, empty.rel_texel.max),
            (0, 0.0, 0.0)
        );
    }

    #[test]
    fn stats_json_shape_and_round_trip() {
        let es = vec![entry(0, 0, 1.1, 2), entry(2, 3, 1.7, 6)];
        let v = stats_json(&es, 1.5);
        let obj = v.as_object().unwrap();
        assert_eq!(obj.len(), 2);
        let summary = &v["summary"];
        for k in [
            "cells",
            "threshold",
            "cells_above",
            "percent_above",
            "rel_texel",
            "levels",
            "texel_stretch_histogram",
        ] {
            assert!(summary.get(k).is_some(), "summary lacks {k}");
        }
        assert_eq!(summary["cells_above"], 1);
        for k in ["p50", "p90", "p99", "max"] {
            assert!(summary["rel_texel"][k].is_number(), "{k}");
        }
        let cells = v["cells"].as_array().unwrap();
        assert_eq!(cells.len(), 2);
        let c = cells[1].as_object().unwrap();
        assert_eq!(c["id"], "2-3-0");
        assert_eq!(
            (c["level"].as_u64(), c["x"].as_u64(), c["y"].as_u64()),
            (Some(2), Some(3), Some(0))
        );
        assert_eq!(c["triangles"], 3);
        assert_eq!(c["max_error"], 0.25);
        assert_eq!(c["rel_texel"], 1.7);
        assert_eq!(c["max_slope_deg"], 17.0);
        for k in [
            "surface_area_tin",
            "surface_area_dem",
            "base_area",
            "used_fraction",
            "mean_slope_deg",
            "steep_texel_fraction",
        ] {
            assert!(c[k].is_number(), "cell lacks {k}");
        }
        assert!(c["texel_stretch"]["p99"].is_number());
        // flat: no nested "stats" object, and it reads back
        assert!(c.get("stats").is_none());
        let back: Vec<CellStatsEntry> = serde_json::from_value(v["cells"].clone()).unwrap();
        assert_eq!(back, es);
        let s: StatsSummary = serde_json::from_value(v["summary"].clone()).unwrap();
        assert_eq!(s, summarize(&es, 1.5));
    }
}
