//! Joint adjustment of several photos' cameras through the points they share and the
//! terrain those points lie on, when no photo's pose is known well enough to anchor the
//! others (a hand-held GPS places each camera within a few metres).
//!
//! Input: start cameras, the rough cameras the priors are centred on (GPS position, compass,
//! EXIF focal length), which cameras are fixed, and per pair of photos the pixels where both
//! show the same point ([`PairTie`], e.g. [`super::ResectFit::ties`]). Output: a
//! [`BundleFit`] with the adjusted cameras and their standard deviations.
//!
//! **Residuals.** For a tie of photos `a` and `b`, the ray of `a` through its pixel meets the
//! terrain (`surface`) at `X`; `b` should show `X` at its pixel: the difference, pixels. The
//! same the other way (`b`'s ray, `a`'s pixel). Each is divided by its expected spread
//! `√(σ_m² + σ_s²)`: the matcher's `σ_m` ([`BundleOptions::match_sigma_px`]) and `σ_s`, how
//! far a terrain error of [`BundleOptions::surface_error_m`] along the first ray moves `X` in
//! the second photo. So the points are not free unknowns: they are held on the terrain model,
//! and moving both cameras together moves them across relief, which is what pins the
//! position where the photos alone (a relative pose) could not. Priors: each free parameter
//! of a camera that is not fixed, its offset from the rough camera over
//! [`BundleOptions::prior_position_m`], [`BundleOptions::prior_angle_deg`] or
//! [`BundleOptions::prior_focal`].
//!
//! **Solve.** Levenberg-Marquardt (`levenberg-marquardt` crate) over offsets of the free
//! parameters from the start, Jacobian by central differences (only the ties of the cameras
//! a parameter belongs to are recomputed), inside reweighting rounds with Huber weights
//! `min(1, δ / |z|)` on the normalised residuals (`δ = 2.45 σ̂`, `σ̂ = median |z| / 1.1774`, as
//! [`super::fit_camera`]); ties beyond `3.03 σ̂` are counted as outliers. Standard deviations
//! from `s² (JᵀJ)⁻¹` with `s²` the normalised tie residuals' variance. Deterministic.

use glam::DVec3;
use levenberg_marquardt::LevenbergMarquardt;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::lsq::{Lsq, Residuals};
use super::params::{CameraParams, Param};
use crate::camera::CameraModel;
use crate::error::{Error, Result};

/// A point two photos show: where the first (`anchor_px`) and the second (`photo_px`) show
/// it, 0-based pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairTie {
    /// Pixel in the first photo.
    pub anchor_px: [f64; 2],
    /// Pixel in the second photo.
    pub photo_px: [f64; 2],
}

/// The ties between cameras `a` and `b` of a bundle (indices into its cameras).
#[derive(Clone, Debug, PartialEq)]
pub struct BundlePair {
    /// The first photo (whose pixels are [`PairTie::anchor_px`]).
    pub a: usize,
    /// The second photo.
    pub b: usize,
    /// The shared points.
    pub ties: Vec<PairTie>,
}

/// How [`adjust_bundle`] fits.
#[derive(Clone, Debug, PartialEq)]
pub struct BundleOptions {
    /// Parameters fitted for every camera that is not fixed. Default yaw, pitch, roll, x,
    /// y, z.
    pub free: Vec<Param>,
    /// Prior standard deviations of the rough position, horizontal and vertical, metres.
    /// Default 5, 3.
    pub prior_position_m: [f64; 2],
    /// Prior standard deviation of the rough angles, degrees. Default 5.
    pub prior_angle_deg: f64,
    /// Prior standard deviation of the rough focal length, relative. Default 0.05.
    pub prior_focal: f64,
    /// Spread of a match's position, pixels. Default 0.15.
    pub match_sigma_px: f64,
    /// Error bound of the terrain (a store's TIN: its `max_error`), metres. Default 0.5.
    pub surface_error_m: f64,
    /// Most reweighting rounds. Default 6.
    pub max_rounds: usize,
}

impl Default for BundleOptions {
    fn default() -> Self {
        BundleOptions {
            free: Param::POSE.to_vec(),
            prior_position_m: [5.0, 3.0],
            prior_angle_deg: 5.0,
            prior_focal: 0.05,
            match_sigma_px: 0.15,
            surface_error_m: 0.5,
            max_rounds: 6,
        }
    }
}

