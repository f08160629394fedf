//! Renderer policy without a GPU: LOD selection, culling, LRU cache, streaming fallback.

mod render_support;

use std::time::Duration;

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::render::{
    CellIndex, LruCache, RenderCamera, Streamer, resolve_draw_list, select_cells,
};
use cliffmap::store::CellRecord;
use glam::DVec3;
use render_support::{Synth, X0, Y0, records};

const SYNTH: Synth = Synth {
    levels: 6,
    size: 4096.0,
    z: 1000.0,
    finest_error: 0.05,
    texels: 4096,
};

fn camera(pos: DVec3, target: DVec3) -> RenderCamera {
    let r = rotation_look_at(pos, target).unwrap();
    RenderCamera::new(
        CameraModel::with_fov(pos, r, 800, 600, 60f64.to_radians()),
        0.5,
    )
}

fn contains_xy(rec: &CellRecord, x: f64, y: f64) -> bool {
    let e = rec.extent;
    x >= e.min_x && x <= e.max_x && y >= e.min_y && y <= e.max_y
}

/// No selected cell may be the ancestor of another, and all selected cells must exist.
fn assert_disjoint(cells: &[CellRecord], sel: &[usize]) {
    for &a in sel {
        for &b in sel {
            if a == b {
                continue;
            }
            let (ka, kb) = (cells[a].key(), cells[b].key());
            let mut k = kb.parent();
            while let Some(p) = k {
                assert_ne!(
                    p,
                    ka,
                    "{} is selected together with its descendant {}",
                    ka.id(),
                    kb.id()
                );
                k = p.parent();
            }
        }
    }
}

#[test]
fn refines_near_the_camera_and_not_far_away() {
    let cells = records(&SYNTH);
    let index = CellIndex::new(&cells);
    let pos = DVec3::new(X0 + 100.0, Y0 - 100.0, 1010.0);
    let cam = camera(pos, DVec3::new(X0 + 4000.0, Y0 - 4000.0, 1000.0));
    let sel = select_cells(&cells, &index, &cam, 0.5);
    assert_disjoint(&cells, &sel.cells);
    let under: Vec<_> = sel
        .cells
        .iter()
        .filter(|&&i| contains_xy(&cells[i], pos.x + 20.0, pos.y - 20.0))
        .collect();
    assert_eq!(
        under.len(),
        1,
        "exactly one cell covers the ground just ahead"
    );
    assert_eq!(
        cells[*under[0]].level,
        SYNTH.levels - 1,
        "the nearest cell is at the finest level"
    );
    let far: Vec<_> = sel
        .cells
        .iter()
        .filter(|&&i| contains_xy(&cells[i], X0 + 4000.0, Y0 - 4000.0))
        .collect();
    assert_eq!(far.len(), 1);
    assert!(
        cells[*far[0]].level < SYNTH.levels - 2,
        "far cells stay coarse, got level {}",
        cells[*far[0]].level
    );
    // Levels never increase with distance along the view diagonal.
    let mut last = u8::MAX;
    for t in [0.05, 0.2, 0.4, 0.6, 0.8, 0.97] {
        let (x, y) = (X0 + t * 4096.0, Y0 - t * 4096.0);
        let l = sel
            .cells
            .iter()
            .find(|&&i| contains_xy(&cells[i], x, y))
            .map(|&i| cells[i].level)
            .unwrap();
        assert!(
            l <= last,
            "level {l} at t={t} exceeds {last} nearer the camera"
        );
        last = l;
    }
}

#[test]
fn culls_cells_behind_the_camera() {
    let cells = records(&SYNTH);
    let index = CellIndex::new(&cells);
    let pos = DVec3::new(X0 + 2048.0, Y0 - 2048.0, 1050.0);
    let cam = camera(pos, pos + DVec3::new(100.0, 0.0, -10.0)); // looking east, slightly down
    let sel = select_cells(&cells, &index, &cam, 0.5);
    assert!(sel.culled > 0);
    assert!(!sel.cells.is_empty());
    for &i in &sel.cells {
        assert!(
            cells[i].bbox_max[0] > pos.x - 1e-6,
            "cell {} lies entirely behind the camera",
            cells[i].id
        );
    }
    // Looking straight up sees no terrain at all.
    let up = camera(pos, pos + DVec3::new(0.0, 1.0, 100.0));
    assert!(select_cells(&cells, &index, &up, 0.5).cells.is_empty());
}

