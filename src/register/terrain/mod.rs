//! Registration of a photo against the terrain, without GCPs (docs/registration.md,
//! "`cliffmap register`").
//!
//! Input: a [`LabelledTerrain`] (the store's finest level, ray-cast on the CPU with the cells'
//! active textures), a decoded photo and its rough camera (world frame), and
//! [`TerrainOptions`] (free parameters, search ranges). Output: a [`TerrainFit`] — the
//! refined camera, the score before and after, a repeatability figure and a verdict.
//!
//! Method: the store seen from the current camera becomes samples (terrain points with a
//! label from their texture grey, steepness and distance; sky directions), and the camera
//! maximises the normalised mutual information between those labels and the photo's grey
//! levels where the camera reprojects the samples (the image-to-geometry registration of
//! Viola & Wells 1997 and Corsini et al. 2009). Mutual information asks only that the
//! photo's greys be *predictable* from the labels, so the sky's edge, the foot of walls
//! against nearer ground and the ortho's broad patterns all count, while the ortho's smear
//! on walls (which defeats patch correlation) does no harm. Coarse to fine: a grid over
//! yaw, pitch and roll on the photo reduced to about 100 pixels across (a power of two),
//! Nelder-Mead over every free parameter on photos 2 and 4 times larger from the three best
//! grid peaks, then from the best through each finer scale to the full photo (by default), the samples
//! re-cast from the current camera between rounds (occlusions follow the pose). The
//! samples within about 48 pixels (24 on the full photo) of a silhouette (the sky's edge, a
//! jump in distance) take part, and of the regions' insides one sample in 3 × 3: the broad
//! insides change little when the camera moves a little and would dilute the peak, but
//! without them a band made mostly of where the store ends can line up with a wrong edge
//! (Engabreen: a pitch 2° off scored higher than the true one). Sample positions are jittered inside their grid cells so that
//! whole-pixel shifts are not favoured (the grid effect of partial-volume interpolation). The verdict comes from a
//! restart: Nelder-Mead from the result moved by a few pixels must come back to it.

mod edges;
mod mi;
mod position;
mod simplex;
mod view;

use std::time::Instant;

use glam::DVec3;
use image::RgbImage;

pub use edges::{ContourPoint, EdgeFit, EdgeImage, EdgeOptions, contour, refine_edges};
pub use mi::{GreyImage, nmi, nmi_by, sample_pixel};
pub use view::{
    GREY_CLASSES, LABELS, LabelTexture, LabelledTerrain, RayEnd, SKY, Sample, SampleAt,
};

use super::params::{CameraParams, Param};
use crate::camera::CameraModel;
use crate::error::{Error, Result};

/// What [`register_to_terrain`] may change and how far.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainOptions {
    /// Free parameters (yaw, pitch, roll, f or fx/fy; others, the position included, are
    /// refused by [`TerrainOptions::validate`]).
    pub free: Vec<Param>,
    /// Half-widths of the coarse grid over yaw, pitch and roll, degrees.
    pub search_deg: [f64; 3],
    /// Largest change accepted: angles (degrees), focal length (fraction), position (metres).
    pub bounds: [f64; 3],
    /// Restart agreement (full-resolution pixels at the image's corners) below which the fit
    /// is called converged.
    pub repeat_px: f64,
    /// Finest photo scale used (1 = full resolution, 2 = half, ...; a power of two).
    pub finest_factor: u32,
    /// Standard deviation (metres) of the rough position, the prior of the position's
    /// refinement when x, y, z are free (a phone's GPS: a few metres).
    pub position_sigma_m: f64,
    /// Allow x, y, z to be free (the silhouette-edge stage). Off by default and not offered
    /// by the command: measured on the demo scene it recovers the position in only a few
    /// starts and can agree with itself on a wrong one (docs/registration.md, "Position").
    pub experimental_position: bool,
    /// `Some(h)`: after the angle search, search the position by the score itself, trials
    /// at `±h` and `±2h` metres up, across and along the view, then at half and a quarter
    /// of those, `h` in (0, 50]; a search that does not settle is refused (the module
    /// `position`; docs/registration.md, "Position by the score at full resolution"). An
    /// experiment, off by default (`cliffmap register --position-search-m`).
    pub position_search_m: Option<f64>,
    /// Which textures give the terrain samples their grey when a caller builds the scene
    /// from these options ([`LabelledTerrain::for_options`]; `pipeline::register_photos_with`
    /// does). [`register_to_terrain`] itself uses the scene it is given.
    pub labels: LabelTexture,
}

