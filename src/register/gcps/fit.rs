//! Fitting a camera to ground control points: robust Levenberg-Marquardt over the free
//! parameters (docs/registration.md).
//!
//! The residual of GCP `i` is its projection through the camera ([`CameraModel::project`])
//! minus its observed pixel, two numbers in pixels. The fit minimises
//! `Σ w_i · ρ_i · |r_i|²` with the GCP's weight `w_i` and a Huber weight `ρ_i = min(1, δ / |r_i|)`
//! re-estimated by iteratively reweighted least squares (each round a full
//! `levenberg-marquardt` solve, Jacobian by central differences): the threshold is
//! `δ = max(2.45 σ̂, 0.5 px)`, with the robust scale `σ̂ = median |r_i| / 1.1774` (the median
//! of the norm of a 2-D Gaussian error of σ per axis is 1.1774 σ; 2.45 σ bounds 95 % of such
//! norms). A GCP whose final `|r_i|` exceeds `3.03 σ̂` (99 %) is flagged as an outlier
//! (it stays in the fit with its Huber weight). Without robustness (`robust: false`) every
//! `ρ_i = 1`: plain least squares, as ImGRAFT's fit.
//!
//! The solver works on offsets from the start camera's values (its trust region scales with
//! the parameters' norm, so absolute UTM coordinates would let a first step move the camera
//! by kilometres). With the position free, the fit is also run from the GCPs' own pose
//! (DLT + RANSAC, [`crate::register::start_from_gcps`]) and the better result kept. GCPs whose
//! observed pixel lies outside the image, or that lie behind the start camera,
//! are left out and reported. Reported: per GCP the residual and its status; the RMSE of
//! the fitted GCPs (unweighted, pixels) and of the inliers; `AIC = n ln(RSS / n) + 2k` (n =
//! 2 × fitted GCPs, k = free parameters, RSS the unweighted sum of squared residuals); and
//! each parameter's standard deviation `√diag(s² (JᵀWJ)⁻¹)` with
//! `s² = Σ w ρ |r|² / (n − k)`.

use levenberg_marquardt::LevenbergMarquardt;
use nalgebra::DVector;

use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::register::gcps::gcp::Gcp;
use crate::register::lsq::{Lsq, Residuals, jacobian, params_at};
use crate::register::params::{CameraParams, Param};

/// How [`fit_camera`] fits.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// The parameters to fit (the rest keep the start camera's values).
    pub free: Vec<Param>,
    /// Huber-weighted IRLS (default) or plain least squares.
    pub robust: bool,
    /// A fixed Huber threshold in pixels instead of `max(2.45 σ̂, 0.5)`.
    pub huber_px: Option<f64>,
    /// Most reweighting rounds (default 20).
    pub max_rounds: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            free: vec![Param::Yaw, Param::Pitch, Param::Roll, Param::F, Param::K1],
            robust: true,
            huber_px: None,
            max_rounds: 20,
        }
    }
}

/// What became of one GCP in the fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GcpStatus {
    /// Fitted, residual within the outlier bound.
    Inlier,
    /// Fitted, residual above `3.03 σ̂` (down-weighted by the Huber loss).
    Outlier,
    /// Left out: its observed pixel is outside the image.
    OutsideImage,
    /// Left out: behind the start camera.
    BehindCamera,
}

impl GcpStatus {
    /// The name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            GcpStatus::Inlier => "inlier",
            GcpStatus::Outlier => "outlier",
            GcpStatus::OutsideImage => "outside_image",
            GcpStatus::BehindCamera => "behind_camera",
        }
    }
}

/// One GCP after the fit.
#[derive(Clone, Debug, PartialEq)]
pub struct GcpResidual {
    /// The GCP's name.
    pub name: String,
    /// Observed pixel (0-based).
    pub observed: [f64; 2],
    /// Its projection through the fitted camera (`None` behind it).
    pub projected: Option<[f64; 2]>,
    /// `projected − observed`, pixels (`None` behind the camera).
    pub residual: Option<[f64; 2]>,
    /// Final Huber weight `ρ` in (0, 1] (0 for GCPs left out).
    pub robust_weight: f64,
    /// Status.
    pub status: GcpStatus,
}

