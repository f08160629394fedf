//! Inverse of the radial distortion of [`CameraModel::project`] and pixel rays.
//!
//! The forward model scales normalized image coordinates by `d(r²) = 1 + k1·r² + k2·r⁴`
//! with `r² = min(x² + y², 4)`, so the distorted radius is `f(r) = r·d(min(r², 4))`. `f` is
//! inverted on its first monotone branch `[0, r_fold)`, where `r_fold` is the first radius at
//! which `f` stops increasing (the smallest positive root of `f'(r) = 1 + 3k1·r² + 5k2·r⁴`
//! below 2, or 2 if the linear tail `r·d(4)` beyond the clamp does not increase, else ∞).
//! Distorted radii beyond `f(r_fold)` have no unique ray (the model folds the image there):
//! they give `None`. For whole rows of a photo's corner rays the inverse ratio is tabulated
//! over the image's range (`RayCaster::with_table`), so no ray needs an iteration.

use glam::DVec3;

use super::CameraModel;

/// The radial distortion function of a camera, with its monotone range.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Radial {
    k1: f64,
    k2: f64,
    /// End of the first monotone branch of `f` (∞ if `f` increases everywhere).
    r_fold: f64,
    /// `f(r_fold)` (∞ if `r_fold` is ∞).
    f_fold: f64,
}

impl Radial {
    pub(crate) fn new(k1: f64, k2: f64) -> Radial {
        let mut r = Radial {
            k1,
            k2,
            r_fold: f64::INFINITY,
            f_fold: f64::INFINITY,
        };
        // Smallest positive root s = r² < 4 of 1 + 3k1·s + 5k2·s² = 0.
        let (a, b, c) = (5.0 * k2, 3.0 * k1, 1.0);
        let mut roots = [f64::NAN; 2];
        if a.abs() < 1e-300 {
            if b != 0.0 {
                roots[0] = -c / b;
            }
        } else {
            let disc = b * b - 4.0 * a * c;
            if disc >= 0.0 {
                let q = -0.5 * (b + b.signum() * disc.sqrt());
                roots = [q / a, if q != 0.0 { c / q } else { f64::NAN }];
            }
        }
        let s_fold = roots
            .into_iter()
            .filter(|s| s.is_finite() && *s > 0.0 && *s < 4.0)
            .fold(f64::INFINITY, f64::min);
        if s_fold.is_finite() {
            r.r_fold = s_fold.sqrt();
        } else if r.d(4.0) <= 0.0 {
            r.r_fold = 2.0;
        }
        if r.r_fold.is_finite() {
            r.f_fold = r.f(r.r_fold);
        }
        r
    }

    /// The largest distorted radius with a ray: `f(r_fold)` (∞ when `f` increases
    /// everywhere).
    pub(crate) fn fold_radius(&self) -> f64 {
        if self.k1 == 0.0 && self.k2 == 0.0 {
            f64::INFINITY
        } else {
            self.f_fold
        }
    }

    /// Distortion factor for a squared radius (clamped at 4 as in the forward model).
    fn d(&self, r2: f64) -> f64 {
        let s = r2.min(4.0);
        1.0 + self.k1 * s + self.k2 * s * s
    }

    /// Distorted radius of an undistorted radius `r ≥ 0`.
    fn f(&self, r: f64) -> f64 {
        r * self.d(r * r)
    }

    /// Undistorted radius `r` with `f(r) = rd` on the first monotone branch, or `None` if `rd`
    /// lies beyond it (or is not finite).
    pub(crate) fn invert(&self, rd: f64) -> Option<f64> {
        self.invert_near(rd, rd)
    }