/// The result of [`adjust_bundle`].
#[derive(Clone, Debug, PartialEq)]
pub struct BundleFit {
    /// The adjusted cameras, in input order (fixed ones unchanged).
    pub cameras: Vec<CameraModel>,
    /// Per camera, standard deviations of the position (east, north, up), metres; NaN for
    /// a fixed camera or a parameter not fitted.
    pub sigma_position_m: Vec<[f64; 3]>,
    /// Per camera, standard deviations of yaw, pitch and roll, degrees (NaN as above).
    pub sigma_angles_deg: Vec<[f64; 3]>,
    /// RMS (pixels) of the inlier tie residuals, both directions.
    pub rmse_px: f64,
    /// Per pair: inlier residuals (of two per tie) and residuals used.
    pub inliers: Vec<(usize, usize)>,
    /// Reweighting rounds run.
    pub rounds: usize,
}

/// The normalised residual standing for a tie whose ray stopped meeting the terrain, or
/// whose point went behind the other camera, during the search (the step is rejected for
/// its cost).
const LOST: f64 = 1e3;

/// One direction of one tie: from camera `from`'s pixel through the terrain to camera
/// `to`'s pixel.
#[derive(Clone, Copy, Debug)]
struct Ray {
    from: usize,
    to: usize,
    from_px: [f64; 2],
    to_px: [f64; 2],
    /// `√(w ρ) / σ_m`: the factor from pixels to the normalised residual (0: not used).
    scale: f64,
}

/// Where `from`'s ray through `from_px` meets the terrain, seen by `to`; `None` if it
/// misses or is behind `to`.
fn transfer(
    cams: &[CameraModel],
    r: &Ray,
    surface: &(impl Fn(DVec3, DVec3) -> Option<DVec3> + Sync),
) -> Option<[f64; 2]> {
    let (cf, ct) = (&cams[r.from], &cams[r.to]);
    let d = cf.pixel_ray(r.from_px[0], r.from_px[1])?;
    let x = surface(cf.position, d)?;
    ct.project(x)
}

/// The camera parameters of one camera of the problem.
struct Block {
    camera: usize,
    /// First column of its parameters.
    col: usize,
}

struct Problem<'a, S> {
    start: Vec<CameraModel>,
    base: Vec<CameraParams>,
    prior: Vec<CameraParams>,
    blocks: Vec<Block>,
    free: &'a [Param],
    /// Per block and free parameter: the prior's standard deviation.
    prior_sigma: Vec<f64>,
    rays: Vec<Ray>,
    /// Per camera: the rays it takes part in.
    rays_of: Vec<Vec<usize>>,
    surface: &'a S,
}

