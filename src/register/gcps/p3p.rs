//! The perspective-three-point problem (P3P): the camera poses that see three known world
//! points along three known bearings, and a start camera from as few as four GCPs with it
//! inside RANSAC (the position unknown, the focal length known or searched).
//!
//! Grunert's elimination (Haralick et al. 1994): with the distances `s₂ = u s₁`, `s₃ = v s₁`
//! along the bearings, the law of cosines on the three sides gives two conics in `(u, v)`;
//! their difference is linear in `u`, and substituting it back leaves a quartic in `v`,
//! formed here by polynomial arithmetic (no hand-expanded coefficients) and solved through
//! the eigenvalues of its companion matrix, each real root polished by Newton steps. Every
//! root with positive distances gives the camera-frame points, and the pose is the rigid
//! motion between them and the world points (Procrustes, [`crate::register::rotation_from_bearings`]).

use glam::{DMat3, DVec3};
use nalgebra::Matrix4;

use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::register::gcps::bearings::{rotation_from_bearings, sample_picker, search_focal};
use crate::register::gcps::gcp::Gcp;

/// The poses (world-to-camera rotation, camera position) under which unit bearings
/// `bearing[i]` (camera frame: x right, y down, z forward) point at world points `world[i]`;
/// up to four, none for degenerate input (collinear points, parallel bearings).
pub fn p3p(bearing: [DVec3; 3], world: [DVec3; 3]) -> Vec<(DMat3, DVec3)> {
    let a2 = world[1].distance_squared(world[2]);
    let b2 = world[0].distance_squared(world[2]);
    let c2 = world[0].distance_squared(world[1]);
    if !(a2 > 0.0 && b2 > 0.0 && c2 > 0.0) {
        return Vec::new();
    }
    let cos_a = bearing[1].dot(bearing[2]);
    let cos_b = bearing[0].dot(bearing[2]);
    let cos_g = bearing[0].dot(bearing[1]);
    // u = N(v) / D(v) from the difference of the two conics
    let k = (c2 - a2) / b2;
    let q = [1.0, -2.0 * cos_b, 1.0]; // 1 + v² − 2 v cos β
    let n = add(&scale(&q, k), &[-1.0, 0.0, 1.0]);
    let d = [-2.0 * cos_g, 2.0 * cos_a];
    // (1 + u² − 2 u cos γ − (c²/b²) q(v)) · D² = 0
    let d2 = mul(&d, &d);
    let quartic = add(
        &add(&d2, &mul(&n, &n)),
        &add(
            &scale(&mul(&n, &d), -2.0 * cos_g),
            &scale(&mul(&q, &d2), -c2 / b2),
        ),
    );
    let mut poses = Vec::new();
    for v in real_roots(&quartic) {
        let (dv, nv) = (eval(&d, v), eval(&n, v));
        let qv = eval(&q, v);
        if !(v > 0.0 && qv > 0.0 && dv.abs() > 1e-12) {
            continue;
        }
        let u = nv / dv;
        if !(u > 0.0) {
            continue;
        }
        let s1 = (b2 / qv).sqrt();
        let cam = [
            bearing[0] * s1,
            bearing[1] * (u * s1),
            bearing[2] * (v * s1),
        ];
        if let Some(pose) = rigid_motion(&cam, &world) {
            poses.push(pose);
        }
    }
    poses
}

/// The rotation `R` and position `C` with `cam[i] ≈ R (world[i] − C)`.
fn rigid_motion(cam: &[DVec3; 3], world: &[DVec3; 3]) -> Option<(DMat3, DVec3)> {
    let cc = (cam[0] + cam[1] + cam[2]) / 3.0;
    let cw = (world[0] + world[1] + world[2]) / 3.0;
    let dc = cam.map(|p| p - cc);
    let dw = world.map(|p| p - cw);
    let r = rotation_from_bearings(&dc, &dw, &[1.0; 3])?;
    let centre = cw - r.transpose() * cc;
    centre.is_finite().then_some((r, centre))
}

/// Polynomials as coefficients from the constant term up.
fn add(a: &[f64], b: &[f64]) -> Vec<f64> {
    (0..a.len().max(b.len()))
        .map(|i| a.get(i).unwrap_or(&0.0) + b.get(i).unwrap_or(&0.0))
        .collect()
}

fn mul(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

fn scale(a: &[f64], k: f64) -> Vec<f64> {
    a.iter().map(|x| x * k).collect()
}

fn eval(p: &[f64], x: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, c| acc * x + c)
}

