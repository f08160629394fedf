//! Benchmark of `cliffmap::parameterize` on synthetic and real (Engabreen) terrain cells.
//!
//! Usage: cargo run --release --example param_bench -- [OUT_DIR] [--quick]
//!
//! For every cell and configuration (θ, relax tolerance, sweep cap) prints the median
//! time and the chart metrics; writes each cell as OBJ (v, vt of the default
//! configuration, f) into OUT_DIR/cells and all results into OUT_DIR/ours.json, which
//! benches/peers/param_libigl.py reads to compare with libigl (SLIM, ARAP, LSCM).

use cliffmap::param::degener_energy;
use cliffmap::{ParamMesh, ParamOptions, chart_metrics, parameterize};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[path = "bench_util/mod.rs"]
mod bench_util;
#[path = "../tests/param_util/mod.rs"]
mod param_util;
use bench_util::{median, shared_data, write_obj};

/// An n x n grid with `spacing` and heights z(r, c) (the tests' triangulation).
fn grid(n: usize, spacing: f64, z: impl Fn(usize, usize) -> f64) -> ParamMesh {
    let xs: Vec<f64> = (0..n).map(|i| i as f64 * spacing).collect();
    param_util::grid_mesh(&xs, &xs, z, [0.0; 3])
}

/// Deterministic value noise (hash of lattice points), for the fractal hills.
fn hash(ix: i64, iy: i64, oct: u32) -> f64 {
    let mut h = (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (iy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (oct as u64) << 7;
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

fn value_noise(x: f64, y: f64, oct: u32) -> f64 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let s = |t: f64| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let (i, j) = (x0 as i64, y0 as i64);
    let a = hash(i, j, oct) * (1.0 - sx) + hash(i + 1, j, oct) * sx;
    let b = hash(i, j + 1, oct) * (1.0 - sx) + hash(i + 1, j + 1, oct) * sx;
    a * (1.0 - sy) + b * sy
}

/// Synthetic cells on an n x n grid with 3 m spacing.
fn synthetic(n: usize) -> Vec<(String, ParamMesh)> {
    let sp = 3.0;
    let w = (n - 1) as f64 * sp;
    let t80 = 80f64.to_radians().tan();
    let t89 = 89f64.to_radians().tan();
    let mid = (n - 1) / 2;
    let wall_w = (n - 1) / 8;
    let wall = grid(n, sp, move |_, c| {
        let c0 = mid - wall_w / 2;
        t80 * sp * (c.saturating_sub(c0).min(wall_w)) as f64
    });
    let (lo, hi) = (n / 3, n - 1 - n / 3);
    let plateau = grid(n, sp, move |r, c| {
        if (lo..=hi).contains(&r) && (lo..=hi).contains(&c) {
            t89 * sp
        } else {
            0.0
        }
    });
    let canyon = grid(n, sp, move |r, c| {
        // A meandering canyon, 75-85° walls, 0.4 of the cell deep.
        let x = c as f64 * sp;
        let y = r as f64 * sp;
        let centre = 0.5 * w + 0.12 * w * (y / w * 6.0).sin();
        let d = (x - centre).abs();
        let floor = 0.06 * w;
        let depth = 0.4 * w;
        let slope = 80f64.to_radians().tan() * (1.0 + 0.3 * (y / w * 11.0).cos()).min(1.2);
        -(depth - (d - floor).max(0.0) * slope).max(0.0)
    });
    let hills = grid(n, sp, move |r, c| {
        let (x, y) = (c as f64 / (n - 1) as f64, r as f64 / (n - 1) as f64);
        let mut h = 0.0;
        let mut amp = 0.35 * w;
        let mut f = 2.0;
        for o in 0..6 {
            h += amp * value_noise(x * f, y * f, o);
            amp *= 0.55;
            f *= 2.0;
        }
        h
    });
    vec![
        (format!("wall80_{n}"), wall),
        (format!("box89_{n}"), plateau),
        (format!("canyon_{n}"), canyon),
        (format!("hills_{n}"), hills),
    ]
}

/// The `count` steepest non-overlapping n x n patches of the Engabreen DEM (by mean slope).
fn engabreen(n: usize, count: usize) -> anyhow::Result<Vec<(String, ParamMesh)>> {
    let path = shared_data("engabreen/engabreen_dem_3m_507x590.f32");
    let bytes = std::fs::read(&path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let (cols, rows) = (507usize, 590usize);
    anyhow::ensure!(
        bytes.len() == cols * rows * 4,
        "{}: expected {} bytes",
        path.display(),
        cols * rows * 4
    );
    let z: Vec<f64> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
        .collect();
    let sp = 3.0;
    // Slope magnitude per sample (central differences).
    let mut slope = vec![0.0; cols * rows];
    for r in 1..rows - 1 {
        for c in 1..cols - 1 {
            let gx = (z[r * cols + c + 1] - z[r * cols + c - 1]) / (2.0 * sp);
            let gy = (z[(r + 1) * cols + c] - z[(r - 1) * cols + c]) / (2.0 * sp);
            slope[r * cols + c] = (gx * gx + gy * gy).sqrt().atan().to_degrees();
        }
    }
    let mut cands = Vec::new();
    let step = 8;
    for r0 in (0..rows - n).step_by(step) {
        for c0 in (0..cols - n).step_by(step) {
            let mut s = 0.0;
            for r in r0..r0 + n {
                for c in c0..c0 + n {
                    s += slope[r * cols + c];
                }
            }
            cands.push((s / (n * n) as f64, r0, c0));
        }
    }
    cands.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut chosen: Vec<(f64, usize, usize)> = Vec::new();
    for c in cands {
        if chosen
            .iter()
            .all(|o| o.1.abs_diff(c.1) >= n || o.2.abs_diff(c.2) >= n)
        {
            chosen.push(c);
        }
        if chosen.len() == count {
            break;
        }
    }
    Ok(chosen
        .into_iter()
        .map(|(s, r0, c0)| {
            // Rows run south: y = -row, so flip rows to keep triangles CCW seen from above.
            let m = grid(n, sp, |r, c| z[(r0 + (n - 1 - r)) * cols + c0 + c]);
            (format!("engabreen_r{r0}_c{c0}_{n}_slope{:.0}", s), m)
        })
        .collect())
}

/// Reads an OBJ's `v` and `f` lines (1-based, `i/j` accepted) into a mesh.
fn read_obj(path: &Path) -> anyhow::Result<ParamMesh> {
    let text =
        std::fs::read_to_string(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let mut m = ParamMesh::default();
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let v: Vec<f64> = it
                    .take(3)
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<_, _>>()?;
                anyhow::ensure!(v.len() == 3, "{}:{}: bad vertex", path.display(), ln + 1);
                m.positions.push([v[0], v[1], v[2]]);
            }
            Some("f") => {
                let f: Vec<u32> = it
                    .take(3)
                    .map(|x| x.split('/').next().unwrap_or("").parse::<u32>())
                    .collect::<Result<_, _>>()?;
                anyhow::ensure!(
                    f.len() == 3 && f.iter().all(|&i| i >= 1),
                    "{}:{}: bad face",
                    path.display(),
                    ln + 1
                );
                m.triangles.push([f[0] - 1, f[1] - 1, f[2] - 1]);
            }
            _ => {}
        }
    }
    Ok(m)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // `--time-obj FILE REPS`: time the default options on one OBJ and print JSON (used by
    // the peer script so that ours and the peers are timed in the same run, same load).
    if let Some(i) = args.iter().position(|a| a == "--time-obj") {
        let path = PathBuf::from(
            args.get(i + 1)
                .ok_or_else(|| anyhow::anyhow!("--time-obj needs a file"))?,
        );
        let reps: usize = args
            .get(i + 2)
            .map(|s| s.parse())
            .transpose()?
            .unwrap_or(3)
            .max(1);
        let m = read_obj(&path)?;
        let mut times = Vec::new();
        let mut chart = None;
        for _ in 0..reps {
            let t = Instant::now();
            chart = Some(parameterize(&m, &ParamOptions::default())?);
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let ch = chart.ok_or_else(|| anyhow::anyhow!("no run"))?;
        println!(
            "{}",
            serde_json::json!({"ms_median": median(times), "metrics": ch.metrics})
        );
        return Ok(());
    }
    let quick = args.iter().any(|a| a == "--quick");
    let out = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("cliffmap_param_bench"));
    std::fs::create_dir_all(out.join("cells"))?;

    let mut cells = Vec::new();
    for n in [33usize, 65] {
        cells.extend(synthetic(n));
        cells.extend(engabreen(n, 2)?);
    }
    let def = ParamOptions::default();
    let mut configs: Vec<(String, ParamOptions)> = vec![("default".into(), def)];
    if !quick {
        // θ ≠ 1 has no global finish: the local relaxation's quality budget 1e-4/32.
        for theta in [0.0, 0.5, 2.0, 3.0] {
            configs.push((
                format!("theta={theta}"),
                ParamOptions {
                    theta,
                    relax_tolerance: 1e-4,
                    max_sweeps: 32,
                    ..def
                },
            ));
        }
        // The hierarchy alone (no global finish) at several relaxation budgets; the
        // 1e-4/32 row is the default before the global finish existed.
        for (tol, sweeps) in [(1e-2, 4), (1e-3, 8), (1e-4, 32), (1e-5, 64)] {
            configs.push((
                format!("local-only tol={tol:e},sweeps={sweeps}"),
                ParamOptions {
                    relax_tolerance: tol,
                    max_sweeps: sweeps,
                    newton_iterations: 0,
                    ..def
                },
            ));
        }
        // The global finish's knobs.
        configs.push((
            "newton tol=1e-2".into(),
            ParamOptions {
                newton_tolerance: 1e-2,
                ..def
            },
        ));
        configs.push((
            "newton tol=1e-5".into(),
            ParamOptions {
                newton_tolerance: 1e-5,
                newton_iterations: 50,
                ..def
            },
        ));
        configs.push((
            "relax 1e-4/32 + newton".into(),
            ParamOptions {
                relax_tolerance: 1e-4,
                max_sweeps: 32,
                ..def
            },
        ));
        configs.push((
            "objective=packed-stretch".into(),
            ParamOptions {
                objective: cliffmap::param::Objective::PackedStretch,
                ..def
            },
        ));
    }
    println!(
        "{:<34} {:<34} {:>6} {:>9} {:>5} {:>8} {:>8} {:>9} {:>6} {:>8} {:>7}",
        "cell",
        "config",
        "tris",
        "ms(med)",
        "flip",
        "|logA|",
        "s1/s2",
        "symD-4",
        "newton",
        "L2str",
        "reltex"
    );
    let mut json = Vec::new();
    for (name, m) in &cells {
        // The orthographic chart of the cell, scaled into the unit square.
        let ext = m
            .positions
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |a, p| {
                [a[0].min(p[0].min(p[1])), a[1].max(p[0].max(p[1]))]
            });
        let ortho: Vec<[f64; 2]> = m
            .positions
            .iter()
            .map(|p| {
                [
                    (p[0] - ext[0]) / (ext[1] - ext[0]),
                    (p[1] - ext[0]) / (ext[1] - ext[0]),
                ]
            })
            .collect();
        let om = chart_metrics(&m.positions, &m.triangles, &ortho, None)?;
        let oe = degener_energy(&m.positions, &m.triangles, &ortho, 1.0)?;
        println!(
            "{:<34} {:<34} {:>6} {:>9} {:>5} {:>8.4} {:>8.4} {:>9.4} {:>6} {:>8.4} {:>7.2}",
            name,
            "orthographic",
            om.triangles,
            "-",
            om.flipped,
            om.area_distortion_mean,
            om.angle_distortion_mean,
            om.symmetric_dirichlet_excess(),
            "-",
            om.stretch_l2,
            om.rel_texel
        );
        json.push(serde_json::json!({"cell": name, "config": "orthographic", "triangles": om.triangles, "metrics": om, "energy_theta1": oe}));
        for (cname, o) in &configs {
            let reps = if quick {
                1
            } else if m.triangles.len() > 4000 {
                3
            } else {
                5
            };
            let mut times = Vec::new();
            let mut chart = None;
            for _ in 0..reps {
                let t = Instant::now();
                let ch = parameterize(m, o)?;
                times.push(t.elapsed().as_secs_f64() * 1e3);
                chart = Some(ch);
            }
            let Some(ch) = chart else { continue };
            let ms = median(times);
            let e1 = degener_energy(&m.positions, &m.triangles, &ch.uvs, 1.0)?;
            let mm = ch.metrics;
            println!(
                "{:<34} {:<34} {:>6} {:>9.2} {:>5} {:>8.4} {:>8.4} {:>9.4} {:>6} {:>8.4} {:>7.2}",
                name,
                cname,
                mm.triangles,
                ms,
                mm.flipped,
                mm.area_distortion_mean,
                mm.angle_distortion_mean,
                mm.symmetric_dirichlet_excess(),
                ch.newton_iterations,
                mm.stretch_l2,
                mm.rel_texel
            );
            json.push(serde_json::json!({"cell": name, "config": cname, "theta": o.theta, "relax_tolerance": o.relax_tolerance,
                "max_sweeps": o.max_sweeps, "newton_iterations": o.newton_iterations, "newton_tolerance": o.newton_tolerance,
                "newton_iterations_used": ch.newton_iterations, "overlap_repaired": ch.overlap_repaired, "projection_start": ch.projection_start, "triangles": mm.triangles, "ms_median": ms, "metrics": mm, "energy_theta1": e1, "rounds": ch.rounds, "tutte_base": ch.tutte_base}));
            if cname == "default" {
                write_obj(&out.join("cells").join(format!("{name}.obj")), m, &ch.uvs)?;
            }
        }
    }
    // Growth of the time with the triangle count (fractal hills, default options).
    println!("\nscaling (hills, default options)");
    println!(
        "{:>6} {:>8} {:>10} {:>14}",
        "n", "tris", "ms(med)", "us/(T log2 T)"
    );
    let sizes: &[usize] = if quick {
        &[17, 33, 65]
    } else {
        &[17, 33, 65, 129, 257]
    };
    for &n in sizes {
        let (_, m) = synthetic(n)
            .into_iter()
            .nth(3)
            .ok_or_else(|| anyhow::anyhow!("no hills cell"))?;
        let reps = if n >= 257 { 1 } else { 3 };
        let mut times = Vec::new();
        let mut flips = 0;
        for _ in 0..reps {
            let t = Instant::now();
            let ch = parameterize(&m, &def)?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
            flips = ch.metrics.flipped;
        }
        let ms = median(times);
        let t = m.triangles.len() as f64;
        println!(
            "{:>6} {:>8} {:>10.2} {:>14.4}   flips {}",
            n,
            m.triangles.len(),
            ms,
            ms * 1e3 / (t * t.log2()),
            flips
        );
        json.push(serde_json::json!({"cell": format!("scaling_hills_{n}"), "config": "default", "triangles": m.triangles.len(), "ms_median": ms}));
    }
    std::fs::write(out.join("ours.json"), serde_json::to_string_pretty(&json)?)?;
    println!(
        "\nwrote {} and {}",
        out.join("cells").display(),
        out.join("ours.json").display()
    );
    Ok(())
}