    /// [`Radial::invert`] with Newton started at `guess` (e.g. the solution at a neighbouring
    /// pixel): the same root to the iteration's tolerance (1e-15 relative), in fewer steps.
    pub(crate) fn invert_near(&self, rd: f64, guess: f64) -> Option<f64> {
        if !(rd.is_finite() && rd >= 0.0) {
            return None;
        }
        if self.k1 == 0.0 && self.k2 == 0.0 {
            return Some(rd);
        }
        if rd > self.f_fold {
            return None;
        }
        let hi_end = self.r_fold.min(2.0);
        if hi_end < 2.0 || rd <= self.f(2.0) {
            // On [0, hi_end] f is increasing: safeguarded Newton.
            let (mut lo, mut hi) = (0.0f64, hi_end);
            let mut r = if guess.is_finite() && guess >= 0.0 {
                guess.min(hi_end)
            } else {
                rd.min(hi_end)
            };
            for _ in 0..60 {
                let fr = self.f(r) - rd;
                if fr.abs() <= 1e-15 * rd.max(1e-300) {
                    return Some(r);
                }
                if fr > 0.0 {
                    hi = r;
                } else {
                    lo = r;
                }
                let s = r * r;
                let df = 1.0 + 3.0 * self.k1 * s + 5.0 * self.k2 * s * s;
                let newton = r - fr / df;
                r = if df > 0.0 && newton > lo && newton < hi {
                    newton
                } else {
                    0.5 * (lo + hi)
                };
                if hi - lo <= 1e-16 * hi {
                    break;
                }
            }
            Some(r)
        } else {
            // Linear tail beyond the clamp: f(r) = r·d(4), d(4) > 0 here.
            Some(rd / self.d(4.0))
        }
    }
}

impl CameraModel {
    /// Undistorts normalized image coordinates: the pinhole `(x, y)` (= camera-frame
    /// `c.x/c.z`, `c.y/c.z`) that [`CameraModel::project`]'s distortion maps to `(xd, yd)`.
    /// `None` where the distortion model folds (beyond its first monotone radius, see the
    /// module docs) or for non-finite input.
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<[f64; 2]> {
        undistort_with(&Radial::new(self.k1, self.k2), xd, yd)
    }

    /// Unit world direction of the ray through the pixel position `(u, v)` (pixel-centre
    /// convention: pixel `(c, r)` covers `u ∈ [c − 0.5, c + 0.5]`, `v ∈ [r − 0.5, r + 0.5]`),
    /// undistorted; `project` of any point on the ray gives back `(u, v)`. `None` where the
    /// distortion has no unique inverse or the camera's numbers are not finite.
    pub fn pixel_ray(&self, u: f64, v: f64) -> Option<DVec3> {
        self.ray_caster().ray(u, v)
    }

    /// A reusable pixel-ray generator (precomputes the distortion inverse's range).
    pub(crate) fn ray_caster(&self) -> RayCaster {
        RayCaster {
            cam: *self,
            radial: Radial::new(self.k1, self.k2),
            camera_to_world: self.world_to_camera.transpose(),
            table: None,
        }
    }
}

fn undistort_with(radial: &Radial, xd: f64, yd: f64) -> Option<[f64; 2]> {
    let rd = (xd * xd + yd * yd).sqrt();
    if rd == 0.0 {
        return Some([0.0, 0.0]);
    }
    let r = radial.invert(rd)?;
    let s = r / rd;
    Some([xd * s, yd * s])
}

/// A pixel ray: its unit world direction and its point `(x, y)` on the undistorted image
/// plane (camera frame `c.x / c.z`, `c.y / c.z`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PlaneRay {
    pub dir: DVec3,
    pub xy: [f64; 2],
}

/// The ray through `(x, y)` of the undistorted image plane.
#[inline]
fn plane_ray(camera_to_world: &glam::DMat3, x: f64, y: f64) -> Option<PlaneRay> {
    // `try_normalize` succeeds only with a finite, positive reciprocal length, so every
    // component of `d` (at most 1 in magnitude) is finite.
    let d = (*camera_to_world * DVec3::new(x, y, 1.0)).try_normalize()?;
    Some(PlaneRay { dir: d, xy: [x, y] })
}

/// Pixel rays of one camera (see [`CameraModel::pixel_ray`]).
#[derive(Clone, Debug)]
pub(crate) struct RayCaster {
    cam: CameraModel,
    radial: Radial,
    camera_to_world: glam::DMat3,
    /// The undistortion ratio over the image, if tabulated ([`RayCaster::with_table`]).
    table: Option<RatioTable>,
}

/// Intervals of a [`RatioTable`].
const TABLE_INTERVALS: usize = 2048;

/// The undistortion ratio `q = r / rd` as a function of `s = rd²` on `[0, s_max]`: a
/// piecewise cubic Hermite interpolant of the exact ratio and its exact derivative at
/// [`TABLE_INTERVALS`] + 1 equally spaced nodes. `q` is analytic there (the range stays
/// inside the first monotone branch and below the clamp), so with nodes this dense the
/// interpolation error is at the level of f64 rounding (tested: below 1e-14 relative).
#[derive(Clone, Debug)]
struct RatioTable {
    /// Nodes per unit of `s`.
    inv_h: f64,
    /// Per interval, the cubic in the local parameter `t ∈ [0, 1]`: `c0 + t(c1 + t(c2 + t c3))`.
    coef: Vec<[f64; 4]>,
}

