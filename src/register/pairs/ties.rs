//! Photo-to-photo ties: a photo taken from the same place as an already placed one (a
//! camera on a tripod or a time-lapse station that turned between shots) gets its rotation
//! from patch matches between the two ([`crate::register::match_photos`], [`crate::register::fit_rotation`]),
//! where the terrain alone cannot place it (little skyline, few silhouettes).
//!
//! The tied photo takes the anchor's position and intrinsics (the same camera body); only
//! matches whose ray from the anchor meets a surface the caller calls stable are used (the
//! terrain, not sky or clouds; optionally not a moving glacier). Of those, the matches one
//! rotation explains within [`TieOptions::consensus_px`] ([`crate::register::rotation_consensus`])
//! go to the robust fit; when a second rotation explains at least half as many of the
//! others (and at least [`TieOptions::min_inliers`]), part of the scene moved and the tie is
//! refused as ambiguous. The tie is accepted when at
//! least [`TieOptions::min_inliers`] matches are inliers of the robust fit, their RMSE is at
//! most [`TieOptions::max_rmse_px`], and the photo turned at most
//! [`TieOptions::max_turn_deg`] from its given camera; otherwise the reason is reported.

use std::time::Instant;

use glam::DVec3;
use image::RgbImage;

use crate::camera::CameraModel;
use crate::error::Result;
use crate::register::gcps::fit::GcpStatus;
use crate::register::pairs::consensus::rotation_consensus;
use crate::register::pairs::pair::{MatchOptions, fit_rotation, match_photos, stable_matches};

/// When a tie is tried and accepted.
#[derive(Clone, Debug, PartialEq)]
pub struct TieOptions {
    /// Most distance (metres) between the given positions of the photo and its anchor.
    pub max_distance_m: f64,
    /// Most RMSE (pixels) of the inlier matches.
    pub max_rmse_px: f64,
    /// Fewest inlier matches.
    pub min_inliers: usize,
    /// Most rotation (degrees) between the given camera and the tied one.
    pub max_turn_deg: f64,
    /// Tolerance (pixels) of the consensus that picks the matches one rotation explains
    /// ([`crate::register::rotation_consensus`]) before the robust fit.
    pub consensus_px: f64,
}

impl Default for TieOptions {
    fn default() -> Self {
        TieOptions {
            max_distance_m: 2.0,
            max_rmse_px: 1.0,
            min_inliers: 12,
            max_turn_deg: 8.0,
            consensus_px: 1.0,
        }
    }
}

/// The outcome of [`tie_photo`].
#[derive(Clone, Debug, PartialEq)]
pub struct TieFit {
    /// The tied camera (the anchor's position and intrinsics, the fitted rotation).
    pub camera: CameraModel,
    /// Whether the tie passed the checks of [`TieOptions`].
    pub accepted: bool,
    /// Why not, when not accepted.
    pub reason: Option<String>,
    /// Patch matches found / on stable surfaces / inliers of the robust fit.
    pub matches: [usize; 3],
    /// RMSE of the inlier matches, pixels.
    pub rmse_inliers_px: f64,
    /// Rotation from the given camera to the tied one, degrees.
    pub turn_deg: f64,
    /// Seconds spent.
    pub seconds: f64,
}

