//! Benchmark of `cliffmap::resample`: speed and accuracy of the subtexel estimate
//! (N = 1, 2, 4, 8) and of bilinear-only lookup against the exact (polygon clipping) mode.
//!
//! Cases: steep patches of the Engabreen lidar DEM (65 x 65 samples, 3 m) textured from its
//! 3 m ortho, parameterized by arc length along the patch's mean uphill direction, plus the
//! orthographic chart of one patch; and a generated near-vertical ruled wall (arc length
//! along the wall profile, exact and area-preserving) over a 1-pixel chessboard and a
//! white-noise source, the hard cases. Timings: median of `--runs` (default 7) timings, each
//! the mean over calls repeated for at least 0.1 s, modes interleaved, on a 2-thread rayon
//! pool; Mtexels/s counts output texels (texels², including rasterization and fill).
//!
//! Run: `cargo run --release --example resample_bench -- [--runs N] [--plot docs/img/resampling.png]`
//! Data: `$CLIFFMAP_SHARED_DATA`, else `<crate>/../shared/data/real`, else `/work/shared/data/real`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use cliffmap::GridGeoref;
use cliffmap::resample::{
    ChartMesh, Fill, Mode, PixelMap, ResampleOptions, Resampled, Source, resample, resample_timed,
};
use image::{Rgba, RgbaImage};
use plotters::prelude::*;

fn data_dir() -> PathBuf {
    if let Ok(d) = std::env::var("CLIFFMAP_SHARED_DATA") {
        return PathBuf::from(d);
    }
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"));
    if p.exists() {
        p
    } else {
        PathBuf::from("/work/shared/data/real")
    }
}

struct Chart {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    uvs: Vec<[f64; 2]>,
}

