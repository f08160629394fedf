//! Placing a photo, position included, from a placed photo taken elsewhere that sees the
//! same terrain (a surveyed time-lapse camera and a hand-held photo a few tens of metres
//! away): the placed photo's pixels are put on the terrain, found in the new photo, and the
//! new photo's camera is fitted to them as to ground control points (a resection).
//!
//! 1. **Points.** On a grid over the anchor photo (every [`ResectOptions::spacing_px`]),
//!    each textured pixel's ray meets the terrain (`surface`) at `X`; two more rays 2 px
//!    away give the surface's normal there. Points on surfaces `stable` refuses (a moving
//!    glacier), in sky, or on a silhouette (a neighbouring ray lands 25 times farther than
//!    on a surface facing the anchor) are dropped.
//! 2. **Templates as the new photo would see them.** Around `X`, the template's pixels are
//!    the anchor photo's grey sampled where the new camera's rays through them meet the
//!    plane of `X` and its normal: the anchor's view warped to the new viewpoint (scale,
//!    foreshortening, rotation), so that normalised cross-correlation still matches when the
//!    two photos see a wall from different distances and sides.
//! 3. **Coarse.** The templates (photos reduced 4×) are searched exhaustively within the
//!    rough camera's uncertainty ([`ResectOptions::search_deg`]) around where the rough
//!    camera puts `X`; a robust start comes from P3P inside RANSAC over the matches (the
//!    rough focal length), or the rough camera if more matches agree with it; on the
//!    matches that agree, the pose is fitted with the focal length fixed, then with it free
//!    (kept within 15 % of the rough focal length).
//! 4. **Fine.** Twice: templates at full resolution from the current camera, searched within
//!    ±6 px of its prediction, the peak refined to sub-pixel (parabola, then Lucas-Kanade);
//!    each match weighted by how far a terrain error of [`ResectOptions::surface_error_m`]
//!    along the anchor's ray would move its point in the photo (near points seen from a
//!    different angle move most); the camera fitted to the matched points with the free
//!    parameters
//!    ([`ResectOptions::free`]: angles, position and focal length by default) by robust
//!    Levenberg-Marquardt ([`super::fit_camera`]). Run from the coarse camera and from it
//!    turned 2 px each way in yaw and pitch; the fit with the most inliers (then the lowest
//!    RMSE) is kept: a texture that repeats within the search can hold a fit a pixel off.
//!
//! The fit is accepted with at least [`ResectOptions::min_inliers`] inlier matches, an
//! inlier RMSE of at most [`ResectOptions::max_rmse_px`], position standard deviations of
//! at most [`ResectOptions::max_sigma_m`] and a move of at most
//! [`ResectOptions::max_move_m`] from the rough position; else the rough camera stands and
//! the reason is reported. The points inherit the terrain model's error along the anchor's
//! rays (a TIN within 0.2 m moves a point 150 m away by up to 0.08° seen from elsewhere),
//! which bounds what the resection can reach; the figures are in docs/registration.md.

use std::time::Instant;

use glam::DVec3;
use image::RgbImage;
use rayon::prelude::*;

use super::bundle::PairTie;
use super::gcps::fit::{CameraFit, FitOptions, GcpStatus, fit_camera_local};
use super::gcps::gcp::Gcp;
use super::gcps::p3p::start_from_gcps_p3p;
use super::grey::{Grey, grid_centres};
use super::params::{CameraParams, Param};
use crate::camera::CameraModel;
use crate::error::Result;