impl RatioTable {
    /// The table for `s ∈ [0, s_max]`, or `None` if that range comes near the fold or the
    /// clamp of the distortion model (there the Newton inversion is used).
    fn new(radial: &Radial, s_max: f64) -> Option<RatioTable> {
        if !(s_max.is_finite() && s_max > 0.0) {
            return None;
        }
        let r_max = radial.invert(s_max.sqrt())?;
        if !(r_max < 0.98 * radial.r_fold.min(2.0)) {
            return None;
        }
        let (k1, k2) = (radial.k1, radial.k2);
        let h = s_max / TABLE_INTERVALS as f64;
        let node = |i: usize| -> Option<(f64, f64)> {
            let s = i as f64 * h;
            let q = if i == 0 {
                1.0
            } else {
                let rd = s.sqrt();
                radial.invert(rd)? / rd
            };
            // q·d(q²s) = 1: implicit derivative dq/ds.
            let (q2, q3) = (q * q, q * q * q);
            let dq = -(k1 * q3 + 2.0 * k2 * q3 * q2 * s)
                / (1.0 + 3.0 * k1 * q2 * s + 5.0 * k2 * q2 * q2 * s * s);
            (q.is_finite() && dq.is_finite()).then_some((q, dq * h))
        };
        let nodes: Vec<(f64, f64)> = (0..=TABLE_INTERVALS).map(node).collect::<Option<_>>()?;
        let coef = nodes
            .windows(2)
            .map(|w| {
                let ((q0, m0), (q1, m1)) = (w[0], w[1]);
                [
                    q0,
                    m0,
                    3.0 * (q1 - q0) - 2.0 * m0 - m1,
                    2.0 * (q0 - q1) + m0 + m1,
                ]
            })
            .collect();
        Some(RatioTable {
            inv_h: 1.0 / h,
            coef,
        })
    }

    /// `q(s)`, or `None` outside the table's range.
    #[inline]
    fn ratio(&self, s: f64) -> Option<f64> {
        let x = s * self.inv_h;
        let n = self.coef.len();
        if !(x >= 0.0 && x <= n as f64 * (1.0 + 1e-12)) {
            return None;
        }
        // (x >= 0: a signed conversion, one instruction on x86-64)
        let i = (x as i64 as usize).min(n - 1);
        let t = x - i as f64;
        let c = &self.coef[i];
        Some(c[0] + t * (c[1] + t * (c[2] + t * c[3])))
    }
}

impl RayCaster {
    /// The rays through the pixel positions `(u0 + i, v)`, `i = 0..out.len()` (`None` where
    /// [`CameraModel::pixel_ray`] has none). Each undistortion starts from its left
    /// neighbour's solution, so a row costs about one Newton step per ray; the directions
    /// equal `pixel_ray`'s to the iteration's tolerance.
    #[cfg(test)]
    pub(crate) fn row(&self, u0: f64, v: f64, out: &mut [Option<PlaneRay>]) {
        self.row_with(u0, v, out.len(), |i, r| out[i] = r);
    }

    /// This caster with the undistortion of every pixel position of the image tabulated
    /// ([`RatioTable`]): [`RayCaster::row_with`] then costs no iteration per ray, and its rays
    /// agree with [`CameraModel::pixel_ray`]'s to about 1e-14. Without distortion, or when the
    /// image reaches near the distortion's fold, nothing changes.
    pub(crate) fn with_table(mut self) -> RayCaster {
        let c = &self.cam;
        if c.k1 == 0.0 && c.k2 == 0.0 {
            return self;
        }
        // rd² is convex in (u, v): its maximum over the image is at a corner.
        let (u1, v1) = (c.width as f64 - 0.5, c.height as f64 - 0.5);
        let s_max = [(-0.5, -0.5), (u1, -0.5), (-0.5, v1), (u1, v1)]
            .iter()
            .map(|&(u, v)| {
                let (xd, yd) = ((u - c.cx) / c.fx, (v - c.cy) / c.fy);
                xd * xd + yd * yd
            })
            .fold(0.0f64, f64::max);
        self.table = RatioTable::new(&self.radial, s_max);
        self
    }