impl<S: Fn(DVec3, DVec3) -> Option<DVec3> + Sync> Problem<'_, S> {
    fn n_params(&self) -> usize {
        self.blocks.len() * self.free.len()
    }

    /// The cameras at offsets `x` (fixed cameras exactly as given).
    fn cameras_at(&self, x: &DVector<f64>) -> Vec<CameraModel> {
        let mut cams = self.start.clone();
        for b in &self.blocks {
            let mut p = self.base[b.camera];
            for (k, &param) in self.free.iter().enumerate() {
                p.set(param, p.get(param) + x[b.col + k]);
            }
            cams[b.camera] = p.camera();
        }
        cams
    }

    /// The normalised residuals (2 per ray) of the rays `which` for cameras `cams`.
    fn ray_residuals(&self, cams: &[CameraModel], which: &[usize]) -> Vec<[f64; 2]> {
        which
            .par_iter()
            .map(|&i| {
                let r = &self.rays[i];
                if r.scale == 0.0 {
                    return [0.0; 2];
                }
                match transfer(cams, r, self.surface) {
                    Some(q) => [(q[0] - r.to_px[0]) * r.scale, (q[1] - r.to_px[1]) * r.scale],
                    None => [LOST; 2],
                }
            })
            .collect()
    }

    /// The prior rows at offsets `x`.
    fn prior_residuals(&self, x: &DVector<f64>) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.n_params());
        for b in &self.blocks {
            for (k, &param) in self.free.iter().enumerate() {
                let v = self.base[b.camera].get(param) + x[b.col + k];
                let mut d = v - self.prior[b.camera].get(param);
                if param.is_angle() {
                    d = (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI;
                }
                out.push(d / self.prior_sigma[b.col + k]);
            }
        }
        out
    }

    fn all_residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        let cams = self.cameras_at(x);
        let all: Vec<usize> = (0..self.rays.len()).collect();
        let rays = self.ray_residuals(&cams, &all);
        let prior = self.prior_residuals(x);
        DVector::from_iterator(
            2 * rays.len() + prior.len(),
            rays.iter().flat_map(|r| r.iter().copied()).chain(prior),
        )
    }

    fn jacobian_matrix(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let n_rows = 2 * self.rays.len() + self.n_params();
        let mut j = DMatrix::zeros(n_rows, self.n_params());
        for b in &self.blocks {
            let which = &self.rays_of[b.camera];
            for (k, &param) in self.free.iter().enumerate() {
                let col = b.col + k;
                let h = param.step();
                let (mut lo, mut hi) = (x.clone(), x.clone());
                lo[col] -= h;
                hi[col] += h;
                let rl = self.ray_residuals(&self.cameras_at(&lo), which);
                let rh = self.ray_residuals(&self.cameras_at(&hi), which);
                for ((&i, l), hh) in which.iter().zip(&rl).zip(&rh) {
                    for c in 0..2 {
                        j[(2 * i + c, col)] = (hh[c] - l[c]) / (2.0 * h);
                    }
                }
                j[(2 * self.rays.len() + col, col)] = 1.0 / self.prior_sigma[col];
            }
        }
        j
    }
}

