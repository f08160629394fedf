//! Splatting throughput: footprints per second deposited by `photo::PhotoAccum::add_all`
//! (one thread, one 256² cell) for footprints of different sizes relative to a texel, with
//! the bilinear-only deposit of the same footprints (centre point, collapsed path) as the
//! peer measured in the same run. Prints three Markdown tables (medians of 5 runs): square
//! footprints of a given side, long thin oblique ones (foreshortened wall pixels in the
//! enlarged photo textures, the common case of a real projection), each footprint on its
//! own, and the same shapes as a pixel mesh whose neighbours share corners (what the strip
//! splatter of `photo/strip.rs` takes in blocks).
//!
//! Run: `cargo run --release --example splat_bench [mesh]` (`mesh`: the third table only)

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::time::Instant;

use cliffmap::photo::{ColourTransform, ConfidenceParams, PhotoAccum, PixelFootprint};
use image::RgbImage;

/// A grid of `n × n` slightly rotated and sheared pixel footprints of side `s` texels,
/// starting at texel (1, 1) of a 256² texture (wrapped to stay inside).
fn footprints(n: u32, s: f32, collapse: bool) -> Vec<PixelFootprint> {
    footprints_shaped(n, [s * 0.98, s * 0.17], [-s * 0.12, s * 1.01], collapse)
}

/// Footprints of sides `short × long` texels, the long side at `angle_deg` from the texel
/// rows (the long, thin, oblique footprints of foreshortened wall pixels in enlarged photo
/// textures), otherwise as [`footprints`].
fn thin_footprints(
    n: u32,
    short: f32,
    long: f32,
    angle_deg: f32,
    collapse: bool,
) -> Vec<PixelFootprint> {
    let (sin, cos) = angle_deg.to_radians().sin_cos();
    footprints_shaped(
        n,
        [long * cos, long * sin],
        [-short * sin, short * cos],
        collapse,
    )
}

/// A grid of `n × n` footprints with sides `a` and `b` (texels), each starting where the
/// lattice `c·a + r·b` puts it, wrapped into a 256² texture from texel (1, 1).
fn footprints_shaped(n: u32, a: [f32; 2], b: [f32; 2], collapse: bool) -> Vec<PixelFootprint> {
    let span = 250.0;
    (0..n)
        .flat_map(|r| (0..n).map(move |c| (c, r)))
        .map(|(c, r)| {
            let o = [
                1.0 + (c as f32 * a[0] + r as f32 * b[0]).rem_euclid(span),
                1.0 + (c as f32 * a[1] + r as f32 * b[1]).rem_euclid(span),
            ];
            // shrunk below `MIN_SPLAT_AREA` (even the 4-texel ones: 1.6e-7 texel²)
            let (a, b) = if collapse {
                (a.map(|v| v * 1e-4), b.map(|v| v * 1e-4))
            } else {
                (a, b)
            };
            let corners = [
                o,
                [o[0] + a[0], o[1] + a[1]],
                [o[0] + a[0] + b[0], o[1] + a[1] + b[1]],
                [o[0] + b[0], o[1] + b[1]],
            ];
            PixelFootprint {
                cell: 0,
                pixel: [c, r],
                corners,
                cos_view: 0.9,
                distance: 100.0,
                reconstructed: 0,
            }
        })
        .collect()
}

/// A grid of `n × n` pixel footprints whose corners are shared with their neighbours (the
/// corners of a sheared lattice of sides `a` and `b`, as a photo's pixel mesh gives them):
/// tiles of 24 × 16 pixels, each placed inside a 256² texture, footprints in row-major
/// order of the whole grid, as a cell receives them. What the strip splatter
/// (`photo/strip.rs`) takes in blocks.
fn mesh_footprints(n: u32, a: [f32; 2], b: [f32; 2]) -> Vec<PixelFootprint> {
    const TW: u32 = 24;
    const TH: u32 = 16;
    // the tile's extent and its lowest corner relative to its origin, per axis
    let ext = |k: usize| TW as f32 * a[k].abs() + TH as f32 * b[k].abs();
    let low = |k: usize| TW as f32 * a[k].min(0.0) + TH as f32 * b[k].min(0.0);
    (0..n)
        .flat_map(|r| (0..n).map(move |c| (c, r)))
        .map(|(c, r)| {
            // (the lattice restarts every tile so that it stays inside the texture; the
            // tile's place moves with the tile)
            let (tc, tr) = ((c / TW) as f32, (r / TH) as f32);
            let place = [tc * 37.0 + tr * 11.0, tr * 29.0 + tc * 7.0];
            let origin: [f32; 2] = std::array::from_fn(|k| {
                1.0 + place[k].rem_euclid((254.0 - ext(k)).max(1.0)) - low(k)
            });
            let (i, j) = ((c % TW) as f32, (r % TH) as f32);
            let p = |i: f32, j: f32| {
                [
                    origin[0] + i * a[0] + j * b[0],
                    origin[1] + i * a[1] + j * b[1],
                ]
            };
            PixelFootprint {
                cell: 0,
                pixel: [c, r],
                corners: [p(i, j), p(i + 1.0, j), p(i + 1.0, j + 1.0), p(i, j + 1.0)],
                cos_view: 0.9,
                distance: 100.0,
                reconstructed: 0,
            }
        })
        .collect()
}

