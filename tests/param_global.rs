//! The global finish (projected Newton on the symmetric Dirichlet energy) and the
//! boundary self-overlap check and repair.

mod param_util;

use cliffmap::{ParamMesh, ParamOptions, chart_metrics, parameterize};
use param_util::{box_plateau, height_grid, wall};

/// A helicoid strip (a spiral ramp) turning `turns` times around the z axis between
/// radii r0 and r1, with a small pitch: nearly isometric to a flat annulus that turns
/// `turns` times, so a low-distortion layout with turns > 1 folds over itself.
fn helicoid(turns: f64, r0: f64, r1: f64, pitch: f64, nr: usize, na: usize) -> ParamMesh {
    let mut positions = Vec::new();
    for j in 0..na {
        let a = turns * std::f64::consts::TAU * j as f64 / (na - 1) as f64;
        for i in 0..nr {
            let r = r0 + (r1 - r0) * i as f64 / (nr - 1) as f64;
            positions.push([r * a.cos(), r * a.sin(), pitch * a]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..na - 1 {
        for i in 0..nr - 1 {
            let p = (j * nr + i) as u32;
            let (q, s, t) = (p + 1, p + nr as u32, p + nr as u32 + 1);
            // counter-clockwise seen from +z (radius outwards, angle increasing)
            triangles.push([p, q, t]);
            triangles.push([p, t, s]);
        }
    }
    ParamMesh {
        positions,
        triangles,
    }
}

#[test]
fn a_strip_turning_one_and_a_half_times_is_repaired_to_a_simple_boundary() {
    let m = helicoid(1.5, 10.0, 14.0, 0.3, 5, 121);
    let ch = parameterize(&m, &ParamOptions::default()).unwrap();
    // Without the check the hierarchy's low-distortion layout wraps over itself.
    let no_finish = ParamOptions {
        newton_iterations: 0,
        ..Default::default()
    };
    let plain = parameterize(&m, &no_finish).unwrap();
    assert!(
        plain.overlap_repaired,
        "the hierarchy's layout was expected to overlap"
    );
    assert!(ch.overlap_repaired);
    assert_eq!(ch.metrics.flipped, 0, "{:?}", ch.metrics);
    assert_eq!(ch.metrics.boundary_crossings, 0, "{:?}", ch.metrics);
    assert!(
        ch.uvs
            .iter()
            .all(|uv| (0.0..=1.0).contains(&uv[0]) && (0.0..=1.0).contains(&uv[1]))
    );
    // A simple chart of a strip longer than a full turn must distort, but stays bounded.
    assert!(ch.metrics.symmetric_dirichlet_mean.is_finite());
}

#[test]
fn the_repair_also_works_for_other_thetas() {
    // θ ≠ 1: the guarded local relaxation does the repair.
    let m = helicoid(1.5, 10.0, 14.0, 0.3, 5, 121);
    for theta in [0.0, 3.0] {
        let ch = parameterize(
            &m,
            &ParamOptions {
                theta,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(ch.overlap_repaired, "theta {theta}");
        assert_eq!(ch.metrics.flipped, 0, "theta {theta}");
        assert_eq!(ch.metrics.boundary_crossings, 0, "theta {theta}");
    }
}

#[test]
fn a_strip_turning_less_than_once_is_not_touched_by_the_repair() {
    let m = helicoid(0.6, 10.0, 14.0, 0.3, 5, 49);
    let ch = parameterize(&m, &ParamOptions::default()).unwrap();
    assert!(!ch.overlap_repaired);
    assert_eq!(ch.metrics.boundary_crossings, 0);
    assert_eq!(ch.metrics.flipped, 0);
    // Nearly developable: close to an isometry.
    assert!(
        ch.metrics.symmetric_dirichlet_excess() < 0.01,
        "{:?}",
        ch.metrics
    );
}

#[test]
fn the_global_finish_lowers_the_excess_and_never_flips() {
    for (name, m) in [
        ("wall 80", wall(17, 80.0)),
        ("box 85", box_plateau(17, 85.0)),
        (
            "hills",
            height_grid(17, |r, c| {
                6.0 * ((0.9 * r as f64).sin() * (0.6 * c as f64).cos())
            }),
        ),
    ] {
        let off = parameterize(
            &m,
            &ParamOptions {
                newton_iterations: 0,
                ..Default::default()
            },
        )
        .unwrap();
        let on = parameterize(&m, &ParamOptions::default()).unwrap();
        assert_eq!(on.metrics.flipped, 0, "{name}");
        assert_eq!(on.metrics.boundary_crossings, 0, "{name}");
        let (a, b) = (
            off.metrics.symmetric_dirichlet_excess(),
            on.metrics.symmetric_dirichlet_excess(),
        );
        assert!(b <= a * (1.0 + 1e-9), "{name}: excess {a} -> {b}");
        // The reported metrics agree with an independent evaluation of the chart.
        let re = chart_metrics(&m.positions, &m.triangles, &on.uvs, None).unwrap();
        assert!(
            (re.symmetric_dirichlet_mean - on.metrics.symmetric_dirichlet_mean).abs() < 1e-9,
            "{name}"
        );
    }
}

#[test]
fn a_developable_wall_becomes_an_isometry() {
    // A straight 80° wall is developable: converged, the excess is 0.
    let m = wall(17, 80.0);
    let ch = parameterize(
        &m,
        &ParamOptions {
            newton_tolerance: 1e-8,
            newton_iterations: 50,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        ch.metrics.symmetric_dirichlet_excess() < 1e-5,
        "{:?}",
        ch.metrics
    );
}

/// The jagged random field (8×8, unit spacing, heights ±14 m) on which the hierarchy's
/// finished layout was worse than the plain orthographic projection (found by
/// `param_props`): the projection start must be taken and win, for θ = 1 and θ = 3.
#[test]
fn a_jagged_field_finishes_from_the_projection_when_that_is_better() {
    let (n, amp) = (8usize, 27.799523817048335);
    let mut s = 18350060494918895370u64 | 1;
    let h: Vec<f64> = (0..n * n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            amp * ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        })
        .collect();
    let m = height_grid(n, |r, c| h[r * n + c]);
    let ortho: Vec<[f64; 2]> = m.positions.iter().map(|p| [p[0], p[1]]).collect();
    let plain = parameterize(&m, &ParamOptions::default()).unwrap();
    assert!(
        plain.projection_start,
        "this field's hierarchy layout is known to lose to the projection"
    );
    for theta in [1.0, 3.0] {
        let ch = parameterize(
            &m,
            &ParamOptions {
                theta,
                ..ParamOptions::default()
            },
        )
        .unwrap();
        let ours =
            cliffmap::param::degener_energy(&m.positions, &m.triangles, &ch.uvs, theta).unwrap();
        let o = cliffmap::param::degener_energy(&m.positions, &m.triangles, &ortho, theta).unwrap();
        assert!(ours < o, "theta {theta}: ours {ours} ortho {o}");
        assert_eq!(ch.metrics.flipped, 0);
        assert_eq!(ch.metrics.boundary_crossings, 0);
    }
}