/// A fitted parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedParam {
    /// Which.
    pub param: Param,
    /// Start value (radians, metres, pixels).
    pub start: f64,
    /// Fitted value.
    pub value: f64,
    /// Standard deviation (NaN when the fit has no redundancy).
    pub sigma: f64,
}

/// The result of [`fit_camera`].
#[derive(Clone, Debug, PartialEq)]
pub struct CameraFit {
    /// The fitted camera.
    pub camera: CameraModel,
    /// Per GCP, in input order.
    pub gcps: Vec<GcpResidual>,
    /// Per free parameter.
    pub params: Vec<FittedParam>,
    /// RMSE (pixels) of the fitted GCPs' residual norms, unweighted.
    pub rmse_px: f64,
    /// RMSE (pixels) of the inliers alone.
    pub rmse_inliers_px: f64,
    /// Akaike information criterion of the fit (see the module docs).
    pub aic: f64,
    /// Robust scale `σ̂` of the final residuals, pixels.
    pub sigma_px: f64,
    /// Reweighting rounds run.
    pub rounds: usize,
}

/// The least-squares problem of one reweighting round.
struct Problem<'a> {
    base: CameraParams,
    free: &'a [Param],
    /// Per fitted GCP: world point, observed pixel, √(w ρ).
    points: Vec<(glam::DVec3, [f64; 2], f64)>,
}

/// A residual standing for a point that went behind the camera during the search (the LM
/// step that causes it is rejected for its cost).
const BEHIND_PX: f64 = 1e6;

impl Problem<'_> {
    fn params_at(&self, x: &DVector<f64>) -> CameraParams {
        params_at(&self.base, self.free, x)
    }
}

impl Residuals for Problem<'_> {
    fn free(&self) -> &[Param] {
        self.free
    }

    fn residuals_at(&self, x: &DVector<f64>) -> DVector<f64> {
        let cam = self.params_at(x).camera();
        let mut r = DVector::zeros(2 * self.points.len());
        for (i, (world, obs, sw)) in self.points.iter().enumerate() {
            let (du, dv) = match cam.project(*world) {
                Some(p) => (p[0] - obs[0], p[1] - obs[1]),
                None => (BEHIND_PX, BEHIND_PX),
            };
            r[2 * i] = sw * du;
            r[2 * i + 1] = sw * dv;
        }
        r
    }
}

/// Fits the free parameters of `start` to `gcps` (see the module docs (`src/register/fit.rs`)).
///
/// Errors (never panics): no free parameters, fewer usable GCP coordinates than free
/// parameters, GCPs that do not determine the free parameters (the Jacobian with unit
/// columns has a singular value below 1e-7 of its largest), or a solver failure
/// (non-finite residuals at the start).
pub fn fit_camera(start: &CameraModel, gcps: &[Gcp], opts: &FitOptions) -> Result<CameraFit> {
    let fit = fit_from(start, gcps, opts)?;
    // With the position free, a start metres off can end in a wrong minimum; the fit is
    // repeated from the GCPs' own pose (DLT + RANSAC, with the start's intrinsics) and the
    // better of the two kept: lower sum of squared residual norms capped at 3 × the smaller
    // robust scale (at least 1 px).
    let position_free = opts
        .free
        .iter()
        .any(|p| matches!(p, Param::X | Param::Y | Param::Z));
    if !position_free || gcps.len() < 6 {
        return Ok(fit);
    }
    let Ok(dlt) = crate::register::gcps::start::start_from_gcps(start.width, start.height, gcps)
    else {
        return Ok(fit);
    };
    let other_start = CameraModel {
        position: dlt.position,
        world_to_camera: dlt.world_to_camera,
        ..*start
    };
    let Ok(other) = fit_from(&other_start, gcps, opts) else {
        return Ok(fit);
    };
    let cap = (3.0 * fit.sigma_px.min(other.sigma_px)).max(1.0);
    let cost = |f: &CameraFit| -> f64 {
        f.gcps
            .iter()
            .map(|g| {
                g.residual
                    .map_or(cap, |r| r[0].hypot(r[1]).min(cap))
                    .powi(2)
            })
            .sum()
    };
    Ok(if cost(&other) < cost(&fit) {
        other
    } else {
        fit
    })
}

