//! End-to-end tests of the `cliffmap` binary: demo, build on real data, stats, export-obj,
//! resume, determinism across thread counts, and bad input handling.

mod cli_util;
mod common;

use std::path::Path;
use std::process::Command;

use cli_util::{fails_naming, ok};
use cliffmap::store::Store;
use common::real_data;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

/// Every file under `dir` (relative name, CRC-32 of its content), sorted by name.
fn all_files(dir: &Path) -> Vec<(String, u32)> {
    // (.lock holds the pid of the last writer, not store content)
    cli_util::files_under(dir)
        .into_iter()
        .filter(|p| p.file_name().is_some_and(|n| n != ".lock"))
        .map(|p| {
            (
                p.strip_prefix(dir).unwrap().display().to_string(),
                crc32fast::hash(&std::fs::read(&p).unwrap()),
            )
        })
        .collect()
}

#[test]
fn demo_runs_whole_pipeline_and_is_deterministic_across_threads() {
    let t = tempfile::tempdir().unwrap();
    let (a, b) = (t.path().join("a"), t.path().join("b"));
    let small = [
        "--samples",
        "129",
        "--photo-width",
        "480",
        "--photo-supersample",
        "1",
        "--quiet",
    ];
    ok(&[&["--threads", "1", "demo", "--out", s(&a)][..], &small[..]].concat());
    ok(&[&["--threads", "2", "demo", "--out", s(&b)][..], &small[..]].concat());
    let store = a.join("store");
    assert!(store.join("manifest.json").is_file() && store.join("stats.json").is_file());
    assert!(store.join("stats_histogram.png").is_file());
    // the frame and its photo share (GPU tests need Mesa anyway)
    let share = image::open(a.join("frame_photo_share.png"))
        .unwrap()
        .to_rgb8();
    assert!(a.join("frame.png").is_file());
    let yellow = share
        .pixels()
        .filter(|p| p.0[0] > 200 && p.0[1] > 200 && p.0[2] < 60)
        .count();
    assert!(yellow > 0, "no texel shows photo colour alone");
    assert_eq!(
        all_files(&a.join("store")),
        all_files(&b.join("store")),
        "outputs differ between 1 and 2 threads"
    );
    let st = Store::open(&store).unwrap();
    assert!(st.manifest.cells.len() >= 5);
    // The demo scene has cliffs: some cell must be stretched well above the threshold.
    let max_rel = st
        .manifest
        .cells
        .iter()
        .map(|c| c.stats.rel_texel)
        .fold(0.0, f64::max);
    assert!(max_rel > 1.3, "max rel_texel {max_rel}");
    for c in &st.manifest.cells {
        assert!(
            c.max_error <= c.epsilon + 1e-6,
            "cell {} error {} > {}",
            c.id,
            c.max_error,
            c.epsilon
        );
        let m = st.read_mesh(c).unwrap();
        assert_eq!(m.surface_triangles, c.triangles);
    }
    // The ground-photo stage ran: photo textures exist and steep texels got closer to the truth.
    assert!(
        st.manifest.cells.iter().any(|c| c.photo.is_some()),
        "no cell got a photo texture"
    );
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("truth.json")).unwrap()).unwrap();
    let (before, after) = (&truth["before"], &truth["after"]);
    let psnr = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
    assert!(
        psnr(after, "steep_psnr") > psnr(before, "steep_psnr"),
        "{truth}"
    );
    assert!(
        psnr(after, "flat_psnr") > psnr(before, "flat_psnr") - 0.1,
        "{truth}"
    );
    // Where photos dominate, steep texels are much closer to the truth than the ortho was.
    let (cb, ca) = (
        &truth["photo_covered_before"],
        &truth["photo_covered_after"],
    );
    assert!(ca["steep_texels"].as_u64().unwrap() > 100, "{truth}");
    assert!(
        psnr(ca, "steep_psnr") > psnr(cb, "steep_psnr") + 3.0,
        "{truth}"
    );
}

