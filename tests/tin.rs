//! TIN simplification: error bound against every sample (independent brute-force check),
//! topology, crack-free borders between cells, determinism, and the Engabreen DEM.

mod common;

use std::collections::{BTreeSet, HashMap};

use cliffmap::cells::{
    LevelBorders, build_dem_tin, build_level, build_tin, level_epsilon, measure_max_error,
    simplify_rect_border,
};
use cliffmap::{CellKey, Dem, GridGeoref, Quadtree, SampleRect, Tin};
use proptest::prelude::*;

/// Height fields of several kinds, generated from a seed.
fn field(w: usize, h: usize, kind: u8, seed: u64) -> Vec<f32> {
    let mut s = seed.wrapping_mul(0x9E3779B97F4A7C15) | 1;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let (a, b, t) = (rnd() - 0.5, rnd() - 0.5, rnd());
    let mut out = Vec::with_capacity(w * h);
    for r in 0..h {
        for c in 0..w {
            let (x, y) = (c as f64, r as f64);
            let v = match kind {
                0 => rnd() * 100.0,
                1 => {
                    if rnd() < 0.03 {
                        (rnd() - 0.5) * 1000.0
                    } else {
                        0.0
                    }
                }
                2 => {
                    let side = a * x + b * y - t * (w.min(h) as f64) * 0.3;
                    (if side > 0.0 { 250.0 } else { 0.0 }) + rnd() * 2.0
                }
                3 => (x * 0.21 + a).sin() * 40.0 + (y * 0.13 + b).cos() * 25.0 + x * 0.5,
                4 => 123.5,
                5 => 2.0 * x - 3.0 * y,
                _ => ((x * 0.17).sin() * 4.0 + (y * 0.11).cos() * 4.0).round() * 10.0,
            };
            out.push(v as f32);
        }
    }
    out
}

fn dem(w: usize, h: usize, heights: Vec<f32>) -> Dem {
    Dem::from_heights(w, h, heights, GridGeoref::new(1000.0, 5000.0, 2.0)).unwrap()
}