/// [`fit_camera`] from `start` alone, without the second start from the GCPs' own pose:
/// for callers whose start is already close (and whose points may lie on one plane, where
/// the direct linear transform has no unique answer).
pub(crate) fn fit_camera_local(
    start: &CameraModel,
    gcps: &[Gcp],
    opts: &FitOptions,
) -> Result<CameraFit> {
    fit_from(start, gcps, opts)
}

fn fit_from(start: &CameraModel, gcps: &[Gcp], opts: &FitOptions) -> Result<CameraFit> {
    if opts.free.is_empty() {
        return Err(Error::BadOption("fit-camera: no free parameters".into()));
    }
    let mut status = screen_gcps(start, gcps);
    let used: Vec<usize> = (0..gcps.len()).filter(|&i| status[i].is_none()).collect();
    let k = opts.free.len();
    if 2 * used.len() < k {
        let hint = if used.is_empty() {
            "; check the column order (X Y Z U V: world metres, then pixels), the pixel origin \
             and that the start camera faces the points"
        } else {
            ""
        };
        return Err(Error::Unusable(format!(
            "fit-camera: {} usable GCPs give {} equations for {} free parameters ({} outside the image or behind the camera){hint}",
            used.len(),
            2 * used.len(),
            k,
            gcps.len() - used.len()
        )));
    }
    let base = CameraParams::from_camera(start);
    // the solver works on offsets from the start (its trust region scales with the norm of
    // the parameters: absolute UTM coordinates would allow steps of kilometres)
    let x0 = DVector::from_iterator(k, opts.free.iter().map(|&p| base.get(p)));
    let (x, rho, sigma_px, rounds) = robust_rounds(base, gcps, &used, opts)?;
    // final statistics at x
    let problem = Problem {
        base,
        free: &opts.free,
        points: fitted_points(gcps, &used, &rho),
    };
    let camera = problem.params_at(&x).camera();
    let e = residual_norms(gcps, &used, &x, &problem);
    let n = 2 * used.len();
    let rss: f64 = e.iter().map(|v| v * v).sum();
    let wr = problem.residuals_at(&x);
    let s2 = if n > k {
        wr.norm_squared() / (n - k) as f64
    } else {
        f64::NAN
    };
    let jac = jacobian(&problem, &x);
    if let Some(j) = &jac {
        check_determined(j, used.len(), &opts.free)?;
    }
    let cov = jac.and_then(|j| (j.transpose() * &j).try_inverse());
    let params = opts
        .free
        .iter()
        .enumerate()
        .map(|(i, &param)| FittedParam {
            param,
            start: x0[i],
            value: x0[i] + x[i],
            sigma: cov
                .as_ref()
                .map_or(f64::NAN, |c| (s2 * c[(i, i)]).max(0.0).sqrt()),
        })
        .collect();
    let bound = 3.03 * sigma_px;
    for (j, &i) in used.iter().enumerate() {
        status[i] = Some(if e[j] > bound && e[j] > 0.5 {
            GcpStatus::Outlier
        } else {
            GcpStatus::Inlier
        });
    }
    let report = gcp_residuals(gcps, &camera, &status, &used, &rho);
    let inl: Vec<f64> = used
        .iter()
        .zip(&e)
        .filter(|(i, _)| status[**i] == Some(GcpStatus::Inlier))
        .map(|(_, v)| *v)
        .collect();
    Ok(CameraFit {
        camera,
        gcps: report,
        params,
        rmse_px: rmse(&e),
        rmse_inliers_px: rmse(&inl),
        aic: n as f64 * (rss.max(1e-300) / n as f64).ln() + 2.0 * k as f64,
        sigma_px,
        rounds,
    })
}