    /// `true` if [`RayCaster::row_with`] computes every ray on its own (no distortion, or a
    /// tabulated one), so a ray does not depend on the row it is cast in.
    pub(crate) fn rays_independent(&self) -> bool {
        self.table.is_some() || (self.cam.k1 == 0.0 && self.cam.k2 == 0.0)
    }

    /// [`RayCaster::row`] handing each ray to `f(i, ray)` in order instead of storing it.
    #[inline]
    pub(crate) fn row_with(
        &self,
        u0: f64,
        v: f64,
        n: usize,
        mut f: impl FnMut(usize, Option<PlaneRay>),
    ) {
        let c = &self.cam;
        let yd = (v - c.cy) / c.fy;
        if let Some(tab) = &self.table {
            for i in 0..n {
                let xd = (u0 + i as f64 - c.cx) / c.fx;
                let ray = match tab.ratio(xd * xd + yd * yd) {
                    Some(q) => plane_ray(&self.camera_to_world, xd * q, yd * q),
                    None => undistort_with(&self.radial, xd, yd)
                        .and_then(|[x, y]| plane_ray(&self.camera_to_world, x, y)),
                };
                f(i, ray);
            }
            return;
        }
        let no_distortion = c.k1 == 0.0 && c.k2 == 0.0;
        // r / rd of the last two rays, extrapolated linearly in rd for the next guess.
        let (mut ratio, mut slope, mut rd_prev) = (1.0, 0.0, f64::NAN);
        for i in 0..n {
            let xd = (u0 + i as f64 - c.cx) / c.fx;
            if no_distortion {
                f(i, plane_ray(&self.camera_to_world, xd, yd));
                continue;
            }
            let rd = (xd * xd + yd * yd).sqrt();
            let xy = if rd == 0.0 {
                Some([0.0, 0.0])
            } else {
                let guess = if rd_prev.is_finite() {
                    ratio + slope * (rd - rd_prev)
                } else {
                    ratio
                };
                self.radial.invert_near(rd, rd * guess).map(|r| {
                    let q = r / rd;
                    slope = if rd_prev.is_finite() && rd != rd_prev {
                        (q - ratio) / (rd - rd_prev)
                    } else {
                        0.0
                    };
                    (ratio, rd_prev) = (q, rd);
                    [xd * q, yd * q]
                })
            };
            f(
                i,
                xy.and_then(|[x, y]| plane_ray(&self.camera_to_world, x, y)),
            );
        }
    }

