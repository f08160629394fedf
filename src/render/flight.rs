//! Camera flights for `cliffmap fly`: a path file or a default low-altitude path over the
//! store's steepest cells, and the fly-through benchmark report.

use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::accuracy::percentile;
use super::store_renderer::StoreRenderer;
use crate::camera::{CameraModel, rotation_look_at};
use crate::error::{Error, Result};
use crate::store::Manifest;

/// One key of a flight: where the camera is and what it looks at (world metres).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlightKey {
    /// Camera position.
    pub position: [f64; 3],
    /// Point looked at (must differ from `position`).
    pub look_at: [f64; 3],
}

/// A flight path: keys visited at constant speed, positions and targets interpolated linearly.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlightPath {
    /// Vertical field of view, degrees, in (0, 180).
    pub fov_y_deg: f64,
    /// At least two keys.
    pub keys: Vec<FlightKey>,
}

impl FlightPath {
    /// Reads a path file (`{"fov_y_deg": 60, "keys": [{"position": [...], "look_at": [...]}, ...]}`).
    pub fn from_json_file(path: &Path) -> Result<FlightPath> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let p: FlightPath = serde_json::from_str(&text)
            .map_err(|e| Error::bad_input(path, format!("invalid flight path: {e}")))?;
        p.validate().map_err(|m| Error::bad_input(path, m))?;
        Ok(p)
    }

    fn validate(&self) -> std::result::Result<(), String> {
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(format!(
                "fov_y_deg must be in (0, 180), got {}",
                self.fov_y_deg
            ));
        }
        if self.keys.len() < 2 {
            return Err("a flight path needs at least two keys".into());
        }
        for (i, k) in self.keys.iter().enumerate() {
            let (p, t) = (DVec3::from(k.position), DVec3::from(k.look_at));
            if !p.is_finite() || !t.is_finite() || (p - t).length() < 1e-6 {
                return Err(format!(
                    "key {i}: position and look_at must be finite and distinct"
                ));
            }
        }
        Ok(())
    }

    /// The default flight over a store: the finest-level cells with the highest relief
    /// ((bbox height range) / cell width, ties by manifest order), at most 12, visited in a
    /// greedy nearest-neighbour order starting with the steepest, at half a finest cell width
    /// above each cell's highest point, looking at the next cell.
    pub fn default_for(m: &Manifest) -> Result<FlightPath> {
        let finest = m
            .cells
            .iter()
            .map(|c| c.level)
            .max()
            .ok_or_else(|| Error::BadOption("store has no cells".into()))?;
        let mut cand: Vec<(f64, usize)> = m
            .cells
            .iter()
            .enumerate()
            .filter(|(_, c)| c.level == finest)
            .map(|(i, c)| {
                (
                    (c.bbox_max[2] - c.bbox_min[2]) / c.extent.width().abs().max(1e-9),
                    i,
                )
            })
            .collect();
        cand.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        cand.truncate(12);
        let centre = |i: usize| {
            let c = &m.cells[i];
            DVec3::new(
                (c.extent.min_x + c.extent.max_x) / 2.0,
                (c.extent.min_y + c.extent.max_y) / 2.0,
                c.bbox_max[2],
            )
        };
        let mut order = vec![cand[0].1];
        let mut rest: Vec<usize> = cand[1..].iter().map(|c| c.1).collect();
        while !rest.is_empty() {
            let last = centre(order[order.len() - 1]);
            let (k, _) = rest
                .iter()
                .enumerate()
                .min_by(|a, b| {
                    (centre(*a.1) - last)
                        .length()
                        .total_cmp(&(centre(*b.1) - last).length())
                })
                .unwrap_or((0, &0));
            order.push(rest.remove(k));
        }
        let width = m.cells[order[0]].extent.width().abs();
        let clearance = 0.5 * width;
        let mut pts: Vec<DVec3> = order
            .iter()
            .map(|&i| centre(i) + DVec3::new(0.0, 0.0, clearance))
            .collect();
        if pts.len() < 2 {
            // A single cell: fly across it from west to east.
            let p = pts[0];
            pts = vec![
                p - DVec3::new(width, 0.0, 0.0),
                p + DVec3::new(width, 0.0, 0.0),
            ];
        }
        let keys = (0..pts.len())
            .map(|i| {
                let dir = if i + 1 < pts.len() {
                    pts[i + 1] - pts[i]
                } else {
                    pts[i] - pts[i - 1]
                };
                let flat = DVec3::new(dir.x, dir.y, 0.0)
                    .try_normalize()
                    .unwrap_or(DVec3::X);
                let target = pts[i] + flat * width - DVec3::new(0.0, 0.0, clearance * 1.5);
                FlightKey {
                    position: pts[i].to_array(),
                    look_at: target.to_array(),
                }
            })
            .collect();
        let p = FlightPath {
            fov_y_deg: 60.0,
            keys,
        };
        p.validate().map_err(Error::BadOption)?;
        Ok(p)
    }

    /// `frames` cameras of `width × height` at constant speed along the keys (first and last
    /// frame on the first and last key).
    pub fn cameras(&self, frames: usize, width: u32, height: u32) -> Vec<CameraModel> {
        let pts: Vec<DVec3> = self.keys.iter().map(|k| DVec3::from(k.position)).collect();
        let tgs: Vec<DVec3> = self.keys.iter().map(|k| DVec3::from(k.look_at)).collect();
        let mut cum = vec![0.0];
        for w in pts.windows(2) {
            cum.push(cum[cum.len() - 1] + (w[1] - w[0]).length());
        }
        let total = cum[cum.len() - 1];
        (0..frames)
            .map(|f| {
                let s = if frames > 1 {
                    total * f as f64 / (frames - 1) as f64
                } else {
                    0.0
                };
                let seg = (1..cum.len())
                    .find(|&j| cum[j] >= s)
                    .unwrap_or(cum.len() - 1);
                let len = cum[seg] - cum[seg - 1];
                let t = if len > 0.0 {
                    ((s - cum[seg - 1]) / len).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let p = pts[seg - 1].lerp(pts[seg], t);
                let mut target = tgs[seg - 1].lerp(tgs[seg], t);
                if (target - p).length() < 1e-6 {
                    target = p + DVec3::X;
                }
                let r = rotation_look_at(p, target).unwrap_or(glam::DMat3::IDENTITY);
                CameraModel::with_fov(p, r, width, height, self.fov_y_deg.to_radians())
            })
            .collect()
    }
}

