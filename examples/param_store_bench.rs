//! Benchmark of `cliffmap::parameterize` on real TIN cells taken from cell stores.
//!
//! Usage: cargo run --release --example param_store_bench -- [OUT_DIR] [--per-store N]
//!
//! Builds four stores with the library (`pipeline::build_store`, orthos derived from the
//! DEM): Engabreen (3 m, max error 0.5 m), Mount St Helens (10 m, max error 2 m), one Grand
//! Canyon Terrain-RGB tile (30.9 m, max error 2 m) and the demo scene (2 m, 0.5 m). From each
//! it takes the N (default 3) finest-level cells with the highest ortho `rel_texel` plus the
//! finest cell with the highest `max_slope_deg` (if not among them), reads
//! their surface meshes back from the store (`Store::read_mesh`, cell-local f32 -> f64,
//! skirts dropped) and times `parameterize` with the default options (median of 5 runs).
//! Writes each cell as OBJ (v, vt = our default chart, f) into OUT_DIR/cells and the results
//! into OUT_DIR/ours.json, in the layout benches/peers/param_libigl.py reads.
//!
//! Real data: env CLIFFMAP_SHARED_DATA, else $CARGO_MANIFEST_DIR/../shared/data/real, else
//! /work/shared/data/real.

use cliffmap::demo_scene::DemoScene;
use cliffmap::param::Objective;
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
use cliffmap::store::Store;
use cliffmap::{
    Dem, DemLoadOptions, ParamMesh, ParamOptions, chart_metrics, load_dem, parameterize,
};
use std::path::PathBuf;
use std::time::Instant;

#[path = "bench_util/mod.rs"]
mod bench_util;
use bench_util::{median, shared_data, write_obj};

/// One store to build: name, DEM, a description of its source, the finest max error.
struct StoreSpec {
    name: &'static str,
    dem: Dem,
    source: String,
    max_error: f64,
}

fn load(rel: &str, opts: DemLoadOptions) -> anyhow::Result<(Dem, String)> {
    let path = shared_data(rel);
    let dem = load_dem(&path, &opts).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok((dem, path.display().to_string()))
}

