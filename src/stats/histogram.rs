//! The histogram of average texel stretch per cell (`rel_texel`), as a PNG.

use std::path::Path;

use plotters::prelude::*;

use crate::error::{Error, Result};
use crate::font::register_font;
use crate::stats::quantile_sorted;

/// Number of regular bins of the rel_texel histogram.
const BINS: usize = 40;

/// Binning of `rel_texel` values for the histogram plot (see [`rel_texel_bins`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RelTexelBins {
    /// Lower edge of the first bin.
    pub lo: f64,
    /// Upper edge of the last regular bin; larger values go to `overflow`.
    pub hi: f64,
    /// Cells per regular bin (equal widths `(hi - lo) / counts.len()`).
    pub counts: Vec<u64>,
    /// Cells with `rel_texel > hi`.
    pub overflow: u64,
}

/// Bins finite `rel_texels` into 40 equal bins on a linear scale from `min(1, smallest value)`
/// to `max(p99.5, threshold)` (at least 0.01 wide), plus an overflow bin for larger values.
pub fn rel_texel_bins(rel_texels: &[f64], threshold: f64) -> RelTexelBins {
    let mut v: Vec<f64> = rel_texels
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    v.sort_unstable_by(f64::total_cmp);
    let lo = v.first().map_or(1.0, |&m| m.min(1.0));
    let p995 = if v.is_empty() {
        lo
    } else {
        quantile_sorted(&v, 0.995)
    };
    let mut hi = p995.max(if threshold.is_finite() { threshold } else { lo });
    if hi - lo < 0.01 {
        hi = lo + 0.01;
    }
    let width = (hi - lo) / BINS as f64;
    let mut counts = vec![0u64; BINS];
    let mut overflow = 0;
    for &x in &v {
        if x > hi {
            overflow += 1;
        } else {
            let k = (((x - lo) / width).floor().max(0.0) as usize).min(BINS - 1);
            counts[k] += 1;
        }
    }
    RelTexelBins {
        lo,
        hi,
        counts,
        overflow,
    }
}

/// Plot size in pixels.
const SIZE: (u32, u32) = (1000, 600);

/// Writes the "histogram of average texel stretch per cell" to `path` as a 1000 x 600 RGB
/// PNG: x = `rel_texel` (linear bins up to p99.5, see [`rel_texel_bins`], plus a red-outlined
/// overflow bin), y = number of cells, a vertical line at `threshold`, title and axis
/// labels. The file is replaced atomically. Errors name `path`.
pub fn write_histogram_png(path: &Path, rel_texels: &[f64], threshold: f64) -> Result<()> {
    let fail = |msg: String| Error::io(path, std::io::Error::other(msg));
    register_font().map_err(fail)?;
    let bins = rel_texel_bins(rel_texels, threshold);
    let (w, h) = SIZE;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    draw(&mut buf, &bins, rel_texels.len(), threshold)
        .map_err(|e| fail(format!("drawing the histogram: {e}")))?;
    let img = image::RgbImage::from_raw(w, h, buf)
        .ok_or_else(|| fail("plot buffer has the wrong size".into()))?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| fail(format!("encoding PNG: {e}")))?;
    crate::fsutil::write_atomic(path, &png)
}

fn draw(
    buf: &mut [u8],
    bins: &RelTexelBins,
    n_cells: usize,
    threshold: f64,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(buf, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let width = (bins.hi - bins.lo) / bins.counts.len() as f64;
    let x_max = bins.hi + if bins.overflow > 0 { 2.0 * width } else { 0.0 };
    let y_max = bins
        .counts
        .iter()
        .copied()
        .chain([bins.overflow])
        .max()
        .unwrap_or(0)
        .max(1);
    let y_max = y_max + (y_max / 10).max(1);
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("Average texel stretch per cell ({n_cells} cells)"),
            ("sans-serif", 26),
        )
        .margin(20)
        .x_label_area_size(55)
        .y_label_area_size(70)
        .build_cartesian_2d(bins.lo..x_max, 0u64..y_max)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_desc("Rel_texel = TIN surface area / clipped base area (1 = no stretch)")
        .y_desc("number of cells")
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .draw()?;
    let bar = RGBColor(70, 110, 180);
    chart
        .draw_series(
            bins.counts
                .iter()
                .enumerate()
                .filter(|(_, c)| **c > 0)
                .map(|(k, &c)| {
                    let x0 = bins.lo + k as f64 * width;
                    Rectangle::new([(x0, 0), (x0 + width, c)], bar.filled())
                }),
        )?
        .label(format!("cells per bin (width {width:.3})"))
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], bar.filled()));
    if bins.overflow > 0 {
        let x0 = bins.hi + width;
        let over = RGBColor(200, 60, 60);
        chart
            .draw_series([Rectangle::new(
                [(x0, 0), (x0 + width, bins.overflow)],
                over.mix(0.5).filled(),
            )])?
            .label(format!(
                "overflow: {} cell(s) > {:.3} (p99.5)",
                bins.overflow, bins.hi
            ))
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 5), (x + 14, y + 5)], over.mix(0.5).filled())
            });
    }
    if threshold.is_finite() && threshold >= bins.lo && threshold <= x_max {
        chart
            .draw_series(LineSeries::new(
                [(threshold, 0), (threshold, y_max)],
                BLACK.stroke_width(2),
            ))?
            .label(format!("threshold {threshold}"))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 14, y)], BLACK.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_cover_values_and_overflow() {
        let mut v: Vec<f64> = (0..1000).map(|k| 1.0 + k as f64 * 0.001).collect();
        v.extend([50.0, 80.0]);
        let b = rel_texel_bins(&v, 1.2);
        assert_eq!(b.lo, 1.0);
        assert!(b.hi < 50.0 && b.hi > 1.9);
        assert_eq!(b.counts.len(), BINS);
        assert_eq!(b.counts.iter().sum::<u64>() + b.overflow, v.len() as u64);
        assert!(b.overflow >= 2);
        // threshold beyond the data stretches the range to include it
        let b = rel_texel_bins(&[1.0, 1.1], 3.0);
        assert_eq!((b.hi, b.overflow), (3.0, 0));
        let b = rel_texel_bins(&[], 1.5);
        assert_eq!(b.counts.iter().sum::<u64>(), 0);
    }

    #[test]
    fn histogram_png_is_written_and_decodes() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("hist.png");
        let v: Vec<f64> = (0..500)
            .map(|k| 1.0 + (k as f64 * 0.37).sin().abs() * (k % 7) as f64 * 0.2)
            .collect();
        write_histogram_png(&p, &v, 1.5).unwrap();
        let img = image::open(&p).unwrap();
        assert_eq!((img.width(), img.height()), SIZE);
        // something other than white was drawn (bars, text)
        let rgb = img.to_rgb8();
        let dark = rgb
            .pixels()
            .filter(|p| p.0.iter().all(|&c| c < 100))
            .count();
        assert!(dark > 1000, "{dark} dark pixels");
        // empty input still plots
        write_histogram_png(&p, &[], 1.5).unwrap();
        // a parent that is a file cannot hold the PNG: an error, not a panic
        std::fs::write(dir.path().join("afile"), b"x").unwrap();
        assert!(write_histogram_png(&dir.path().join("afile/h.png"), &v, 1.5).is_err());
    }
}
