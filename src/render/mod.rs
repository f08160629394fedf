//! The quadtree renderer over a cell store.
//!
//! Policy (plain Rust, no GPU): [`RenderCamera`] (f64 camera-relative matrices, reverse-Z),
//! [`Frustum`], LOD selection by screen-space error ([`select_cells`]), an LRU cache with a
//! byte budget ([`LruCache`]) and background loading with ancestor fallback ([`Streamer`],
//! [`resolve_draw_list`]), geomorphing towards parent cells ([`geomorph`]) and the pinhole view
//! of distorted cameras ([`distortion`]). GPU side: [`gpu`] (headless wgpu: cell uploads,
//! pipelines, offscreen frames, the distortion pass, PNG readback) and [`StoreRenderer`] (a store
//! with cache, loaders and frames); [`downsample_rgba`] reduces supersampled frames. The GPU
//! side needs the crate feature `render` (on by default); the policy compiles without it.

mod cache;
mod camera;
#[cfg(feature = "render")]
mod distort_pass;
pub mod distortion;
mod frustum;
pub mod geomorph;
mod lod;
mod overlay;
mod stream;
mod supersample;
#[cfg(feature = "render")]
mod target;

pub use cache::LruCache;
pub use camera::RenderCamera;
pub use distortion::{DistortedView, DistortionMode};
pub use frustum::Frustum;
pub use geomorph::GeomorphOptions;
pub use lod::{
    CellIndex, LodSelection, cell_error, distance_to_bbox, geometric_error, screen_space_error,
    select_cells, select_cells_with_margin,
};
pub use overlay::{
    NO_PHOTO_COLOUR, Overlay, heat_colour, share_colour, share_map, stretch_heatmap,
};
pub use stream::{DrawList, Streamer, resolve_draw_list};
pub use supersample::downsample_rgba;

pub mod accuracy;
pub use accuracy::percentile;
#[cfg(feature = "render")]
mod cell_data;
#[cfg(feature = "render")]
mod context;
#[cfg(feature = "render")]
pub mod gpu;
#[cfg(feature = "render")]
mod store_renderer;

#[cfg(feature = "render")]
pub use gpu::{
    CellData, CellDraw, FrameOptions, GpuCell, GpuContext, MorphData, TerrainRenderer, UvMode,
};
#[cfg(feature = "render")]
pub use store_renderer::{FrameReport, SceneOptions, StoreRenderer};
#[cfg(feature = "render")]
mod flight;
mod fly_camera;

pub use fly_camera::{FAST_FACTOR, FlyCamera, FlyInput, MAX_PITCH, adjust_sse};

#[cfg(feature = "render")]
pub use flight::{FlightKey, FlightPath, FlyReport, fly};
