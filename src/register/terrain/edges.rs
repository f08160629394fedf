//! Pose refinement by silhouette edges, position included (docs/registration.md,
//! "Position").
//!
//! The terrain's silhouettes seen from the current camera (its outline against the sky and
//! every ridge in front of farther ground) are found on a grid of rays and located to a
//! hundredth of a pixel by bisection; each becomes a [`ContourPoint`]: the grazing point on
//! the occluding surface (world metres) and the silhouette's normal in the image. Each is
//! matched to the photo's strongest luma edge along that normal within a search range (the
//! "moving edges" of model-based tracking, Bouthemy 1989; Drummond & Cipolla 2002), and the
//! camera's free parameters, position included, are fitted to the point-to-edge-line
//! distances by robust Levenberg-Marquardt (Huber IRLS, the `levenberg-marquardt` crate),
//! with weak priors tying the position and focal length to the rough camera's (a GPS fix and
//! EXIF). Silhouettes at different distances move differently when the camera moves
//! (parallax), which is what fixes the position; a silhouette of smooth terrain slides over
//! the surface as the camera moves, so the silhouettes are found again from the new camera
//! and the fit repeated until it stops moving, on the photo reduced 4×, 2× and at full size.

use glam::DVec3;
use image::RgbImage;
use levenberg_marquardt::LevenbergMarquardt;
use nalgebra::DVector;
use rayon::prelude::*;

use super::view::{LabelledTerrain, RayEnd};
use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::register::grey::Grey;
use crate::register::lsq::{Lsq, Residuals, jacobian, params_at};
use crate::register::params::{CameraParams, Param};

/// One silhouette point of the terrain seen from a camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContourPoint {
    /// The grazing point on the occluding surface, world metres.
    pub point: DVec3,
    /// Where the camera shows it (pixels of the camera it was found with).
    pub pixel: [f64; 2],
    /// Unit normal of the silhouette in the image, from the occluder towards what lies
    /// behind (sky or farther ground).
    pub normal: [f64; 2],
}

/// Distance ratio between neighbouring rays above which their hits are in different
/// layers (the nearer one occludes the farther).
const JUMP: f64 = 1.25;

/// One located crossing of [`contour`]: the grazing point (world metres), its pixel and the
/// image axis from the near side towards the far side.
type Crossing = (DVec3, [f64; 2], [f64; 2]);