/// How [`resect_photo`] matches and when it accepts.
#[derive(Clone, Debug, PartialEq)]
pub struct ResectOptions {
    /// Grid spacing of the points in the anchor photo, pixels. Default 24.
    pub spacing_px: u32,
    /// Template half size at full resolution, pixels (side `2·half + 1`). Default 10.
    pub half: u32,
    /// Angular uncertainty of the rough camera searched at the coarse scale, degrees
    /// (position errors show as angles too: 5 m at 150 m is 1.9°). Default 6.
    pub search_deg: f64,
    /// Lowest NCC of a coarse match. Default 0.6.
    pub min_ncc_coarse: f64,
    /// Lowest NCC of a fine match. Default 0.75.
    pub min_ncc: f64,
    /// Parameters fitted. Default yaw, pitch, roll, x, y, z, f.
    pub free: Vec<Param>,
    /// Fewest inlier matches for the result to stand. Default 20.
    pub min_inliers: usize,
    /// Most RMSE (pixels) of the inlier matches. Default 1.5.
    pub max_rmse_px: f64,
    /// Most distance (metres) between the rough and the fitted position. Default 30.
    pub max_move_m: f64,
    /// Error bound (metres) of the terrain the points are put on (a store's TIN: its
    /// `max_error`); each match is weighted by how far such an error along the anchor's ray
    /// moves the point in the photo (errors in the points, not only in the matches).
    /// Default 0.5.
    pub surface_error_m: f64,
    /// Most standard deviation (metres, from the fit's covariance) of each coordinate of
    /// the fitted position: above it the matches do not pin the position down (points at
    /// one distance with the focal length free: the distance along the view trades against
    /// the focal length). Default 0.5.
    pub max_sigma_m: f64,
    /// Steepest surface (degrees from horizontal) whose points are matched; steeper ones
    /// are dropped (an anchor rendered from an orthophoto smears walls). Default 90: all.
    pub max_slope_deg: f64,
}

impl Default for ResectOptions {
    fn default() -> Self {
        ResectOptions {
            spacing_px: 24,
            half: 10,
            search_deg: 6.0,
            min_ncc_coarse: 0.6,
            min_ncc: 0.75,
            free: [Param::POSE.as_slice(), &[Param::F]].concat(),
            min_inliers: 20,
            max_rmse_px: 1.5,
            max_move_m: 30.0,
            max_sigma_m: 0.5,
            surface_error_m: 0.5,
            max_slope_deg: 90.0,
        }
    }
}

/// The outcome of [`resect_photo`].
#[derive(Clone, Debug, PartialEq)]
pub struct ResectFit {
    /// The fitted camera when accepted, else the rough one.
    pub camera: CameraModel,
    /// The fitted camera, accepted or not (the rough one if no fit ran).
    pub found: CameraModel,
    /// Whether the fit passed the checks of [`ResectOptions`].
    pub accepted: bool,
    /// Why not, when not accepted.
    pub reason: Option<String>,
    /// Terrain points from the anchor / matched at the coarse scale / matched finely /
    /// inliers of the final fit.
    pub counts: [usize; 4],
    /// RMSE of the final fit's inlier matches, pixels.
    pub rmse_inliers_px: f64,
    /// Standard deviations of the fitted position (east, north, up), metres (NaN if not
    /// fitted).
    pub sigma_position_m: [f64; 3],
    /// Distance from the rough to the fitted position, metres.
    pub moved_m: f64,
    /// Whether the focal length was fitted (else the rough camera's was kept, e.g. the
    /// anchor's for a photo of the same camera body).
    pub focal_fitted: bool,
    /// Seconds spent.
    pub seconds: f64,
    /// The inlier matches of the final fit as ties between the two photos (anchor pixel,
    /// photo pixel), accepted or not: what [`super::adjust_bundle`] needs to fit both
    /// cameras together when the anchor's own pose is uncertain.
    pub ties: Vec<PairTie>,
}

/// One run of the fine stage: the camera it ended at, its last fit, its match count, and
/// the anchor pixels of the matches of its last fit (in the fit's GCP order).
type FineRun = (CameraModel, Option<CameraFit>, usize, Vec<[f64; 2]>);

/// A terrain point seen by the anchor: where, and the surface's unit normal (towards the
/// anchor).
#[derive(Clone, Copy, Debug)]
struct Point {
    /// The anchor pixel whose ray met the terrain here.
    pixel: [f64; 2],
    world: DVec3,
    normal: DVec3,
    /// Unit direction of the anchor's ray to it.
    ray: DVec3,
}

/// Spread (pixels) of a fine match's position: the matcher's own.
const MATCH_SIGMA_PX: f64 = 0.15;

/// The weight of a match of `p` in the photo of `cam`: `σ_m² / (σ_m² + σ_s²)` with the
/// matcher's spread `σ_m` and `σ_s` the pixels by which a terrain error `e` along the
/// anchor's ray moves the point in the photo (its part across the photo's ray, over the
/// distance, times the focal length).
fn match_weight(cam: &CameraModel, p: &Point, e: f64) -> f64 {
    let to = p.world - cam.position;
    let dist = to.length();
    if !(dist > 0.0) {
        return 0.0;
    }
    let d = to / dist;
    let across = (p.ray - d * p.ray.dot(d)).length();
    let s = cam.fx * e * across / dist;
    MATCH_SIGMA_PX.powi(2) / (MATCH_SIGMA_PX.powi(2) + s * s)
}

