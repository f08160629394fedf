//! A search over the camera position by the mutual-information score itself (docs/
//! registration.md, "Position by the score at full resolution"): an experiment
//! ([`super::TerrainOptions::position_search_m`], `cliffmap register --position-search-m`,
//! off by default).
//!
//! Input: the angle search's result (found with the rough position) and the photo. Output:
//! the camera at the position found, and how far the search was from settling. Per round, along three axes in turn (up,
//! horizontal across the view, horizontal along it), the position is tried at `±h` and
//! `±2h`. A trial camera is first turned so that the point it looked at (the image centre
//! at the view's median distance) stays in the centre, with the same horizon tilt; then the
//! terrain is sampled from it at every pixel of the photo reduced to at most
//! [`DENSE_SAMPLES`] pixels (no silhouette band, so every trial is scored over the same
//! photo pixels and only the labels follow the camera), its free angles and focal length
//! are refitted (Nelder-Mead), and sampled and refitted once more. The camera moves to the
//! vertex of the least-squares parabola through the five scores ([`peak_offset`]), not to
//! the best trial. `h` halves each round. (Since 2026-12-06, session 26: before, the
//! trials were scored on one band of samples cast from the centre camera, which pulled
//! cameras near the ground upwards and backwards, and the axes went along, across, up: the
//! along-view profile is flat and leans the wrong way until the other two are right.)

use glam::DVec3;
use rayon::prelude::*;

use super::mi::GreyImage;
use super::view::LabelledTerrain;
use super::view::Sample;
use super::{Space, refine_on};
use crate::camera::{rotation_look_at, yaw_pitch_roll_from_rotation};
use crate::error::Result;
use crate::register::params::CameraParams;

/// `cam` moved to `position`, turned so that the point `depth` metres ahead of its old
/// position along its view axis stays on its view axis, with the same turn about that axis
/// against a level camera (the horizon's tilt in the image is kept).
pub(super) fn moved_keeping_target(
    cam: &CameraParams,
    position: DVec3,
    depth: f64,
) -> CameraParams {
    let model = cam.camera();
    let target = model.position + model.forward() * depth;
    let mut out = *cam;
    out.position = position;
    // the camera's turn about its view axis against a level camera looking at the target,
    // kept at the new position (so the horizon keeps its tilt in the image)
    if let (Some(level_old), Some(level_new)) = (
        rotation_look_at(model.position, target),
        rotation_look_at(position, target),
    ) {
        let (y, p, r) = yaw_pitch_roll_from_rotation(
            &(model.world_to_camera * level_old.transpose() * level_new),
        );
        out.angles = [y, p, r];
    }
    out
}

/// The three search axes for a camera looking along `forward`: horizontal along the view,
/// horizontal across it, up (unit vectors; east and north when the view is vertical).
fn axes(forward: DVec3) -> [DVec3; 3] {
    let h = DVec3::new(forward.x, forward.y, 0.0);
    let along = if h.length() > 1e-6 {
        h.normalize()
    } else {
        DVec3::Y
    };
    let across = DVec3::new(along.y, -along.x, 0.0);
    [along, across, DVec3::Z]
}

/// The search described in the module comment from `cam`, on `photo` reduced at least
/// `finest` times, steps `step_m`, `step_m / 2`, ... for `rounds` rounds; returns the
/// camera found (its score on the search's samples is not comparable with scores at
/// another scale, so not returned), the number of score evaluations, and the largest amount by
/// which a trial of the last round scored above its axis's centre (near 0 when the search
/// settled on a peak along every axis; infinite when a trial of that round could not be
/// scored; see [`SETTLED`]).
pub(super) fn search_position(
    terrain: &LabelledTerrain,
    space: &Space,
    cam: CameraParams,
    photo: &super::MaskedPhoto,
    finest: u32,
    step_m: f64,
    rounds: usize,
) -> Result<(CameraParams, usize, f64)> {
    let (mut best, mut evals) = (cam, 0usize);
    let mut above = 0.0f64;
    let depth = space.depth;
    let factor = dense_factor(photo.width(), photo.height()).max(finest);
    let grey = photo.grey(factor);
    let grey = &grey;
    // a trial: moved, sampled on the full grid, refitted, sampled and refitted again
    let trial = |from: &CameraParams, p: DVec3| -> Result<(CameraParams, f64, usize)> {
        let c = moved_keeping_target(from, p, depth);
        // bounds from the rough camera as it would look from `p` (since session 28: from
        // the rough camera itself, trials that had to turn for the move fell outside them)
        let space = &space.moved_to(p);
        let s = dense_samples(terrain, &c, grey)?;
        let (c1, _, e1) = refine_on(&s, space, &c, grey, 2.0);
        let s = dense_samples(terrain, &c1, grey)?;
        let (c2, v, e2) = refine_on(&s, space, &c1, grey, 2.0);
        Ok((c2, v, e1 + e2))
    };
    let mut h = step_m;
    for round in 0..rounds {
        let [along, across, up] = axes(best.camera().forward());
        for axis in [up, across, along] {
            let (p0, c0) = (best.position, best);
            let offsets = [-2.0 * h, -h, 0.0, h, 2.0 * h];
            let trials: Vec<(CameraParams, f64, usize)> = offsets
                .par_iter()
                .with_max_len(1)
                .map(|&t| trial(&c0, p0 + axis * t))
                .collect::<Result<_>>()?;
            let mut points = Vec::with_capacity(offsets.len());
            for (t, (_, s, e)) in offsets.iter().zip(&trials) {
                evals += e;
                points.push((*t, *s));
            }
            let t = peak_offset(&points, 2.0 * h);
            if round + 1 == rounds {
                let top = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
                above = above.max(top - points[2].1);
                // a trial that could not be scored (turned beyond the search's bounds, or
                // seeing too little terrain: 0 or the score's floor of 1) leaves the
                // position unjudged
                if points.iter().any(|p| !(p.1 > 1.0)) {
                    above = f64::INFINITY;
                }
            }
            let (c, _, e) = if t == 0.0 {
                trials[2]
            } else {
                trial(&c0, p0 + axis * t)?
            };
            evals += e;
            best = c;
        }
        h /= 2.0;
    }
    Ok((best, evals, above))
}

