//! Which patch matches one rotation explains: a RANSAC over pairs of matches for photos taken
//! from the same place ([`crate::register::pairs::ties`]), so that a surface that moved between the shots (a
//! glacier, clouds, water) cannot pull the rotation fit, and so that a scene with two
//! motions of similar support is recognised as ambiguous instead of being fitted to one of
//! them silently.
//!
//! Model: photo B is photo A's camera turned (same position and intrinsics). A match's
//! world bearing is A's ray through its pixel in A; its bearing in B's camera frame is the
//! camera-frame ray of A's intrinsics through its pixel in B. Two matches with bearings at
//! least 0.1° apart give a rotation ([`crate::register::rotation_from_bearings`]); a match agrees with
//! it when the angle between the rotated world bearing and its B bearing, times the focal
//! length, is at most the tolerance (pixels). Hypotheses: every pair when there are at most
//! 2 000, else 2 000 pairs from a fixed pseudo-random sequence. The largest set wins (ties:
//! the earlier hypothesis); the same search over the matches it leaves gives the second
//! motion's support. Deterministic.

use glam::DVec3;

use crate::camera::CameraModel;
use crate::register::gcps::bearings::{rotation_from_bearings, sample_picker};
use crate::register::pairs::pair::PatchMatch;

/// Most rotation hypotheses tried.
const MAX_HYPOTHESES: usize = 2000;
/// Least angle between the two bearings of a hypothesis, radians (0.1°).
const MIN_SPREAD_RAD: f64 = 1.745e-3;

/// The outcome of [`rotation_consensus`].
#[derive(Clone, Debug, PartialEq)]
pub struct RotationConsensus {
    /// Indices (into the matches given) that the best rotation explains, ascending.
    pub inliers: Vec<usize>,
    /// How many of the remaining matches a second rotation explains (the support of another
    /// motion in the scene; 0 when none).
    pub second: usize,
}

/// The matches one rotation of camera `a` explains within `tol_px` pixels, and the support
/// of the best second rotation among the others (see the module docs (`src/register/consensus.rs`)). Matches
/// whose pixels give no ray (outside the model's domain) are never inliers.
pub fn rotation_consensus(
    a: &CameraModel,
    matches: &[PatchMatch],
    tol_px: f64,
) -> RotationConsensus {
    // per usable match: its index, its world bearing through A and its camera-frame
    // bearing in B (A's intrinsics)
    let rays = a.ray_caster();
    let usable: Vec<Bearing> = matches
        .iter()
        .enumerate()
        .filter_map(|(i, m)| {
            let w = rays.ray(m.a[0], m.a[1])?;
            let b = a.world_to_camera * rays.ray(m.b[0], m.b[1])?;
            Some((i, w.normalize(), b.normalize()))
        })
        .collect();
    let cos_tol = (tol_px / a.fx.max(a.fy).max(1e-9)).cos();
    let best = best_set(&usable, cos_tol);
    let rest: Vec<Bearing> = usable
        .iter()
        .copied()
        .filter(|u| best.binary_search(&u.0).is_err())
        .collect();
    let second = best_set(&rest, cos_tol).len();
    RotationConsensus {
        inliers: best,
        second,
    }
}

/// A match's index, world bearing and camera bearing (unit vectors).
type Bearing = (usize, DVec3, DVec3);