/// Fly-through figures (all per rendered frame, the warm-up frame excluded).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlyReport {
    /// Frames timed.
    pub frames: usize,
    /// Frame size.
    pub width: u32,
    /// Frame size.
    pub height: u32,
    /// UV mode ("mixed", "ortho", "reparam").
    pub mode: String,
    /// Screen-space error threshold, pixels.
    pub sse_px: f64,
    /// Adapter name.
    pub adapter: String,
    /// Backend (Vulkan, Gl, ...).
    pub backend: String,
    /// Device type (Cpu = software rasterizer).
    pub device_type: String,
    /// Median frames per second (1000 / median frame time).
    pub fps_median: f64,
    /// 5th percentile of frames per second (slow frames).
    pub fps_p5: f64,
    /// Median frame time, ms.
    pub frame_ms_median: f64,
    /// 95th percentile frame time, ms.
    pub frame_ms_p95: f64,
    /// Median triangles drawn per frame.
    pub triangles_per_frame_median: f64,
    /// Median cells drawn per frame.
    pub cells_per_frame_median: f64,
    /// Largest GPU memory held by cached cells (buffers + textures with mips), bytes.
    pub gpu_bytes_max: u64,
    /// The cache budget, bytes.
    pub gpu_budget_bytes: u64,
    /// Frames in which at least one selected cell was not loaded (drawn coarser or missing).
    pub load_stall_frames: usize,
    /// Sum over frames of selected cells drawn through an ancestor.
    pub substituted_cells: usize,
    /// Sum over frames of selected cells with nothing to draw.
    pub hole_cells: usize,
    /// Cells uploaded during the timed frames.
    pub uploads: usize,
    /// Time of the warm-up frame (first view loaded completely), ms.
    pub warmup_ms: f64,
    /// Whether the flight geomorphed cells towards their parents.
    #[serde(default)]
    pub geomorph: bool,
    /// Median over frames of the cells drawn with a morph factor > 0.
    #[serde(default)]
    pub morphed_cells_per_frame_median: f64,
}

/// Flies `cams`: the first camera is a warm-up frame that waits for its cells; the others
/// never wait for loads. `mode` and `budget` are copied into the report.
pub fn fly(
    scene: &mut StoreRenderer,
    cams: &[CameraModel],
    mode: &str,
    sse_px: f64,
    budget: u64,
) -> Result<FlyReport> {
    let (first, rest) = cams
        .split_first()
        .ok_or_else(|| Error::BadOption("a flight needs at least 2 frames".into()))?;
    if rest.is_empty() {
        return Err(Error::BadOption("a flight needs at least 2 frames".into()));
    }
    let warm = scene.frame(first, true)?;
    let mut reports = Vec::with_capacity(rest.len());
    for c in rest {
        reports.push(scene.frame(c, false)?);
    }
    let ms: Vec<f64> = reports.iter().map(|r| r.frame_ms).collect();
    let fps: Vec<f64> = ms.iter().map(|m| 1e3 / m.max(1e-9)).collect();
    let info = &scene.gpu().info;
    Ok(FlyReport {
        frames: reports.len(),
        width: first.width,
        height: first.height,
        mode: mode.to_string(),
        sse_px,
        adapter: info.name.clone(),
        backend: format!("{:?}", info.backend),
        device_type: format!("{:?}", info.device_type),
        fps_median: 1e3 / percentile(&ms, 0.5),
        fps_p5: percentile(&fps, 0.05),
        frame_ms_median: percentile(&ms, 0.5),
        frame_ms_p95: percentile(&ms, 0.95),
        triangles_per_frame_median: percentile(
            &reports
                .iter()
                .map(|r| r.triangles as f64)
                .collect::<Vec<_>>(),
            0.5,
        ),
        cells_per_frame_median: percentile(
            &reports.iter().map(|r| r.drawn as f64).collect::<Vec<_>>(),
            0.5,
        ),
        gpu_bytes_max: reports
            .iter()
            .map(|r| r.gpu_bytes)
            .chain([warm.gpu_bytes])
            .max()
            .unwrap_or(0),
        gpu_budget_bytes: budget,
        load_stall_frames: reports
            .iter()
            .filter(|r| r.substituted + r.holes > 0)
            .count(),
        substituted_cells: reports.iter().map(|r| r.substituted).sum(),
        hole_cells: reports.iter().map(|r| r.holes).sum(),
        uploads: reports.iter().map(|r| r.uploads).sum(),
        warmup_ms: warm.frame_ms,
        geomorph: scene.options().geomorph.enabled,
        morphed_cells_per_frame_median: percentile(
            &reports.iter().map(|r| r.morphed as f64).collect::<Vec<_>>(),
            0.5,
        ),
    })
}