impl Default for TerrainOptions {
    /// Yaw, pitch, roll and focal length free; grid ±4° yaw, ±2.5° pitch and
    /// ±2° roll; changes up to 8° / 8 % / 15 m; converged when restarts agree within 1 px;
    /// the finest scale is the full photo.
    fn default() -> Self {
        TerrainOptions {
            free: vec![Param::Yaw, Param::Pitch, Param::Roll, Param::F],
            search_deg: [4.0, 2.5, 2.0],
            bounds: [8.0, 0.08, 15.0],
            repeat_px: 1.0,
            finest_factor: 1,
            position_sigma_m: 5.0,
            experimental_position: false,
            position_search_m: None,
            labels: LabelTexture::Active,
        }
    }
}

impl TerrainOptions {
    /// Errors for a free parameter that cannot be refined against the terrain (k1, k2, cx,
    /// cy; x, y, z unless `experimental_position`), an empty free set, a search half-width
    /// outside 0..=30°, a non-positive repeatability bound, a free position without the
    /// three angles, or a non-positive position prior.
    pub fn validate(&self) -> Result<()> {
        if self.free.is_empty() {
            return Err(Error::BadOption("register: no free parameters".into()));
        }
        if self.search_deg.iter().any(|&x| !(0.0..=30.0).contains(&x)) {
            return Err(Error::BadOption(format!(
                "--search-deg: each half-width must be in 0..=30 degrees, got {:?}",
                self.search_deg
            )));
        }
        if !(self.repeat_px.is_finite() && self.repeat_px > 0.0) {
            return Err(Error::BadOption(format!(
                "--repeat-px must be positive, got {}",
                self.repeat_px
            )));
        }
        if let Some(p) = self.free.iter().find(|p| {
            !matches!(
                p,
                Param::Yaw
                    | Param::Pitch
                    | Param::Roll
                    | Param::F
                    | Param::Fx
                    | Param::Fy
                    | Param::X
                    | Param::Y
                    | Param::Z
            )
        }) {
            return Err(Error::BadOption(format!(
                "register: parameter {} cannot be refined against the terrain (free: yaw, pitch, roll, f, fx, fy, x, y, z)",
                p.name()
            )));
        }
        if let Some(h) = self.position_search_m
            && !(h.is_finite() && h > 0.0 && h <= 50.0)
        {
            return Err(Error::BadOption(format!(
                "register: position search step {h} m must be in (0, 50]"
            )));
        }
        if self.position_free() && !self.experimental_position {
            return Err(Error::BadOption(
                "register: the camera position cannot be refined against the terrain reliably yet (measured: \
                 silhouettes alone leave the distance along the view traded against the focal length, \
                 docs/registration.md, \"Position\"); fit it from GCPs with fit-camera, or keep it fixed"
                    .into(),
            ));
        }
        if self.position_free()
            && ![Param::Yaw, Param::Pitch, Param::Roll]
                .iter()
                .all(|p| self.free.contains(p))
        {
            return Err(Error::BadOption(
                "register: a free position needs yaw, pitch and roll free as well".into(),
            ));
        }
        if !(self.position_sigma_m > 0.0 && self.position_sigma_m.is_finite()) {
            return Err(Error::BadOption(format!(
                "register: the position's standard deviation must be positive, got {}",
                self.position_sigma_m
            )));
        }
        Ok(())
    }

    /// Whether x, y or z is free.
    pub fn position_free(&self) -> bool {
        self.free
            .iter()
            .any(|p| matches!(p, Param::X | Param::Y | Param::Z))
    }
}