/// Ties `photo` (given camera `rough`) to `anchor_image` seen by camera `anchor`;
/// `surface(origin, dir)` gives where a ray meets the terrain and `stable(point)` whether a
/// match there may be used. Errors only for unusable input (the images' sizes differ from
/// their cameras'); a tie that fails its checks is a result with `accepted: false`.
pub fn tie_photo(
    anchor: &CameraModel,
    anchor_image: &RgbImage,
    photo: &RgbImage,
    rough: &CameraModel,
    surface: impl Fn(DVec3, DVec3) -> Option<DVec3>,
    stable: impl Fn(DVec3) -> bool,
    opts: &TieOptions,
) -> Result<TieFit> {
    let t0 = Instant::now();
    let fail = |reason: String, matches: [usize; 3], rmse: f64, turn: f64| TieFit {
        camera: *rough,
        accepted: false,
        reason: Some(reason),
        matches,
        rmse_inliers_px: rmse,
        turn_deg: turn,
        seconds: t0.elapsed().as_secs_f64(),
    };
    if anchor_image.dimensions() != (anchor.width, anchor.height)
        || photo.dimensions() != anchor_image.dimensions()
    {
        return Ok(fail(
            format!(
                "the photo ({}x{}) and its anchor ({}x{}, camera {}x{}) differ in size",
                photo.width(),
                photo.height(),
                anchor_image.width(),
                anchor_image.height(),
                anchor.width,
                anchor.height
            ),
            [0; 3],
            f64::NAN,
            f64::NAN,
        ));
    }
    let found = match_photos(anchor_image, photo, &MatchOptions::default())?;
    let kept = stable_matches(anchor, &found, surface, stable);
    if kept.len() < opts.min_inliers {
        return Ok(fail(
            format!(
                "{} of {} patch matches on stable terrain, fewer than {}",
                kept.len(),
                found.len(),
                opts.min_inliers
            ),
            [found.len(), kept.len(), 0],
            f64::NAN,
            f64::NAN,
        ));
    }
    // the matches one rotation explains; a second motion of comparable support (a surface
    // that moved between the shots) makes the tie ambiguous
    let consensus = rotation_consensus(anchor, &kept, opts.consensus_px);
    if consensus.second >= opts.min_inliers && 2 * consensus.second >= consensus.inliers.len() {
        return Ok(fail(
            format!(
                "two motions between the photos: one rotation explains {} matches, another {} \
                 (part of the scene moved? mark it with --moving-mask)",
                consensus.inliers.len(),
                consensus.second
            ),
            [found.len(), kept.len(), consensus.inliers.len()],
            f64::NAN,
            f64::NAN,
        ));
    }
    if consensus.inliers.len() < opts.min_inliers {
        return Ok(fail(
            format!(
                "{} of {} matches on stable terrain agree on one rotation (within {} px), fewer \
                 than {}",
                consensus.inliers.len(),
                kept.len(),
                opts.consensus_px,
                opts.min_inliers
            ),
            [found.len(), kept.len(), consensus.inliers.len()],
            f64::NAN,
            f64::NAN,
        ));
    }
    let agreed: Vec<_> = consensus.inliers.iter().map(|&i| kept[i]).collect();
    let fit = fit_rotation(anchor, &agreed)?;
    let inliers = fit
        .gcps
        .iter()
        .filter(|g| g.status == GcpStatus::Inlier)
        .count();
    let rmse = fit.rmse_inliers_px;
    let turn = rotation_angle_deg(rough, &fit.camera);
    let counts = [found.len(), kept.len(), inliers];
    let reason = if inliers < opts.min_inliers {
        Some(format!(
            "{inliers} inlier matches, fewer than {}",
            opts.min_inliers
        ))
    } else if !(rmse <= opts.max_rmse_px) {
        Some(format!(
            "inlier match RMSE {rmse:.2} px above {} px (not the same place?)",
            opts.max_rmse_px
        ))
    } else if !(turn <= opts.max_turn_deg) {
        Some(format!(
            "turned {turn:.1}° from the given camera, more than {}°",
            opts.max_turn_deg
        ))
    } else {
        None
    };
    Ok(match reason {
        Some(r) => fail(r, counts, rmse, turn),
        None => TieFit {
            camera: fit.camera,
            accepted: true,
            reason: None,
            matches: counts,
            rmse_inliers_px: rmse,
            turn_deg: turn,
            seconds: t0.elapsed().as_secs_f64(),
        },
    })
}

/// The angle (degrees) of the rotation between two cameras' orientations.
fn rotation_angle_deg(a: &CameraModel, b: &CameraModel) -> f64 {
    let r = a.world_to_camera * b.world_to_camera.transpose();
    let c = ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) / 2.0).clamp(-1.0, 1.0);
    c.acos().to_degrees()
}