/// Places `photo` (rough camera `rough`) from `anchor_image` seen by the placed camera
/// `anchor` (module docs). `surface(origin, unit dir)` gives where a ray meets the terrain;
/// `stable(point)` whether a point may be matched. Errors only for unusable input (an image
/// not of its camera's size); a fit that fails its checks is a result with `accepted:
/// false` and the rough camera.
pub fn resect_photo(
    anchor: &CameraModel,
    anchor_image: &RgbImage,
    photo: &RgbImage,
    rough: &CameraModel,
    surface: impl Fn(DVec3, DVec3) -> Option<DVec3> + Sync,
    stable: impl Fn(DVec3) -> bool + Sync,
    opts: &ResectOptions,
) -> Result<ResectFit> {
    let t0 = Instant::now();
    let mut out = unplaced(rough, opts);
    for (img, cam, what) in [(anchor_image, anchor, "anchor"), (photo, rough, "photo")] {
        if img.dimensions() != (cam.width, cam.height) {
            return Err(crate::error::Error::BadOption(format!(
                "the {what} image is {}x{}, its camera {}x{}",
                img.width(),
                img.height(),
                cam.width,
                cam.height
            )));
        }
    }
    let (ga, gb) = (Grey::of(anchor_image), Grey::of(photo));
    let half = opts.half.max(3) as i64;
    let points = terrain_points(
        anchor,
        &ga,
        half,
        opts.spacing_px.max(1),
        opts.max_slope_deg,
        &surface,
        &stable,
    );
    out.counts[0] = points.len();
    let k = 4usize;
    let coarse = coarse_matches(anchor, &ga, &gb, rough, &points, k, half, opts);
    out.counts[1] = coarse.len();
    if coarse.len() < opts.min_inliers {
        out.reason = Some(format!(
            "{} coarse matches of {} terrain points, fewer than {}",
            coarse.len(),
            points.len(),
            opts.min_inliers
        ));
        out.seconds = t0.elapsed().as_secs_f64();
        return Ok(out);
    }
    let start = coarse_start(rough, &coarse, k as f64, opts);
    let fine = FineStage {
        anchor,
        ga: &ga,
        gb: &gb,
        points: &points,
        half,
        opts,
        fit_opts: FitOptions {
            free: opts.free.clone(),
            ..FitOptions::default()
        },
    };
    let (cam, last, n_fine, anchor_px) = fine.best_from(&start);
    out.counts[2] = n_fine;
    out.found = cam;
    out.moved_m = cam.position.distance(rough.position);
    let Some(fit) = last else {
        out.reason = Some(format!(
            "{} fine matches, fewer than {}",
            out.counts[2], opts.min_inliers
        ));
        out.seconds = t0.elapsed().as_secs_f64();
        return Ok(out);
    };
    record_fit(&mut out, &fit, &anchor_px);
    out.reason = rejection_reason(&out, opts);
    if out.reason.is_none() {
        out.accepted = true;
        out.camera = cam;
    }
    out.seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

/// The result before anything is found: the rough camera, not accepted.
fn unplaced(rough: &CameraModel, opts: &ResectOptions) -> ResectFit {
    ResectFit {
        camera: *rough,
        found: *rough,
        accepted: false,
        reason: None,
        counts: [0; 4],
        rmse_inliers_px: f64::NAN,
        sigma_position_m: [f64::NAN; 3],
        moved_m: 0.0,
        focal_fitted: opts
            .free
            .iter()
            .any(|p| matches!(p, Param::F | Param::Fx | Param::Fy)),
        seconds: 0.0,
        ties: Vec::new(),
    }
}

/// Coarse matches: templates on the `k`× reduced images, searched over the rough camera's
/// uncertainty (`opts.search_deg`); a match is the terrain point and where the photo shows it.
#[allow(clippy::too_many_arguments)]
fn coarse_matches(
    anchor: &CameraModel,
    ga: &Grey,
    gb: &Grey,
    rough: &CameraModel,
    points: &[Point],
    k: usize,
    half: i64,
    opts: &ResectOptions,
) -> Vec<Gcp> {
    let (ca, cb) = (ga.reduced(k), gb.reduced(k));
    let coarse_half = (half / 2).max(4);
    let rad = ((opts.search_deg.to_radians() * rough.fx) / k as f64).ceil() as i64 + 1;
    points
        .par_iter()
        .filter_map(|p| {
            let (t, tn, b) = template(anchor, &ca, k as f64, rough, p, coarse_half)?;
            let c = ((b[0] - 1.5) / k as f64, (b[1] - 1.5) / k as f64);
            let (x, y, s, edge) = cb.search(
                &t,
                tn,
                (c.0.round() as i64, c.1.round() as i64),
                rad,
                coarse_half,
            )?;
            (s >= opts.min_ncc_coarse && !edge).then(|| Gcp {
                name: String::new(),
                world: p.world,
                pixel: [x as f64 * k as f64 + 1.5, y as f64 * k as f64 + 1.5],
                weight: 1.0,
            })
        })
        .collect()
}

/// The fine stage: full-resolution templates from the current camera, matched and fitted.
struct FineStage<'a> {
    anchor: &'a CameraModel,
    ga: &'a Grey,
    gb: &'a Grey,
    points: &'a [Point],
    half: i64,
    opts: &'a ResectOptions,
    fit_opts: FitOptions,
}