/// The result of [`register_to_terrain`].
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainFit {
    /// The refined camera (the input camera when not converged).
    pub camera: CameraModel,
    /// The camera the search ended at, converged or not.
    pub found: CameraModel,
    /// Whether the fit is trusted (restarts agree, the score rose, no bound reached).
    pub converged: bool,
    /// Why not, when not converged.
    pub reason: Option<String>,
    /// Normalised mutual information at the input camera and at the result (same samples,
    /// finest scale).
    pub score_start: f64,
    /// See `score_start`.
    pub score_final: f64,
    /// Largest distance (full-resolution pixels, over the image's corners and centre)
    /// between the result and the restarts' results.
    pub repeat_px: f64,
    /// Score evaluations.
    pub evaluations: usize,
    /// With the position free: the silhouette-edge stage's result (else `None`).
    pub edges: Option<EdgeSummary>,
    /// With the position kept (not free, not searched): [`parallax_px_per_m`] of the camera
    /// found, what each metre of error in the given position costs (else `None`).
    pub position_kept_parallax_px_per_m: Option<f64>,
    /// With label photos ([`LabelledTerrain::set_label_photos`]): the share (0..1) of the
    /// terrain samples of the final view whose labels came from their pixels (0: none of
    /// them shows what this photo sees); else `None`.
    pub photo_label_share: Option<f64>,
    /// Seconds spent.
    pub seconds: f64,
}

impl TerrainFit {
    /// The fit of a search that ended at `found`: its camera when `reason` is `None` (the
    /// verdict), else `rough`'s.
    fn judged(
        rough: &CameraModel,
        found: CameraModel,
        reason: Option<String>,
        (score_start, score_final, evaluations): (f64, f64, usize),
        repeat_px: f64,
        edges: Option<EdgeSummary>,
        t0: Instant,
    ) -> TerrainFit {
        TerrainFit {
            camera: if reason.is_none() { found } else { *rough },
            found,
            converged: reason.is_none(),
            reason,
            score_start,
            score_final,
            repeat_px,
            evaluations,
            edges,
            position_kept_parallax_px_per_m: None,
            photo_label_share: None,
            seconds: t0.elapsed().as_secs_f64(),
        }
    }
}

/// What the silhouette-edge stage of [`register_to_terrain`] found (position free).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeSummary {
    /// Silhouette points matched to photo edges in the last fit.
    pub matched: usize,
    /// Median point-to-edge distance of the last fit, full-resolution pixels.
    pub median_px: f64,
    /// Largest distance (metres) between the position found from the search's result and
    /// those found from it moved 2 m east and 2 m south, and 3 m back along the view (the
    /// restarts).
    pub position_repeat_m: f64,
    /// Standard deviation of each free parameter (radians, metres, pixels) from the fit's
    /// covariance.
    pub sigma: Vec<(Param, f64)>,
}

/// Most median point-to-edge distance (full-resolution pixels) of a trusted position fit
/// (measured on the demo scene: 0.35–0.6 px where the position was found within 0.2 m,
/// 0.85–1.8 px where it was not).
const EDGE_MEDIAN_PX: f64 = 0.75;

/// Most distance (metres) between the position found and the restart's.
const POSITION_REPEAT_M: f64 = 0.5;

/// Refines `rough` (the camera of `photo`, sized like it) against the terrain; see the
/// module docs. Errors for parameters that cannot be registered this way or a camera not
/// sized like the photo; a search that does not converge is a result with
/// `converged: false`, not an error.
pub fn register_to_terrain(
    terrain: &LabelledTerrain,
    photo: &RgbImage,
    rough: &CameraModel,
    opts: &TerrainOptions,
) -> Result<TerrainFit> {
    register_masked_to_terrain(terrain, &MaskedPhoto::whole(photo), rough, opts)
}

/// A photo and the pixels of it registration leaves out (the photo list's `"mask"`, its
/// uniform borders): they count as outside the photo for the mutual information and give
/// no edges. Dereferences to the image.
#[derive(Clone, Copy, Debug)]
pub struct MaskedPhoto<'a> {
    /// The photo.
    pub image: &'a RgbImage,
    /// Its pixels to leave out (of its size), if any.
    pub mask: Option<&'a crate::photo::PixelMask>,
}

impl<'a> MaskedPhoto<'a> {
    /// The whole photo (nothing left out).
    pub fn whole(image: &'a RgbImage) -> MaskedPhoto<'a> {
        MaskedPhoto { image, mask: None }
    }

    /// Its grey classes reduced `factor` times ([`GreyImage::from_photo_masked`]).
    fn grey(&self, factor: u32) -> GreyImage {
        GreyImage::from_photo_masked(self.image, self.mask, factor)
    }
}

impl std::ops::Deref for MaskedPhoto<'_> {
    type Target = RgbImage;
    fn deref(&self) -> &RgbImage {
        self.image
    }
}