#[test]
fn engabreen_build_stats_export_and_resume() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("eng.store");
    let dem = real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let ortho = real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let args = common::engabreen_build_args(&dem, &ortho, &out);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    ok(&args);
    let st = Store::open(&out).unwrap();
    let m = &st.manifest;
    assert_eq!((m.dem.width, m.dem.height), (507, 590));
    assert!((m.dem.height_min - 213.1).abs() < 0.1 && (m.dem.height_max - 1078.3).abs() < 0.1);
    // Engabreen has rock walls: a good share of finest cells is stretched.
    let finest: Vec<_> = m
        .cells
        .iter()
        .filter(|c| c.level == m.quadtree.levels - 1)
        .collect();
    let above = finest.iter().filter(|c| c.stats.rel_texel > 1.1).count();
    assert!(
        above * 10 >= finest.len(),
        "{above} of {} finest cells above 1.1",
        finest.len()
    );
    // Cell origins are georeferenced and meshes are local: reconstruct a vertex in world coords.
    let c = &finest[finest.len() / 2];
    let mesh = st.read_mesh(c).unwrap();
    for p in &mesh.positions[..mesh.surface_vertices as usize] {
        let x = p[0] as f64 + c.origin[0];
        let y = p[1] as f64 + c.origin[1];
        let col = (x - 445302.17) / 3.0;
        let row = (7396769.45 - y) / 3.0;
        assert!(
            (col - col.round()).abs() < 1e-3 && (row - row.round()).abs() < 1e-3,
            "vertex off the grid: {col} {row}"
        );
    }

    // stats --json prints the documented shape.
    let o = ok(&["stats", s(&out), "--json", "--threshold", "1.2"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let cells = v["cells"].as_array().unwrap();
    assert_eq!(cells.len(), m.cells.len());
    for key in [
        "id",
        "level",
        "x",
        "y",
        "rel_texel",
        "max_slope_deg",
        "triangles",
        "max_error",
    ] {
        assert!(cells[0].get(key).is_some(), "stats.json cell lacks {key}");
    }
    assert!(v.get("summary").is_some());

    // export-obj: local and world.
    let obj = t.path().join("cell.obj");
    ok(&["export-obj", s(&out), "--cell", &c.id, "--out", s(&obj)]);
    let text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("v ")).count(),
        c.vertices as usize
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("vt ")).count(),
        c.vertices as usize
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("f ")).count(),
        c.triangles as usize
    );
    ok(&[
        "export-obj",
        s(&out),
        "--cell",
        &c.id,
        "--world",
        "--out",
        s(&obj),
    ]);
    let world = std::fs::read_to_string(&obj).unwrap();
    let first_v = world.lines().find(|l| l.starts_with("v ")).unwrap();
    let x: f64 = first_v.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(x > 445_000.0 && x < 447_000.0, "world x {x}");
    fails_naming(
        &["export-obj", s(&out), "--cell", "99-0-0", "--out", s(&obj)],
        "99-0-0",
    );

    // Resume: delete one cell's files and its record; a rerun restores them identically.
    ok(&["stats", s(&out), "--threshold", "1.1"]);
    let before = all_files(&out);
    let stem = out.join(format!("cells/{}/{}-{}", c.level, c.x, c.y));
    std::fs::remove_file(stem.with_extension("png")).unwrap();
    std::fs::remove_file(stem.with_extension("json")).unwrap();
    ok(&args);
    assert_eq!(all_files(&out), before);

    // A corrupted cell file is detected on read.
    std::fs::write(stem.with_extension("mesh"), b"CLIFMESH garbage").unwrap();
    let st = Store::open(&out).unwrap();
    let err = st
        .read_mesh(st.manifest.cell(&c.id).unwrap())
        .unwrap_err()
        .to_string();
    assert!(err.contains("checksum"), "{err}");
    // A different build into the same store is refused without --force.
    let mut other = args.to_vec();
    let i = other.len() - 6;
    other[i] = "2.0"; // --max-error 2.0
    fails_naming(&other, "--force");
}

