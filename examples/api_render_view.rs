//! API example: a frame of a store rendered from a camera, to PNG.
//!
//! ```sh
//! cargo run --release --example api_render_view -- [STORE CAMERA.json OUT.png]
//! ```
//! Without arguments: `engabreen.store` seen from the camera of Engabreen's IMG_8902 (an
//! ImGRAFT camera file), at 1280 × 852 pixels, into `view.png`. Needs a GPU driver or Mesa's
//! software drivers. The same as `cliffmap render`, through the library.

use std::path::PathBuf;

use cliffmap::{SceneOptions, StoreRenderer, camera_from_json_file};

fn main() -> Result<(), cliffmap::Error> {
    let mut args = std::env::args().skip(1);
    let store = args
        .next()
        .map_or(PathBuf::from("engabreen.store"), PathBuf::from);
    let camera = args.next().map_or(
        PathBuf::from("../shared/data/real/engabreen/engabreen_camera_IMG_8902.json"),
        PathBuf::from,
    );
    let out = args.next().map_or(PathBuf::from("view.png"), PathBuf::from);

    // The camera for an image of 1280 × 852 (the photo's 4290 × 2856 scaled down), its lens
    // distortion included.
    let (w, h) = (1280, 852);
    let camera = camera_from_json_file(&camera, (w, h))?.resized(w, h);
    // Each cell's best texture (photo, else reparameterized, else ortho), cells chosen by a
    // screen-space error of 0.5 px.
    let mut view = StoreRenderer::open(&store, w, h, SceneOptions::default())?;
    let report = view.frame(&camera, true)?; // `true`: wait until every cell is loaded
    println!(
        "{} cells drawn ({} culled), {} triangles",
        report.drawn, report.culled, report.triangles
    );
    cliffmap::fsutil::write_png_atomic(&out, &view.read_rgba()?)?;
    println!("wrote {}", out.display());
    Ok(())
}