/// [`register_to_terrain`] with pixels of the photo left out ([`MaskedPhoto`]).
pub fn register_masked_to_terrain(
    terrain: &LabelledTerrain,
    photo: &MaskedPhoto,
    rough: &CameraModel,
    opts: &TerrainOptions,
) -> Result<TerrainFit> {
    let t0 = Instant::now();
    if (rough.width, rough.height) != photo.dimensions() {
        return Err(Error::BadOption(format!(
            "camera is for {} x {} pixels, the photo has {} x {}",
            rough.width,
            rough.height,
            photo.width(),
            photo.height()
        )));
    }
    opts.validate()?;
    // the mutual-information search keeps the position; the edge stage frees it
    let mi_free: Vec<Param> = opts
        .free
        .iter()
        .copied()
        .filter(|p| !matches!(p, Param::X | Param::Y | Param::Z))
        .collect();
    let finest = opts.finest_factor.clamp(1, 16).next_power_of_two();
    let mut evals = 0usize;
    let start = CameraParams::from_camera(rough);
    let depth = median_depth(terrain, rough);
    // Coarse grid over the angles on the photo reduced to about 100 pixels across.
    let q = (photo.width() / 100).max(1);
    let coarse = (1u32 << (31 - q.leading_zeros())).max(finest);
    let peaks = grid_peaks(terrain, photo, rough, &mi_free, opts, coarse, &mut evals)?;
    let mut space = Space {
        base: start,
        free: mi_free,
        depth,
        bounds: opts.bounds,
    };
    let mut cam = refine_from_peaks(terrain, &space, photo, &peaks, coarse, finest, &mut evals)?;

    // Finest scale: two rounds (samples re-cast in between), then restarts for the verdict.
    let grey = photo.grey(finest);
    let mut score = 0.0;
    for _ in 0..2 {
        let (c2, s2, e) = refine(terrain, &space, &cam, &grey, 2.0)?;
        evals += e;
        (cam, score) = (c2, s2);
    }
    let mut unsettled: Option<f64> = None;
    if let (Some(h), false) = (opts.position_search_m, opts.position_free()) {
        let (c2, e, above) = position::search_position(terrain, &space, cam, photo, finest, h, 3)?;
        evals += e;
        cam = c2;
        space = space.moved_to(cam.position);
        unsettled = (above > position::SETTLED).then_some(above);
        // the angles once more at the finest scale from the position found (the search's
        // scores are on another scale and sample set, so not compared with these)
        for _ in 0..2 {
            let (c2, s2, e) = refine(terrain, &space, &cam, &grey, 2.0)?;
            evals += e;
            (cam, score) = (c2, s2);
        }
    }
    let samples = terrain.sample(
        &scaled(&cam.camera(), &grey),
        1.0,
        0.04,
        Some(band_width(finest)),
    )?;
    let score_start = nmi(&samples, &scaled(rough, &grey), &grey);
    let photo_label_share = terrain
        .has_label_photos()
        .then(|| view::photo_label_share(&samples));
    // (with the position free the edge stage restarts instead)
    let repeat = if opts.position_free() {
        0.0
    } else {
        restart_spread(terrain, &space, &cam, &grey, depth, &mut evals)?
    };
    let found = cam.camera();
    let at_bound = space.outside(&cam, 0.98);
    if opts.position_free() {
        return finish_with_edges(
            terrain,
            photo,
            rough,
            &found,
            opts,
            depth,
            (score_start, score, evals),
            t0,
        );
    }
    let reason = verdict_reason(at_bound, repeat, unsettled, (score_start, score), opts);
    let mut fit = TerrainFit::judged(
        rough,
        found,
        reason,
        (score_start, score, evals),
        repeat,
        None,
        t0,
    );
    if opts.position_search_m.is_none() {
        fit.position_kept_parallax_px_per_m = parallax_px_per_m(terrain, &found);
    }
    fit.photo_label_share = photo_label_share;
    Ok(fit)
}