#[test]
fn bad_inputs_fail_cleanly_without_output() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("never");
    let missing = t.path().join("missing.f32");
    fails_naming(
        &[
            "build",
            "--dem",
            s(&missing),
            "--width",
            "4",
            "--height",
            "4",
            "--out",
            s(&out),
        ],
        "missing.f32",
    );
    let trunc = t.path().join("trunc.f32");
    std::fs::write(&trunc, [0u8; 10]).unwrap();
    fails_naming(
        &[
            "build",
            "--dem",
            s(&trunc),
            "--width",
            "4",
            "--height",
            "4",
            "--out",
            s(&out),
        ],
        "trunc.f32",
    );
    let nan = t.path().join("nan.f32");
    let mut bytes: Vec<u8> = (0..16).flat_map(|_| 1.0f32.to_le_bytes()).collect();
    bytes[20..24].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(&nan, &bytes).unwrap();
    fails_naming(
        &[
            "build",
            "--dem",
            s(&nan),
            "--width",
            "4",
            "--height",
            "4",
            "--nodata",
            "none",
            "--out",
            s(&out),
        ],
        "nan.f32",
    );
    let good = t.path().join("good.f32");
    std::fs::write(
        &good,
        (0..16)
            .flat_map(|i| (i as f32).to_le_bytes())
            .collect::<Vec<u8>>(),
    )
    .unwrap();
    fails_naming(
        &[
            "build",
            "--dem",
            s(&good),
            "--width",
            "4",
            "--height",
            "4",
            "--spacing",
            "-3",
            "--out",
            s(&out),
        ],
        "spacing",
    );
    fails_naming(
        &[
            "build",
            "--dem",
            s(&good),
            "--width",
            "4",
            "--height",
            "4",
            "--max-error",
            "0",
            "--out",
            s(&out),
        ],
        "max-error",
    );
    fails_naming(
        &[
            "build",
            "--dem",
            s(&good),
            "--width",
            "100000",
            "--height",
            "100000",
            "--max-memory",
            "1G",
            "--out",
            s(&out),
        ],
        "good.f32",
    );
    assert!(!out.exists(), "a failed build must not leave output behind");
    fails_naming(&["stats", s(&t.path().join("nostore"))], "nostore");
}

#[test]
fn project_flags_fail_cleanly() {
    let t = tempfile::tempdir().unwrap();
    fails_naming(
        &[
            "project",
            s(&t.path().join("nostore")),
            "--photos",
            "p.json",
        ],
        "nostore",
    );
    fails_naming(&["project", s(t.path())], "--photos");
    fails_naming(
        &[
            "project",
            s(t.path()),
            "--photos",
            "a.json",
            "--colmap",
            "d",
        ],
        "--colmap",
    );
    fails_naming(
        &[
            "project",
            s(t.path()),
            "--photos",
            "a.json",
            "--blend",
            "mean",
        ],
        "blend",
    );
    fails_naming(
        &[
            "project",
            s(t.path()),
            "--photos",
            "a.json",
            "--bvh",
            "quick",
        ],
        "bvh",
    );
}