/// Silhouettes of the terrain seen by `cam`: crossings between neighbouring rays of a grid
/// of `step` pixels (inset by `margin` pixels) from terrain to sky or to terrain more than
/// 1.25× farther, each located by 10 bisections of the ray between them (the last ray on
/// the near side gives the point). Normals from the crossings within 2.5 steps (principal
/// direction of their positions), else the grid direction. Deterministic.
pub fn contour(
    terrain: &LabelledTerrain,
    cam: &CameraModel,
    step: f64,
    margin: f64,
) -> Vec<ContourPoint> {
    let (w, h) = (cam.width as f64, cam.height as f64);
    let nu = ((w - 2.0 * margin) / step).floor().max(0.0) as usize;
    let nv = ((h - 2.0 * margin) / step).floor().max(0.0) as usize;
    let at = |i: usize, j: usize| {
        [
            margin + (i as f64 + 0.5) * step,
            margin + (j as f64 + 0.5) * step,
        ]
    };
    let caster = cam.ray_caster();
    let end = |p: [f64; 2]| -> Option<RayEnd> {
        let dir = caster.ray(p[0], p[1])?;
        terrain.classify(cam.position, dir)
    };
    let grid: Vec<Option<RayEnd>> = (0..nu * nv)
        .into_par_iter()
        .map(|k| end(at(k % nu, k / nu)))
        .collect();
    // pairs (near cell, far cell) along x and y
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    let occludes = |a: &Option<RayEnd>, b: &Option<RayEnd>| match (a, b) {
        (Some(RayEnd::Terrain(_, da)), Some(RayEnd::Sky)) => da.is_finite(),
        (Some(RayEnd::Terrain(_, da)), Some(RayEnd::Terrain(_, db))) => *db > JUMP * da,
        _ => false,
    };
    for j in 0..nv {
        for i in 0..nu {
            let k = j * nu + i;
            for n in [
                (i + 1 < nu).then_some(k + 1),
                (j + 1 < nv).then_some(k + nu),
            ]
            .into_iter()
            .flatten()
            {
                if occludes(&grid[k], &grid[n]) {
                    pairs.push((k, n));
                } else if occludes(&grid[n], &grid[k]) {
                    pairs.push((n, k));
                }
            }
        }
    }
    let located: Vec<Option<Crossing>> = pairs
        .par_iter()
        .map(|&(a, b)| {
            let (mut pa, mut pb) = (at(a % nu, a / nu), at(b % nu, b / nu));
            let Some(RayEnd::Terrain(mut xa, da)) = grid[a] else {
                return None;
            };
            let far = match grid[b] {
                Some(RayEnd::Terrain(_, db)) => (da * db).sqrt(),
                _ => JUMP * da,
            };
            for _ in 0..10 {
                let m = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
                match end(m) {
                    Some(RayEnd::Terrain(x, d)) if d < far => {
                        pa = m;
                        xa = x;
                    }
                    _ => pb = m,
                }
            }
            let axis = [(pb[0] - pa[0]).signum(), (pb[1] - pa[1]).signum()];
            let axis = if pb[0] != pa[0] {
                [axis[0], 0.0]
            } else {
                [0.0, axis[1]]
            };
            Some((xa, [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])], axis))
        })
        .collect();
    let pts: Vec<Crossing> = located.into_iter().flatten().collect();
    // normals from the neighbouring crossings (a bucket grid of 2.5-step cells)
    let cell = 2.5 * step;
    let key = |p: [f64; 2]| ((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64);
    let mut buckets: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    for (k, p) in pts.iter().enumerate() {
        buckets.entry(key(p.1)).or_default().push(k);
    }
    pts.iter()
        .map(|&(point, pixel, axis)| {
            let (kx, ky) = key(pixel);
            let (mut sx, mut sy, mut sxx, mut syy, mut sxy, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for &o in buckets.get(&(kx + dx, ky + dy)).into_iter().flatten() {
                        let q = pts[o].1;
                        let (ex, ey) = (q[0] - pixel[0], q[1] - pixel[1]);
                        if ex * ex + ey * ey <= cell * cell {
                            sx += q[0];
                            sy += q[1];
                            sxx += q[0] * q[0];
                            syy += q[1] * q[1];
                            sxy += q[0] * q[1];
                            n += 1.0;
                        }
                    }
                }
            }
            let mut normal = axis;
            if n >= 3.0 {
                let (mx, my) = (sx / n, sy / n);
                let (cxx, cyy, cxy) = (sxx / n - mx * mx, syy / n - my * my, sxy / n - mx * my);
                // principal direction of the positions: the tangent
                let theta = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
                let nrm = [-theta.sin(), theta.cos()];
                let s = if nrm[0] * axis[0] + nrm[1] * axis[1] < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                normal = [s * nrm[0], s * nrm[1]];
            }
            ContourPoint {
                point,
                pixel,
                normal,
            }
        })
        .collect()
}

/// Pixels (of the reduced image) around a masked one without gradient: the blur's reach.
pub const MASK_EDGE_MARGIN: usize = 4;

/// Per pixel of a `w × h` image reduced `factor` times from `mask`'s, whether none of the
/// full-resolution pixels it averages is masked.
pub(crate) fn reduced_validity(
    mask: &crate::photo::PixelMask,
    factor: u32,
    w: usize,
    h: usize,
) -> Vec<bool> {
    let f = factor.max(1);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x as u32, y as u32)))
        .map(|(x, y)| {
            (y * f..(y + 1) * f).all(|yy| (x * f..(x + 1) * f).all(|xx| !mask.is_masked([xx, yy])))
        })
        .collect()
}

/// A photo's luma gradient at one scale (box-filtered by a power of two, then Gaussian σ 1 px).
pub struct EdgeImage {
    width: usize,
    height: usize,
    gx: Vec<f32>,
    gy: Vec<f32>,
}

impl EdgeImage {
    /// The gradient of `photo` box-filtered by `factor` per axis.
    pub fn from_photo(photo: &RgbImage, factor: u32) -> EdgeImage {
        Self::from_photo_masked(photo, None, factor)
    }