/// The three best well-separated angle changes (yaw, pitch, roll in radians) on a grid over
/// the search half-widths, scored on the photo reduced `coarse` times (0.7 px steps).
fn grid_peaks(
    terrain: &LabelledTerrain,
    photo: &MaskedPhoto,
    rough: &CameraModel,
    mi_free: &[Param],
    opts: &TerrainOptions,
    coarse: u32,
    evals: &mut usize,
) -> Result<Vec<[f64; 3]>> {
    let start = CameraParams::from_camera(rough);
    let grey16 = photo.grey(coarse);
    let cam16 = scaled(rough, &grey16);
    let samples = terrain.sample(&cam16, 1.0, 0.08, Some(band_width(coarse)))?;
    let f16 = cam16.fx;
    let angle_free = [Param::Yaw, Param::Pitch, Param::Roll].map(|p| mi_free.contains(&p));
    let step = 0.7 / f16; // radians: 0.7 px at this scale
    let counts: [i64; 3] = [0, 1, 2].map(|k| {
        if angle_free[k] {
            (opts.search_deg[k].to_radians() / step).ceil() as i64
        } else {
            0
        }
    });
    let roll_step = 0.7 / (cam16.width as f64 / 2.0).max(1.0); // radians: 0.7 px at the side
    let roll_n = if angle_free[2] {
        (opts.search_deg[2].to_radians() / roll_step).ceil() as i64
    } else {
        0
    };
    let mut grid: Vec<[f64; 3]> = Vec::new();
    for r in -roll_n..=roll_n {
        for p in -counts[1]..=counts[1] {
            for y in -counts[0]..=counts[0] {
                grid.push([y as f64 * step, p as f64 * step, r as f64 * roll_step]);
            }
        }
    }
    use rayon::prelude::*;
    let scores: Vec<f64> = grid
        .par_iter()
        .map(|d| {
            let mut c = start;
            for (a, dk) in c.angles.iter_mut().zip(d) {
                *a += dk;
            }
            nmi(&samples, &scaled(&c.camera(), &grey16), &grey16)
        })
        .collect();
    *evals += grid.len();
    let mut order: Vec<usize> = (0..grid.len()).collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
    let mut peaks: Vec<[f64; 3]> = Vec::new();
    for &i in &order {
        let g = grid[i];
        if peaks
            .iter()
            .all(|p| (0..3).any(|k| (p[k] - g[k]).abs() > 4.0 * step))
        {
            peaks.push(g);
        }
        if peaks.len() == 3 {
            break;
        }
    }
    Ok(peaks)
}

/// Nelder-Mead from each peak on photos reduced 2 and 4 times less than the grid's; the
/// best goes on through every finer scale down to (not including) `finest`.
fn refine_from_peaks(
    terrain: &LabelledTerrain,
    space: &Space,
    photo: &MaskedPhoto,
    peaks: &[[f64; 3]],
    coarse: u32,
    finest: u32,
    evals: &mut usize,
) -> Result<CameraParams> {
    let start = space.base;
    let mut best: Option<(CameraParams, f64)> = None;
    let levels: Vec<u32> = [coarse / 2, coarse / 4]
        .into_iter()
        .filter(|&f| f > finest)
        .collect();
    for peak in peaks {
        let mut c = start;
        for (a, dk) in c.angles.iter_mut().zip(peak) {
            *a += dk;
        }
        let mut score = f64::NEG_INFINITY;
        for &f in &levels {
            let grey = photo.grey(f);
            let (c2, s2, e) = refine(terrain, space, &c, &grey, 3.0)?;
            *evals += e;
            (c, score) = (c2, s2);
        }
        if best.as_ref().is_none_or(|b| score > b.1) {
            best = Some((c, score));
        }
    }
    let (mut cam, _) = best.ok_or_else(|| Error::BadOption("register: empty search".into()))?;
    let mut f = levels.last().copied().unwrap_or(coarse) / 2;
    while f > finest {
        let grey = photo.grey(f);
        let (c2, _, e) = refine(terrain, space, &cam, &grey, 2.0)?;
        *evals += e;
        cam = c2;
        f /= 2;
    }
    Ok(cam)
}