impl FineStage<'_> {
    /// The fine matches seen from `cam`: each a GCP (terrain point, sub-pixel photo
    /// position, weight by how far the TIN's error moves it) and the anchor pixel.
    fn matches(&self, cam: &CameraModel) -> Vec<(Gcp, [f64; 2])> {
        let (half, opts) = (self.half, self.opts);
        self.points
            .par_iter()
            .filter_map(|p| {
                let (t, tn, b) = template(self.anchor, self.ga, 1.0, cam, p, half)?;
                let c = (b[0].round() as i64, b[1].round() as i64);
                let (x, y, s, edge) = self.gb.search(&t, tn, c, 6, half)?;
                if edge || s < opts.min_ncc {
                    return None;
                }
                let q = self.gb.peak_sub_pixel(&t, tn, (x, y), s, half)?;
                let g = Gcp {
                    name: String::new(),
                    world: p.world,
                    pixel: q,
                    weight: match_weight(cam, p, opts.surface_error_m),
                };
                Some((g, p.pixel))
            })
            .collect()
    }

    /// Two rounds of matching and fitting from `from` (each from the camera the last fit
    /// found): the camera, the last fit, the fine matches of the last round and their
    /// anchor pixels.
    fn run_from(&self, from: CameraModel) -> FineRun {
        let (mut cam, mut last, mut n, mut at) = (from, None, 0, Vec::new());
        for _ in 0..2 {
            let (fine, from_px): (Vec<Gcp>, Vec<[f64; 2]>) = self.matches(&cam).into_iter().unzip();
            n = fine.len();
            if fine.len() < self.opts.min_inliers {
                break;
            }
            match fit_camera_local(&cam, &fine, &self.fit_opts) {
                Ok(f) => {
                    cam = f.camera;
                    last = Some(f);
                    at = from_px;
                }
                Err(_) => break,
            }
        }
        (cam, last, n, at)
    }

    /// Runs from the coarse camera and from it turned by 2 px each way in yaw and pitch
    /// (matches of a texture that repeats within the search can hold a pose a pixel off):
    /// the run with the most inliers (then the lower RMSE).
    fn best_from(&self, start: &CameraModel) -> FineRun {
        // (inliers, −RMSE) of a run's final fit: larger is better
        let key = |r: &FineRun| r.1.as_ref().map(|f| (inliers_of(f), -f.rmse_inliers_px));
        let turn = 2.0 / start.fx;
        let mut best: Option<FineRun> = None;
        for (dy, dp) in [
            (0.0, 0.0),
            (turn, 0.0),
            (-turn, 0.0),
            (0.0, turn),
            (0.0, -turn),
        ] {
            let mut p = CameraParams::from_camera(start);
            p.angles[0] += dy;
            p.angles[1] += dp;
            let r = self.run_from(p.camera());
            let better = match (&best, key(&r)) {
                (None, _) => true,
                (Some(b), Some((n, e))) => {
                    key(b).is_none_or(|(bn, be)| n > bn || (n == bn && e > be))
                }
                (Some(_), None) => false,
            };
            if better {
                best = Some(r);
            }
        }
        best.unwrap_or((*start, None, 0, Vec::new()))
    }
}