    /// [`EdgeImage::from_photo`] with no gradient within `MASK_EDGE_MARGIN` (4) pixels of a
    /// reduced pixel that holds a masked one (a border's edge is no terrain edge).
    pub fn from_photo_masked(
        photo: &RgbImage,
        mask: Option<&crate::photo::PixelMask>,
        factor: u32,
    ) -> EdgeImage {
        let mut e = Self::unmasked(photo, factor);
        if let Some(m) = mask
            && e.width > 0
        {
            let valid = reduced_validity(m, factor.max(1), e.width, e.height);
            let r = MASK_EDGE_MARGIN as isize;
            let (w, h) = (e.width as isize, e.height as isize);
            for y in 0..h {
                for x in 0..w {
                    let near = (-r..=r).any(|dy| {
                        (-r..=r).any(|dx| {
                            let (xx, yy) = (x + dx, y + dy);
                            xx >= 0 && yy >= 0 && xx < w && yy < h && !valid[(yy * w + xx) as usize]
                        })
                    });
                    if near {
                        let i = (y * w + x) as usize;
                        (e.gx[i], e.gy[i]) = (0.0, 0.0);
                    }
                }
            }
        }
        e
    }

    fn unmasked(photo: &RgbImage, factor: u32) -> EdgeImage {
        let Grey { w, h, v: luma } = Grey::of(photo).reduced(factor.max(1) as usize);
        if w == 0 || h == 0 {
            return EdgeImage {
                width: 0,
                height: 0,
                gx: Vec::new(),
                gy: Vec::new(),
            };
        }
        let k: Vec<f32> = (-3..=3)
            .map(|i: i32| (-(i * i) as f32 / 2.0).exp())
            .collect();
        let ks: f32 = k.iter().sum();
        let blur = |src: &[f32], dx: usize, dy: usize| -> Vec<f32> {
            let mut out = vec![0.0f32; w * h];
            out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
                for (x, o) in row.iter_mut().enumerate() {
                    let mut s = 0.0;
                    for (t, kv) in k.iter().enumerate() {
                        let d = t as isize - 3;
                        let xx = (x as isize + d * dx as isize).clamp(0, w as isize - 1) as usize;
                        let yy = (y as isize + d * dy as isize).clamp(0, h as isize - 1) as usize;
                        s += kv * src[yy * w + xx];
                    }
                    *o = s / ks;
                }
            });
            out
        };
        let b = blur(&blur(&luma, 1, 0), 0, 1);
        let at = |x: isize, y: isize| {
            b[(y.clamp(0, h as isize - 1) as usize) * w + x.clamp(0, w as isize - 1) as usize]
        };
        let mut gx = vec![0.0f32; w * h];
        let mut gy = vec![0.0f32; w * h];
        for y in 0..h as isize {
            for x in 0..w as isize {
                let i = y as usize * w + x as usize;
                gx[i] = 0.5 * (at(x + 1, y) - at(x - 1, y));
                gy[i] = 0.5 * (at(x, y + 1) - at(x, y - 1));
            }
        }
        EdgeImage {
            width: w,
            height: h,
            gx,
            gy,
        }
    }

    /// Size in pixels.
    pub fn dimensions(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }

    /// The gradient at pixel position `p` (pixel centres at integers), bilinear; `None`
    /// outside the image.
    fn gradient(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        let (x, y) = (p[0], p[1]);
        if self.width == 0 || self.height == 0 {
            return None;
        }
        if !(x >= 0.0 && y >= 0.0 && x <= (self.width - 1) as f64 && y <= (self.height - 1) as f64)
        {
            return None;
        }
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let s = |g: &[f32]| {
            let a = g[y0 * self.width + x0] as f64;
            let b = g[y0 * self.width + x1] as f64;
            let c = g[y1 * self.width + x0] as f64;
            let d = g[y1 * self.width + x1] as f64;
            (a + (b - a) * fx) * (1.0 - fy) + (c + (d - c) * fx) * fy
        };
        Some([s(&self.gx), s(&self.gy)])
    }

    /// The strongest edge across `normal` within `range` pixels of `p`: the offset along the
    /// normal (sub-pixel) and its strength (luma levels per pixel), if it stands out (at
    /// least `min_strength`, and 1.25× any other maximum farther than 2 px from it).
    fn edge_along(
        &self,
        p: [f64; 2],
        normal: [f64; 2],
        range: f64,
        min_strength: f64,
    ) -> Option<(f64, f64)> {
        let n = (2.0 * range / 0.5).round() as usize + 1;
        let g: Vec<f64> = (0..n)
            .map(|k| {
                let t = -range + 0.5 * k as f64;
                self.gradient([p[0] + t * normal[0], p[1] + t * normal[1]])
                    .map_or(0.0, |g| (g[0] * normal[0] + g[1] * normal[1]).abs())
            })
            .collect();
        let (best, &gb) = g.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
        if gb < min_strength || best == 0 || best + 1 == n {
            return None;
        }
        let others = g
            .iter()
            .enumerate()
            .filter(|(k, _)| (*k as f64 - best as f64).abs() * 0.5 > 2.0)
            .map(|(_, v)| *v)
            .fold(0.0, f64::max);
        if others * 1.25 > gb {
            return None;
        }
        let (a, c) = (g[best - 1], g[best + 1]);
        let den = a - 2.0 * gb + c;
        let frac = if den < 0.0 {
            (0.5 * (a - c) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        Some((-range + 0.5 * (best as f64 + frac), gb))
    }
}

/// How [`refine_edges`] fits.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeOptions {
    /// Free parameters (any of yaw, pitch, roll, f, fx, fy, x, y, z).
    pub free: Vec<Param>,
    /// Standard deviation of the rough position (metres) for its prior.
    pub position_sigma_m: f64,
    /// Standard deviation of the rough focal length (fraction) for its prior.
    pub focal_sigma: f64,
    /// Photo reductions to work at, coarse to fine (powers of two).
    pub factors: Vec<u32>,
    /// Search range along the normal, pixels of the reduced photo.
    pub search_px: f64,
}