#[test]
fn engabreen_reparam_mixed_mode_and_export() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("eng.store");
    let dem = real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let ortho = real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let args = common::engabreen_build_args(&dem, &ortho, &out);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    ok(&["reparam", s(&out), "--threshold", "1.1", "--quiet"]);
    let st = Store::open(&out).unwrap();
    let m = &st.manifest;
    let re: Vec<_> = m.cells.iter().filter(|c| c.reparam.is_some()).collect();
    assert!(!re.is_empty());
    for c in &m.cells {
        // Exactly the cells above the threshold are reparameterized ("model only what a scene requires").
        assert_eq!(
            c.reparam.is_some(),
            c.stats.rel_texel > 1.1,
            "cell {}",
            c.id
        );
    }
    let mut worst_ratios = Vec::new();
    for c in &re {
        let r = c.reparam.as_ref().unwrap();
        assert_eq!(r.metrics.flipped, 0, "cell {} has flips", c.id);
        // The chart spreads texels more evenly than the ortho map: its worst texel is less
        // stretched. The converged symmetric Dirichlet chart minimises the mean distortion,
        // not the worst texel: on one of the 106 cells (4-6-7) its worst texel is more
        // stretched than the ortho map's (6.16 vs 6.08 with spade's TIN, 6.16 vs 5.77 with
        // the half-edge TIN of 2026-12-04, whose cocircular ties differ), so a cell may
        // exceed the ortho's worst texel by 10 % and at most two cells may exceed it at
        // all; over the cells the worst texel is far less stretched (checked below).
        assert!(
            r.texel_stretch.max < 1.10 * c.stats.texel_stretch.max,
            "cell {}: {} vs {}",
            c.id,
            r.texel_stretch.max,
            c.stats.texel_stretch.max
        );
        worst_ratios.push(r.texel_stretch.max / c.stats.texel_stretch.max);
        let mesh = st.read_active_mesh(c).unwrap();
        let uvs = mesh.uvs.as_ref().unwrap();
        assert!(uvs.iter().flatten().all(|u| (0.0..=1.0).contains(u)));
        let tex = st.read_png(&r.files.texture).unwrap();
        assert_eq!(tex.width(), 64);
    }
    worst_ratios.sort_by(f64::total_cmp);
    let above = worst_ratios.iter().filter(|&&r| r > 1.0).count();
    assert!(
        above <= 2,
        "{above} charts with a worse worst texel than the ortho map"
    );
    let median = worst_ratios[worst_ratios.len() / 2];
    assert!(
        median < 0.8,
        "median worst-texel stretch ratio chart / ortho {median}"
    );

    // stats --json reports both parameterizations.
    let o = ok(&["stats", s(&out), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        v["summary"]["parameterization"]["cells_reparam"]
            .as_u64()
            .unwrap() as usize,
        re.len()
    );
    let cell = v["cells"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["id"] == re[0].id.as_str())
        .unwrap();
    assert_eq!(cell["parameterization"], "reparam");
    assert!(
        cell["reparam"]["metrics"]["angle_distortion_mean"]
            .as_f64()
            .unwrap()
            >= 1.0
    );

    // export-obj writes the chart's UVs for a reparameterized cell.
    let obj = t.path().join("re.obj");
    ok(&["export-obj", s(&out), "--cell", &re[0].id, "--out", s(&obj)]);
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(text.contains("parameterization reparam"));
    let vt: Vec<[f32; 2]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("vt "))
        .map(|l| {
            let mut it = l.split_whitespace().map(|x| x.parse::<f32>().unwrap());
            [it.next().unwrap(), it.next().unwrap()]
        })
        .collect();
    let mesh = st.read_active_mesh(re[0]).unwrap();
    let uv0 = mesh.uvs.as_ref().unwrap()[0];
    assert!((vt[0][0] - uv0[0]).abs() < 1e-6 && (vt[0][1] - (1.0 - uv0[1])).abs() < 1e-6);

    // Mixed resolution: reparameterized cells get twice the side; a higher threshold chooses
    // fewer cells and removes the stale reparameterized files of the others.
    ok(&[
        "reparam",
        s(&out),
        "--threshold",
        "1.5",
        "--mixed-resolution",
        "--quiet",
    ]);
    let st2 = Store::open(&out).unwrap();
    let re2: Vec<_> = st2
        .manifest
        .cells
        .iter()
        .filter(|c| c.reparam.is_some())
        .collect();
    assert!(re2.len() < re.len());
    assert!(
        re2.iter()
            .all(|c| c.reparam.as_ref().unwrap().texels == 128)
    );
    let dropped = re.iter().find(|c| c.stats.rel_texel <= 1.5).unwrap();
    assert!(
        !out.join(format!(
            "cells/{}/{}-{}.reparam.png",
            dropped.level, dropped.x, dropped.y
        ))
        .exists()
    );
    fails_naming(&["reparam", s(&out), "--threshold", "-1"], "threshold");
}