impl Chart {
    fn mesh(&self) -> ChartMesh<'_> {
        ChartMesh {
            positions: &self.positions,
            triangles: &self.triangles,
            uvs: &self.uvs,
        }
    }
    fn grid(n: usize, f: impl Fn(usize, usize) -> ([f64; 3], [f64; 2])) -> Chart {
        let (mut positions, mut uvs, mut triangles) = (vec![], vec![], vec![]);
        for j in 0..=n {
            for i in 0..=n {
                let (p, uv) = f(i, j);
                positions.push(p);
                uvs.push(uv);
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Chart {
            positions,
            triangles,
            uvs,
        }
    }
}

/// A chart over an `n x n`-quad grid whose vertex (i, j) lies at `centre + a_i d + b_j e`
/// (d = unit direction, e = d rotated +90°, a_i = (i - n/2) step), heights from `z`,
/// parameterized by arc length along d per row (u, normalised by the longest row) and
/// b (v, down). Positions are relative to `centre`.
// indexed loops: each index serves more than one array or lookup
#[allow(clippy::needless_range_loop)]
fn arc_length_chart(
    n: usize,
    step: f64,
    dir: f64,
    z: impl Fn(f64, f64) -> f64,
    centre: [f64; 2],
) -> Chart {
    let (d, e) = ([dir.cos(), dir.sin()], [-dir.sin(), dir.cos()]);
    let h = n as f64 / 2.0;
    let at = |i: usize, j: usize| {
        let (a, b) = ((i as f64 - h) * step, (h - j as f64) * step);
        let (x, y) = (a * d[0] + b * e[0], a * d[1] + b * e[1]);
        [x, y, z(centre[0] + x, centre[1] + y)]
    };
    let mut arc = vec![vec![0.0; n + 1]; n + 1];
    for j in 0..=n {
        for i in 1..=n {
            let (p, q) = (at(i - 1, j), at(i, j));
            arc[j][i] = arc[j][i - 1]
                + ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt();
        }
    }
    let longest = arc.iter().map(|r| r[n]).fold(0.0, f64::max);
    Chart::grid(n, |i, j| {
        (at(i, j), [arc[j][i] / longest, j as f64 / n as f64])
    })
}

struct Dem {
    w: usize,
    h: usize,
    z: Vec<f32>,
    georef: GridGeoref,
}

impl Dem {
    fn bilinear(&self, x: f64, y: f64) -> f64 {
        let (r, c) = self.georef.grid(x, y);
        let (r, c) = (
            r.clamp(0.0, (self.h - 1) as f64),
            c.clamp(0.0, (self.w - 1) as f64),
        );
        let (r0, c0) = (
            (r.floor() as usize).min(self.h - 2),
            (c.floor() as usize).min(self.w - 2),
        );
        let (fr, fc) = (r - r0 as f64, c - c0 as f64);
        let z = |r: usize, c: usize| self.z[r * self.w + c] as f64;
        (1.0 - fr) * ((1.0 - fc) * z(r0, c0) + fc * z(r0, c0 + 1))
            + fr * ((1.0 - fc) * z(r0 + 1, c0) + fc * z(r0 + 1, c0 + 1))
    }
}

struct Case {
    name: String,
    chart: Chart,
    image: RgbaImage,
    to_pixel: PixelMap,
    texels: u32,
}

fn engabreen_cases() -> Result<Vec<Case>> {
    let dir = data_dir().join("engabreen");
    let (w, h) = (507usize, 590usize);
    let dem_path = dir.join("engabreen_dem_3m_507x590.f32");
    let bytes =
        std::fs::read(&dem_path).with_context(|| format!("reading {}", dem_path.display()))?;
    if bytes.len() != w * h * 4 {
        bail!(
            "{}: expected {} bytes, found {}",
            dem_path.display(),
            w * h * 4,
            bytes.len()
        );
    }
    let z: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let georef = GridGeoref::new(445302.17, 7396769.45, 3.0);
    let dem = Dem { w, h, z, georef };
    let ortho_path = dir.join("engabreen_ortho_3m_507x590.png");
    let mut ortho = image::open(&ortho_path)
        .with_context(|| format!("reading {}", ortho_path.display()))?
        .to_rgba8();
    // the black wedge has no image data
    for p in ortho.pixels_mut() {
        if p[0] == 0 && p[1] == 0 && p[2] == 0 {
            p[3] = 0;
        }
    }
    // mean slope of 65 x 65 windows; keep the steepest non-overlapping ones that stay inside
    // the image (with room for rotation) and over known ortho pixels
    let g = |r: usize, c: usize| {
        let zz = |r: usize, c: usize| dem.z[r * w + c] as f64;
        (
            (zz(r, c + 1) - zz(r, c - 1)) / 6.0,
            (zz(r - 1, c) - zz(r + 1, c)) / 6.0,
        ) // (dz/dx, dz/dy), y north
    };
    let m = 47;
    let mut cands = vec![];
    for r in (m..h - m).step_by(8) {
        for c in (m..w - m).step_by(8) {
            let (mut slope, mut gx, mut gy, mut dark) = (0.0, 0.0, 0.0, false);
            for rr in r - 32..=r + 32 {
                for cc in c - 32..=c + 32 {
                    let (a, b) = g(rr, cc);
                    slope += (a * a + b * b).sqrt().atan();
                    gx += a;
                    gy += b;
                }
            }
            for rr in r - m..=r + m {
                for cc in c - m..=c + m {
                    dark |= ortho.get_pixel(cc as u32, rr as u32)[3] == 0;
                }
            }
            if !dark {
                cands.push((slope / 4225.0, r, c, gy.atan2(gx)));
            }
        }
    }
    cands.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut picked: Vec<(f64, usize, usize, f64)> = vec![];
    for cand in cands {
        if picked
            .iter()
            .all(|p| p.1.abs_diff(cand.1).max(p.2.abs_diff(cand.2)) >= 65)
        {
            picked.push(cand);
        }
        if picked.len() == 3 {
            break;
        }
    }
    let mut cases = vec![];
    for (k, &(slope, r, c, dir)) in picked.iter().enumerate() {
        let (cx, cy) = georef.world(r as f64, c as f64);
        let chart = arc_length_chart(64, 3.0, dir, |x, y| dem.bilinear(x, y), [cx, cy]);
        cases.push(Case {
            name: format!(
                "engabreen wall {} (r{r} c{c}, mean slope {:.0}°)",
                k + 1,
                slope.to_degrees()
            ),
            chart,
            image: ortho.clone(),
            to_pixel: PixelMap::from_georef(&georef, [cx, cy]),
            texels: 128,
        });
        if k == 0 {
            // the orthographic chart of the same (unrotated) 65 x 65 cell
            let chart = Chart::grid(64, |i, j| {
                let (x, y) = ((i as f64 - 32.0) * 3.0, (32.0 - j as f64) * 3.0);
                (
                    [x, y, dem.bilinear(cx + x, cy + y)],
                    [i as f64 / 64.0, j as f64 / 64.0],
                )
            });
            cases.push(Case {
                name: format!("engabreen ortho chart (r{r} c{c})"),
                chart,
                image: ortho.clone(),
                to_pixel: PixelMap::from_georef(&georef, [cx, cy]),
                texels: 48,
            });
        }
    }
    Ok(cases)
}

fn generated_cases() -> Vec<Case> {
    let size = 256u32;
    let chess = RgbaImage::from_fn(size, size, |c, r| {
        let v = if (c + r) % 2 == 0 { 30 } else { 225 };
        Rgba([v, 255 - v, 128, 255])
    });
    let mut s = 0x2545f4914f6cdd1du64;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as u8
    };
    let noise = RgbaImage::from_fn(size, size, |_, _| Rgba([rnd(), rnd(), rnd(), 255]));
    // world = pixel frame: pixel (c, r) centre at (c + 0.5, size - r - 0.5)
    let to_pixel = PixelMap::from_georef(
        &GridGeoref::new(0.5, size as f64 - 0.5, 1.0),
        [128.0, 128.0],
    );
    let dir = 30f64.to_radians();
    // a ruled wall: 120 m high, near-vertical over a few metres, across direction `dir`
    let wall_z = move |x: f64, y: f64| {
        let a = (x - 128.0) * dir.cos() + (y - 128.0) * dir.sin();
        60.0 * (1.0 + (a / 3.0).tanh())
    };
    let mut cases = vec![];
    for (src, img) in [("chessboard 1 px", &chess), ("white noise", &noise)] {
        cases.push(Case {
            name: format!("generated wall, {src}"),
            chart: arc_length_chart(96, 1.8, dir, wall_z, [128.0, 128.0]),
            image: img.clone(),
            to_pixel,
            texels: 192,
        });
        cases.push(Case {
            name: format!("generated ortho chart, {src}"),
            chart: Chart::grid(4, |i, j| {
                (
                    [(i as f64 - 2.0) * 45.0, (2.0 - j as f64) * 45.0, 0.0],
                    [i as f64 / 4.0, j as f64 / 4.0],
                )
            }),
            image: img.clone(),
            to_pixel,
            texels: 128,
        });
    }
    cases
}