impl Default for EdgeOptions {
    fn default() -> Self {
        EdgeOptions {
            free: vec![
                Param::Yaw,
                Param::Pitch,
                Param::Roll,
                Param::F,
                Param::X,
                Param::Y,
                Param::Z,
            ],
            position_sigma_m: 5.0,
            focal_sigma: 0.03,
            factors: vec![4, 2, 1],
            search_px: 6.0,
        }
    }
}

/// The result of [`refine_edges`].
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeFit {
    /// The refined camera.
    pub camera: CameraModel,
    /// Silhouette points matched to a photo edge in the last fit.
    pub matched: usize,
    /// Median absolute point-to-edge distance after the last fit, full-resolution pixels.
    pub median_px: f64,
    /// Robust scale (1.4826 · MAD) of those distances, full-resolution pixels.
    pub sigma_px: f64,
    /// Rounds run (silhouettes found and fitted).
    pub rounds: usize,
    /// Standard deviation of each free parameter from the last fit's covariance
    /// `s² (JᵀWJ)⁻¹` (radians, metres or pixels as the parameter; the priors included).
    pub sigma: Vec<(Param, f64)>,
}

/// One silhouette point matched to a photo edge: world point, edge point (pixels of the
/// working camera), unit normal, weight.
type Match = (DVec3, [f64; 2], [f64; 2], f64);

/// Refines `start` (sized like `photo`) by silhouette edges (see the module docs (`src/register/terrain/edges.rs`)),
/// with `prior` the camera whose position and focal length the priors hold to.
pub fn refine_edges(
    terrain: &LabelledTerrain,
    photo: &RgbImage,
    start: &CameraModel,
    prior: &CameraModel,
    opts: &EdgeOptions,
) -> Result<EdgeFit> {
    refine_masked_edges(
        terrain,
        &super::MaskedPhoto::whole(photo),
        start,
        prior,
        opts,
    )
}