fn specs() -> anyhow::Result<Vec<StoreSpec>> {
    let (eng, eng_src) = load(
        "engabreen/engabreen_dem_3m_507x590.f32",
        DemLoadOptions {
            width: Some(507),
            height: Some(590),
            spacing: Some(3.0),
            origin: Some((445_302.17, 7_396_769.45)),
            ..DemLoadOptions::default()
        },
    )?;
    let (sth, sth_src) = load(
        "argudo_glaciers/sthelens_10m.png",
        DemLoadOptions {
            z_scale: Some(0.1),
            spacing: Some(10.0),
            ..DemLoadOptions::default()
        },
    )?;
    let (gc, gc_src) = load(
        "grand_canyon_tiles/12-758-1608.terrain.png",
        DemLoadOptions {
            spacing: Some(30.9),
            ..DemLoadOptions::default()
        },
    )?;
    let scene = DemoScene::default();
    let (demo, _) = scene.generate()?;
    Ok(vec![
        StoreSpec {
            name: "engabreen",
            dem: eng,
            source: eng_src,
            max_error: 0.5,
        },
        StoreSpec {
            name: "sthelens",
            dem: sth,
            source: sth_src,
            max_error: 2.0,
        },
        StoreSpec {
            name: "grandcanyon",
            dem: gc,
            source: gc_src,
            max_error: 2.0,
        },
        StoreSpec {
            name: "demo",
            dem: demo,
            source: format!("demo:seed={},samples={}", scene.seed, scene.samples),
            max_error: 0.5,
        },
    ])
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let per_store: usize = match args.iter().position(|a| a == "--per-store") {
        Some(i) => args
            .get(i + 1)
            .ok_or_else(|| anyhow::anyhow!("--per-store needs a number"))?
            .parse()?,
        None => 3,
    };
    let out = args
        .iter()
        .enumerate()
        .find(|(i, a)| !a.starts_with("--") && (*i == 0 || args[i - 1] != "--per-store"))
        .map(|(_, a)| PathBuf::from(a))
        .unwrap_or_else(|| std::env::temp_dir().join("cliffmap_param_store_bench"));
    std::fs::create_dir_all(out.join("cells"))?;
    let def = ParamOptions::default();
    // The default, the hierarchy alone (no global finish) and the finish's knobs.
    let configs: Vec<(String, ParamOptions)> = vec![
        ("default".into(), def),
        (
            "relax-1e-2/4-alone".into(),
            ParamOptions {
                newton_iterations: 0,
                ..def
            },
        ),
        (
            "objective=packed-stretch".into(),
            ParamOptions {
                objective: Objective::PackedStretch,
                ..def
            },
        ),
        (
            "newton-tol=1e-2".into(),
            ParamOptions {
                newton_tolerance: 1e-2,
                ..def
            },
        ),
        (
            "newton-tol=1e-4".into(),
            ParamOptions {
                newton_tolerance: 1e-4,
                newton_iterations: 50,
                ..def
            },
        ),
        (
            "relax-1e-4/32+newton".into(),
            ParamOptions {
                relax_tolerance: 1e-4,
                max_sweeps: 32,
                ..def
            },
        ),
        (
            "relax-1e-4/32-alone".into(),
            ParamOptions {
                relax_tolerance: 1e-4,
                max_sweeps: 32,
                newton_iterations: 0,
                ..def
            },
        ),
    ];
    println!(
        "{:<34} {:<18} {:>6} {:>6} {:>7} {:>7} {:>9} {:>5} {:>8} {:>8} {:>9} {:>7} {:>7} {:>7}",
        "cell",
        "config",
        "verts",
        "tris",
        "slope",
        "maxslp",
        "ms(med)",
        "flip",
        "|logA|",
        "s1/s2",
        "symD-4",
        "newton",
        "ortho-4",
        "packL2"
    );
    let mut json = Vec::new();
    for spec in specs()? {
        let dir = out.join("stores").join(spec.name);
        let opts = BuildOptions {
            max_error: spec.max_error,
            force: true,
            ..BuildOptions::default()
        };
        let inputs = BuildInputs {
            dem: &spec.dem,
            ortho: None,
            dem_source: spec.source.clone(),
            ortho_source: None,
            fingerprint: format!("param_store_bench:{}", spec.source),
        };
        let t = Instant::now();
        build_store(&inputs, &opts, &dir)?;
        let build_s = t.elapsed().as_secs_f64();
        let store = Store::open(&dir)?;
        let finest = store.manifest.quadtree.levels.saturating_sub(1);
        let mut recs: Vec<_> = store
            .manifest
            .cells
            .iter()
            .filter(|c| c.level as u32 == finest as u32)
            .collect();
        recs.sort_by(|a, b| {
            b.stats
                .rel_texel
                .total_cmp(&a.stats.rel_texel)
                .then(a.id.cmp(&b.id))
        });
        eprintln!(
            "{}: built {} cells in {build_s:.1} s; {} finest",
            spec.name,
            store.manifest.cells.len(),
            recs.len()
        );
        // The N steepest by ortho rel_texel, plus the cell with the steepest single triangle
        // (max slope) if not among them: on the demo scene that is a box-plateau wall cell,
        // while the rel_texel ranking picks the long canyon walls.
        let mut chosen: Vec<_> = recs.iter().take(per_store).copied().collect();
        if let Some(wall) = recs.iter().max_by(|a, b| {
            a.stats
                .max_slope_deg
                .total_cmp(&b.stats.max_slope_deg)
                .then(b.id.cmp(&a.id))
        }) && !chosen.iter().any(|c| c.id == wall.id)
        {
            chosen.push(wall);
        }
        for rec in chosen {
            let cm = store.read_mesh(rec)?;
            let nv = cm.surface_vertices as usize;
            let m = ParamMesh {
                positions: cm.positions[..nv]
                    .iter()
                    .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
                    .collect(),
                triangles: cm.surface().to_vec(),
            };
            let name = format!("tin_{}_{}", spec.name, rec.id);
            // The orthographic chart (x, y scaled into the unit square) for reference.
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
            json.push(serde_json::json!({"cell": name, "config": "orthographic", "triangles": om.triangles, "metrics": om}));
            let mut default_chart = None;
            for (cname, o) in &configs {
                let mut times = Vec::new();
                let mut chart = None;
                for _ in 0..5 {
                    let t = Instant::now();
                    let ch = parameterize(&m, o)?;
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                    chart = Some(ch);
                }
                let ch = chart.ok_or_else(|| anyhow::anyhow!("no run"))?;
                let ms = median(times);
                let mm = ch.metrics;
                println!(
                    "{:<34} {:<18} {:>6} {:>6} {:>7.1} {:>7.1} {:>9.2} {:>5} {:>8.4} {:>8.4} {:>9.4} {:>7} {:>7.3} {:>7.2}",
                    name,
                    cname,
                    nv,
                    mm.triangles,
                    rec.stats.mean_slope_deg,
                    rec.stats.max_slope_deg,
                    ms,
                    mm.flipped,
                    mm.area_distortion_mean,
                    mm.angle_distortion_mean,
                    mm.symmetric_dirichlet_excess(),
                    ch.newton_iterations,
                    om.symmetric_dirichlet_excess(),
                    mm.packed_stretch_l2()
                );
                json.push(serde_json::json!({"cell": name, "config": cname, "store": spec.name, "id": rec.id,
                    "vertices": nv, "triangles": mm.triangles, "mean_slope_deg": rec.stats.mean_slope_deg,
                    "max_slope_deg": rec.stats.max_slope_deg, "store_rel_texel": rec.stats.rel_texel,
                    "theta": o.theta, "relax_tolerance": o.relax_tolerance, "max_sweeps": o.max_sweeps,
                    "newton_iterations": o.newton_iterations, "newton_tolerance": o.newton_tolerance,
                    "ms_median": ms, "metrics": mm, "rounds": ch.rounds, "tutte_base": ch.tutte_base,
                    "newton_iterations_used": ch.newton_iterations, "overlap_repaired": ch.overlap_repaired, "projection_start": ch.projection_start}));
                if cname == "default" {
                    default_chart = Some(ch);
                }
            }
            let ch = default_chart.ok_or_else(|| anyhow::anyhow!("no default run"))?;
            write_obj(&out.join("cells").join(format!("{name}.obj")), &m, &ch.uvs)?;
        }
    }
    std::fs::write(out.join("ours.json"), serde_json::to_string_pretty(&json)?)?;
    println!(
        "\nwrote {} and {}",
        out.join("cells").display(),
        out.join("ours.json").display()
    );
    Ok(())
}