/// How far (normalised mutual information) a trial of the search's last round may score
/// above its axis's centre for the search to count as settled: a search that ends on a
/// slope (a trial `h` or `2h` away scores higher) has not found the position, and its
/// photo keeps its given camera. Measured on the demo scene's 8 starts (docs/
/// registration.md, "Position by the score at full resolution"): the searches that did not
/// settle ended 1.2–2.9 m from the truth, those that did 0.44–0.51 m (and one 8.3 m off,
/// refused by its restarts); the noise between a refitted centre and its neighbours is
/// about 0.001.
pub const SETTLED: f64 = 0.002;

/// Most samples a position trial casts (one per pixel of the photo reduced by
/// [`dense_factor`]: the demo's 1600 × 1200 photos by 2, a 12-MP photo by 4).
const DENSE_SAMPLES: u64 = 1 << 20;

/// The smallest power-of-two reduction (at most 64) of a `w × h` photo to at most
/// [`DENSE_SAMPLES`] pixels.
fn dense_factor(w: u32, h: u32) -> u32 {
    let mut f = 1u32;
    while (w / f) as u64 * (h / f) as u64 > DENSE_SAMPLES && f < 64 {
        f *= 2;
    }
    f
}

/// Every grid sample of the view of `c` at `grey`'s scale (no band: each trial's score is
/// over the same photo pixels).
fn dense_samples(
    terrain: &LabelledTerrain,
    c: &CameraParams,
    grey: &GreyImage,
) -> Result<Vec<Sample>> {
    terrain.sample(&super::scaled(&c.camera(), grey), 1.0, 0.04, None)
}

/// Scores below the best by more than this are left out of the parabola (a camera moved
/// into the terrain's shadow or under a ridge: the score falls off a cliff, not a parabola).
const FIT_DROP: f64 = 0.01;

