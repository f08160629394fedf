//! Parameterization of hand-made hard cases: near-vertical walls, a box plateau, slivers,
//! UTM-sized coordinates, a flat cell, a spike, and invalid input.

mod param_util;

use cliffmap::param::degener_energy;
use cliffmap::{Error, ParamMesh, ParamOptions, chart_metrics, parameterize};
use param_util::{box_plateau, grid_mesh, height_grid, wall};

fn ortho_uvs(m: &ParamMesh) -> Vec<[f64; 2]> {
    m.positions.iter().map(|p| [p[0], p[1]]).collect()
}

fn check_valid(m: &ParamMesh, what: &str) -> cliffmap::Chart {
    let ch = parameterize(m, &ParamOptions::default()).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(ch.uvs.len(), m.positions.len());
    assert_eq!(ch.metrics.flipped, 0, "{what}: {:?}", ch.metrics);
    for uv in &ch.uvs {
        assert!(
            uv.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)),
            "{what}: uv {uv:?}"
        );
    }
    // The metrics reported are those of the returned UVs.
    let again = chart_metrics(&m.positions, &m.triangles, &ch.uvs, None).unwrap();
    assert_eq!(again, ch.metrics);
    ch
}

#[test]
fn near_vertical_walls_unfold() {
    for deg in [80.0, 89.0, 89.9] {
        let m = wall(17, deg);
        let ch = check_valid(&m, &format!("wall {deg}"));
        let ortho = chart_metrics(&m.positions, &m.triangles, &ortho_uvs(&m), None).unwrap();
        // A straight wall is developable: the chart should be an isometry (the global
        // finish converges to it even at 89.9°, triangles 1 x 573 m), while the
        // orthographic map squeezes the wall by cos(deg) (mean angle distortion ~290 at 89.9°).
        assert!(
            ch.metrics.angle_distortion_mean < 1.001,
            "wall {deg}: {:?}",
            ch.metrics
        );
        assert!(
            ch.metrics.area_distortion_mean < 1e-3,
            "wall {deg}: {:?}",
            ch.metrics
        );
        assert!(
            ch.metrics.symmetric_dirichlet_excess() < 1e-3,
            "wall {deg}: {:?}",
            ch.metrics
        );
        assert!(
            ortho.angle_distortion_mean > 2.5 * ch.metrics.angle_distortion_mean,
            "wall {deg}: ortho {:?}",
            ortho
        );
        // The hierarchy's local relaxation alone converges slowly under such anisotropy.
        if deg > 89.5 {
            let local = ParamOptions {
                newton_iterations: 0,
                relax_tolerance: 1e-4,
                max_sweeps: 32,
                ..ParamOptions::default()
            };
            let ch2 = parameterize(&m, &local).unwrap();
            assert_eq!(ch2.metrics.flipped, 0);
            assert!(ch2.metrics.angle_distortion_mean > 1.2, "{:?}", ch2.metrics);
        }
        assert!(ch.metrics.rel_texel.is_finite() && ch.metrics.rel_texel > 1.0);
    }
}

#[test]
fn box_plateau_has_no_flips_and_beats_ortho() {
    let m = box_plateau(21, 89.0);
    let ch = check_valid(&m, "box");
    let theta = ParamOptions::default().theta;
    let ours = degener_energy(&m.positions, &m.triangles, &ch.uvs, theta).unwrap();
    let ortho = degener_energy(&m.positions, &m.triangles, &ortho_uvs(&m), theta).unwrap();
    assert!(ours < 0.5 * ortho, "box: ours {ours} ortho {ortho}");
    let om = chart_metrics(&m.positions, &m.triangles, &ortho_uvs(&m), None).unwrap();
    assert!(ch.metrics.symmetric_dirichlet_mean < om.symmetric_dirichlet_mean);
}

#[test]
fn sliver_triangles_are_accepted() {
    // Columns alternately 1 m and 1 mm apart: triangles with aspect ratio ~1000.
    let mut xs = vec![0.0];
    for i in 0..12 {
        let last = xs[xs.len() - 1];
        xs.push(last + if i % 2 == 0 { 1.0 } else { 1e-3 });
    }
    let ys: Vec<f64> = (0..13).map(|i| i as f64).collect();
    let m = grid_mesh(
        &xs,
        &ys,
        |r, c| 0.3 * r as f64 + if c > 6 { 5.0 } else { 0.0 },
        [0.0; 3],
    );
    let ch = check_valid(&m, "slivers");
    assert!(ch.metrics.area_distortion_mean.is_finite());
}

#[test]
fn utm_offsets_give_the_same_chart_as_a_local_frame() {
    let z = |r: usize, c: usize| {
        40.0 * ((r as f64) * 0.4).sin() * ((c as f64) * 0.3).cos() + 3.0 * c as f64
    };
    let xs: Vec<f64> = (0..17).map(|i| 3.0 * i as f64).collect();
    let local = grid_mesh(&xs, &xs, z, [0.0; 3]);
    let utm = grid_mesh(&xs, &xs, z, [512_345.25, 7_012_345.75, 2000.0]);
    let a = check_valid(&local, "local");
    let b = check_valid(&utm, "utm");
    for (p, q) in a.uvs.iter().zip(&b.uvs) {
        assert!(
            (p[0] - q[0]).abs() < 1e-6 && (p[1] - q[1]).abs() < 1e-6,
            "{p:?} vs {q:?}"
        );
    }
    assert!((a.metrics.angle_distortion_mean - b.metrics.angle_distortion_mean).abs() < 1e-6);
}