/// [`refine_edges`] with pixels of the photo left out: no edges within
/// [`MASK_EDGE_MARGIN`] pixels (of the reduced image) of them.
pub(crate) fn refine_masked_edges(
    terrain: &LabelledTerrain,
    photo: &super::MaskedPhoto,
    start: &CameraModel,
    prior: &CameraModel,
    opts: &EdgeOptions,
) -> Result<EdgeFit> {
    let mut cam = CameraParams::from_camera(start);
    let prior = CameraParams::from_camera(prior);
    let mut last = (0usize, f64::NAN, f64::NAN);
    let mut sigma = Vec::new();
    let mut rounds = 0;
    for &factor in &opts.factors {
        let f = factor.max(1);
        let edges = EdgeImage::from_photo_masked(photo.image, photo.mask, f);
        let (w, h) = edges.dimensions();
        for _ in 0..6 {
            rounds += 1;
            let work = cam.camera().resized(w, h);
            let pts = contour(terrain, &work, 3.0, 4.0);
            let matches: Vec<Match> = pts
                .par_iter()
                .filter_map(|c| {
                    let (t, s) = edges.edge_along(c.pixel, c.normal, opts.search_px, 2.0)?;
                    Some((
                        c.point,
                        [c.pixel[0] + t * c.normal[0], c.pixel[1] + t * c.normal[1]],
                        c.normal,
                        s,
                    ))
                })
                .collect();
            if matches.len() < 4 * opts.free.len() {
                return Err(Error::BadOption(format!(
                    "register: {} silhouette points matched to photo edges, too few for {} parameters",
                    matches.len(),
                    opts.free.len()
                )));
            }
            let (next, med, sig, psig) = fit_matches(&cam, &prior, &matches, opts, w, h)?;
            sigma = psig;
            let moved = super::pixel_distance(&cam.camera(), &next.camera(), 200.0) / f as f64;
            cam = next;
            last = (matches.len(), med * f as f64, sig * f as f64);
            if moved < 0.05 * f as f64 {
                break;
            }
        }
    }
    Ok(EdgeFit {
        camera: cam.camera(),
        matched: last.0,
        median_px: last.1,
        sigma_px: last.2,
        rounds,
        sigma,
    })
}

/// The least-squares problem of one reweighting round.
struct Problem<'a> {
    base: CameraParams,
    prior: CameraParams,
    free: &'a [Param],
    matches: &'a [Match],
    /// √ of each match's robust weight.
    sw: Vec<f64>,
    size: (u32, u32),
    sigmas: (f64, f64),
    /// Pixels a standard deviation of a prior costs.
    prior_weight: f64,
}

/// The residual of a silhouette point that went behind the camera during the search.
const BEHIND_PX: f64 = 1e6;

impl Problem<'_> {
    /// The working camera at offsets `x`.
    fn camera_at(&self, x: &DVector<f64>) -> CameraModel {
        params_at(&self.base, self.free, x)
            .camera()
            .resized(self.size.0, self.size.1)
    }

    /// Signed distance (working pixels, along the match's normal) from where `cam` shows
    /// match `m`'s silhouette point to its photo edge; `None` behind the camera.
    fn distance(cam: &CameraModel, m: &Match) -> Option<f64> {
        let (world, edge, nrm, _) = m;
        let p = cam.project(*world)?;
        Some((p[0] - edge[0]) * nrm[0] + (p[1] - edge[1]) * nrm[1])
    }

    /// Absolute distances of every match at offsets `x` ([`BEHIND_PX`] behind the camera).
    fn abs_distances(&self, x: &DVector<f64>) -> Vec<f64> {
        let cam = self.camera_at(x);
        self.matches
            .iter()
            .map(|m| Self::distance(&cam, m).map_or(BEHIND_PX, f64::abs))
            .collect()
    }
}

impl Residuals for Problem<'_> {
    fn free(&self) -> &[Param] {
        self.free
    }

    fn residuals_at(&self, x: &DVector<f64>) -> DVector<f64> {
        let params = params_at(&self.base, self.free, x);
        let cam = params.camera().resized(self.size.0, self.size.1);
        let n = self.matches.len();
        let mut r = DVector::zeros(n + 4);
        for (i, m) in self.matches.iter().enumerate() {
            r[i] = Self::distance(&cam, m).map_or(BEHIND_PX, |d| self.sw[i] * d);
        }
        // priors: a standard deviation costs as much as every match off by the matches'
        // robust scale (the matches as independent measurements of what the prior holds)
        let (sp, sf) = self.sigmas;
        let k = self.prior_weight;
        let d = params.position - self.prior.position;
        r[n] = k * d.x / sp;
        r[n + 1] = k * d.y / sp;
        r[n + 2] = k * d.z / sp;
        r[n + 3] = k * (params.focal[0] / self.prior.focal[0] - 1.0) / sf;
        r
    }
}

/// What [`fit_matches`] returns: the camera, the median and robust scale of the absolute
/// point-to-edge distances (working pixels), and each free parameter's standard deviation.
type MatchFit = (CameraParams, f64, f64, Vec<(Param, f64)>);