/// How far (pixels at the median depth) searches restarted from `cam` turned by ±3 px in
/// yaw and pitch end from it: the repeatability the verdict asks for.
fn restart_spread(
    terrain: &LabelledTerrain,
    space: &Space,
    cam: &CameraParams,
    grey: &GreyImage,
    depth: f64,
    evals: &mut usize,
) -> Result<f64> {
    let mut repeat: f64 = 0.0;
    for kick in [[3.0, -3.0], [-3.0, 3.0]] {
        let mut c = *cam;
        let f = scaled(&cam.camera(), grey).fx;
        c.angles[0] += kick[0] / f;
        c.angles[1] += kick[1] / f;
        let (c2, _, e) = refine(terrain, space, &c, grey, 2.0)?;
        *evals += e;
        repeat = repeat.max(pixel_distance(&cam.camera(), &c2.camera(), depth));
    }
    Ok(repeat)
}

/// Why the search's camera is not accepted, if it is not: at the search's bounds, restarts
/// that disagree, a position search that did not settle, or a score that did not rise.
fn verdict_reason(
    at_bound: bool,
    repeat: f64,
    unsettled: Option<f64>,
    (score_start, score): (f64, f64),
    opts: &TerrainOptions,
) -> Option<String> {
    if at_bound {
        Some("the search reached the largest change allowed".to_string())
    } else if repeat > opts.repeat_px {
        Some(format!(
            "restarts disagree by {repeat:.2} px (limit {:.2} px)",
            opts.repeat_px
        ))
    } else if let Some(a) = unsettled {
        Some(if a.is_finite() {
            format!(
                "the position search did not settle (a trial of its last round scored {a:.4} \
                 above the position found; limit {})",
                position::SETTLED
            )
        } else {
            "the position search could not score every trial of its last round (turned \
             beyond the search's bounds, or too little terrain in view)"
                .to_string()
        })
    } else if score <= score_start {
        Some(format!(
            "the score did not rise ({score_start:.4} -> {score:.4})"
        ))
    } else {
        None
    }
}

/// Pixels by which a sideways move of the camera by one metre shifts the near terrain it
/// sees against the far (`fx · (1/near − 1/far)`, near and far the 10th and 90th
/// percentiles of the distances on a 15 × 15 grid of its rays): what each metre of error
/// in a position the search keeps costs between them. `None` when fewer than 10 rays meet
/// the terrain.
pub fn parallax_px_per_m(terrain: &LabelledTerrain, cam: &CameraModel) -> Option<f64> {
    let d = view_depths(terrain, cam);
    if d.len() < 10 {
        return None;
    }
    let at = |q: f64| d[((d.len() - 1) as f64 * q).round() as usize];
    let (near, far) = (at(0.1), at(0.9));
    (near > 0.0).then(|| cam.fx * (1.0 / near - 1.0 / far))
}

