//! API example: a cell store from a DEM and its ortho, then the steep cells reparameterized.
//!
//! ```sh
//! cargo run --release --example api_build_store -- [DEM.f32 ORTHO.png OUT_STORE]
//! ```
//! Without arguments it uses the Engabreen data beside the repository
//! (`../shared/data/real/engabreen/`: a raw f32 DEM of 507 × 590 samples at 3 m and an ortho
//! on the same grid) and writes `engabreen.store`. The same as `cliffmap build` +
//! `cliffmap reparam`, through the library.

use std::path::PathBuf;

use cliffmap::pipeline::{BuildRecipe, RECIPE_VERSION, build_from_recipe};
use cliffmap::{DemLoadOptions, ProgressSink, ReparamOptions, reparam_store};

fn main() -> Result<(), cliffmap::Error> {
    let data = PathBuf::from("../shared/data/real/engabreen");
    let mut args = std::env::args().skip(1);
    let dem = args
        .next()
        .map_or(data.join("engabreen_dem_3m_507x590.f32"), PathBuf::from);
    let ortho = args
        .next()
        .map_or(data.join("engabreen_ortho_3m_507x590.png"), PathBuf::from);
    let out = args
        .next()
        .map_or(PathBuf::from("engabreen.store"), PathBuf::from);

    // What `build` needs: the DEM and how to read it (a raw f32 grid has no header, so its
    // size, spacing and the world position of its north-west sample are given), the ortho
    // and how to place it, and the build options.
    let recipe = BuildRecipe {
        recipe_version: RECIPE_VERSION,
        dem,
        dem_load: DemLoadOptions {
            width: Some(507),
            height: Some(590),
            spacing: Some(3.0),
            origin: Some((445_302.17, 7_396_769.45)), // UTM 33N
            ..DemLoadOptions::default()
        },
        ortho: Some(ortho),
        ortho_same_grid: true, // one ortho pixel per DEM sample
        ortho_extent: None,
        ortho_nodata_colour: Some([0, 0, 0]), // black pixels hold no image
        max_error: 0.5,                       // metres, at the finest level
        cell_intervals: 64,
        cell_texels: 256,
        png_compression: Default::default(),
    };
    let manifest = build_from_recipe(&recipe, &out, ProgressSink::none(), false)?;
    println!(
        "built {} cells in {} levels into {}",
        manifest.cells.len(),
        manifest.quadtree.levels,
        out.display()
    );

    // Cells whose ortho texture is stretched (Rel_texel above 1.1) get their own chart.
    let store = reparam_store(&out, &ReparamOptions::default())?;
    let charts = store
        .manifest
        .cells
        .iter()
        .filter(|c| c.reparam.is_some())
        .count();
    println!("{charts} steep cells reparameterized");
    Ok(())
}
