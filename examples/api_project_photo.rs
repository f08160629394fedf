//! API example: ground photos with known cameras projected into a store's textures.
//!
//! ```sh
//! cargo run --release --example api_project_photo -- [STORE PHOTOS.json]
//! ```
//! Without arguments: `engabreen.store` (made by the `api_build_store` example) and
//! `fixtures/engabreen_photos.json` (the two Engabreen photos and their ImGRAFT camera).
//! The same as `cliffmap project`, through the library.

use std::path::PathBuf;

use cliffmap::photo::read_photo_list;
use cliffmap::{ProjectOptions, project_store};

fn main() -> Result<(), cliffmap::Error> {
    let mut args = std::env::args().skip(1);
    let store = args
        .next()
        .map_or(PathBuf::from("engabreen.store"), PathBuf::from);
    let list = args.next().map_or(
        PathBuf::from("fixtures/engabreen_photos.json"),
        PathBuf::from,
    );

    // Each photo decoded, its camera read, checked and fitted to the image's real size.
    let photos = read_photo_list(&list)?;
    let report = project_store(&store, &photos, &ProjectOptions::default())?;
    for p in &report.settings.photos {
        println!(
            "{}: {} pixels hit the terrain, {} texels took its colour",
            p.name, p.pixels_hit, p.texels_supplied
        );
    }
    println!("{} cells have a photo texture", report.cells_written);
    Ok(())
}
