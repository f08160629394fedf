//! PNG encoding cost of store textures: time and size per compression setting.
//!
//! Usage: cargo run --release --example png_bench -- PNG... [--runs N]
//!
//! Decodes each PNG once, then encodes it N times (default 5) with each setting of the
//! `image` crate's PNG encoder that `cliffmap` can use (`--png-compression`): fast
//! (fdeflate, adaptive filter: `image`'s default and cliffmap's), balanced (a middle zlib
//! level) and best. Prints the median milliseconds, MB/s of raw pixels and the file size
//! ratio to fast, per file and summed. All settings decode to the same pixels (checked).

use image::ImageEncoder;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use std::time::Instant;

#[path = "bench_util/mod.rs"]
mod bench_util;
use bench_util::median;

fn main() -> anyhow::Result<()> {
    let mut files = Vec::new();
    let mut runs = 5usize;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--runs" {
            runs = args
                .next()
                .ok_or_else(|| anyhow::anyhow!("--runs needs a value"))?
                .parse()?;
        } else {
            files.push(a);
        }
    }
    anyhow::ensure!(!files.is_empty(), "usage: png_bench PNG... [--runs N]");
    let settings = [
        ("fast", CompressionType::Fast, FilterType::Adaptive),
        ("balanced", CompressionType::Default, FilterType::Adaptive),
        ("best", CompressionType::Best, FilterType::Adaptive),
    ];
    let mut tot = vec![(0.0f64, 0usize); settings.len()];
    let mut raw_total = 0usize;
    println!(
        "| file | raw MB | {} |",
        settings
            .map(|s| format!("{} ms / MB/s / size ÷ fast", s.0))
            .join(" | ")
    );
    println!("|---|---|{}", "---|".repeat(settings.len()));
    for f in &files {
        let img = image::open(f)?.to_rgba8();
        let (w, h) = img.dimensions();
        let raw = img.as_raw().len();
        raw_total += raw;
        let mut row = Vec::new();
        let mut sizes = Vec::new();
        for (k, (_, c, flt)) in settings.iter().enumerate() {
            let mut ts = Vec::new();
            let mut out = Vec::new();
            for _ in 0..runs {
                out.clear();
                let t = Instant::now();
                PngEncoder::new_with_quality(&mut out, *c, *flt).write_image(
                    img.as_raw(),
                    w,
                    h,
                    image::ExtendedColorType::Rgba8,
                )?;
                ts.push(t.elapsed().as_secs_f64() * 1e3);
            }
            let back = image::load_from_memory(&out)?.to_rgba8();
            anyhow::ensure!(
                back.as_raw() == img.as_raw(),
                "{f}: setting {k} did not round-trip"
            );
            let ms = median(ts);
            tot[k].0 += ms;
            tot[k].1 += out.len();
            sizes.push(out.len());
            row.push((ms, raw as f64 / 1e3 / ms, out.len()));
        }
        let def = sizes[0] as f64;
        println!(
            "| {f} | {:.1} | {} |",
            raw as f64 / 1e6,
            row.iter()
                .map(|(ms, mbs, sz)| format!("{ms:.0} / {mbs:.0} / {:.2}", *sz as f64 / def))
                .collect::<Vec<_>>()
                .join(" | ")
        );
    }
    let def = tot[0].1 as f64;
    println!(
        "| all ({} files) | {:.1} | {} |",
        files.len(),
        raw_total as f64 / 1e6,
        tot.iter()
            .map(|(ms, sz)| format!(
                "{ms:.0} / {:.0} / {:.2}",
                raw_total as f64 / 1e3 / ms,
                *sz as f64 / def
            ))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    Ok(())
}