/// Per GCP, why the fit leaves it out (outside the image, behind the start camera) or
/// `None` if it is used.
fn screen_gcps(start: &CameraModel, gcps: &[Gcp]) -> Vec<Option<GcpStatus>> {
    let (w, h) = (start.width as f64, start.height as f64);
    gcps.iter()
        .map(|g| {
            let [u, v] = g.pixel;
            if !(u >= -0.5 && v >= -0.5 && u <= w - 0.5 && v <= h - 0.5) {
                Some(GcpStatus::OutsideImage)
            } else if start.to_camera(g.world).z <= 0.0 {
                Some(GcpStatus::BehindCamera)
            } else {
                None
            }
        })
        .collect()
}

/// Per fitted GCP (`used`, with robust weights `rho`): world point, observed pixel, √(w ρ).
fn fitted_points(gcps: &[Gcp], used: &[usize], rho: &[f64]) -> Vec<(glam::DVec3, [f64; 2], f64)> {
    used.iter()
        .zip(rho)
        .map(|(&i, r)| (gcps[i].world, gcps[i].pixel, (gcps[i].weight * r).sqrt()))
        .collect()
}

/// The reprojection error (pixels) of each fitted GCP at offsets `x`.
fn residual_norms(gcps: &[Gcp], used: &[usize], x: &DVector<f64>, pr: &Problem) -> Vec<f64> {
    let cam = pr.params_at(x).camera();
    used.iter()
        .map(|&i| {
            cam.project(gcps[i].world).map_or(BEHIND_PX, |p| {
                (p[0] - gcps[i].pixel[0]).hypot(p[1] - gcps[i].pixel[1])
            })
        })
        .collect()
}

/// Levenberg-Marquardt rounds, each reweighting the GCPs (Huber) from the last one's
/// residuals when `opts.robust`, until the weights settle: the offsets from the start, the
/// weights, the robust scale (px) and the rounds run.
fn robust_rounds(
    base: CameraParams,
    gcps: &[Gcp],
    used: &[usize],
    opts: &FitOptions,
) -> Result<(DVector<f64>, Vec<f64>, f64, usize)> {
    let mut rho = vec![1.0f64; used.len()];
    let mut x = DVector::zeros(opts.free.len());
    let mut rounds = 0;
    let mut sigma_px;
    let solver = LevenbergMarquardt::new().with_patience(200);
    loop {
        rounds += 1;
        let problem = Problem {
            base,
            free: &opts.free,
            points: fitted_points(gcps, used, &rho),
        };
        let (
            Lsq {
                problem: solved,
                x: sx,
            },
            report,
        ) = solver.minimize(Lsq {
            problem,
            x: x.clone(),
        });
        if report.termination.was_usage_issue() || !sx.iter().all(|v| v.is_finite()) {
            return Err(Error::BadOption(format!(
                "fit-camera: the solver failed ({:?})",
                report.termination
            )));
        }
        x = sx;
        let e = residual_norms(gcps, used, &x, &solved);
        sigma_px = median(&e) / 1.1774;
        if !opts.robust || rounds >= opts.max_rounds.max(1) {
            break;
        }
        let delta = opts.huber_px.unwrap_or_else(|| (2.45 * sigma_px).max(0.5));
        let new: Vec<f64> = e
            .iter()
            .map(|&ei| if ei <= delta { 1.0 } else { delta / ei })
            .collect();
        let change = new
            .iter()
            .zip(&rho)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        rho = new;
        if change < 1e-4 {
            break;
        }
    }
    Ok((x, rho, sigma_px, rounds))
}

/// Refuses free parameters the GCPs do not determine: the Jacobian `j`'s columns scaled to
/// unit norm, the smallest singular value against the largest (repeated GCPs, points on
/// one ray, or a free set the GCPs cannot tell apart leave it near 0).
fn check_determined(j: &nalgebra::DMatrix<f64>, used: usize, free: &[Param]) -> Result<()> {
    let mut jn = j.clone();
    for mut c in jn.column_iter_mut() {
        let n = c.norm();
        if n > 0.0 {
            c /= n;
        }
    }
    let sv = jn.singular_values();
    let (lo, hi) = (sv.min(), sv.max());
    if !(lo > 1e-7 * hi) {
        let names: Vec<&str> = free.iter().map(|p| p.name()).collect();
        return Err(Error::Unusable(format!(
            "fit-camera: the {used} usable GCPs do not determine the free parameters {} (repeated points, points on one ray, or too many free parameters)",
            names.join(",")
        )));
    }
    Ok(())
}