fn cross(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> f64 {
    (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
}

/// World-oriented position of a vertex (x = col east, y = -row north), in grid units.
fn world(v: [u32; 2]) -> [f64; 2] {
    [v[0] as f64, -(v[1] as f64)]
}

/// Brute-force, independent of the crate's scan conversion: for every triangle, every
/// sample in its bounding box is tested with barycentric coordinates and the TIN height is
/// the barycentric interpolation. Returns the max error, panicking if a sample is uncovered.
fn brute_force_error(d: &Dem, rect: SampleRect, tin: &Tin) -> f64 {
    let (w, h) = (
        (rect.c1 - rect.c0 + 1) as usize,
        (rect.r1 - rect.r0 + 1) as usize,
    );
    let mut err = vec![f64::NAN; w * h];
    for t in &tin.triangles {
        let v = t.map(|i| tin.vertices[i as usize]);
        let p = v.map(world);
        let hz = v.map(|q| d.at(q[1] as usize, q[0] as usize) as f64);
        let area = cross(p[0], p[1], p[2]);
        let cmin = v.iter().map(|q| q[0]).min().unwrap();
        let cmax = v.iter().map(|q| q[0]).max().unwrap();
        let rmin = v.iter().map(|q| q[1]).min().unwrap();
        let rmax = v.iter().map(|q| q[1]).max().unwrap();
        for r in rmin..=rmax {
            for c in cmin..=cmax {
                let s = world([c, r]);
                let l0 = cross(p[1], p[2], s) / area;
                let l1 = cross(p[2], p[0], s) / area;
                let l2 = cross(p[0], p[1], s) / area;
                if l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12 {
                    continue;
                }
                let z = l0 * hz[0] + l1 * hz[1] + l2 * hz[2];
                let e = (d.at(r as usize, c as usize) as f64 - z).abs();
                let slot = &mut err[(r - rect.r0) as usize * w + (c - rect.c0) as usize];
                *slot = if slot.is_nan() { e } else { slot.max(e) };
            }
        }
    }
    assert!(
        err.iter().all(|e| !e.is_nan()),
        "some samples are not covered by the TIN"
    );
    err.iter().cloned().fold(0.0, f64::max)
}

/// Topology checks: vertices unique and inside the rect, every vertex used, triangles
/// non-degenerate and CCW in world, areas sum to the rect, each directed edge used once,
/// boundary edges exactly on the rect boundary, Euler characteristic of a disc.
fn check_topology(rect: SampleRect, tin: &Tin) {
    let set: BTreeSet<[u32; 2]> = tin.vertices.iter().copied().collect();
    assert_eq!(set.len(), tin.vertices.len(), "duplicate vertices");
    for v in &tin.vertices {
        assert!(
            v[0] >= rect.c0 && v[0] <= rect.c1 && v[1] >= rect.r0 && v[1] <= rect.r1,
            "vertex {v:?} outside"
        );
    }
    for c in [
        [rect.c0, rect.r0],
        [rect.c1, rect.r0],
        [rect.c0, rect.r1],
        [rect.c1, rect.r1],
    ] {
        assert!(set.contains(&c), "corner {c:?} missing");
    }
    let mut used = vec![false; tin.vertices.len()];
    let mut twice_area = 0i64;
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &tin.triangles {
        let v = t.map(|i| tin.vertices[i as usize]);
        let p = v.map(|q| [q[0] as i64, -(q[1] as i64)]);
        let a2 =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        assert!(a2 > 0, "triangle {v:?} degenerate or not CCW in world");
        twice_area += a2;
        for k in 0..3 {
            used[t[k] as usize] = true;
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    assert!(used.iter().all(|&u| u), "unused vertex");
    let rect_area2 = 2 * (rect.c1 - rect.c0) as i64 * (rect.r1 - rect.r0) as i64;
    assert_eq!(twice_area, rect_area2, "triangles do not tile the rect");
    assert!(
        directed.values().all(|&n| n == 1),
        "a directed edge is used twice (non-manifold)"
    );
    let mut undirected = BTreeSet::new();
    for &(a, b) in directed.keys() {
        undirected.insert((a.min(b), a.max(b)));
        if !directed.contains_key(&(b, a)) {
            let (p, q) = (tin.vertices[a as usize], tin.vertices[b as usize]);
            let on = |f: fn(&[u32; 2]) -> u32, val: u32| f(&p) == val && f(&q) == val;
            assert!(
                on(|v| v[0], rect.c0)
                    || on(|v| v[0], rect.c1)
                    || on(|v| v[1], rect.r0)
                    || on(|v| v[1], rect.r1),
                "boundary edge {p:?}-{q:?} not on the rect boundary"
            );
        }
    }
    let euler = tin.vertices.len() as i64 - undirected.len() as i64 + tin.triangles.len() as i64;
    assert_eq!(euler, 1, "Euler characteristic of a disc");
}

/// The TIN's error bound checked by brute force: every sample within `eps`, the reported
/// error equal to the measured one.
fn error_bound_holds(
    d: &Dem,
    rect: SampleRect,
    tin: &Tin,
    eps: f64,
) -> Result<(), proptest::test_runner::TestCaseError> {
    let brute = brute_force_error(d, rect, tin);
    prop_assert!(brute <= eps + 1e-6, "brute-force error {brute} > eps {eps}");
    prop_assert!(
        tin.max_error <= eps,
        "reported {} > eps {eps}",
        tin.max_error
    );
    prop_assert!(
        (brute - tin.max_error).abs() <= 1e-6,
        "reported {} vs brute {brute}",
        tin.max_error
    );
    prop_assert!((measure_max_error(d, rect, tin) - brute).abs() <= 1e-6);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, ..ProptestConfig::default() })]

    #[test]
    fn tin_is_within_epsilon_of_every_sample(
        w in 2usize..80, h in 2usize..80, kind in 0u8..7, seed in any::<u64>(),
        stride_exp in 0u32..5, eps_i in 0usize..5, sub in any::<(u8, u8, u8, u8)>(),
    ) {
        let d = dem(w, h, field(w, h, kind, seed));
        let eps = [0.0, 0.05, 1.0, 7.5, 60.0][eps_i];
        let stride = 1u32 << stride_exp;
        // a random sub-rectangle with at least 2x2 samples
        let c0 = sub.0 as u32 % (w as u32 - 1);
        let r0 = sub.1 as u32 % (h as u32 - 1);
        let c1 = c0 + 1 + sub.2 as u32 % (w as u32 - 1 - c0);
        let r1 = r0 + 1 + sub.3 as u32 % (h as u32 - 1 - r0);
        let rect = SampleRect { c0, r0, c1, r1 };
        let border = simplify_rect_border(&d, rect, stride, eps);
        let tin = build_tin(&d, rect, stride, eps, &border).unwrap();
        check_topology(rect, &tin);
        error_bound_holds(&d, rect, &tin, eps)?;
        if kind == 4 || (kind == 5 && eps > 0.0) {
            // constant and planar fields need only the two corner triangles
            prop_assert_eq!(tin.triangles.len(), 2);
        }
    }

    #[test]
    fn whole_dem_tin_is_within_epsilon_of_every_sample(
        w in 2usize..90, h in 2usize..90, kind in 0u8..7, seed in any::<u64>(),
        eps_i in 0usize..5,
    ) {
        // the whole-DEM TIN refines its outer edge greedily (no pre-simplified border)
        let d = dem(w, h, field(w, h, kind, seed));
        let eps = [0.0, 0.05, 1.0, 7.5, 60.0][eps_i];
        let rect = SampleRect { c0: 0, r0: 0, c1: w as u32 - 1, r1: h as u32 - 1 };
        let tin = build_dem_tin(&d, eps).unwrap();
        check_topology(rect, &tin);
        error_bound_holds(&d, rect, &tin, eps)?;
        let again = build_dem_tin(&d, eps).unwrap();
        prop_assert_eq!(&again.vertices, &tin.vertices);
        prop_assert_eq!(&again.triangles, &tin.triangles);
        if kind == 4 || (kind == 5 && eps > 0.0) {
            prop_assert_eq!(tin.triangles.len(), 2);
        }
    }

    #[test]
    fn neighbouring_cells_share_border_vertices(
        w in 3usize..110, h in 3usize..110, kind in 0u8..7, seed in any::<u64>(),
        s_exp in 1u32..4, eps_i in 0usize..4,
    ) {
        let d = dem(w, h, field(w, h, kind, seed));
        let tree = Quadtree::new(w as u32, h as u32, 1 << s_exp);
        let eps_finest = [0.0, 0.5, 3.0, 20.0][eps_i];
        for level in 0..tree.levels {
            let eps = level_epsilon(&tree, level, eps_finest);
            let cells = build_level(&d, &tree, level, eps_finest).unwrap();
            prop_assert_eq!(cells.len(), tree.cells(level).len());
            let by_key: HashMap<CellKey, (SampleRect, &Tin)> =
                cells.iter().map(|(k, t)| (*k, (tree.clipped(*k).unwrap(), t))).collect();
            for (key, (rect, tin)) in &by_key {
                check_topology(*rect, tin);
                let m = measure_max_error(&d, *rect, tin);
                prop_assert!(m <= eps + 1e-6, "cell {} error {m} > {eps}", key.id());
                prop_assert!((m - tin.max_error).abs() <= 1e-6);
                let side = |t: &Tin, col: Option<u32>, row: Option<u32>| -> BTreeSet<[u32; 2]> {
                    t.vertices.iter().copied()
                        .filter(|v| col.is_none_or(|c| v[0] == c) && row.is_none_or(|r| v[1] == r))
                        .collect()
                };
                let east = CellKey { x: key.x + 1, ..*key };
                if let Some((erect, etin)) = by_key.get(&east) {
                    prop_assert_eq!(erect.c0, rect.c1);
                    prop_assert_eq!(side(tin, Some(rect.c1), None), side(etin, Some(erect.c0), None));
                }
                let south = CellKey { y: key.y + 1, ..*key };
                if let Some((srect, stin)) = by_key.get(&south) {
                    prop_assert_eq!(srect.r0, rect.r1);
                    prop_assert_eq!(side(tin, None, Some(rect.r1)), side(stin, None, Some(srect.r0)));
                }
            }
        }
    }
}

#[test]
fn tiny_flat_and_planar_cells_are_two_triangles() {
    let d = dem(2, 2, vec![1.0, 2.0, 3.0, 9.0]);
    let tin = build_dem_tin(&d, 0.0).unwrap();
    assert_eq!((tin.vertices.len(), tin.triangles.len()), (4, 2));
    check_topology(
        SampleRect {
            c0: 0,
            r0: 0,
            c1: 1,
            r1: 1,
        },
        &tin,
    );
    let d = dem(50, 40, vec![7.0; 2000]);
    let tin = build_dem_tin(&d, 0.0).unwrap();
    assert_eq!(tin.triangles.len(), 2);
    assert_eq!(tin.max_error, 0.0);
    let cells = build_level(&d, &Quadtree::new(50, 40, 8), 3, 0.0).unwrap();
    assert!(
        cells
            .iter()
            .all(|(_, t)| t.triangles.len() == 2 && t.max_error == 0.0)
    );
    // a spike in the middle of a flat square needs its vertex
    let mut hs = vec![0.0f32; 9 * 9];
    hs[4 * 9 + 4] = 10.0;
    let d = dem(9, 9, hs);
    let tin = build_dem_tin(&d, 1.0).unwrap();
    assert!(tin.vertices.contains(&[4, 4]));
    assert!(tin.max_error <= 1.0);
    check_topology(
        SampleRect {
            c0: 0,
            r0: 0,
            c1: 8,
            r1: 8,
        },
        &tin,
    );
    // ... but not when the bound tolerates it
    assert_eq!(build_dem_tin(&d, 10.0).unwrap().triangles.len(), 2);
}

#[test]
fn bad_arguments_are_errors() {
    let d = dem(10, 10, vec![0.0; 100]);
    assert!(
        build_tin(
            &d,
            SampleRect {
                c0: 0,
                r0: 0,
                c1: 10,
                r1: 5
            },
            1,
            1.0,
            &[]
        )
        .is_err()
    );
    assert!(
        build_tin(
            &d,
            SampleRect {
                c0: 3,
                r0: 0,
                c1: 3,
                r1: 5
            },
            1,
            1.0,
            &[]
        )
        .is_err()
    );
    assert!(
        build_tin(
            &d,
            SampleRect {
                c0: 0,
                r0: 0,
                c1: 9,
                r1: 9
            },
            0,
            1.0,
            &[]
        )
        .is_err()
    );
    assert!(build_dem_tin(&d, -1.0).is_err());
    assert!(build_dem_tin(&d, f64::NAN).is_err());
    assert!(build_level(&d, &Quadtree::new(11, 10, 4), 0, 1.0).is_err());
    assert!(build_level(&d, &Quadtree::new(10, 10, 4), 9, 1.0).is_err());
    assert!(LevelBorders::compute(&d, &Quadtree::new(10, 10, 4), 0, f64::INFINITY).is_err());
}

#[test]
fn output_does_not_depend_on_thread_count() {
    let (w, h) = (150, 130);
    let d = dem(
        w,
        h,
        field(w, h, 3, 7)
            .iter()
            .zip(field(w, h, 0, 9))
            .map(|(a, b)| a + b * 0.05)
            .collect(),
    );
    let tree = Quadtree::new(w as u32, h as u32, 16);
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            (0..tree.levels)
                .map(|l| build_level(&d, &tree, l, 0.2).unwrap())
                .collect::<Vec<_>>()
        })
    };
    assert_eq!(run(1), run(2));
    assert_eq!(
        build_dem_tin(&d, 0.3).unwrap(),
        build_dem_tin(&d, 0.3).unwrap()
    );
}