/// Fits the free parameters to the matches (Huber IRLS, 4 rounds): the camera, the median
/// and robust scale of the absolute point-to-edge distances (working pixels), and each free
/// parameter's standard deviation.
fn fit_matches(
    start: &CameraParams,
    prior: &CameraParams,
    matches: &[Match],
    opts: &EdgeOptions,
    w: u32,
    h: u32,
) -> Result<MatchFit> {
    let mut problem = Problem {
        base: *start,
        prior: *prior,
        free: &opts.free,
        matches,
        sw: vec![1.0; matches.len()],
        size: (w, h),
        sigmas: (opts.position_sigma_m.max(1e-3), opts.focal_sigma.max(1e-6)),
        prior_weight: 1.0,
    };
    let mut x = DVector::zeros(opts.free.len());
    for _ in 0..4 {
        let d = problem.abs_distances(&x);
        let med = median(&d);
        let scale = (1.4826 * med).max(0.3);
        let delta = 1.345 * scale;
        problem.sw = d
            .iter()
            .map(|&v| if v <= delta { 1.0 } else { (delta / v).sqrt() })
            .collect();
        problem.prior_weight = (matches.len() as f64 / 16.0).sqrt() * scale.max(0.5);
        let (solved, report) = LevenbergMarquardt::new().minimize(Lsq { problem, x });
        (problem, x) = (solved.problem, solved.x);
        if !report.termination.was_successful() && !x.iter().all(|v| v.is_finite()) {
            return Err(Error::BadOption("register: the edge fit failed".into()));
        }
    }
    let d = problem.abs_distances(&x);
    let med = median(&d);
    // covariance s² (JᵀJ)⁻¹ of the weighted problem, s² its residual variance
    let mut sigma = Vec::new();
    let r = problem.residuals_at(&x);
    if let (Some(j), true) = (jacobian(&problem, &x), r.iter().all(|v| v.is_finite())) {
        let dof = (r.len() as f64 - opts.free.len() as f64).max(1.0);
        let s2 = r.norm_squared() / dof;
        if let Some(inv) = (j.transpose() * &j).try_inverse() {
            for (k, &p) in opts.free.iter().enumerate() {
                sigma.push((p, (s2 * inv[(k, k)]).max(0.0).sqrt()));
            }
        }
    }
    Ok((
        params_at(&problem.base, problem.free, &x),
        med,
        1.4826 * med,
        sigma,
    ))
}

fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_unstable_by(f64::total_cmp);
    s[s.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::uniform_border;
    use crate::register::terrain::GreyImage;

    /// A textured photo with a black banner and white text along its bottom 10 rows.
    fn banner_photo() -> RgbImage {
        RgbImage::from_fn(120, 80, |x, y| {
            if y >= 70 {
                let text = (10..100).contains(&x) && (73..77).contains(&y) && x % 3 == 0;
                image::Rgb(if text { [255; 3] } else { [0; 3] })
            } else {
                let v = ((x * 37 + y * 91) % 97) as u8;
                image::Rgb([60 + v, 50 + v / 2, 40 + v / 3])
            }
        })
    }

    #[test]
    fn masked_pixels_give_no_grey_and_no_edges() {
        let photo = banner_photo();
        let (mask, sides) = uniform_border(&photo);
        assert_eq!(sides.len(), 1);
        assert_eq!(mask.count(), 120 * 10);
        // unmasked: the banner's top is a strong edge and its pixels have grey values
        let plain = EdgeImage::from_photo(&photo, 1);
        assert!(
            plain
                .gradient([60.0, 69.5])
                .is_some_and(|g| g[1].abs() > 5.0)
        );
        let grey = GreyImage::from_photo(&photo, 1);
        assert!(grey.at(60.0, 75.0).is_some());
        // masked: no gradient within the margin of the banner, none of its grey values
        let edges = EdgeImage::from_photo_masked(&photo, Some(&mask), 1);
        assert_eq!(edges.gradient([60.0, 69.5]), Some([0.0, 0.0]));
        assert_eq!(edges.gradient([60.0, 66.0]), Some([0.0, 0.0]));
        assert!(
            edges
                .gradient([60.0, 30.0])
                .is_some_and(|g| g != [0.0, 0.0])
        );
        let masked = GreyImage::from_photo_masked(&photo, Some(&mask), 2);
        assert!(masked.at(30.0, 36.0).is_none() && masked.at(30.0, 20.0).is_some());
        // without a mask the masked constructors equal the plain ones
        let none = GreyImage::from_photo_masked(&photo, None, 2);
        let plain2 = GreyImage::from_photo(&photo, 2);
        assert_eq!(none.at(17.3, 21.7), plain2.at(17.3, 21.7));
    }
}