/// Where along an axis the score peaks, from noisy scores `points` (offset, score): the
/// vertex of the least-squares parabola through the points within [`FIT_DROP`] of the
/// best, when concave, clamped to `±reach`; otherwise the best point's offset.
fn peak_offset(points: &[(f64, f64)], reach: f64) -> f64 {
    let top = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let best = points
        .iter()
        .copied()
        .filter(|p| p.1 == top)
        .map(|p| p.0)
        .next()
        .unwrap_or(0.0);
    let kept: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.1 >= top - FIT_DROP && p.1.is_finite())
        .collect();
    if kept.len() < 3 {
        return best;
    }
    // least squares for s = a + b t + c t² (normal equations)
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    let mut r = nalgebra::Vector3::<f64>::zeros();
    for &(t, s) in &kept {
        let v = nalgebra::Vector3::new(1.0, t, t * t);
        m += v * v.transpose();
        r += v * s;
    }
    let Some(x) = m.lu().solve(&r) else {
        return best;
    };
    let (b, c) = (x[1], x[2]);
    if !(c < 0.0) {
        return best;
    }
    (-b / (2.0 * c)).clamp(-reach, reach)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;

    #[test]
    fn a_moved_camera_still_looks_at_its_target() {
        let (pos, target) = (DVec3::new(10.0, -200.0, 50.0), DVec3::new(30.0, 0.0, 20.0));
        let rot = crate::camera::rotation_look_at(pos, target).expect("distinct points");
        let cam = CameraModel::pinhole(pos, rot, 800, 600, 1000.0);
        let mut p = CameraParams::from_camera(&cam);
        p.angles[2] += 0.2; // a tilted horizon
        let depth = (DVec3::new(30.0, 0.0, 20.0) - cam.position).length();
        let moved = moved_keeping_target(&p, cam.position + DVec3::new(3.0, -2.0, 1.5), depth);
        let m = moved.camera();
        let [u, v] = m
            .project(DVec3::new(30.0, 0.0, 20.0))
            .expect("target in front of the moved camera");
        assert!(
            (u - m.cx).abs() < 1e-6 && (v - m.cy).abs() < 1e-6,
            "{u} {v}"
        );
        // the horizon keeps its tilt
        assert!(
            (moved.angles[2] - p.angles[2]).abs() < 1e-9,
            "{:?}",
            moved.angles
        );
    }

    #[test]
    fn bounds_follow_the_turn_a_move_asks_for() {
        use crate::register::params::Param;
        // a camera 20 m from its target moved 6 m sideways turns about 16 degrees to keep
        // it in view: beyond 8-degree bounds from the rough camera, inside them from the
        // rough camera moved the same way
        let (pos, target) = (DVec3::new(0.0, -20.0, 5.0), DVec3::ZERO);
        let rot = crate::camera::rotation_look_at(pos, target).expect("distinct points");
        let base = CameraParams::from_camera(&CameraModel::pinhole(pos, rot, 800, 600, 1000.0));
        let depth = (target - pos).length();
        let space = Space {
            base,
            free: vec![Param::Yaw, Param::Pitch, Param::Roll],
            depth,
            bounds: [8.0, 0.08, 50.0],
        };
        let p = pos + DVec3::new(6.0, 0.0, 0.0);
        let moved = moved_keeping_target(&base, p, depth);
        assert!(space.outside(&moved, 1.0), "{:?}", moved.angles);
        assert!(!space.moved_to(p).outside(&moved, 1.0));
        // and a turn of 9 degrees more is still outside the moved bounds
        let mut turned = moved;
        turned.angles[0] += 9f64.to_radians();
        assert!(space.moved_to(p).outside(&turned, 1.0));
    }

    #[test]
    fn the_peak_of_noisy_scores_is_the_parabola_vertex() {
        // s = 1 - 0.001 (t - 0.7)², exact and with a cliff at -2 left out
        let f = |t: f64| 1.0 - 0.001 * (t - 0.7) * (t - 0.7);
        let pts: Vec<(f64, f64)> = [-2.0, -1.0, 0.0, 1.0, 2.0].map(|t| (t, f(t))).to_vec();
        assert!((peak_offset(&pts, 2.0) - 0.7).abs() < 1e-9);
        let mut cliff = pts.clone();
        cliff[0].1 = 0.5;
        assert!((peak_offset(&cliff, 2.0) - 0.7).abs() < 1e-9);
        // clamped to the reach; a convex set gives the best point
        assert_eq!(peak_offset(&pts, 0.5), 0.5);
        let convex: Vec<(f64, f64)> = [-1.0, 0.0, 1.0].map(|t| (t, t * t)).to_vec();
        assert_eq!(peak_offset(&convex, 1.0), -1.0);
    }

    #[test]
    fn a_bad_search_step_is_refused() {
        use super::super::TerrainOptions;
        for h in [0.0, -1.0, f64::NAN, f64::INFINITY, 100.0] {
            let o = TerrainOptions {
                position_search_m: Some(h),
                ..TerrainOptions::default()
            };
            assert!(o.validate().is_err(), "{h}");
        }
        let o = TerrainOptions {
            position_search_m: Some(1.5),
            ..TerrainOptions::default()
        };
        assert!(o.validate().is_ok());
    }

    #[test]
    fn trials_sample_at_most_a_million_pixels() {
        assert_eq!(dense_factor(800, 600), 1);
        assert_eq!(dense_factor(1600, 1200), 2);
        assert_eq!(dense_factor(4290, 2856), 4);
        assert_eq!(dense_factor(1024, 1024), 1);
        assert_eq!(dense_factor(1025, 1024), 2);
        assert_eq!(dense_factor(u32::MAX, u32::MAX), 64);
    }

    #[test]
    fn the_axes_are_along_across_and_up() {
        let [a, c, z] = axes(DVec3::new(0.6, 0.6, -0.52));
        assert!((a - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-12);
        assert!(a.dot(c).abs() < 1e-12 && c.z == 0.0 && z == DVec3::Z);
    }
}