/// The real roots of the polynomial `p` (constant term first, degree ≤ 4), polished.
fn real_roots(p: &[f64]) -> Vec<f64> {
    let scale_p = p.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if !(scale_p > 0.0) || !scale_p.is_finite() {
        return Vec::new();
    }
    let mut deg = p.len() - 1;
    while deg > 0 && p[deg].abs() <= 1e-12 * scale_p {
        deg -= 1;
    }
    let roots: Vec<f64> = match deg {
        0 => Vec::new(),
        1 => vec![-p[0] / p[1]],
        _ => {
            // companion matrix of the monic polynomial, padded to 4 × 4 with zero roots
            let lead = p[deg];
            let mut m = Matrix4::<f64>::zeros();
            for i in 1..deg {
                m[(i, i - 1)] = 1.0;
            }
            for i in 0..deg {
                m[(i, deg - 1)] = -p[i] / lead;
            }
            m.complex_eigenvalues()
                .iter()
                .take(4)
                .filter(|z| z.im.abs() <= 1e-7 * (1.0 + z.re.abs()))
                .map(|z| z.re)
                .collect()
        }
    };
    let dp: Vec<f64> = (1..=deg).map(|i| i as f64 * p[i]).collect();
    roots
        .into_iter()
        .map(|mut x| {
            for _ in 0..4 {
                let (f, df) = (eval(&p[..=deg], x), eval(&dp, x));
                if df.abs() > 0.0 {
                    let step = f / df;
                    if step.is_finite() {
                        x -= step;
                    }
                }
            }
            x
        })
        .filter(|x| x.is_finite())
        .collect()
}

/// A start camera for a `width × height` photo from `gcps` with the position unknown: P3P
/// on triples of GCPs inside RANSAC (every triple when there are at most 300, else 300
/// deterministic samples), each pose scored by how many GCPs it reprojects within 2 % of
/// the image diagonal (then by the sum of errors capped there), distortion 0, principal
/// point at the image centre. `focal_px` fixes the focal length; without it the horizontal
/// field of view is searched over 3°–140° (log grid of 64 steps, then golden section).
/// Needs 4 GCPs (3 to solve, one to choose among the solutions). Deterministic.
pub fn start_from_gcps_p3p(
    width: u32,
    height: u32,
    gcps: &[Gcp],
    focal_px: Option<f64>,
) -> Result<CameraModel> {
    if gcps.len() < 4 {
        return Err(Error::BadOption(format!(
            "fit-camera: a start without a camera or position needs at least 4 GCPs, got {}",
            gcps.len()
        )));
    }
    if let Some(f) = focal_px
        && !(f.is_finite() && f > 0.0)
    {
        return Err(Error::BadOption(format!(
            "fit-camera: focal length must be positive pixels, got {f}"
        )));
    }
    let (w, h) = (width as f64, height as f64);
    let (cx, cy) = ((w - 1.0) / 2.0, (h - 1.0) / 2.0);
    let triples = sample_triples(gcps.len());
    let tol = 0.02 * w.hypot(h);
    let best_at = |f: f64| -> Option<(usize, f64, CameraModel)> {
        let bearing =
            |g: &Gcp| DVec3::new((g.pixel[0] - cx) / f, (g.pixel[1] - cy) / f, 1.0).normalize();
        let mut best: Option<(usize, f64, CameraModel)> = None;
        for t in &triples {
            let b = t.map(|i| bearing(&gcps[i]));
            let x = t.map(|i| gcps[i].world);
            for (r, c) in p3p(b, x) {
                let cam = CameraModel::pinhole(c, r, width, height, f);
                let (n, s) = score(&cam, gcps, tol);
                if best
                    .as_ref()
                    .is_none_or(|b| n > b.0 || (n == b.0 && s < b.1))
                {
                    best = Some((n, s, cam));
                }
            }
        }
        best
    };
    let best = match focal_px {
        Some(f) => best_at(f),
        None => {
            // fewer inliers first, then the capped error sum
            let n = gcps.len() as f64;
            let f = search_focal(w, 64, |f| {
                best_at(f).map_or(f64::INFINITY, |(k, s, _)| (n - k as f64) * tol * n + s)
            });
            best_at(f)
        }
    };
    match best {
        Some((n, _, cam)) if n >= 4 => Ok(cam),
        _ => Err(Error::BadOption(
            "fit-camera: no camera from three GCPs reprojects a fourth within 2 % of the image \
             diagonal (GCPs on one line, or wrong pixel coordinates?)"
                .into(),
        )),
    }
}