    /// Unit world direction through pixel position `(u, v)`, as [`CameraModel::pixel_ray`].
    pub(crate) fn ray(&self, u: f64, v: f64) -> Option<DVec3> {
        let c = &self.cam;
        let xd = (u - c.cx) / c.fx;
        let yd = (v - c.cy) / c.fy;
        let [x, y] = undistort_with(&self.radial, xd, yd)?;
        let d = self.camera_to_world * DVec3::new(x, y, 1.0);
        let d = d.try_normalize()?;
        d.is_finite().then_some(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_from_yaw_pitch_roll;

    fn cam(k1: f64, k2: f64) -> CameraModel {
        let r = rotation_from_yaw_pitch_roll(0.4, 0.1, -0.02);
        let mut c =
            CameraModel::with_fov(DVec3::new(431_000.0, 6_878_000.0, 700.0), r, 640, 480, 0.9);
        c.cx += 3.5;
        c.cy -= 2.0;
        c.k1 = k1;
        c.k2 = k2;
        c
    }

    #[test]
    fn pixel_ray_round_trips_through_project() {
        for (k1, k2) in [(0.0, 0.0), (-0.115, 0.0), (0.08, -0.01), (-0.2, 0.05)] {
            let c = cam(k1, k2);
            for j in 0..=12 {
                for i in 0..=16 {
                    let (u, v) = (i as f64 * 40.0 - 0.5, j as f64 * 40.0 - 0.5);
                    let d = c.pixel_ray(u, v).expect("inside the monotone range");
                    assert!((d.length() - 1.0).abs() < 1e-12);
                    let p = c.project(c.position + d * 250.0).unwrap();
                    assert!(
                        (p[0] - u).abs() < 1e-7 && (p[1] - v).abs() < 1e-7,
                        "k=({k1},{k2}) {u},{v} -> {p:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn undistort_handles_the_clamp_and_the_fold() {
        // k1 < 0: f(r) = r(1 + k1 r²) peaks at r² = -1/(3k1) < 4, beyond it no unique inverse.
        let c = cam(-0.115, 0.0);
        let rmax = (1.0f64 / (3.0 * 0.115)).sqrt();
        let fmax = rmax * (1.0 - 0.115 * rmax * rmax);
        let [x, _] = c.undistort(fmax * 0.999, 0.0).unwrap();
        assert!(x > 0.0 && x < rmax && (x * (1.0 - 0.115 * x * x) - fmax * 0.999).abs() < 1e-12);
        assert!(c.undistort(fmax * 1.001, 0.0).is_none());
        // k1 > 0: monotone everywhere, beyond r = 2 the clamp makes the map linear.
        let c = cam(0.05, 0.0);
        let d4 = 1.0 + 0.05 * 4.0;
        let [x, y] = c.undistort(0.0, 3.0 * d4).unwrap();
        assert!(x.abs() < 1e-15 && (y - 3.0).abs() < 1e-12);
        let [x, y] = c.undistort(1.2, -0.5).unwrap();
        let r2 = (x * x + y * y).min(4.0);
        let d = 1.0 + 0.05 * r2;
        assert!((x * d - 1.2).abs() < 1e-12 && (y * d + 0.5).abs() < 1e-12);
        assert!(c.undistort(f64::NAN, 0.0).is_none());
        assert_eq!(c.undistort(0.0, 0.0), Some([0.0, 0.0]));
    }

    #[test]
    fn row_rays_equal_pixel_rays() {
        for (k1, k2) in [(0.0, 0.0), (-0.115, 0.0), (0.08, -0.01), (-0.2, 0.05)] {
            let c = cam(k1, k2);
            let rc = c.ray_caster();
            let mut row = vec![None; 641];
            for j in [0, 1, 240, 479, 480] {
                let v = j as f64 - 0.5;
                rc.row(-0.5, v, &mut row);
                for (i, r) in row.iter().enumerate() {
                    let u = i as f64 - 0.5;
                    let want = c.pixel_ray(u, v);
                    assert_eq!(r.is_some(), want.is_some(), "k=({k1},{k2}) ({u},{v})");
                    if let (Some(r), Some(w)) = (r, want) {
                        assert!(
                            (r.dir - w).length() < 1e-13,
                            "k=({k1},{k2}) ({u},{v}): {:?} vs {w:?}",
                            r.dir
                        );
                        let cf = c.world_to_camera * r.dir;
                        assert!(
                            (cf.x / cf.z - r.xy[0]).abs() < 1e-12
                                && (cf.y / cf.z - r.xy[1]).abs() < 1e-12
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn tabulated_rows_equal_pixel_rays() {
        for (k1, k2) in [
            (-0.115, 0.0),
            (0.08, -0.01),
            (-0.2, 0.05),
            (0.3, 0.1),
            (-0.02, -0.001),
        ] {
            let c = cam(k1, k2);
            let rc = c.ray_caster().with_table();
            assert!(rc.table.is_some(), "k=({k1},{k2})");
            let mut row = vec![None; 641];
            for j in [0, 1, 97, 240, 479, 480] {
                let v = j as f64 - 0.5;
                rc.row(-0.5, v, &mut row);
                for (i, r) in row.iter().enumerate() {
                    let u = i as f64 - 0.5;
                    let (r, w) = (r.expect("inside the table"), c.pixel_ray(u, v).unwrap());
                    assert!(
                        (r.dir - w).length() < 1e-14,
                        "k=({k1},{k2}) ({u},{v}): {:?} vs {w:?}",
                        r.dir
                    );
                }
            }
        }
        // near the fold (k1 < 0 with a wide field of view) the table is not used
        let mut wide = cam(-0.115, 0.0);
        wide.fx *= 0.45;
        wide.fy *= 0.45;
        assert!(wide.ray_caster().with_table().table.is_none());
        assert!(cam(0.0, 0.0).ray_caster().with_table().table.is_none());
    }

    #[test]
    fn pixel_corners_bracket_the_pixel_centre() {
        let c = cam(0.0, 0.0);
        let centre = c.pixel_ray(10.0, 20.0).unwrap();
        let p = c.project(c.position + centre * 100.0).unwrap();
        assert!((p[0] - 10.0).abs() < 1e-6 && (p[1] - 20.0).abs() < 1e-6);
        let a = c.pixel_ray(9.5, 19.5).unwrap();
        let b = c.pixel_ray(10.5, 20.5).unwrap();
        assert!(((a + b).normalize() - centre).length() < 1e-6);
    }
}