/// The inlier GCPs of a fit.
fn inliers_of(f: &CameraFit) -> usize {
    f.gcps
        .iter()
        .filter(|g| g.status == GcpStatus::Inlier)
        .count()
}

/// The fit's inliers, ties (anchor pixel → photo pixel), RMSE and position deviations.
fn record_fit(out: &mut ResectFit, fit: &CameraFit, anchor_px: &[[f64; 2]]) {
    out.counts[3] = inliers_of(fit);
    out.ties = fit
        .gcps
        .iter()
        .zip(anchor_px)
        .filter(|(g, _)| g.status == GcpStatus::Inlier)
        .map(|(g, &a)| PairTie {
            anchor_px: a,
            photo_px: g.observed,
        })
        .collect();
    out.rmse_inliers_px = fit.rmse_inliers_px;
    for p in &fit.params {
        let i = match p.param {
            Param::X => 0,
            Param::Y => 1,
            Param::Z => 2,
            _ => continue,
        };
        out.sigma_position_m[i] = p.sigma;
    }
}

/// Why the fit is refused, if it is: too few inliers, an RMSE above the bound, a position
/// not pinned down, or a move beyond reach.
fn rejection_reason(out: &ResectFit, opts: &ResectOptions) -> Option<String> {
    let inliers = out.counts[3];
    if inliers < opts.min_inliers {
        Some(format!(
            "{inliers} inlier matches, fewer than {}",
            opts.min_inliers
        ))
    } else if !(out.rmse_inliers_px <= opts.max_rmse_px) {
        Some(format!(
            "inlier match RMSE {:.2} px above {} px",
            out.rmse_inliers_px, opts.max_rmse_px
        ))
    } else if let Some(sig) = out
        .sigma_position_m
        .iter()
        .copied()
        .filter(|v| !v.is_nan())
        .reduce(f64::max)
        .filter(|&v| !(v <= opts.max_sigma_m))
    {
        Some(format!(
            "the position is not pinned down (standard deviation {sig:.2} m, more than {} m{})",
            opts.max_sigma_m,
            if out.focal_fitted {
                "; the focal length trades against the distance: a known focal length would help"
            } else {
                ""
            }
        ))
    } else if !(out.moved_m <= opts.max_move_m) {
        Some(format!(
            "moved {:.1} m from the rough position, more than {} m",
            out.moved_m, opts.max_move_m
        ))
    } else {
        None
    }
}

/// The camera the fine stage starts from (module docs, step 3): P3P inside RANSAC over the
/// coarse matches (the rough focal length), or the rough camera if that agrees with more
/// matches (within 3 coarse pixels); then, on the matches it agrees with, the free
/// parameters but the focal length fitted, then all of them (kept only if the focal length
/// stays within 15 % of the rough one and the position within reach).
fn coarse_start(rough: &CameraModel, coarse: &[Gcp], k: f64, opts: &ResectOptions) -> CameraModel {
    let tol = 3.0 * k;
    let agree = |c: &CameraModel| -> Vec<Gcp> {
        coarse
            .iter()
            .filter(|g| {
                c.project(g.world)
                    .is_some_and(|p| (p[0] - g.pixel[0]).hypot(p[1] - g.pixel[1]) <= tol)
            })
            .cloned()
            .collect()
    };
    let reach = 2.0 * opts.max_move_m;
    let p3p = start_from_gcps_p3p(rough.width, rough.height, coarse, Some(rough.fx))
        .ok()
        .map(|s| CameraModel {
            k1: rough.k1,
            k2: rough.k2,
            cx: rough.cx,
            cy: rough.cy,
            fy: s.fx * rough.fy / rough.fx,
            ..s
        })
        .filter(|s| s.position.distance(rough.position) <= reach);
    let (mut cam, mut used) = (*rough, agree(rough));
    if let Some(s) = p3p {
        let a = agree(&s);
        if a.len() > used.len() {
            (cam, used) = (s, a);
        }
    }
    if used.len() < opts.min_inliers.max(8) {
        used = coarse.to_vec();
    }
    let is_focal = |p: &Param| matches!(p, Param::F | Param::Fx | Param::Fy);
    let no_focal: Vec<Param> = opts.free.iter().copied().filter(|p| !is_focal(p)).collect();
    let ok = |c: &CameraModel| {
        c.position.distance(rough.position) <= reach && (c.fx / rough.fx - 1.0).abs() <= 0.15
    };
    for free in [no_focal, opts.free.clone()] {
        if free.is_empty() {
            continue;
        }
        let o = FitOptions {
            free,
            ..FitOptions::default()
        };
        if let Ok(f) = fit_camera_local(&cam, &used, &o)
            && ok(&f.camera)
        {
            cam = f.camera;
        }
    }
    cam
}

