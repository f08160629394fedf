//! A cell's renderable mesh ([`CellMesh`]) in the cell-local f32 frame, its texture
//! coordinates, and the conversion from a [`Tin`] on DEM samples ([`local_mesh`]), with
//! skirts along the cell border. The store writes it as a `.mesh` file
//! (`crate::store`'s format).

use crate::cells::{SampleRect, Tin};
use crate::dem::Dem;
use crate::georef::WorldRect;

/// One cell's renderable mesh in its cell-local f32 frame. The first
/// `surface_vertices` / `surface_triangles` are the terrain surface; the rest is skirt.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellMesh {
    /// Cell-local positions in metres (world minus the cell origin).
    pub positions: Vec<[f32; 3]>,
    /// Texture coordinates in \[0,1\]² (u east, v south); `None` = orthographic (derived from x, y).
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangles, CCW seen from above (skirts: from outside the cell).
    pub triangles: Vec<[u32; 3]>,
    /// Number of leading vertices that belong to the surface.
    pub surface_vertices: u32,
    /// Number of leading triangles that belong to the surface.
    pub surface_triangles: u32,
}

impl CellMesh {
    /// The surface triangles (skirt excluded).
    pub fn surface(&self) -> &[[u32; 3]] {
        &self.triangles[..self.surface_triangles as usize]
    }

    /// Texture coordinate of vertex `i`: the stored UV, or for orthographic meshes (no
    /// UVs) the position mapped over the cell's nominal square `extent` (u east, v south,
    /// both in \[0,1\] inside the cell); `origin` is the world origin of the cell-local frame.
    pub fn texcoord(&self, i: usize, origin: [f64; 3], extent: &WorldRect) -> [f32; 2] {
        if let Some(uvs) = &self.uvs {
            return uvs[i];
        }
        let p = self.positions[i];
        let x = p[0] as f64 + origin[0];
        let y = p[1] as f64 + origin[1];
        [
            ((x - extent.min_x) / extent.width()) as f32,
            ((extent.max_y - y) / extent.height()) as f32,
        ]
    }

    /// [`CellMesh::texcoord`] of every surface vertex.
    pub fn surface_texcoords(&self, origin: [f64; 3], extent: &WorldRect) -> Vec<[f32; 2]> {
        let n = (self.surface_vertices as usize).min(self.positions.len());
        (0..n).map(|i| self.texcoord(i, origin, extent)).collect()
    }
}

/// A cell's mesh together with the f64 facts the manifest records.
pub struct LocalMesh {
    /// The mesh (positions relative to `origin`).
    pub mesh: CellMesh,
    /// World origin of the local frame.
    pub origin: [f64; 3],
    /// World bounding box of the surface.
    pub bbox_min: [f64; 3],
    /// World bounding box of the surface.
    pub bbox_max: [f64; 3],
}