#[test]
fn threshold_is_monotone() {
    let cells = records(&SYNTH);
    let index = CellIndex::new(&cells);
    let pos = DVec3::new(X0 + 700.0, Y0 - 300.0, 1100.0);
    let cam = camera(pos, DVec3::new(X0 + 3000.0, Y0 - 3500.0, 1000.0));
    let probes: Vec<(f64, f64)> = (0..64)
        .map(|i| {
            (
                X0 + 32.0 + 64.0 * (i % 8) as f64 * 8.0,
                Y0 - 32.0 - 64.0 * (i / 8) as f64 * 8.0,
            )
        })
        .collect();
    let mut prev: Option<(usize, Vec<Option<u8>>)> = None;
    for thr in [0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 16.0, 1e9] {
        let sel = select_cells(&cells, &index, &cam, thr);
        assert_disjoint(&cells, &sel.cells);
        let levels: Vec<Option<u8>> = probes
            .iter()
            .map(|&(x, y)| {
                sel.cells
                    .iter()
                    .find(|&&i| contains_xy(&cells[i], x, y))
                    .map(|&i| cells[i].level)
            })
            .collect();
        if let Some((n, pl)) = &prev {
            assert!(
                sel.cells.len() <= *n,
                "threshold {thr}: {} cells > {n}",
                sel.cells.len()
            );
            for (a, b) in levels.iter().zip(pl) {
                if let (Some(a), Some(b)) = (a, b) {
                    assert!(a <= b, "threshold {thr}: a probe got finer ({a} > {b})");
                }
            }
        }
        prev = Some((sel.cells.len(), levels));
    }
    assert_eq!(
        prev.unwrap().0,
        1,
        "an infinite threshold selects only the root"
    );
}

#[test]
fn lru_evicts_oldest_first_within_budget() {
    let mut c: LruCache<&str> = LruCache::new(100);
    c.begin_frame();
    assert!(c.insert(1, "a", 40).is_empty());
    c.begin_frame();
    assert!(c.insert(2, "b", 40).is_empty());
    c.begin_frame();
    assert!(c.get(1).is_some()); // 1 is now more recent than 2
    c.begin_frame();
    let ev = c.insert(3, "c", 40);
    assert_eq!(ev, vec![(2, "b")]);
    assert_eq!(c.used_bytes(), 80);
    c.begin_frame();
    let ev = c.insert(4, "d", 90);
    assert_eq!(
        ev.iter().map(|e| e.0).collect::<Vec<_>>(),
        vec![1, 3],
        "oldest first"
    );
    assert!(c.used_bytes() <= c.budget_bytes());
    // Entries used in the current frame are never evicted: the cache goes over budget instead.
    c.begin_frame();
    assert!(c.get(4).is_some());
    assert!(c.insert(5, "e", 50).is_empty());
    assert_eq!(c.used_bytes(), 140);
    assert!(c.contains(4) && c.contains(5));
    // Replacing an entry accounts its size once.
    c.begin_frame();
    c.insert(5, "e2", 10);
    assert_eq!(c.used_bytes(), 100);
}

#[test]
fn missing_cells_fall_back_to_the_nearest_loaded_ancestor() {
    let cells = records(&Synth { levels: 3, ..SYNTH });
    let index = CellIndex::new(&cells);
    let id = |s: &str| cells.iter().position(|c| c.id == s).unwrap();
    let selected = vec![
        id("2-0-0"),
        id("2-1-0"),
        id("1-1-0"),
        id("1-0-1"),
        id("1-1-1"),
    ];
    let loaded = [id("0-0-0"), id("2-0-0"), id("1-1-0"), id("1-1-1")];
    let dl = resolve_draw_list(&selected, &cells, &index, |i| loaded.contains(&i));
    // 2-1-0 and 1-0-1 are missing: both fall back to the root, which hides everything else.
    assert_eq!(dl.draw, vec![id("0-0-0")]);
    assert_eq!(dl.missing, vec![id("1-0-1"), id("2-1-0")]);
    assert_eq!((dl.substituted, dl.holes), (2, 0));
    let dl = resolve_draw_list(&selected[2..], &cells, &index, |i| {
        i != id("0-0-0") && i != id("1-0-1")
    });
    assert_eq!(dl.draw, vec![id("1-1-0"), id("1-1-1")]);
    assert_eq!(dl.holes, 1);
}