/// The anchor's terrain points (module docs, step 1), in grid order.
fn terrain_points(
    anchor: &CameraModel,
    ga: &Grey,
    half: i64,
    spacing: u32,
    max_slope_deg: f64,
    surface: &(impl Fn(DVec3, DVec3) -> Option<DVec3> + Sync),
    stable: &(impl Fn(DVec3) -> bool + Sync),
) -> Vec<Point> {
    let centres = grid_centres(ga.w, ga.h, half + 2, spacing as i64);
    // smallest |normal.z| of a surface no steeper than max_slope_deg
    let min_up = max_slope_deg.to_radians().cos() - 1e-12;
    let hit = |x: f64, y: f64| {
        let d = anchor.pixel_ray(x, y)?;
        surface(anchor.position, d)
    };
    centres
        .par_iter()
        .filter_map(|&(x, y)| {
            let (_, tn) = ga.patch(x, y, half)?;
            if tn / ((2 * half + 1) as f32) < 2.0 {
                return None; // no texture to match
            }
            let (xf, yf) = (x as f64, y as f64);
            let p = hit(xf, yf)?;
            if !stable(p) {
                return None;
            }
            let (px, py) = (hit(xf + 2.0, yf)?, hit(xf, yf + 2.0)?);
            // a silhouette: a neighbour 2 px away lands more than 25 times the distance
            // 2 px cover on a surface facing the anchor (grazing surfaces reach ~10 times)
            let far = 25.0 * 2.0 * p.distance(anchor.position) / anchor.fx;
            if px.distance(p) > far || py.distance(p) > far {
                return None;
            }
            let mut n = (px - p).cross(py - p).normalize_or_zero();
            if n == DVec3::ZERO {
                return None;
            }
            if n.dot(anchor.position - p) < 0.0 {
                n = -n;
            }
            if n.z.abs() < min_up {
                return None;
            }
            Some(Point {
                pixel: [xf, yf],
                world: p,
                normal: n,
                ray: (p - anchor.position).normalize(),
            })
        })
        .collect()
}

/// The zero-mean template (half size `r`, pixel step `step` of the photo's full
/// resolution) of `p` as camera `cam` would see it, sampled from the anchor's grey `src`
/// (the anchor photo box-reduced by `step`), its norm, and where `cam` puts `p` (full
/// resolution pixels). `None` if `p` is not in front of `cam` or the template leaves either
/// image, or has no texture.
fn template(
    anchor: &CameraModel,
    src: &Grey,
    step: f64,
    cam: &CameraModel,
    p: &Point,
    r: i64,
) -> Option<(Vec<f32>, f32, [f64; 2])> {
    let b = cam.project(p.world)?;
    let n = p.normal;
    let denom_min = 0.05;
    let shift = (step - 1.0) / 2.0;
    let mut t = Vec::with_capacity(((2 * r + 1) * (2 * r + 1)) as usize);
    for j in -r..=r {
        for i in -r..=r {
            let q = [b[0] + step * i as f64, b[1] + step * j as f64];
            let d = cam.pixel_ray(q[0], q[1])?;
            let cos = n.dot(d);
            if cos.abs() < denom_min {
                return None; // grazing: the plane does not say where the ray lands
            }
            let s = n.dot(p.world - cam.position) / cos;
            if !(s > 0.0) {
                return None;
            }
            let a = anchor.project(cam.position + d * s)?;
            t.push(src.at((a[0] - shift) / step, (a[1] - shift) / step)?);
        }
    }
    let mean = t.iter().sum::<f32>() / t.len() as f32;
    t.iter_mut().for_each(|v| *v -= mean);
    let norm = t.iter().map(|v| v * v).sum::<f32>().sqrt();
    (norm / ((2 * r + 1) as f32) >= 1.0).then_some((t, norm, b))
}