#[test]
fn geotiff_with_nodata_and_terrain_rgb_build() {
    let t = tempfile::tempdir().unwrap();
    // ASTER GeoTIFF, UTM 18S, with -9999 no-data: georeference and CRS come from the file.
    let out = t.path().join("expl.store");
    let dem = real_data("misc/exploradores_aster_dem_30m_utm18s.tif");
    ok(&[
        "build",
        "--dem",
        s(&dem),
        "--max-error",
        "5",
        "--cell-texels",
        "32",
        "--out",
        s(&out),
        "--quiet",
    ]);
    let m = Store::open(&out).unwrap().manifest;
    assert_eq!(m.crs.as_deref(), Some("EPSG:32718"));
    assert!(
        (m.georef.origin_x - 627190.0).abs() < 1e-6 && (m.georef.origin_y - 4852070.0).abs() < 1e-6
    );
    assert!(
        m.dem.void_fraction > 0.02 && m.dem.void_fraction < 0.035,
        "{}",
        m.dem.void_fraction
    );
    assert!(
        m.cells
            .iter()
            .all(|c| c.max_error <= c.epsilon + 1e-6 && c.stats.rel_texel.is_finite())
    );
    // Textures over voids are marked unknown (alpha 0) somewhere in the finest level.
    let st = Store::open(&out).unwrap();
    let finest = m.quadtree.levels - 1;
    let unknown: usize = m
        .cells
        .iter()
        .filter(|c| c.level == finest)
        .map(|c| {
            st.read_texture(c)
                .unwrap()
                .pixels()
                .filter(|p| p.0[3] == 0)
                .count()
        })
        .sum();
    assert!(unknown > 0, "voids must show as unknown texels");

    // Terrain-RGB tile with its (palette) map tile as ortho on the same grid.
    let out2 = t.path().join("gc.store");
    let terrain = real_data("grand_canyon_tiles/12-758-1608.terrain.png");
    let sat = real_data("grand_canyon_tiles/12-758-1608.satellite.png");
    ok(&[
        "build",
        "--dem",
        s(&terrain),
        "--spacing",
        "30.9",
        "--ortho",
        s(&sat),
        "--ortho-same-grid",
        "--max-error",
        "2",
        "--cell-texels",
        "32",
        "--cell-intervals",
        "32",
        "--out",
        s(&out2),
        "--quiet",
    ]);
    let m2 = Store::open(&out2).unwrap().manifest;
    assert!(m2.dem.height_min >= 439.0 && m2.dem.height_max <= 2184.5);
    assert!(m2.cells.iter().any(|c| c.stats.max_slope_deg > 60.0));
}