/// The position stage: [`refine_edges`] from the mutual-information result `mi` (found with
/// the rough position), and again from it moved by 2 m east and 2 m south and 3 m back
/// along the view (the restarts); trusted when all end within [`POSITION_REPEAT_M`] and `opts.repeat_px` of each other,
/// the matches fit within [`EDGE_MEDIAN_PX`] and no parameter reached its bound.
#[allow(clippy::too_many_arguments)]
fn finish_with_edges(
    terrain: &LabelledTerrain,
    photo: &MaskedPhoto,
    rough: &CameraModel,
    mi: &CameraModel,
    opts: &TerrainOptions,
    depth: f64,
    (score_start, score, evals): (f64, f64, usize),
    t0: Instant,
) -> Result<TerrainFit> {
    let eopts = EdgeOptions {
        free: opts.free.clone(),
        position_sigma_m: opts.position_sigma_m,
        ..EdgeOptions::default()
    };
    let not_fitted = |why: String| {
        TerrainFit::judged(
            rough,
            *mi,
            Some(why),
            (score_start, score, evals),
            f64::NAN,
            None,
            t0,
        )
    };
    // (an edge fit that cannot be made, e.g. too few silhouettes matched, is a verdict)
    let first = match edges::refine_masked_edges(terrain, photo, mi, rough, &eopts) {
        Ok(f) => f,
        Err(e) => return Ok(not_fitted(e.to_string())),
    };
    // restarts: moved sideways, and back along the view (where distance trades with focal
    // length when the silhouettes lie at similar distances)
    let axis = mi.world_to_camera.row(2);
    let back = -DVec3::new(axis.x, axis.y, 0.0).normalize_or_zero() * 3.0;
    let found = first.camera;
    let (mut position_repeat_m, mut repeat) = (0.0f64, 0.0f64);
    for kick in [DVec3::new(2.0, -2.0, 0.0), back] {
        let mut kicked = *mi;
        kicked.position += kick;
        let again = match edges::refine_masked_edges(terrain, photo, &kicked, rough, &eopts) {
            Ok(f) => f,
            Err(e) => return Ok(not_fitted(format!("restart: {e}"))),
        };
        position_repeat_m =
            position_repeat_m.max((found.position - again.camera.position).length());
        repeat = repeat.max(pixel_distance(&found, &again.camera, depth));
    }
    let space = Space {
        base: CameraParams::from_camera(rough),
        free: opts.free.clone(),
        depth,
        bounds: opts.bounds,
    };
    let reason = if space.outside(&CameraParams::from_camera(&found), 0.98) {
        Some("the search reached the largest change allowed".to_string())
    } else if !(first.median_px <= EDGE_MEDIAN_PX) {
        Some(format!(
            "the silhouettes fit the photo's edges to {:.2} px (median; limit {EDGE_MEDIAN_PX} px)",
            first.median_px
        ))
    } else if position_repeat_m > POSITION_REPEAT_M || repeat > opts.repeat_px {
        Some(format!(
            "restarts disagree by {position_repeat_m:.2} m and {repeat:.2} px (limits {POSITION_REPEAT_M} m, {:.2} px)",
            opts.repeat_px
        ))
    } else {
        None
    };
    let summary = EdgeSummary {
        matched: first.matched,
        median_px: first.median_px,
        position_repeat_m,
        sigma: first.sigma,
    };
    Ok(TerrainFit::judged(
        rough,
        found,
        reason,
        (score_start, score, evals),
        repeat,
        Some(summary),
        t0,
    ))
}

/// The free parameters as a vector in pixel units at one scale: an angle step moves the
/// image centre by a pixel (roll: the image's side), a focal step the image's side, a
/// position step a point at the view's median depth.
struct Space {
    base: CameraParams,
    free: Vec<Param>,
    depth: f64,
    bounds: [f64; 3],
}

impl Space {
    fn unit(&self, p: Param, cam: &CameraModel) -> f64 {
        let f = cam.fx;
        let half = cam.width as f64 / 2.0;
        match p {
            Param::Yaw | Param::Pitch => 1.0 / f,
            Param::Roll => 1.0 / half,
            Param::F | Param::Fx | Param::Fy => self.base.focal[0] / half,
            _ => self.depth / f,
        }
    }

    /// This space with its base camera moved to `position`, turned so that the point it
    /// looked at (the view's median depth ahead) stays in the image centre, horizon tilt
    /// kept: the bounds then count how far a camera turned from where the rough camera would
    /// look from there, not the turn the move itself asks for.
    fn moved_to(&self, position: DVec3) -> Space {
        Space {
            base: position::moved_keeping_target(&self.base, position, self.depth),
            free: self.free.clone(),
            depth: self.depth,
            bounds: self.bounds,
        }
    }

    fn apply(&self, from: &CameraParams, x: &[f64], cam: &CameraModel) -> CameraParams {
        let mut c = *from;
        for (p, v) in self.free.iter().zip(x) {
            c.set(*p, from.get(*p) + v * self.unit(*p, cam));
        }
        c
    }

    /// Whether `c` is beyond `frac` of the bounds from the base camera.
    fn outside(&self, c: &CameraParams, frac: f64) -> bool {
        self.free.iter().any(|&p| {
            let d = (c.get(p) - self.base.get(p)).abs();
            match p {
                Param::Yaw | Param::Pitch | Param::Roll => d.to_degrees() > frac * self.bounds[0],
                Param::F | Param::Fx | Param::Fy => d / self.base.focal[0] > frac * self.bounds[1],
                _ => d > frac * self.bounds[2],
            }
        })
    }
}

