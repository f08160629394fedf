//! Stage 1: the quadtree of error-bounded TIN cells.
//!
//! Data types: [`Quadtree`] and [`CellKey`] address cells; [`SampleRect`] is a cell's
//! clipped rectangle of DEM samples; [`Tin`] is one cell's simplified triangulation on DEM
//! sample positions, with its measured maximum vertical error against every full-resolution
//! sample of the cell; [`CellMesh`] is its renderable mesh in the cell-local f32 frame
//! ([`local_mesh`] converts a TIN, [`CellMesh::texcoord`] gives texture coordinates).
//! [`LevelBorders`] holds the simplified cell sides of one level, shared
//! by neighbouring cells so their TINs are crack-free. Per-cell images: [`ortho_texture`]
//! (RGBA colour + coverage) and [`normal_map`] (world-frame normals from the
//! full-resolution DEM) and [`relief_map`] (the DEM's height above the cell's TIN), all
//! covering the cell's [`nominal_extent`].
//!
//! Entry points: [`build_level`] (all cells of a level, parallel), [`build_tin`] (one
//! rectangle with a given border), [`build_dem_tin`] (one TIN for the whole DEM) and
//! [`measure_max_error`] (independent full-resolution check).

mod border;
mod extent;
mod face_heap;
mod halfedge;
mod lattice_tiles;
mod mesh;
pub mod normals;
mod quadtree;
mod raster;
pub mod relief;
pub mod relief_reach;
#[cfg(target_arch = "x86_64")]
mod scan_x4;
mod taps;
pub mod texture;
mod tin;

pub use border::{LevelBorders, simplify_rect_border};
pub use extent::{clipped_extent, nominal_extent};
pub use mesh::{CellMesh, LocalMesh, local_mesh};
pub use normals::normal_map;
pub use quadtree::{CellKey, Quadtree, SampleRect};
pub use relief::{ReliefMap, relief_map};
pub use relief_reach::relief_reach;
pub use texture::ortho_texture;
pub use tin::{build_dem_tin, build_level, build_tin, level_epsilon, measure_max_error};

/// The unsimplified grid triangulation of `rect` (a reference TIN, and the densest one a cell
/// can have) using every `stride`-th sample (plus the last row and
/// column): two triangles per quad, split NW–SE, counter-clockwise seen from above in world
/// coordinates (rows run south).
pub fn grid_tin(rect: SampleRect, stride: u32) -> Tin {
    let axis = |a: u32, b: u32| {
        let mut v: Vec<u32> = (a..b).step_by(stride as usize).collect();
        v.push(b);
        v
    };
    let (cols, rows) = (axis(rect.c0, rect.c1), axis(rect.r0, rect.r1));
    let nc = cols.len() as u32;
    let vertices = rows
        .iter()
        .flat_map(|&r| cols.iter().map(move |&c| [c, r]))
        .collect();
    let mut triangles = Vec::new();
    for j in 0..rows.len() as u32 - 1 {
        for i in 0..nc - 1 {
            let (nw, ne, sw, se) = (
                j * nc + i,
                j * nc + i + 1,
                (j + 1) * nc + i,
                (j + 1) * nc + i + 1,
            );
            triangles.push([nw, sw, se]);
            triangles.push([nw, se, ne]);
        }
    }
    Tin {
        vertices,
        triangles,
        max_error: 0.0,
    }
}

/// A cell's simplified TIN. Vertices are DEM sample indices (their heights come from the
/// DEM); triangles are counter-clockwise seen from above (x east, y north).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tin {
    /// `[col, row]` of each vertex in the full-resolution DEM.
    pub vertices: Vec<[u32; 2]>,
    /// Vertex indices, CCW seen from above in world coordinates.
    pub triangles: Vec<[u32; 3]>,
    /// Largest vertical distance from any full-resolution DEM sample of the cell to the TIN.
    pub max_error: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_tin_is_ccw_in_world() {
        let t = grid_tin(
            SampleRect {
                c0: 2,
                r0: 3,
                c1: 9,
                r1: 7,
            },
            2,
        );
        assert_eq!(t.vertices.len(), 5 * 3);
        assert_eq!(t.triangles.len(), 2 * 4 * 2);
        for tri in &t.triangles {
            // world (x, y) = (col, -row)
            let p = tri.map(|k| {
                let v = t.vertices[k as usize];
                (v[0] as f64, -(v[1] as f64))
            });
            let twice =
                (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0);
            assert!(twice > 0.0);
        }
    }
}
