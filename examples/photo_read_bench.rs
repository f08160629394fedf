//! What a reader pays for photo textures stored in blocks (docs/projection.md, "Photo
//! textures in blocks"): projects IMG_8902 onto a copy of the reparameterized Engabreen store
//! (STORE_DIR, as for `project_bench`), then, per photo cell, times
//! `Store::read_photo_texture` (decode the block atlases and the active texture, magnify it,
//! paste the blocks) against decoding the same whole texture and confidence map stored as
//! dense PNGs (encoded once beforehand with the store's default PNG compression). Both are
//! timed in the same run, interleaved cell by cell, RUNS times; prints the medians of the
//! totals and the bytes each layout keeps on disk.
//!
//! ```sh
//! cargo run --release --example photo_read_bench -- [STORE_DIR] [RUNS]
//! ```

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::time::Instant;

use bench_util::median;
use cliffmap::fsutil::{PngCompression, encode_png};
use cliffmap::pipeline::{ProjectOptions, project_store};
use cliffmap::store::Store;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let tmp = tempfile::tempdir()?;
    let dir = bench_util::store_arg(&args, tmp.path());
    let runs = bench_util::runs_arg(&args, 2, 3)?;
    if !dir.join("manifest.json").is_file() {
        bench_util::build_engabreen_reparam_store(&dir, "photo-read-bench")?;
    }
    let work = tmp.path().join("work");
    bench_util::copy_dir(&dir, &work)?;
    let photos = bench_util::img8902_photos(tmp.path())?;
    project_store(
        &work,
        &photos,
        &ProjectOptions {
            ..ProjectOptions::default()
        },
    )?;
    let store = Store::open(&work)?;
    let cells: Vec<_> = store
        .manifest
        .cells
        .iter()
        .filter(|c| c.photo.is_some())
        .collect();
    // the dense layout of the same textures, encoded once
    let mut dense = Vec::with_capacity(cells.len());
    let (mut dense_bytes, mut block_bytes, mut texels) = (0u64, 0u64, 0u64);
    for c in &cells {
        let Some(p) = &c.photo else { continue };
        let (t, conf) = store.read_photo_texture(c, p)?;
        let path = work.join(&p.texture.path);
        let a = encode_png(&path, &t, PngCompression::default())?;
        let b = encode_png(&path, &conf, PngCompression::default())?;
        dense_bytes += (a.len() + b.len()) as u64;
        block_bytes += p.texture.bytes + p.confidence.bytes;
        texels += p.texels as u64 * p.texels as u64;
        dense.push((a, b));
    }
    let (mut blocks_s, mut dense_s) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let (mut tb, mut td) = (0.0, 0.0);
        for (c, (a, b)) in cells.iter().zip(&dense) {
            let Some(p) = &c.photo else { continue };
            let t0 = Instant::now();
            let got = store.read_photo_texture(c, p)?;
            tb += t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let ta = image::load_from_memory_with_format(a, image::ImageFormat::Png)?.to_rgba8();
            let tc = image::load_from_memory_with_format(b, image::ImageFormat::Png)?.to_luma8();
            td += t0.elapsed().as_secs_f64();
            anyhow::ensure!(ta == got.0 && tc == got.1, "{}: layouts differ", c.id);
        }
        blocks_s.push(tb);
        dense_s.push(td);
    }
    println!(
        "Engabreen + IMG_8902: {} photo cells, {:.0} M texels, {} threads, {runs} runs\n",
        cells.len(),
        texels as f64 / 1e6,
        rayon::current_num_threads()
    );
    println!("| layout | read all photo cells, s (median) | × dense | files on disk, MB |");
    println!("|---|---|---|---|");
    let (mb, md) = (median(blocks_s), median(dense_s));
    println!(
        "| blocks (`read_photo_texture`) | {mb:.2} | {:.2} | {:.0} |",
        mb / md,
        block_bytes as f64 / 1e6
    );
    println!(
        "| dense PNG (decode) | {md:.2} | 1.00 | {:.0} |",
        dense_bytes as f64 / 1e6
    );
    Ok(())
}