/// The indices (ascending) of the largest subset of `among` that one rotation explains to
/// within the angle whose cosine is `cos_tol`.
fn best_set(among: &[Bearing], cos_tol: f64) -> Vec<usize> {
    let n = among.len();
    if n < 2 {
        return Vec::new();
    }
    let mut best: Vec<usize> = Vec::new();
    let try_pair = |(_, wi, bi): Bearing, (_, wj, bj): Bearing, best: &mut Vec<usize>| {
        if wi.cross(wj).length() < MIN_SPREAD_RAD || bi.cross(bj).length() < MIN_SPREAD_RAD {
            return;
        }
        let Some(r) = rotation_from_bearings(&[bi, bj], &[wi, wj], &[1.0, 1.0]) else {
            return;
        };
        let set: Vec<usize> = among
            .iter()
            .filter(|(_, w, b)| (r * *w).dot(*b) >= cos_tol)
            .map(|u| u.0)
            .collect();
        if set.len() > best.len() {
            *best = set;
        }
    };
    if n * (n - 1) / 2 <= MAX_HYPOTHESES {
        for x in 0..n {
            for y in x + 1..n {
                try_pair(among[x], among[y], &mut best);
            }
        }
    } else {
        let mut pick = sample_picker(0x9e37_79b9_7f4a_7c15);
        for _ in 0..MAX_HYPOTHESES {
            let x = pick(n);
            let y = (x + 1 + pick(n - 1)) % n;
            try_pair(among[x], among[y], &mut best);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_from_yaw_pitch_roll;

    /// Matches on a 12 × 8 grid of A's image seen by B (A turned by `turn`), the matches
    /// listed in `moved` shifted by `shift` pixels in B, plus `spread · (k mod 5)` in u.
    fn scene(
        turn: [f64; 3],
        moved: impl Fn(usize) -> bool,
        shift: [f64; 2],
        spread: f64,
    ) -> (CameraModel, Vec<PatchMatch>, CameraModel) {
        let a = CameraModel::with_fov(
            DVec3::new(10.0, 20.0, 300.0),
            rotation_from_yaw_pitch_roll(0.4, 0.1, 0.0),
            1200,
            800,
            0.8,
        );
        let mut b = a;
        b.world_to_camera = rotation_from_yaw_pitch_roll(0.4 + turn[0], 0.1 + turn[1], turn[2]);
        let mut out = Vec::new();
        for k in 0..96 {
            let (u, v) = (
                50.0 + 100.0 * (k % 12) as f64,
                50.0 + 100.0 * (k / 12) as f64,
            );
            let d = a.pixel_ray(u, v).unwrap();
            let mut pb = b.project(a.position + d * 1e4).unwrap();
            if moved(k) {
                pb = [pb[0] + shift[0] + spread * (k % 5) as f64, pb[1] + shift[1]];
            }
            out.push(PatchMatch {
                a: [u, v],
                b: pb,
                ncc: 0.95,
            });
        }
        (a, out, b)
    }

    #[test]
    fn the_still_background_wins_over_a_smaller_moving_part() {
        // 30 % of the matches on a surface that moved by about 6 px between the shots
        let (a, m, b) = scene([0.002, -0.001, 0.0005], |k| k % 10 < 3, [6.0, 2.0], 0.8);
        let c = rotation_consensus(&a, &m, 1.0);
        let want: Vec<usize> = (0..96).filter(|k| k % 10 >= 3).collect();
        assert_eq!(c.inliers, want);
        // the moved part's own shifts spread over 3.2 px: no rotation takes all of it
        assert!(c.second < c.inliers.len() / 2, "{}", c.second);
        let r = rotation_from_bearings(
            &c.inliers
                .iter()
                .map(|&i| a.world_to_camera * a.pixel_ray(m[i].b[0], m[i].b[1]).unwrap())
                .collect::<Vec<_>>(),
            &c.inliers
                .iter()
                .map(|&i| a.pixel_ray(m[i].a[0], m[i].a[1]).unwrap())
                .collect::<Vec<_>>(),
            &vec![1.0; c.inliers.len()],
        )
        .unwrap();
        assert!(r.abs_diff_eq(b.world_to_camera, 1e-9));
    }

    #[test]
    fn two_motions_of_similar_support_are_both_reported() {
        // half of the matches moved uniformly: a second rotation explains all of them
        let (a, m, _) = scene([0.002, 0.0, 0.0], |k| k % 2 == 0, [5.0, 0.0], 0.0);
        let c = rotation_consensus(&a, &m, 1.0);
        assert!(
            c.inliers.len() >= 40 && c.second >= 40,
            "{} {}",
            c.inliers.len(),
            c.second
        );
    }

    #[test]
    fn too_few_matches_give_an_empty_set() {
        let (a, m, _) = scene([0.0; 3], |_| false, [0.0; 2], 0.0);
        assert!(rotation_consensus(&a, &m[..1], 1.0).inliers.is_empty());
        assert!(rotation_consensus(&a, &[], 1.0).inliers.is_empty());
    }
}
