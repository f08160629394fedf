//! Before/after figures of ground-photo projection, for docs/projection.md.
//!
//! `cargo run --release --example projection_figures -- STORE PHOTOS.json OUT_DIR [N]`
//!
//! STORE must already be built (and usually reparameterized). The example copies it twice,
//! projects PHOTOS.json into both copies (footprint reconstruction on and off), and writes
//! for the N finest-level cells with the most steep photo texels a strip
//! `OUT_DIR/{name}_cell_{id}.png`: active texture before | after | confidence | after
//! without reconstruction. It prints a table of the per-photo counts of both runs.

use std::path::{Path, PathBuf};

use cliffmap::fsutil::write_png_atomic;
use cliffmap::photo::{FootprintOptions, read_photo_list};
use cliffmap::pipeline::{ProjectOptions, project_store};
use cliffmap::store::Store;
use image::{Rgba, RgbaImage};

fn copy_dir(src: &Path, dst: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dst)?;
    for e in std::fs::read_dir(src)? {
        let e = e?;
        let to = dst.join(e.file_name());
        if e.file_type()?.is_dir() {
            copy_dir(&e.path(), &to)?
        } else {
            std::fs::copy(e.path(), &to).map(|_| ())?
        }
    }
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        anyhow::bail!("usage: projection_figures STORE PHOTOS.json OUT_DIR [N]");
    }
    let (store, list, out) = (
        PathBuf::from(&args[1]),
        PathBuf::from(&args[2]),
        PathBuf::from(&args[3]),
    );
    let n: usize = args.get(4).map_or(Ok(3), |s| s.parse())?;
    let name = store
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or("store")
        .to_string();
    let tmp = tempfile::tempdir()?;
    let (with, without) = (tmp.path().join("with"), tmp.path().join("without"));
    copy_dir(&store, &with)?;
    copy_dir(&store, &without)?;
    let photos = read_photo_list(&list)?;
    let opts = ProjectOptions {
        ..ProjectOptions::default()
    };
    let t0 = std::time::Instant::now();
    let a = project_store(&with, &photos, &opts)?;
    let wall = t0.elapsed();
    let no_rec = ProjectOptions {
        footprint: FootprintOptions {
            reconstruct: false,
            ..FootprintOptions::default()
        },
        ..opts
    };
    let b = project_store(&without, &photos, &no_rec)?;
    println!(
        "projection of {} photos: {:.1} s wall (2 cores, shared)",
        photos.len(),
        wall.as_secs_f64()
    );
    println!("| photo | run | pixels hit | texels written | silhouette rejected | reconstructed |");
    println!("|---|---|---|---|---|---|");
    for (run, r) in [("reconstruct", &a), ("no reconstruct", &b)] {
        for p in &r.settings.photos {
            println!(
                "| {} | {run} | {} | {} | {} | {} |",
                p.name,
                p.pixels_hit,
                p.texels_written,
                p.rejected_silhouette,
                p.reconstructed_footprints
            );
        }
    }
    let (sa, sb) = (Store::open(&with)?, Store::open(&without)?);
    let finest = sa.manifest.quadtree.levels - 1;
    let mut cells: Vec<_> = sa
        .manifest
        .cells
        .iter()
        .filter(|c| c.level == finest && c.photo.is_some())
        .collect();
    cells.sort_by_key(|c| std::cmp::Reverse(c.photo.as_ref().map_or(0, |p| p.steep_photo_texels)));
    std::fs::create_dir_all(&out)?;
    for rec in cells.into_iter().take(n) {
        let Some(photo) = &rec.photo else { continue };
        let before = sa.read_active_texture(rec)?;
        let (after, conf) = sa.read_photo_texture(rec, photo)?;
        let other = sb.cell(&rec.id)?;
        let after_b = match &other.photo {
            Some(p) => sb.read_photo_texture(other, p)?.0,
            None => sb.read_active_texture(other)?,
        };
        let t = before.width();
        let gap = 4;
        let mut strip = RgbaImage::from_pixel(4 * t + 3 * gap, t, Rgba([255, 255, 255, 255]));
        for (k, img) in [
            before,
            after,
            RgbaImage::from_fn(t, t, |x, y| {
                let v = conf.get_pixel(x, y)[0];
                Rgba([v, v, v, 255])
            }),
            after_b,
        ]
        .iter()
        .enumerate()
        {
            for (x, y, p) in img.enumerate_pixels() {
                strip.put_pixel(k as u32 * (t + gap) + x, y, Rgba([p[0], p[1], p[2], 255]));
            }
        }
        let path = out.join(format!("{name}_cell_{}.png", rec.id));
        write_png_atomic(&path, &strip)?;
        println!(
            "wrote {} ({} steep photo texels of {})",
            path.display(),
            photo.steep_photo_texels,
            photo.steep_texels
        );
    }
    Ok(())
}