#[test]
fn streamer_loads_in_the_background_and_reports_errors() {
    let mut s: Streamer<usize> = Streamer::new(2, |i| {
        std::thread::sleep(Duration::from_millis(5));
        if i == 13 {
            Err(cliffmap::Error::BadOption("thirteen".into()))
        } else {
            Ok(i * 10)
        }
    });
    assert!(s.request(1) && s.request(13) && s.request(2));
    assert!(!s.request(1), "a pending cell is not requested twice");
    let mut got: Vec<(usize, Result<usize, String>)> = s
        .poll()
        .into_iter()
        .map(|(i, r)| (i, r.map_err(|e| e.to_string())))
        .collect();
    while let Some((i, r)) = s.wait_one() {
        got.push((i, r.map_err(|e| e.to_string())));
    }
    got.sort();
    assert_eq!(
        got,
        vec![
            (1, Ok(10)),
            (2, Ok(20)),
            (13, Err("invalid option: thirteen".into()))
        ]
    );
    assert_eq!(s.pending(), 0);
}

#[test]
fn default_flight_visits_the_steepest_cells_at_low_altitude() {
    use cliffmap::render::{FlightPath, percentile};
    let s = Synth { levels: 3, ..SYNTH };
    let mut cells = records(&s);
    // Give two finest cells strong relief: 3-... cells "2-3-1" (steepest) and "2-0-2".
    for (id, top) in [("2-3-1", 1600.0), ("2-0-2", 1300.0)] {
        let c = cells.iter_mut().find(|c| c.id == id).unwrap();
        c.bbox_max[2] = top;
    }
    let m = cliffmap::store::Manifest {
        format: "cliffmap-store".into(),
        version: 1,
        generator: "t".into(),
        crs: None,
        georef: cliffmap::georef::GridGeoref {
            origin_x: X0,
            origin_y: Y0,
            spacing_x: 1.0,
            spacing_y: 1.0,
        },
        dem: cliffmap::store::DemInfo {
            source: "t".into(),
            width: 2,
            height: 2,
            height_min: 0.0,
            height_max: 0.0,
            void_fraction: 0.0,
        },
        ortho: None,
        ortho_spacing: None,
        quadtree: cliffmap::cells::Quadtree {
            dem_width: 33,
            dem_height: 33,
            finest_intervals: 8,
            levels: 3,
        },
        max_error: 0.05,
        cell_texels: 16,
        reparam: None,
        photos: None,
        build_key: "0".into(),
        cells,
        content_crc32: None,
    };
    let path = FlightPath::default_for(&m).unwrap();
    let first = path.keys[0].position;
    let steep = m.cell("2-3-1").unwrap();
    assert!(first[0] > steep.extent.min_x && first[0] < steep.extent.max_x);
    assert!(first[2] > 1600.0 && first[2] < 1600.0 + steep.extent.width());
    let second = m.cell("2-0-2").unwrap();
    assert!(
        path.keys.iter().any(|k| second.extent.min_x < k.position[0]
            && k.position[0] < second.extent.max_x
            && second.extent.min_y < k.position[1]
            && k.position[1] < second.extent.max_y),
        "the second-steepest cell is visited"
    );
    assert!(path.keys.len() <= 12);
    let cams = path.cameras(50, 320, 200);
    assert_eq!(cams.len(), 50);
    assert!((cams[0].position - DVec3::from(first)).length() < 1e-9);
    assert!((cams[49].position - DVec3::from(path.keys.last().unwrap().position)).length() < 1e-6);
    // Constant speed: consecutive frames are equally far apart along straight segments.
    let d1 = (cams[1].position - cams[0].position).length();
    let d2 = (cams[2].position - cams[1].position).length();
    assert!((d1 - d2).abs() < 1e-6 * d1.max(1.0));
    assert_eq!(percentile(&[5.0, 1.0, 3.0, 2.0, 4.0], 0.5), 3.0);
    assert_eq!(percentile(&[5.0, 1.0, 3.0, 2.0, 4.0], 0.05), 1.0);
    assert_eq!(percentile(&[5.0, 1.0, 3.0, 2.0, 4.0], 0.95), 5.0);
}
