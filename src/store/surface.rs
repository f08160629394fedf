//! Where a point lies against the store's terrain: the height of the finest TIN surface
//! under a world position ([`Store::surface_at`]), and where a camera stands against it
//! ([`CameraPlacement`]): every command that has a store and a camera checks it (a camera
//! below the surface sees the terrain's back faces, which cliffmap never textures).
//!
//! Takes the store and a world position or a [`CameraModel`] (store frame, f64); returns
//! plain data.

use crate::camera::CameraModel;
use crate::error::Result;
use crate::store::{CellRecord, Store};

/// The terrain surface under a world point.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Height of the finest TIN surface there (metres, the store's vertical datum).
    pub height: f64,
    /// That cell's measured vertical error against the DEM (metres): the DEM lies within
    /// this of `height`.
    pub max_error: f64,
    /// Id of the cell ("LEVEL-X-Y").
    pub cell: String,
}

impl Store {
    /// The finest cell surface under world `(x, y)`, or `None` outside every cell's surface
    /// (outside the DEM, or over a void). Reads the meshes of the cells whose bounding box
    /// holds the point, finest level first.
    pub fn surface_at(&self, x: f64, y: f64) -> Result<Option<SurfacePoint>> {
        let mut cells: Vec<&CellRecord> = self
            .manifest
            .cells
            .iter()
            .filter(|c| {
                (c.bbox_min[0]..=c.bbox_max[0]).contains(&x)
                    && (c.bbox_min[1]..=c.bbox_max[1]).contains(&y)
            })
            .collect();
        cells.sort_by_key(|c| std::cmp::Reverse(c.level));
        for rec in cells {
            let mesh = self.read_mesh(rec)?;
            let p = [x - rec.origin[0], y - rec.origin[1]];
            for t in mesh.surface() {
                let v = t.map(|i| mesh.positions.get(i as usize).copied());
                let [Some(a), Some(b), Some(c)] = v else {
                    continue;
                };
                if let Some(z) = height_in_triangle(p, [a, b, c]) {
                    return Ok(Some(SurfacePoint {
                        height: z + rec.origin[2],
                        max_error: rec.max_error.max(0.0),
                        cell: rec.id.clone(),
                    }));
                }
            }
        }
        Ok(None)
    }
}

/// The height at `p` (cell-local x, y) of triangle `t` if `p` lies in its xy projection
/// (edges included, to 1e-9 of the barycentric range).
fn height_in_triangle(p: [f64; 2], t: [[f32; 3]; 3]) -> Option<f64> {
    let [a, b, c] = t.map(|v| v.map(f64::from));
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if det.abs() < 1e-12 {
        return None;
    }
    let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
    let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
    let l0 = 1.0 - l1 - l2;
    let eps = -1e-9;
    (l0 >= eps && l1 >= eps && l2 >= eps).then(|| l0 * a[2] + l1 * b[2] + l2 * c[2])
}

/// Where a camera stands against a store's terrain.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPlacement {
    /// The camera centre (store frame).
    pub position: [f64; 3],
    /// The surface under it, `None` when it stands outside the terrain (beside the DEM, or
    /// over a void).
    pub ground: Option<SurfacePoint>,
    /// The store's terrain extent (world x, y of the DEM samples): min x, min y, max x, max y.
    pub terrain: [f64; 4],
}

impl CameraPlacement {
    /// Measures where `camera` stands against the terrain of `store`.
    pub fn of(store: &Store, camera: &CameraModel) -> Result<CameraPlacement> {
        let p = camera.position;
        let (g, d) = (&store.manifest.georef, &store.manifest.dem);
        let (x0, y0) = g.world(0.0, 0.0);
        let (x1, y1) = g.world((d.height - 1) as f64, (d.width - 1) as f64);
        Ok(CameraPlacement {
            position: p.to_array(),
            ground: store.surface_at(p.x, p.y)?,
            terrain: [x0.min(x1), y0.min(y1), x0.max(x1), y0.max(y1)],
        })
    }

    /// Height of the camera above the surface under it (negative: below), if over terrain.
    pub fn height_above_ground(&self) -> Option<f64> {
        self.ground.as_ref().map(|g| self.position[2] - g.height)
    }

    /// Whether the camera stands below the surface by more than the TIN's error there (so
    /// below the DEM too): it would see only the terrain's back faces.
    pub fn is_underground(&self) -> bool {
        match (&self.ground, self.height_above_ground()) {
            (Some(g), Some(dz)) => dz < -g.max_error,
            _ => false,
        }
    }

    /// Horizontal distance (metres) from the camera to the terrain extent (0 inside).
    pub fn distance_outside(&self) -> f64 {
        let [x0, y0, x1, y1] = self.terrain;
        let dx = (x0 - self.position[0]).max(self.position[0] - x1).max(0.0);
        let dy = (y0 - self.position[1]).max(self.position[1] - y1).max(0.0);
        dx.hypot(dy)
    }

    /// One sentence on where the camera stands, for messages: "3.2 m below the terrain
    /// surface at (x, y) (ground 812.40 m, camera 809.20 m)", "1.7 m above ...", or "outside
    /// the terrain, 250 m from its edge".
    pub fn describe(&self) -> String {
        let [x, y, z] = self.position;
        match (&self.ground, self.height_above_ground()) {
            (Some(g), Some(dz)) => format!(
                "{:.1} m {} the terrain surface at ({x:.2}, {y:.2}) (ground {:.2} m, camera \
                 {z:.2} m)",
                dz.abs(),
                if dz < 0.0 { "below" } else { "above" },
                g.height
            ),
            _ => {
                let d = self.distance_outside();
                if d > 0.0 {
                    format!(
                        "outside the terrain, {d:.0} m from its edge (camera at ({x:.2}, \
                         {y:.2}, {z:.2}))"
                    )
                } else {
                    format!("over a void of the terrain (camera at ({x:.2}, {y:.2}, {z:.2}))")
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_inside_a_triangle_and_none_outside() {
        let t = [[0.0, 0.0, 1.0], [2.0, 0.0, 3.0], [0.0, 2.0, 5.0]];
        assert_eq!(height_in_triangle([0.0, 0.0], t), Some(1.0));
        assert!((height_in_triangle([1.0, 0.5], t).unwrap() - 3.0).abs() < 1e-12);
        assert_eq!(height_in_triangle([1.5, 1.5], t), None);
        assert_eq!(height_in_triangle([-0.1, 0.5], t), None);
        // degenerate
        let flat = [[0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [2.0, 2.0, 1.0]];
        assert_eq!(height_in_triangle([1.0, 1.0], flat), None);
    }
}