impl<S: Fn(DVec3, DVec3) -> Option<DVec3> + Sync> Residuals for Problem<'_, S> {
    fn free(&self) -> &[Param] {
        self.free
    }

    fn residuals_at(&self, x: &DVector<f64>) -> DVector<f64> {
        self.all_residuals(x)
    }

    fn jacobian_at(&self, x: &DVector<f64>) -> Option<DMatrix<f64>> {
        let j = self.jacobian_matrix(x);
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

/// `σ_m / √(σ_m² + σ_s²)` over `σ_m`: the factor from pixels to a normalised residual of the
/// ray from `from` through `from_px` seen by `to`, `σ_s` the pixels a terrain error `e` along
/// the ray moves its point in `to` (0 if the ray misses).
fn ray_scale(
    cams: &[CameraModel],
    r: &Ray,
    surface: &impl Fn(DVec3, DVec3) -> Option<DVec3>,
    sigma_m: f64,
    e: f64,
) -> f64 {
    let (cf, ct) = (&cams[r.from], &cams[r.to]);
    let Some(ray) = cf.pixel_ray(r.from_px[0], r.from_px[1]) else {
        return 0.0;
    };
    let Some(x) = surface(cf.position, ray) else {
        return 0.0;
    };
    if ct.project(x).is_none() {
        return 0.0;
    }
    let to = x - ct.position;
    let dist = to.length();
    if !(dist > 0.0) {
        return 0.0;
    }
    let d = to / dist;
    let across = (ray - d * ray.dot(d)).length();
    let s = ct.fx * e * across / dist;
    1.0 / (sigma_m * sigma_m + s * s).sqrt()
}

/// Adjusts the cameras `start` (not those marked in `fixed`) to the ties `pairs` through
/// the terrain `surface(origin, unit dir) -> hit`, with priors centred on `prior` (see the
/// module docs (`src/register/bundle.rs`)). `start`, `prior` and `fixed` have one entry per camera.
///
/// Errors (never panics): lengths that differ, a pair naming a camera out of range or the
/// same camera twice, no free camera, no tie that meets the terrain, or a solver failure.
pub fn adjust_bundle(
    start: &[CameraModel],
    prior: &[CameraModel],
    fixed: &[bool],
    pairs: &[BundlePair],
    surface: impl Fn(DVec3, DVec3) -> Option<DVec3> + Sync,
    opts: &BundleOptions,
) -> Result<BundleFit> {
    let n = start.len();
    check_bundle_inputs(n, prior, fixed, pairs, opts)?;
    let blocks = free_blocks(fixed, opts)?;
    let prior_sigma = prior_sigmas(&blocks, prior, opts)?;
    let (rays, rays_of) = tie_rays(pairs, n);
    let k = blocks.len() * opts.free.len();
    let problem = Problem {
        start: start.to_vec(),
        base: start.iter().map(CameraParams::from_camera).collect(),
        prior: prior.iter().map(CameraParams::from_camera).collect(),
        blocks,
        free: &opts.free,
        prior_sigma,
        rays,
        rays_of,
        surface: &surface,
    };
    let lsq = Lsq {
        problem,
        x: DVector::zeros(k),
    };
    let (lsq, inlier, rounds) = robust_rounds(lsq, opts)?;
    let (sigma_position_m, sigma_angles_deg) = parameter_sigmas(&lsq, opts, n, k);
    let cams = lsq.problem.cameras_at(&lsq.x);
    let (rmse_px, inliers) = inlier_residuals(&lsq.problem, &cams, pairs, &inlier);
    Ok(BundleFit {
        cameras: cams,
        sigma_position_m,
        sigma_angles_deg,
        rmse_px,
        inliers,
        rounds,
    })
}

/// Refuses lists of different lengths, a pair naming a camera out of range or the same
/// camera twice, and an empty free set.
fn check_bundle_inputs(
    n: usize,
    prior: &[CameraModel],
    fixed: &[bool],
    pairs: &[BundlePair],
    opts: &BundleOptions,
) -> Result<()> {
    if prior.len() != n || fixed.len() != n {
        return Err(Error::BadOption(format!(
            "bundle: {n} start cameras, {} priors, {} fixed flags",
            prior.len(),
            fixed.len()
        )));
    }
    if let Some(p) = pairs.iter().find(|p| p.a >= n || p.b >= n || p.a == p.b) {
        return Err(Error::BadOption(format!(
            "bundle: a pair of cameras {} and {} among {n}",
            p.a, p.b
        )));
    }
    if opts.free.is_empty() {
        return Err(Error::BadOption("bundle: no free parameters".into()));
    }
    Ok(())
}

/// A block of columns per camera not `fixed`; an error when every camera is.
fn free_blocks(fixed: &[bool], opts: &BundleOptions) -> Result<Vec<Block>> {
    let mut blocks = Vec::new();
    for c in (0..fixed.len()).filter(|&c| !fixed[c]) {
        blocks.push(Block {
            camera: c,
            col: blocks.len() * opts.free.len(),
        });
    }
    if blocks.is_empty() {
        return Err(Error::BadOption("bundle: every camera is fixed".into()));
    }
    Ok(blocks)
}

/// Per block and free parameter, the prior's standard deviation (all must be positive).
fn prior_sigmas(blocks: &[Block], prior: &[CameraModel], opts: &BundleOptions) -> Result<Vec<f64>> {
    let prior_sigma: Vec<f64> = blocks
        .iter()
        .flat_map(|b| {
            opts.free.iter().map(move |&p| match p {
                Param::X | Param::Y => opts.prior_position_m[0],
                Param::Z => opts.prior_position_m[1],
                Param::Yaw | Param::Pitch | Param::Roll => opts.prior_angle_deg.to_radians(),
                Param::F | Param::Fx | Param::Fy => opts.prior_focal * prior[b.camera].fx,
                Param::Cx | Param::Cy => 0.05 * prior[b.camera].width as f64,
                Param::K1 | Param::K2 => 0.1,
            })
        })
        .collect();
    if prior_sigma.iter().any(|s| !(*s > 0.0)) {
        return Err(Error::BadOption(
            "bundle: prior standard deviations must be positive".into(),
        ));
    }
    Ok(prior_sigma)
}

/// Two rays per tie (each photo's pixel transferred into the other), pair by pair, and per
/// camera the rays it takes part in.
fn tie_rays(pairs: &[BundlePair], n: usize) -> (Vec<Ray>, Vec<Vec<usize>>) {
    let mut rays = Vec::new();
    for p in pairs {
        for t in &p.ties {
            for (from, to, fp, tp) in [
                (p.a, p.b, t.anchor_px, t.photo_px),
                (p.b, p.a, t.photo_px, t.anchor_px),
            ] {
                rays.push(Ray {
                    from,
                    to,
                    from_px: fp,
                    to_px: tp,
                    scale: 0.0,
                });
            }
        }
    }
    let mut rays_of = vec![Vec::new(); n];
    for (i, r) in rays.iter().enumerate() {
        rays_of[r.from].push(i);
        rays_of[r.to].push(i);
    }
    (rays, rays_of)
}

/// Levenberg-Marquardt rounds, the rays' scales and Huber weights renewed from each
/// round's residuals until the weights settle: the solved problem, each ray's inlier flag
/// and the rounds run.
fn robust_rounds<'a, S: Fn(DVec3, DVec3) -> Option<DVec3> + Sync>(
    mut lsq: Lsq<Problem<'a, S>>,
    opts: &BundleOptions,
) -> Result<(Lsq<Problem<'a, S>>, Vec<bool>, usize)> {
    let surface = lsq.problem.surface;
    let solver = LevenbergMarquardt::new().with_patience(100);
    let mut rho = vec![1.0f64; lsq.problem.rays.len()];
    let mut rounds = 0;
    let mut inlier = vec![false; lsq.problem.rays.len()];
    loop {
        rounds += 1;
        let cams = lsq.problem.cameras_at(&lsq.x);
        // the rays' scales at the current cameras, with the Huber weights
        let scales: Vec<f64> = lsq
            .problem
            .rays
            .par_iter()
            .map(|r| ray_scale(&cams, r, surface, opts.match_sigma_px, opts.surface_error_m))
            .collect();
        for ((r, s), w) in lsq.problem.rays.iter_mut().zip(scales).zip(&rho) {
            r.scale = s * w.sqrt();
        }
        if lsq.problem.rays.iter().all(|r| r.scale == 0.0) {
            return Err(Error::BadOption(
                "bundle: no tie's ray meets the terrain".into(),
            ));
        }
        let (solved, report) = solver.minimize(lsq);
        lsq = solved;
        if !report.termination.was_successful() && !report.objective_function.is_finite() {
            return Err(Error::BadOption(format!(
                "bundle: the solver failed ({:?})",
                report.termination
            )));
        }
        // normalised residuals without the Huber weights, for the next weights
        let cams = lsq.problem.cameras_at(&lsq.x);
        let z: Vec<Option<f64>> = lsq
            .problem
            .rays
            .par_iter()
            .zip(&rho)
            .map(|(r, w)| {
                if r.scale == 0.0 {
                    return None;
                }
                let q = transfer(&cams, r, surface)?;
                let unweighted = r.scale / w.sqrt();
                Some((q[0] - r.to_px[0]).hypot(q[1] - r.to_px[1]) * unweighted)
            })
            .collect();
        let mut used: Vec<f64> = z.iter().flatten().copied().collect();
        used.sort_by(f64::total_cmp);
        let sigma = used.get(used.len() / 2).copied().unwrap_or(0.0) / 1.1774;
        let delta = (2.45 * sigma).max(1e-9);
        let new_rho: Vec<f64> = z
            .iter()
            .map(|v| v.map_or(1.0, |v| (delta / v.max(1e-300)).min(1.0)))
            .collect();
        for (f, v) in inlier.iter_mut().zip(&z) {
            *f = v.is_some_and(|v| v <= 3.03 * sigma);
        }
        let change = new_rho
            .iter()
            .zip(&rho)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        rho = new_rho;
        if change < 1e-3 || rounds >= opts.max_rounds.max(1) {
            break;
        }
    }
    Ok((lsq, inlier, rounds))
}