struct Row {
    case: usize,
    mode: Mode,
    /// whole `resample` call
    mtexels_s: f64,
    /// the per-texel kernel alone
    kernel_mtexels_s: f64,
    /// median milliseconds per call: prepare (maps, rasterization), kernel, fill
    phases_ms: [f64; 3],
    rmse: f64,
    max: f64,
    psnr: f64,
    fallbacks: usize,
    covered: usize,
}

fn compare(a: &Resampled, exact: &Resampled) -> (f64, f64) {
    let (mut s, mut n, mut mx) = (0.0, 0usize, 0.0f64);
    for (p, q) in a.image.pixels().zip(exact.image.pixels()) {
        if p[3] == 255 && q[3] == 255 {
            for c in 0..3 {
                let d = p[c] as f64 - q[c] as f64;
                s += d * d;
                mx = mx.max(d.abs());
                n += 1;
            }
        }
    }
    ((s / n.max(1) as f64).sqrt(), mx)
}

fn label(m: Mode) -> String {
    match m {
        Mode::Subtexel(n) => format!("subtexel N={n}"),
        Mode::Bilinear => "bilinear".into(),
        Mode::Exact => "exact".into(),
    }
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let runs: usize = arg("--runs")
        .map(|v| v.parse())
        .transpose()
        .context("--runs")?
        .unwrap_or(7)
        .max(1);
    let plot = arg("--plot");
    // --profile CASE MODE SECONDS: loop one mode (n1..n64, bilinear, exact) on the cases
    // whose name contains CASE, print nothing else (for `perf record`)
    let profile = match args.iter().position(|a| a == "--profile") {
        Some(i) => {
            let get = |k: usize| {
                args.get(i + k)
                    .cloned()
                    .context("--profile CASE MODE SECONDS")
            };
            let mode = match get(2)?.as_str() {
                "exact" => Mode::Exact,
                "bilinear" => Mode::Bilinear,
                m => Mode::Subtexel(
                    m.trim_start_matches('n')
                        .parse()
                        .context("--profile mode: n<N>, bilinear or exact")?,
                ),
            };
            Some((
                get(1)?,
                mode,
                get(3)?.parse::<f64>().context("--profile seconds")?,
            ))
        }
        None => None,
    };
    let threads: usize = arg("--threads")
        .map(|v| v.parse())
        .transpose()
        .context("--threads")?
        .unwrap_or(2)
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let mut cases = engabreen_cases()?;
    cases.extend(generated_cases());
    let modes = [
        Mode::Subtexel(1),
        Mode::Subtexel(2),
        Mode::Subtexel(4),
        Mode::Subtexel(8),
        Mode::Bilinear,
        Mode::Exact,
    ];
    let mut rows = vec![];
    for (ci, case) in cases.iter().enumerate() {
        let src = Source {
            image: &case.image,
            to_pixel: case.to_pixel,
        };
        let mesh = case.chart.mesh();
        let opts = |mode: Mode| ResampleOptions {
            mode,
            texels: case.texels,
            fill: Fill::AverageBorder,
            gutter_texels: 4,
        };
        // one timing = mean time per call over calls repeated for at least 0.1 s (whole call,
        // and each stage as timed inside the call); the modes are interleaved within each
        // repetition so load changes hit them alike
        let time_once = |mode: Mode| -> Result<[f64; 4]> {
            let o = opts(mode);
            let t = Instant::now();
            let mut calls = 0u32;
            let mut phases = [0.0; 3];
            while calls == 0 || t.elapsed().as_secs_f64() < 0.1 {
                let (_, tm) = pool.install(|| resample_timed(&mesh, &src, &o))?;
                phases[0] += tm.prepare.as_secs_f64();
                phases[1] += tm.kernel.as_secs_f64();
                phases[2] += tm.fill.as_secs_f64();
                calls += 1;
            }
            let c = calls as f64;
            Ok([
                t.elapsed().as_secs_f64() / c,
                phases[0] / c,
                phases[1] / c,
                phases[2] / c,
            ])
        };
        if let Some((case_filter, mode, secs)) = &profile {
            // a plain loop of one mode on the matching cases, for `perf record`
            if case.name.contains(case_filter.as_str()) {
                let t = Instant::now();
                let cpu0 = process_cpu_seconds();
                let mut calls = 0u32;
                let mut ph = [0.0; 3];
                while t.elapsed().as_secs_f64() < *secs {
                    let (_, tm) = pool.install(|| resample_timed(&mesh, &src, &opts(*mode)))?;
                    ph[0] += tm.prepare.as_secs_f64();
                    ph[1] += tm.kernel.as_secs_f64();
                    ph[2] += tm.fill.as_secs_f64();
                    calls += 1;
                }
                let cpu = process_cpu_seconds() - cpu0;
                let c = calls as f64;
                println!(
                    "{}: {} x {calls} calls, {:.3} ms CPU per call ({:.2} Mtexels per CPU \
                     second); wall ms per call: prepare {:.3} kernel {:.3} fill {:.3}",
                    case.name,
                    label(*mode),
                    1e3 * cpu / c,
                    (case.texels as f64).powi(2) * c / cpu / 1e6,
                    1e3 * ph[0] / c,
                    1e3 * ph[1] / c,
                    1e3 * ph[2] / c
                );
            }
            continue;
        }
        let mut times = vec![[vec![], vec![], vec![], vec![]]; modes.len()];
        for _ in 0..runs {
            for (k, &mode) in modes.iter().enumerate() {
                let t = time_once(mode)?;
                for p in 0..4 {
                    times[k][p].push(t[p]);
                }
            }
        }
        let exact = pool.install(|| resample(&mesh, &src, &opts(Mode::Exact)))?;
        for (k, &mode) in modes.iter().enumerate() {
            let r = pool.install(|| resample(&mesh, &src, &opts(mode)))?;
            let med = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let t = med(&mut times[k][0]);
            let phases_ms = [
                1e3 * med(&mut times[k][1]),
                1e3 * med(&mut times[k][2]),
                1e3 * med(&mut times[k][3]),
            ];
            let (rmse, max) = compare(&r, &exact);
            let psnr = if rmse > 0.0 {
                20.0 * (255.0 / rmse).log10()
            } else {
                f64::INFINITY
            };
            rows.push(Row {
                case: ci,
                mode,
                mtexels_s: (case.texels as f64).powi(2) / t / 1e6,
                kernel_mtexels_s: (case.texels as f64).powi(2) / (phases_ms[1] * 1e-3) / 1e6,
                phases_ms,
                rmse,
                max,
                psnr,
                fallbacks: r.stats.bilinear_fallbacks,
                covered: r.stats.covered_texels,
            });
        }
    }
    if profile.is_some() {
        return Ok(());
    }
    let exact_row = |case: usize| {
        rows.iter()
            .find(|r| r.case == case && r.mode == Mode::Exact)
    };
    println!(
        "| case | texels | mode | call Mtexels/s | call × exact | kernel Mtexels/s | kernel × exact \
         | prepare / kernel / fill ms | RMSE vs exact | max err | PSNR dB | fallbacks |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for row in &rows {
        let (ex, exk) =
            exact_row(row.case).map_or((f64::NAN, f64::NAN), |r| (r.mtexels_s, r.kernel_mtexels_s));
        let c = &cases[row.case];
        println!(
            "| {} | {}² | {} | {:.2} | {:.1} | {:.2} | {:.1} | {:.2} / {:.2} / {:.2} | {:.3} | {:.0} | {} | {:.1} % |",
            c.name,
            c.texels,
            label(row.mode),
            row.mtexels_s,
            row.mtexels_s / ex,
            row.kernel_mtexels_s,
            row.kernel_mtexels_s / exk,
            row.phases_ms[0],
            row.phases_ms[1],
            row.phases_ms[2],
            row.rmse,
            row.max,
            if row.psnr.is_finite() {
                format!("{:.1}", row.psnr)
            } else {
                "∞".into()
            },
            100.0 * row.fallbacks as f64 / row.covered.max(1) as f64
        );
    }
    // summary per mode: worst-case RMSE and median / minimum speed-up over exact
    println!("\n| mode | worst RMSE | call × exact: median | min | kernel × exact: median | min |");
    println!("|---|---|---|---|---|---|");
    for &mode in &modes[..5] {
        let sel: Vec<&Row> = rows.iter().filter(|r| r.mode == mode).collect();
        let ratios = |f: &dyn Fn(&Row) -> f64| {
            let mut v: Vec<f64> = sel
                .iter()
                .map(|r| f(r) / exact_row(r.case).map_or(f64::NAN, f))
                .collect();
            v.sort_by(f64::total_cmp);
            (v[v.len() / 2], v[0])
        };
        let (cm, cmin) = ratios(&|r| r.mtexels_s);
        let (km, kmin) = ratios(&|r| r.kernel_mtexels_s);
        let worst = sel.iter().map(|r| r.rmse).fold(0.0, f64::max);
        println!(
            "| {} | {:.3} | {:.1} | {:.1} | {:.1} | {:.1} |",
            label(mode),
            worst,
            cm,
            cmin,
            km,
            kmin
        );
    }
    if let Some(path) = plot {
        draw(&path, &cases, &rows)?;
        println!("\nplot written to {path}");
    }
    Ok(())
}