fn main() {
    let n = 1000u32; // 1 Mpixel per run
    let img = RgbImage::from_fn(n, n, |x, y| {
        image::Rgb([(x % 251) as u8, (y % 241) as u8, ((x ^ y) % 256) as u8])
    });
    let params = ConfidenceParams::default();
    if std::env::args().nth(1).as_deref() == Some("mesh") {
        mesh_table(n, &img, &params);
        return;
    }
    println!(
        "| footprint side (texels) | exact splat, Mfootprints/s | bilinear peer, Mfootprints/s | ratio |"
    );
    println!("|---|---|---|---|");
    for s in [0.1f32, 0.35, 0.7, 1.5, 4.0, 8.0, 16.0] {
        let time = |collapse: bool| throughput(&footprints(n, s, collapse), &img, &params);
        let (exact, bil) = (time(false), time(true));
        println!("| {s} | {exact:.2} | {bil:.2} | {:.2} |", bil / exact);
    }
    println!();
    println!(
        "| thin footprint, short × long side (texels) at angle | exact splat, Mfootprints/s | bilinear peer, Mfootprints/s | ratio |"
    );
    println!("|---|---|---|---|");
    for (short, long, angle) in [
        (0.8f32, 2.5f32, 35.0f32),
        (1.0, 3.0, 35.0),
        (1.2, 5.0, 25.0),
        (2.0, 8.0, 15.0),
    ] {
        let (exact, bil) = (
            throughput(
                &thin_footprints(n, short, long, angle, false),
                &img,
                &params,
            ),
            throughput(&thin_footprints(n, short, long, angle, true), &img, &params),
        );
        println!(
            "| {short} × {long} at {angle}° | {exact:.2} | {bil:.2} | {:.2} |",
            bil / exact
        );
    }
    mesh_table(n, &img, &params);
}

/// Footprints of neighbouring pixels (corners shared both ways, tiles of 24 × 16) at the thin
/// shapes above.
fn mesh_table(n: u32, img: &RgbImage, params: &ConfidenceParams) {
    println!();
    println!(
        "| pixel mesh (shared corners), short × long side (texels) at angle | Mfootprints/s |"
    );
    println!("|---|---|");
    for (short, long, angle) in [
        (0.7f32, 0.7f32, 0.0f32),
        (0.8, 2.5, 35.0),
        (1.2, 5.0, 25.0),
        (2.0, 8.0, 15.0),
    ] {
        let (sin, cos) = angle.to_radians().sin_cos();
        let fps = mesh_footprints(n, [short * cos, short * sin], [-long * sin, long * cos]);
        println!(
            "| {short} × {long} at {angle}° | {:.2} |",
            throughput(&fps, img, params)
        );
    }
}

/// Median over 5 runs of footprints deposited per second (millions) into a fresh 256² cell.
fn throughput(fps: &[PixelFootprint], img: &RgbImage, params: &ConfidenceParams) -> f64 {
    let runs: Vec<f64> = (0..5)
        .map(|_| {
            let mut acc = PhotoAccum::new(256);
            let t = Instant::now();
            acc.add_all(fps, img, [1000.0; 2], &ColourTransform::IDENTITY, params);
            std::hint::black_box(&acc);
            fps.len() as f64 / t.elapsed().as_secs_f64() / 1e6
        })
        .collect();
    bench_util::median(runs)
}