/// Each GCP's residual at `camera`, its robust weight (0 if not fitted) and status.
fn gcp_residuals(
    gcps: &[Gcp],
    camera: &CameraModel,
    status: &[Option<GcpStatus>],
    used: &[usize],
    rho: &[f64],
) -> Vec<GcpResidual> {
    let mut rho_of = vec![0.0; gcps.len()];
    for (j, &i) in used.iter().enumerate() {
        rho_of[i] = rho[j];
    }
    gcps.iter()
        .enumerate()
        .map(|(i, g)| {
            let projected = camera.project(g.world);
            GcpResidual {
                name: g.name.clone(),
                observed: g.pixel,
                projected,
                residual: projected.map(|p| [p[0] - g.pixel[0], p[1] - g.pixel[1]]),
                robust_weight: rho_of[i],
                status: status[i].unwrap_or(GcpStatus::Inlier),
            }
        })
        .collect()
}

/// Root mean square of `v` (NaN if empty).
fn rmse(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
    }
}

fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len() % 2 == 1 {
        s[m]
    } else {
        0.5 * (s[m - 1] + s[m])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_from_yaw_pitch_roll;
    use glam::DVec3;

    /// A camera 300 m from a field of points, like a ground photo of a valley side.
    fn truth() -> CameraModel {
        CameraModel {
            position: DVec3::new(500_000.0, 7_000_000.0, 800.0),
            world_to_camera: rotation_from_yaw_pitch_roll(0.7, 0.08, -0.01),
            width: 4000,
            height: 3000,
            fx: 3500.0,
            fy: 3500.0,
            cx: 1999.5,
            cy: 1499.5,
            k1: -0.08,
            k2: 0.0,
        }
    }

    /// Points the true camera sees, spread over the image, with pseudo-random depths.
    fn gcps(cam: &CameraModel, n: usize, noise: f64) -> Vec<Gcp> {
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64) / ((1u64 << 53) as f64)
        };
        let inv = cam.world_to_camera.transpose();
        (0..n)
            .map(|i| {
                let (x, y, d) = (rnd() * 1.6 - 0.8, rnd() * 1.2 - 0.6, 200.0 + 600.0 * rnd());
                let world = cam.position + inv * DVec3::new(x * d * 0.5, y * d * 0.5, d);
                let p = cam.project(world).unwrap();
                let a = rnd() * std::f64::consts::TAU;
                let r = noise * (-2.0 * rnd().max(1e-12).ln()).sqrt();
                Gcp {
                    name: format!("p{i}"),
                    world,
                    pixel: [p[0] + r * a.cos(), p[1] + r * a.sin()],
                    weight: 1.0,
                }
            })
            .collect()
    }

    fn perturbed(cam: &CameraModel) -> CameraModel {
        let mut p = CameraParams::from_camera(cam);
        p.angles[0] += 2f64.to_radians();
        p.angles[1] -= 1f64.to_radians();
        p.angles[2] += 1f64.to_radians();
        p.focal = [p.focal[0] * 1.03, p.focal[1] * 1.03];
        p.k = [0.0, 0.0];
        p.camera()
    }

    #[test]
    fn recovers_the_camera_from_exact_and_noisy_gcps() {
        let cam = truth();
        let exact = gcps(&cam, 20, 0.0);
        let fit = fit_camera(&perturbed(&cam), &exact, &FitOptions::default()).unwrap();
        assert!(fit.rmse_px < 1e-4, "{}", fit.rmse_px);
        let p = CameraParams::from_camera(&fit.camera);
        let t = CameraParams::from_camera(&cam);
        for k in 0..3 {
            assert!(
                (p.angles[k] - t.angles[k]).abs() < 1e-7,
                "{k}: {} vs {}",
                p.angles[k],
                t.angles[k]
            );
        }
        assert!((p.focal[0] - 3500.0).abs() < 1e-3 && (p.k[0] + 0.08).abs() < 1e-6);
        // 1 px of noise: within a few sigma of the truth, RMSE near the noise (√2 px norm)
        let noisy = gcps(&cam, 40, 1.0);
        let fit = fit_camera(&perturbed(&cam), &noisy, &FitOptions::default()).unwrap();
        assert!(fit.rmse_px > 0.8 && fit.rmse_px < 2.0, "{}", fit.rmse_px);
        let p = CameraParams::from_camera(&fit.camera);
        for (f, (k, want)) in
            fit.params
                .iter()
                .zip([(0, t.angles[0]), (1, t.angles[1]), (2, t.angles[2])])
        {
            assert!(f.sigma > 0.0 && f.sigma < 1e-3, "{:?}", f);
            assert!(
                (p.angles[k] - want).abs() < 5.0 * f.sigma,
                "{:?}: {} vs {}",
                f.param,
                p.angles[k],
                want
            );
        }
        assert!(fit.aic.is_finite());
    }

    #[test]
    fn a_free_position_metres_off_converges() {
        let cam = truth();
        let g = gcps(&cam, 20, 0.3);
        let free = crate::register::parse_free("angles,position,f").unwrap();
        for (k, d) in [
            DVec3::new(5.0, -5.0, 3.0),
            DVec3::new(-5.0, 4.0, -3.0),
            DVec3::new(4.0, 5.0, 2.0),
        ]
        .into_iter()
        .enumerate()
        {
            let mut start = perturbed(&cam);
            start.position += d;
            start.k1 = cam.k1;
            let fit = fit_camera(
                &start,
                &g,
                &FitOptions {
                    free: free.clone(),
                    ..FitOptions::default()
                },
            )
            .unwrap();
            let off = (fit.camera.position - cam.position).length();
            assert!(
                off < 0.5 && fit.rmse_px < 0.6,
                "start {k}: {off} m, {} px",
                fit.rmse_px
            );
        }
    }

    #[test]
    fn outliers_are_flagged_and_do_not_pull_the_fit() {
        let cam = truth();
        let mut g = gcps(&cam, 30, 0.5);
        for k in [3, 11, 17] {
            g[k].pixel[0] += 60.0;
            g[k].pixel[1] -= 40.0;
        }
        let robust = fit_camera(&perturbed(&cam), &g, &FitOptions::default()).unwrap();
        let plain = fit_camera(
            &perturbed(&cam),
            &g,
            &FitOptions {
                robust: false,
                ..FitOptions::default()
            },
        )
        .unwrap();
        let flagged: Vec<usize> = (0..g.len())
            .filter(|&i| robust.gcps[i].status == GcpStatus::Outlier)
            .collect();
        assert_eq!(flagged, vec![3, 11, 17]);
        assert!(robust.rmse_inliers_px < 1.2, "{}", robust.rmse_inliers_px);
        let yaw_err = |f: &CameraFit| (CameraParams::from_camera(&f.camera).angles[0] - 0.7).abs();
        assert!(
            yaw_err(&robust) < 0.3 * yaw_err(&plain),
            "{} vs {}",
            yaw_err(&robust),
            yaw_err(&plain)
        );
    }

    #[test]
    fn points_behind_or_outside_are_reported_not_fatal() {
        let cam = truth();
        let mut g = gcps(&cam, 12, 0.0);
        g[0].pixel = [-30.0, 10.0];
        g[1].world = cam.position - cam.forward() * 100.0;
        let fit = fit_camera(&perturbed(&cam), &g, &FitOptions::default()).unwrap();
        assert_eq!(fit.gcps[0].status, GcpStatus::OutsideImage);
        assert_eq!(fit.gcps[1].status, GcpStatus::BehindCamera);
        assert!(fit.gcps[1].residual.is_none());
        assert!(fit.rmse_px < 1e-4);
        // too few equations is an error, not a panic
        let e = fit_camera(&cam, &g[..3], &FitOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("usable GCPs"), "{e}");
        // so are GCPs that do not determine the parameters (one point repeated)
        let same = vec![g[5].clone(); 4];
        let e = fit_camera(&cam, &same, &FitOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("do not determine"), "{e}");
    }
}