fn engabreen() -> Dem {
    let path = common::real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes.len(), 507 * 590 * 4, "{}", path.display());
    let heights = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Dem::from_heights(
        507,
        590,
        heights,
        GridGeoref::new(445302.17, 7396769.45, 3.0),
    )
    .unwrap()
}

#[test]
fn engabreen_every_cell_of_every_level_is_within_its_bound() {
    let d = engabreen();
    let tree = Quadtree::new(507, 590, 32);
    let finest = 0.5;
    let mut total = 0;
    for level in 0..tree.levels {
        let eps = level_epsilon(&tree, level, finest);
        let cells = build_level(&d, &tree, level, finest).unwrap();
        assert_eq!(cells.len(), tree.cells(level).len());
        for (key, tin) in &cells {
            let rect = tree.clipped(*key).unwrap();
            let m = measure_max_error(&d, rect, tin);
            assert!(m <= eps + 1e-9, "cell {}: error {m} > {eps}", key.id());
            assert!((m - tin.max_error).abs() < 1e-9);
            assert!(tin.triangles.len() >= 2);
            total += tin.triangles.len();
        }
        eprintln!(
            "level {level}: eps {eps} m, {} cells, {total} triangles so far",
            cells.len()
        );
    }
    // whole-DEM TIN at the finest bound, checked independently
    let rect = SampleRect {
        c0: 0,
        r0: 0,
        c1: 506,
        r1: 589,
    };
    let tin = build_dem_tin(&d, finest).unwrap();
    check_topology(rect, &tin);
    let brute = brute_force_error(&d, rect, &tin);
    assert!(brute <= finest + 1e-6, "{brute}");
    // a real glacier + rock-wall DEM is far from flat: the TIN must be substantially refined
    assert!(tin.triangles.len() > 10_000, "{}", tin.triangles.len());
}