/// Converts `tin` (vertices on DEM samples of `rect`) to cell-local f32 coordinates around
/// the rect's centre and the mid height, and appends a skirt of depth `skirt_depth`: every
/// border edge gets a vertical flange facing outwards, so cracks against neighbours of
/// another level are hidden.
pub fn local_mesh(dem: &Dem, rect: SampleRect, tin: &Tin, skirt_depth: f64) -> LocalMesh {
    let g = &dem.georef;
    let world: Vec<[f64; 3]> = tin
        .vertices
        .iter()
        .map(|&[c, r]| {
            let (x, y) = g.world(r as f64, c as f64);
            [x, y, dem.at(r as usize, c as usize) as f64]
        })
        .collect();
    let mut bmin = [f64::INFINITY; 3];
    let mut bmax = [f64::NEG_INFINITY; 3];
    for p in &world {
        for k in 0..3 {
            bmin[k] = bmin[k].min(p[k]);
            bmax[k] = bmax[k].max(p[k]);
        }
    }
    let (cx, cy) = g.world(
        (rect.r0 + rect.r1) as f64 / 2.0,
        (rect.c0 + rect.c1) as f64 / 2.0,
    );
    let origin = [cx, cy, ((bmin[2] + bmax[2]) / 2.0).round()];
    let mut positions: Vec<[f32; 3]> = world
        .iter()
        .map(|p| {
            [
                (p[0] - origin[0]) as f32,
                (p[1] - origin[1]) as f32,
                (p[2] - origin[2]) as f32,
            ]
        })
        .collect();
    let mut triangles = tin.triangles.clone();
    let n_surface = positions.len() as u32;
    let n_surface_tris = triangles.len() as u32;
    // Border edges: used by exactly one triangle; in CCW triangles they run with the outside on the right.
    let mut edges: Vec<(u32, u32)> = tin
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    let mut undirected: Vec<(u32, u32)> =
        edges.iter().map(|&(a, b)| (a.min(b), a.max(b))).collect();
    undirected.sort_unstable();
    edges.retain(|&(a, b)| {
        let k = (a.min(b), a.max(b));
        let lo = undirected.partition_point(|e| *e < k);
        undirected.get(lo + 1) != Some(&k)
    });
    edges.sort_unstable();
    let mut lowered = vec![u32::MAX; positions.len()];
    let drop = skirt_depth as f32;
    let mut low = |v: u32, positions: &mut Vec<[f32; 3]>| {
        if lowered[v as usize] == u32::MAX {
            let p = positions[v as usize];
            lowered[v as usize] = positions.len() as u32;
            positions.push([p[0], p[1], p[2] - drop]);
        }
        lowered[v as usize]
    };
    for (a, b) in edges {
        let (la, lb) = (low(a, &mut positions), low(b, &mut positions));
        triangles.push([a, la, b]);
        triangles.push([b, la, lb]);
    }
    LocalMesh {
        mesh: CellMesh {
            positions,
            uvs: None,
            triangles,
            surface_vertices: n_surface,
            surface_triangles: n_surface_tris,
        },
        origin,
        bbox_min: bmin,
        bbox_max: bmax,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::georef::GridGeoref;

    #[test]
    fn utm_scale_local_frame_keeps_precision_and_skirts_face_out() {
        // A 3x3 DEM at UTM coordinates, two triangles over the corners (CCW seen from above).
        let g = GridGeoref::new(512_345.678, 7_012_345.678, 0.5);
        let dem = Dem::from_heights(3, 3, vec![2000.25; 9], g).unwrap();
        let rect = SampleRect {
            c0: 0,
            r0: 0,
            c1: 2,
            r1: 2,
        };
        // vertices: 0 = NW (0,0), 1 = NE (2,0), 2 = SW (0,2), 3 = SE (2,2)
        let tin = Tin {
            vertices: vec![[0, 0], [2, 0], [0, 2], [2, 2]],
            triangles: vec![[0, 2, 3], [0, 3, 1]],
            max_error: 0.0,
        };
        let lm = local_mesh(&dem, rect, &tin, 3.0);
        let m = &lm.mesh;
        assert_eq!(m.surface_vertices, 4);
        assert_eq!(m.positions.len(), 8);
        assert_eq!(m.triangles.len(), 2 + 8);
        for (i, &[c, r]) in tin.vertices.iter().enumerate() {
            let (x, y) = g.world(r as f64, c as f64);
            let p = m.positions[i];
            // Reconstructed world position within 1e-6 m although x ~ 5e5, y ~ 7e6.
            assert!((p[0] as f64 + lm.origin[0] - x).abs() < 1e-6);
            assert!((p[1] as f64 + lm.origin[1] - y).abs() < 1e-6);
            assert!((p[2] as f64 + lm.origin[2] - 2000.25).abs() < 1e-6);
        }
        // Every skirt triangle's normal points away from the cell centre.
        for t in &m.triangles[2..] {
            let [a, b, c] = t.map(|i| glam::Vec3::from(m.positions[i as usize]));
            let n = (b - a).cross(c - a);
            let centre = (a + b + c) / 3.0;
            assert!(
                n.z.abs() < 1e-6 && n.x * centre.x + n.y * centre.y > 0.0,
                "{t:?} normal {n}"
            );
        }
    }
}