#[test]
fn flat_cell_is_a_similarity_of_the_orthographic_map() {
    let xs: Vec<f64> = (0..13).map(|i| 2.0 * i as f64).collect();
    let ys: Vec<f64> = (0..7).map(|i| 3.0 * i as f64).collect();
    let m = grid_mesh(&xs, &ys, |_, _| 150.0, [0.0; 3]);
    let ch = check_valid(&m, "flat");
    assert!(
        (ch.metrics.angle_distortion_mean - 1.0).abs() < 1e-6,
        "{:?}",
        ch.metrics
    );
    assert!(ch.metrics.area_distortion_max < 1e-6, "{:?}", ch.metrics);
    // Fit uv = s R xy + t from two vertices, check all others.
    let p0 = m.positions[0];
    let p1 = m.positions[m.positions.len() - 1];
    let (u0, u1) = (ch.uvs[0], ch.uvs[m.positions.len() - 1]);
    // Complex ratio (u1-u0)/(p1-p0) = s·e^{iφ}.
    let (dx, dy) = (p1[0] - p0[0], p1[1] - p0[1]);
    let (du, dv) = (u1[0] - u0[0], u1[1] - u0[1]);
    let den = dx * dx + dy * dy;
    let (a, b) = ((du * dx + dv * dy) / den, (dv * dx - du * dy) / den);
    for (p, uv) in m.positions.iter().zip(&ch.uvs) {
        let (x, y) = (p[0] - p0[0], p[1] - p0[1]);
        let pred = [u0[0] + a * x - b * y, u0[1] + b * x + a * y];
        assert!(
            (pred[0] - uv[0]).abs() < 1e-7 && (pred[1] - uv[1]).abs() < 1e-7,
            "{pred:?} vs {uv:?}"
        );
    }
    // The whole rectangle uses its best rotation: aligned with the texture axes.
    let used = ch.metrics.used_fraction;
    let g = 1.0 - 2.0 * 2.0 / 256.0;
    assert!((used - g * g * (18.0 / 24.0)).abs() < 1e-6, "used {used}");
}

#[test]
fn single_huge_spike() {
    let m = height_grid(15, |r, c| if r == 7 && c == 7 { 1000.0 } else { 0.0 });
    let ch = check_valid(&m, "spike");
    let ortho = chart_metrics(&m.positions, &m.triangles, &ortho_uvs(&m), None).unwrap();
    assert!(
        ch.metrics.symmetric_dirichlet_mean < ortho.symmetric_dirichlet_mean,
        "{:?} vs {:?}",
        ch.metrics,
        ortho
    );
}

#[test]
fn deterministic() {
    let m = box_plateau(17, 85.0);
    let a = parameterize(&m, &ParamOptions::default()).unwrap();
    let b = parameterize(&m, &ParamOptions::default()).unwrap();
    assert_eq!(a, b);
}

#[test]
fn single_triangle_and_bad_meshes() {
    let tri = ParamMesh {
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 5.0], [0.0, 1.0, 0.0]],
        triangles: vec![[0, 1, 2]],
    };
    let ch = check_valid(&tri, "triangle");
    assert!(
        ch.metrics.area_distortion_max < 1e-9
            && (ch.metrics.angle_distortion_max - 1.0).abs() < 1e-9
    );

    let base = height_grid(4, |_, _| 0.0);
    let mut cases: Vec<(&str, ParamMesh)> = Vec::new();
    let mut m = base.clone();
    m.triangles[0][1] = 99;
    cases.push(("index out of range", m));
    let mut m = base.clone();
    m.triangles[0] = [0, 0, 1];
    cases.push(("repeated vertex", m));
    let mut m = base.clone();
    m.triangles.push(m.triangles[3]);
    cases.push(("duplicate", m));
    let mut m = base.clone();
    m.triangles[2].swap(0, 1);
    cases.push(("flipped orientation", m));
    let mut m = base.clone();
    m.positions[5][0] = f64::NAN;
    cases.push(("nan", m));
    let mut m = base.clone();
    m.positions.push([9.0, 9.0, 9.0]);
    cases.push(("unused vertex", m));
    let mut m = base.clone();
    let t = m.positions[1];
    m.positions[0] = t;
    cases.push(("zero area", m));
    // Two squares touching at one vertex (non-manifold vertex).
    let mut m = height_grid(2, |_, _| 0.0);
    let k = m.positions.len() as u32;
    m.positions
        .extend([[2.0, 1.0, 0.0], [2.0, 2.0, 0.0], [1.0, 2.0, 0.0]]);
    m.triangles.extend([[3, k, k + 1], [3, k + 1, k + 2]]);
    cases.push(("non-manifold vertex", m));
    // An annulus (3x3 grid without its centre quad): not a disc.
    let mut m = height_grid(4, |_, _| 0.0);
    m.triangles.retain(|t| !(t.contains(&5) && t.contains(&10)));
    cases.push(("annulus", m));
    cases.push(("empty", ParamMesh::default()));
    for (what, m) in cases {
        match parameterize(&m, &ParamOptions::default()) {
            Err(Error::BadOption(msg)) => assert!(msg.contains("mesh"), "{what}: {msg}"),
            other => panic!("{what}: expected an error, got {other:?}"),
        }
    }
}