#[test]
fn engabreen_photos_project_onto_the_rock_walls() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("eng.store");
    let dem = real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let ortho = real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let args = common::engabreen_build_args(&dem, &ortho, &out);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    ok(&["reparam", s(&out), "--quiet"]);
    // The two ground photos of the README: IMG_8902 with its fitted pose, IMG_8937 with
    // ImGRAFT's rotation delta.
    let cam = real_data("engabreen/engabreen_camera_IMG_8902.json");
    let list = serde_json::json!({"photos": [
        {"image": real_data("engabreen/IMG_8902.jpg"), "imgraft": cam},
        {"image": real_data("engabreen/IMG_8937.jpg"), "imgraft": cam,
         "rotation_delta_deg": [0.12633, 0.017584, 0.015242]},
    ]});
    let photos = t.path().join("photos.json");
    std::fs::write(&photos, list.to_string()).unwrap();
    ok(&["project", s(&out), "--photos", s(&photos), "--quiet"]);
    let o = ok(&["stats", s(&out), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let sum = &v["summary"];
    let frac = sum["photo_improved_steep_fraction"].as_f64().unwrap();
    assert!(
        frac > 0.05 && frac <= 1.0,
        "photo_improved_steep_fraction {frac}"
    );
    let reports = sum["photos"].as_array().unwrap();
    assert_eq!(reports.len(), 2);
    for p in reports {
        // Most of the 12 MP photo sees the DEM crop; the walls and ridges cause silhouettes.
        assert!(p["pixels_hit"].as_u64().unwrap() > 2_000_000, "{p}");
        assert!(p["texels_written"].as_u64().unwrap() > 10_000, "{p}");
        assert!(p["rejected_silhouette"].as_u64().unwrap() > 0, "{p}");
        assert!(p["reconstructed_footprints"].as_u64().is_some(), "{p}");
    }
    let st = Store::open(&out).unwrap();
    let photo_cells = st
        .manifest
        .cells
        .iter()
        .filter(|c| c.photo.is_some())
        .count();
    assert!(
        photo_cells > 0 && photo_cells < st.manifest.cells.len(),
        "{photo_cells} photo cells"
    );
    // Every photo texture reads back intact and has the active texture's size times a power
    // of two (photo-driven sizes), at most the 2048-texel default cap; the photos resolve the
    // walls more finely than the 64-texel textures, so some cells are enlarged.
    let mut upsized = 0;
    for c in st.manifest.cells.iter().filter(|c| c.photo.is_some()) {
        let p = c.photo.as_ref().unwrap();
        let img = st.read_photo_texture(c, p).unwrap().0;
        let base = cliffmap::store::active_texels(c);
        assert_eq!((img.width(), img.height()), (p.texels, p.texels));
        assert!(
            p.texels % base == 0 && (p.texels / base).is_power_of_two() && p.texels <= 2048,
            "{} {}",
            p.texels,
            base
        );
        upsized += (p.texels > base) as usize;
    }
    assert!(upsized > 0);
}

#[test]
fn view_fails_cleanly_without_display_or_store() {
    let t = tempfile::tempdir().unwrap();
    ok(&[
        "demo",
        "--out",
        s(t.path()),
        "--samples",
        "65",
        "--no-photos",
        "--quiet",
    ]);
    let store = t.path().join("store");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_cliffmap"))
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("cannot start cliffmap")
    };
    let o = run(&["view", s(&store)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "view without a display should fail: {err}"
    );
    assert!(err.contains("no display available"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let missing = t.path().join("nope");
    let o = run(&["view", s(&missing)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && !err.contains("panicked"), "{err}");
    assert!(err.contains("nope") && !err.contains("no display"), "{err}");
}

/// An Xvfb server on a free display (`-displayfd`), killed on drop.
struct Xvfb {
    child: std::process::Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        use std::io::BufRead;
        let mut child = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1024x768x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("cannot start Xvfb (apt-get install xvfb xauth; .ci/run installs it)");
        let mut line = String::new();
        let out = child.stdout.take().expect("Xvfb stdout");
        std::io::BufReader::new(out)
            .read_line(&mut line)
            .expect("Xvfb display number");
        let n: u32 = line
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("Xvfb printed {line:?}"));
        Xvfb {
            child,
            display: format!(":{n}"),
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        // SIGTERM lets Xvfb remove its socket and lock file; SIGKILL only if it lingers.
        let _ = Command::new("kill")
            .arg(self.child.id().to_string())
            .status();
        for _ in 0..50 {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn view_opens_resizes_captures_and_exits_under_xvfb() {
    let t = tempfile::tempdir().unwrap();
    ok(&[
        "demo",
        "--out",
        s(t.path()),
        "--samples",
        "65",
        "--no-photos",
        "--quiet",
    ]);
    let store = t.path().join("store");
    let x = Xvfb::start();
    let runtime = t.path().join("xdg");
    std::fs::create_dir(&runtime).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_cliffmap"))
        .args([
            "view",
            s(&store),
            "--size",
            "320x200",
            "--smoke-test",
            "--frames",
            "8",
        ])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("XDG_RUNTIME_DIR", &runtime)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("cannot start cliffmap");
    // A hang guard only (not a timing assertion): a stuck window is killed after 10 minutes.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(600);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            let _ = child.kill();
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "view under Xvfb failed:\n{err}");
    for needle in [
        "view: resized to 240x150 (surface and render target)",
        "view: geomorphing on",
        "view: 8 frames presented, last at 240x150",
    ] {
        assert!(err.contains(needle), "missing {needle:?} in:\n{err}");
    }
    assert!(
        err.contains("view: mouse captured") || err.contains("view: mouse capture unavailable"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}