/// Nelder-Mead at one scale from `from`, with samples cast from `from`: the best camera, its
/// score and the evaluations spent.
fn refine(
    terrain: &LabelledTerrain,
    space: &Space,
    from: &CameraParams,
    grey: &GreyImage,
    step_px: f64,
) -> Result<(CameraParams, f64, usize)> {
    let samples = cast_samples(terrain, from, grey)?;
    Ok(refine_on(&samples, space, from, grey, step_px))
}

/// The samples [`refine`] scores `from` with: cast from it at `grey`'s scale, those in the
/// band around silhouettes and one in [`INNER_STRIDE`]² of the others.
fn cast_samples(
    terrain: &LabelledTerrain,
    from: &CameraParams,
    grey: &GreyImage,
) -> Result<Vec<Sample>> {
    let cam = scaled(&from.camera(), grey);
    let factor = (from.size.0 / grey.width.max(1)).max(1);
    terrain.sample(&cam, 1.0, 0.06, Some(band_width(factor)))
}

/// [`refine`] with the samples given (cast from another camera near `from`).
fn refine_on(
    samples: &[Sample],
    space: &Space,
    from: &CameraParams,
    grey: &GreyImage,
    step_px: f64,
) -> (CameraParams, f64, usize) {
    let cam = scaled(&from.camera(), grey);
    let mut f = |x: &[f64]| {
        let c = space.apply(from, x, &cam);
        if space.outside(&c, 1.0) {
            return 0.0;
        }
        nmi(samples, &scaled(&c.camera(), grey), grey)
    };
    let x0 = vec![0.0; space.free.len()];
    let (x, v, evals) = simplex::maximise(&mut f, &x0, step_px, 0.02, 1e-7, 150 * space.free.len());
    (space.apply(from, &x, &cam), v, evals)
}

/// Half-width (grid steps) of the band of samples kept around silhouettes on a photo
/// reduced `factor` times: about 48 full-resolution pixels (24 on the full photo), at
/// least 3 steps.
fn band_width(factor: u32) -> usize {
    (48 / factor.max(1) as usize).clamp(3, 24)
}

/// `cam` resized to the grey image's size.
pub(super) fn scaled(cam: &CameraModel, grey: &GreyImage) -> CameraModel {
    cam.resized(grey.width, grey.height)
}

/// Median distance of the terrain seen by `cam` (a coarse grid of rays), 100 m if none.
fn median_depth(terrain: &LabelledTerrain, cam: &CameraModel) -> f64 {
    let d = view_depths(terrain, cam);
    d.get(d.len() / 2).copied().unwrap_or(100.0)
}

/// Sorted distances (metres) from `cam` to where its rays through a 15 × 15 grid inside
/// the image meet the terrain.
fn view_depths(terrain: &LabelledTerrain, cam: &CameraModel) -> Vec<f64> {
    let mut d: Vec<f64> = Vec::new();
    for j in 1..16 {
        for i in 1..16 {
            let (u, v) = (
                cam.width as f64 * i as f64 / 16.0,
                cam.height as f64 * j as f64 / 16.0,
            );
            if let Some(dir) = cam.pixel_ray(u, v)
                && let Some(p) = terrain.hit(cam.position, dir)
            {
                d.push((p - cam.position).length());
            }
        }
    }
    d.sort_unstable_by(f64::total_cmp);
    d
}

/// Largest image distance (pixels of `a`) between where `a` and `b` show the points at
/// `depth` along `a`'s rays through the image's corners and centre.
pub fn pixel_distance(a: &CameraModel, b: &CameraModel, depth: f64) -> f64 {
    let (w, h) = (a.width as f64, a.height as f64);
    let mut worst: f64 = 0.0;
    for (u, v) in [
        (0.0, 0.0),
        (w - 1.0, 0.0),
        (0.0, h - 1.0),
        (w - 1.0, h - 1.0),
        (w / 2.0, h / 2.0),
    ] {
        let Some(dir) = a.pixel_ray(u, v) else {
            continue;
        };
        let p: DVec3 = a.position + dir * depth;
        match b.project(p) {
            Some(q) => worst = worst.max(((q[0] - u).powi(2) + (q[1] - v).powi(2)).sqrt()),
            None => return f64::INFINITY,
        }
    }
    worst
}