/// Standard deviations of each free camera's position (m) and angles (°): s² (JᵀJ)⁻¹ with
/// the tie rows' variance; NaN where not free or not determined.
#[allow(clippy::type_complexity)]
fn parameter_sigmas<S: Fn(DVec3, DVec3) -> Option<DVec3> + Sync>(
    lsq: &Lsq<Problem<'_, S>>,
    opts: &BundleOptions,
    n: usize,
    k: usize,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let x = lsq.x.clone();
    let j = lsq.problem.jacobian_matrix(&x);
    let r = lsq.problem.all_residuals(&x);
    let n_ray_rows = 2 * lsq.problem.rays.len();
    let used_rows = 2 * lsq.problem.rays.iter().filter(|r| r.scale > 0.0).count();
    let rss: f64 = r.rows(0, n_ray_rows).iter().map(|v| v * v).sum();
    let s2 = if used_rows > k {
        rss / (used_rows - k) as f64
    } else {
        f64::NAN
    };
    let cov = (j.transpose() * &j).try_inverse();
    let mut sigma_position_m = vec![[f64::NAN; 3]; n];
    let mut sigma_angles_deg = vec![[f64::NAN; 3]; n];
    for b in &lsq.problem.blocks {
        for (kk, &param) in opts.free.iter().enumerate() {
            let col = b.col + kk;
            let sd = cov
                .as_ref()
                .map_or(f64::NAN, |c| (c[(col, col)] * s2).max(0.0).sqrt());
            match param {
                Param::X => sigma_position_m[b.camera][0] = sd,
                Param::Y => sigma_position_m[b.camera][1] = sd,
                Param::Z => sigma_position_m[b.camera][2] = sd,
                Param::Yaw => sigma_angles_deg[b.camera][0] = sd.to_degrees(),
                Param::Pitch => sigma_angles_deg[b.camera][1] = sd.to_degrees(),
                Param::Roll => sigma_angles_deg[b.camera][2] = sd.to_degrees(),
                _ => {}
            }
        }
    }
    (sigma_position_m, sigma_angles_deg)
}