/// GCPs within `tol` pixels of where `cam` projects them, and the sum of the errors capped
/// at `tol` (points behind the camera count as `tol`).
pub(crate) fn score(cam: &CameraModel, gcps: &[Gcp], tol: f64) -> (usize, f64) {
    gcps.iter().fold((0, 0.0), |(n, s), g| {
        let e = cam.project(g.world).map_or(f64::INFINITY, |p| {
            (p[0] - g.pixel[0]).hypot(p[1] - g.pixel[1])
        });
        (n + (e <= tol) as usize, s + e.min(tol))
    })
}

/// Every triple of `0..n` when there are at most 300, else 300 distinct pseudo-random ones
/// (fixed seed).
fn sample_triples(n: usize) -> Vec<[usize; 3]> {
    let all = n * n.saturating_sub(1) * n.saturating_sub(2) / 6;
    if all <= 300 {
        let mut out = Vec::with_capacity(all);
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    out.push([i, j, k]);
                }
            }
        }
        return out;
    }
    let mut next = sample_picker(0x9E37_79B9_7F4A_7C15);
    let mut out: Vec<[usize; 3]> = Vec::with_capacity(300);
    while out.len() < 300 {
        let mut t = [next(n), next(n), next(n)];
        t.sort_unstable();
        if t[0] != t[1] && t[1] != t[2] && !out.contains(&t) {
            out.push(t);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_from_yaw_pitch_roll;

    fn camera(f: f64) -> CameraModel {
        let r = rotation_from_yaw_pitch_roll(0.7, 0.12, -0.03);
        let mut cam = CameraModel::with_fov(DVec3::new(500.0, -200.0, 1300.0), r, 1600, 1200, 1.0);
        cam.fx = f;
        cam.fy = f;
        cam
    }

    /// GCPs seen by `cam`: terrain-like points 150–900 m in front of it.
    fn gcps(cam: &CameraModel, n: usize) -> Vec<Gcp> {
        let mut out = Vec::new();
        let mut k = 0u32;
        while out.len() < n {
            k += 1;
            let (px, py) = (
                (k * 7919 % 1500) as f64 + 50.0,
                (k * 104729 % 1100) as f64 + 50.0,
            );
            let depth = 150.0 + (k * 6151 % 750) as f64;
            let ray = cam.world_to_camera.transpose()
                * DVec3::new((px - cam.cx) / cam.fx, (py - cam.cy) / cam.fy, 1.0);
            let world = cam.position + ray * depth;
            out.push(Gcp {
                world,
                pixel: [px, py],
                weight: 1.0,
                name: format!("g{k}"),
            });
        }
        out
    }

    #[test]
    fn p3p_recovers_the_pose_among_its_solutions() {
        let cam = camera(1650.0);
        let g = gcps(&cam, 3);
        let b = [0, 1, 2].map(|i| {
            DVec3::new(
                (g[i].pixel[0] - cam.cx) / cam.fx,
                (g[i].pixel[1] - cam.cy) / cam.fy,
                1.0,
            )
            .normalize()
        });
        let poses = p3p(b, [g[0].world, g[1].world, g[2].world]);
        assert!(!poses.is_empty() && poses.len() <= 4);
        let best = poses
            .iter()
            .map(|(r, c)| {
                (
                    c.distance(cam.position),
                    (*r - cam.world_to_camera).abs_diff_eq(DMat3::ZERO, 1e-6),
                )
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        assert!(best.0 < 1e-5 && best.1, "{best:?} of {poses:?}");
        // degenerate: coincident points
        assert!(p3p(b, [g[0].world, g[0].world, g[2].world]).is_empty());
    }

    #[test]
    fn four_gcps_and_the_focal_length_give_the_camera() {
        let cam = camera(1650.0);
        let g = gcps(&cam, 4);
        let got = start_from_gcps_p3p(1600, 1200, &g, Some(1650.0)).unwrap();
        assert!(
            got.position.distance(cam.position) < 1e-4,
            "{:?}",
            got.position
        );
        // an outlier among six is voted out
        let mut g = gcps(&cam, 6);
        g[2].pixel = [900.0, 100.0];
        let got = start_from_gcps_p3p(1600, 1200, &g, Some(1650.0)).unwrap();
        assert!(got.position.distance(cam.position) < 1e-4);
        assert!(start_from_gcps_p3p(1600, 1200, &g[..3], Some(1650.0)).is_err());
    }

    #[test]
    fn the_focal_length_is_searched_when_unknown() {
        let cam = camera(2100.0);
        let g = gcps(&cam, 8);
        let got = start_from_gcps_p3p(1600, 1200, &g, None).unwrap();
        assert!((got.fx / 2100.0 - 1.0).abs() < 0.01, "f {}", got.fx);
        assert!(
            got.position.distance(cam.position) < 0.02 * 500.0,
            "{:?}",
            got.position
        );
    }
}
