//! Stage 1: the quadtree of error-bounded TIN cells.
//!
//! Data types: [`Quadtree`] and [`CellKey`] address cells; [`SampleRect`] is a cell's
//! clipped rectangle of DEM samples; [`Tin`] is one cell's simplified triangulation on DEM
//! sample positions, with its measured maximum vertical error against every full-resolution
//! sample of the cell. [`LevelBorders`] holds the simplified cell sides of one level, shared
//! by neighbouring cells so their TINs are crack-free. Per-cell images: [`ortho_texture`]
//! (RGBA colour + coverage) and [`normal_map`] (world-frame normals from the
//! full-resolution DEM), both covering the cell's [`nominal_extent`].
//!
//! Entry points: [`build_level`] (all cells of a level, parallel), [`build_tin`] (one
//! rectangle with a given border), [`build_dem_tin`] (one TIN for the whole DEM) and
//! [`measure_max_error`] (independent full-resolution check).

mod border;
mod extent;
mod face_heap;
pub mod normals;
mod quadtree;
mod raster;
mod taps;
pub mod texture;
mod tiles;
mod tin;

pub use border::{LevelBorders, simplify_rect_border};
pub use extent::{clipped_extent, nominal_extent};
pub use normals::normal_map;
pub use quadtree::{CellKey, Quadtree, SampleRect};
pub use texture::ortho_texture;
pub use tin::{build_dem_tin, build_level, build_tin, level_epsilon, measure_max_error};

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