/// The RMSE (px, unweighted) of the inlier rays at `cams`, and per pair its inlier rays
/// and all its rays.
fn inlier_residuals<S: Fn(DVec3, DVec3) -> Option<DVec3> + Sync>(
    problem: &Problem<'_, S>,
    cams: &[CameraModel],
    pairs: &[BundlePair],
    inlier: &[bool],
) -> (f64, Vec<(usize, usize)>) {
    let px: Vec<Option<f64>> = problem
        .rays
        .par_iter()
        .map(|r| {
            let q = transfer(cams, r, problem.surface)?;
            Some((q[0] - r.to_px[0]).hypot(q[1] - r.to_px[1]))
        })
        .collect();
    let (mut sum, mut cnt) = (0.0, 0usize);
    let mut inliers = Vec::with_capacity(pairs.len());
    let mut at = 0;
    for p in pairs {
        let m = 2 * p.ties.len();
        let mut good = 0;
        for i in at..at + m {
            if inlier[i]
                && let Some(e) = px[i]
            {
                sum += e * e;
                cnt += 1;
                good += 1;
            }
        }
        inliers.push((good, m));
        at += m;
    }
    let rmse = if cnt > 0 {
        (sum / cnt as f64).sqrt()
    } else {
        f64::NAN
    };
    (rmse, inliers)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_from_yaw_pitch_roll;

    /// Ground height of the test terrain: flat (z = 0) up to x = 60, then a ramp rising
    /// 0.5 m per metre to x = 100.
    fn ground(x: f64) -> f64 {
        0.5 * (x - 60.0).max(0.0)
    }

    /// A terrain with no similarity that maps it onto itself: a floor, a ramp, and walls at
    /// x = 100 and y = 100 up to 80 m (three planes through one point would be invariant
    /// under scaling about it, and so would their photos).
    fn corner(o: DVec3, d: DVec3) -> Option<DVec3> {
        let planes = [
            (DVec3::Z, 0.0),
            (DVec3::new(-0.5, 0.0, 1.0), -30.0),
            (DVec3::X, 100.0),
            (DVec3::Y, 100.0),
        ];
        let mut best: Option<(f64, DVec3)> = None;
        for (k, (n, c)) in planes.into_iter().enumerate() {
            let den = n.dot(d);
            if den.abs() < 1e-12 {
                continue;
            }
            let t = (c - n.dot(o)) / den;
            let p = o + d * t;
            let e = 1e-9;
            let inside = p.x <= 100.0 + e
                && p.y <= 100.0 + e
                && p.z <= 80.0
                && match k {
                    0 => p.x <= 60.0 + e,
                    1 => p.x >= 60.0 - e,
                    _ => p.z >= ground(p.x) - e,
                };
            if t > 0.0 && inside && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, p));
            }
        }
        best.map(|(_, p)| p)
    }

    fn camera(pos: DVec3, yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> CameraModel {
        let r = rotation_from_yaw_pitch_roll(
            yaw_deg.to_radians(),
            pitch_deg.to_radians(),
            roll_deg.to_radians(),
        );
        CameraModel::with_fov(pos, r, 800, 600, 0.9)
    }

    fn ties(a: &CameraModel, b: &CameraModel) -> Vec<PairTie> {
        let mut out = Vec::new();
        for v in (10..600).step_by(30) {
            for u in (10..800).step_by(30) {
                let px = [u as f64, v as f64];
                let Some(x) = a
                    .pixel_ray(px[0], px[1])
                    .and_then(|d| corner(a.position, d))
                else {
                    continue;
                };
                if let Some(q) = b.project(x)
                    && (0.0..800.0).contains(&q[0])
                    && (0.0..600.0).contains(&q[1])
                    // seen by b too (not hidden behind a wall)
                    && b.pixel_ray(q[0], q[1])
                        .and_then(|d| corner(b.position, d))
                        .is_some_and(|y| y.distance(x) < 1e-6)
                {
                    out.push(PairTie {
                        anchor_px: px,
                        photo_px: q,
                    });
                }
            }
        }
        out
    }

    #[test]
    fn two_rough_cameras_are_placed_by_ties_held_on_the_terrain() {
        let ta = camera(DVec3::new(20.0, 10.0, 5.0), 48.0, -2.0, 0.0);
        let tb = camera(DVec3::new(5.0, 40.0, 4.0), 35.0, -1.0, 0.0);
        let pairs = [BundlePair {
            a: 0,
            b: 1,
            ties: ties(&ta, &tb),
        }];
        assert!(pairs[0].ties.len() > 100, "{} ties", pairs[0].ties.len());
        let ra = camera(DVec3::new(21.0, 9.2, 5.5), 48.4, -2.3, 0.2);
        let rb = camera(DVec3::new(4.3, 40.6, 3.7), 34.7, -0.8, -0.2);
        let opts = BundleOptions {
            surface_error_m: 0.01,
            ..BundleOptions::default()
        };
        let fit = adjust_bundle(&[ra, rb], &[ra, rb], &[false, false], &pairs, corner, &opts)
            .expect("adjusts");
        for (got, want) in fit.cameras.iter().zip([ta, tb]) {
            assert!(
                got.position.distance(want.position) < 0.02,
                "{:?} against {:?}",
                got.position,
                want.position
            );
            let (g, w) = (
                CameraParams::from_camera(got),
                CameraParams::from_camera(&want),
            );
            for k in 0..3 {
                assert!((g.angles[k] - w.angles[k]).abs().to_degrees() < 0.005);
            }
        }
        assert!(fit.rmse_px < 0.01, "{}", fit.rmse_px);
        assert!(fit.sigma_position_m.iter().flatten().all(|s| *s < 0.05));
        // a camera held fixed stays where it is
        let fixed = adjust_bundle(&[ta, rb], &[ta, rb], &[true, false], &pairs, corner, &opts)
            .expect("adjusts");
        assert_eq!(fixed.cameras[0], ta);
        assert!(fixed.cameras[1].position.distance(tb.position) < 0.02);
        assert!(fixed.sigma_position_m[0].iter().all(|s| s.is_nan()));
    }

    #[test]
    fn bad_bundles_are_errors() {
        let c = camera(DVec3::ZERO, 45.0, 0.0, 0.0);
        let opts = BundleOptions::default();
        let pair = |a, b| BundlePair { a, b, ties: vec![] };
        assert!(adjust_bundle(&[c], &[c, c], &[false], &[], corner, &opts).is_err());
        assert!(
            adjust_bundle(&[c, c], &[c, c], &[false; 2], &[pair(0, 2)], corner, &opts).is_err()
        );
        assert!(
            adjust_bundle(&[c, c], &[c, c], &[false; 2], &[pair(1, 1)], corner, &opts).is_err()
        );
        assert!(adjust_bundle(&[c, c], &[c, c], &[true; 2], &[pair(0, 1)], corner, &opts).is_err());
        // no tie at all
        assert!(
            adjust_bundle(&[c, c], &[c, c], &[false; 2], &[pair(0, 1)], corner, &opts).is_err()
        );
    }
}