/// CPU time (user + system) of this process so far, in seconds, from /proc/self/stat
/// (clock ticks of 10 ms; NaN where unavailable).
fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // fields after the parenthesised command name; utime and stime are fields 14 and 15
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| {
        f.get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    (ticks(11) + ticks(12)) / 100.0
}

/// Registers a sans-serif font for plotters (the repo's assets/fonts/DejaVuSans.ttf, or the
/// system's DejaVu Sans).
fn register_font() -> Result<()> {
    let candidates = [
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/fonts/DejaVuSans.ttf"),
        "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    ];
    let Some(bytes) = candidates.iter().find_map(|p| std::fs::read(p).ok()) else {
        bail!("no DejaVuSans.ttf found in {candidates:?}");
    };
    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
        .map_err(|_| anyhow::anyhow!("invalid font file"))?;
    Ok(())
}

fn draw(path: &str, cases: &[Case], rows: &[Row]) -> Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1200, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(600);
    let ns = [1u32, 2, 4, 8];
    let series = |f: &dyn Fn(&Row) -> f64| -> Vec<(String, Vec<(f64, f64)>)> {
        (0..cases.len())
            .map(|ci| {
                let pts = ns
                    .iter()
                    .filter_map(|&n| {
                        rows.iter()
                            .find(|r| r.case == ci && r.mode == Mode::Subtexel(n))
                            .map(|r| (n as f64, f(r)))
                    })
                    .collect();
                (cases[ci].name.clone(), pts)
            })
            .collect()
    };
    let rmse = series(&|r| r.rmse.max(1e-3));
    let speed = series(&|r| {
        let ex = rows
            .iter()
            .find(|e| e.case == r.case && e.mode == Mode::Exact)
            .map_or(f64::NAN, |e| e.mtexels_s);
        r.mtexels_s / ex
    });
    let ymax = rmse
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .fold(1.0, f64::max)
        * 1.1;
    let mut ch = ChartBuilder::on(&left)
        .caption("RMSE vs exact (8-bit levels)", ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(35)
        .y_label_area_size(50)
        .build_cartesian_2d((0.8f64..9.5).log_scale(), 0.0..ymax)?;
    ch.configure_mesh()
        .x_desc("subtexels N per axis")
        .y_desc("RMSE")
        .draw()?;
    ch.draw_series(LineSeries::new(
        [(0.8, 2.55), (9.5, 2.55)],
        RED.stroke_width(1),
    ))?
    .label("1 % of range (2.55)")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], RED));
    for (k, (name, pts)) in rmse.iter().enumerate() {
        let col = Palette99::pick(k).to_rgba();
        ch.draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], col.stroke_width(2)));
        ch.draw_series(pts.iter().map(|&p| Circle::new(p, 3, col.filled())))?;
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()?;
    let smax = speed
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .fold(1.0, f64::max)
        * 1.2;
    let mut ch = ChartBuilder::on(&right)
        .caption("speed relative to exact (2 threads)", ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(35)
        .y_label_area_size(50)
        .build_cartesian_2d((0.8f64..9.5).log_scale(), (0.3f64..smax).log_scale())?;
    ch.configure_mesh()
        .x_desc("subtexels N per axis")
        .y_desc("× exact")
        .draw()?;
    ch.draw_series(LineSeries::new(
        [(0.8, 10.0), (9.5, 10.0)],
        RED.stroke_width(1),
    ))?;
    for (k, (_, pts)) in speed.iter().enumerate() {
        let col = Palette99::pick(k).to_rgba();
        ch.draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))?;
        ch.draw_series(pts.iter().map(|&p| Circle::new(p, 3, col.filled())))?;
    }
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()?;
    root.present()?;
    Ok(())
}
