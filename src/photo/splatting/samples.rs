//! A photo image prepared for splatting ([`PhotoSamples`]): its colours through the
//! leveling transform into the working colour space, the border feather of every pixel,
//! the angle a pixel subtends, the pixels left out (a mask, a minimum distance) and, if on,
//! the occlusion margin's inputs. Made once per photo
//! and level; [`crate::photo::PhotoAccum::add_samples`] reads it per footprint.

use image::RgbImage;

use crate::colour::ColourSpace;
use crate::photo::splatting::colour_transform::ColourTransform;
use crate::photo::splatting::confidence::{BorderFeather, ConfidenceParams};
use crate::photo::splatting::occlusion::{OcclusionMap, occlusion_weight};
use crate::photo::{PixelFootprint, PixelMask};

/// A photo image prepared for splatting: its 8-bit values mapped by a colour transform and
/// decoded into the working colour space (per channel, the same numbers as transforming and
/// decoding each pixel), the border feather of every pixel
/// ([`ConfidenceParams::border_feather`]) and the angle a pixel subtends.
#[derive(Clone, Debug)]
pub struct PhotoSamples<'a> {
    pub(in crate::photo) image: &'a RgbImage,
    /// Per channel and 8-bit value, the working-space value (leveling applied).
    pub(in crate::photo) lut: [[f32; 256]; 3],
    pub(in crate::photo) feather: BorderFeather,
    /// Radians per pixel: `1 / √(fx·fy)` of the camera the footprints were cast with.
    pub(in crate::photo) pixel_angle: f32,
    /// The occlusion margin's inputs, if on.
    occlusion: Option<OcclusionTerm<'a>>,
    /// Pixels not to use (of this image's size), if any.
    mask: Option<&'a PixelMask>,
    /// Surface points nearer to the camera than this (metres) are left out (0: none).
    min_distance: f32,
}

/// Why a footprint's pixel is left out ([`PhotoSamples::excluded`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exclusion {
    /// The photo's mask leaves it out (a mask file or a uniform border).
    Masked,
    /// The surface there is nearer to the camera than the minimum distance.
    Near,
}

/// What [`PhotoSamples`] needs for the occlusion margin ([`crate::photo::splatting::occlusion`]).
#[derive(Clone, Debug)]
struct OcclusionTerm<'a> {
    map: &'a OcclusionMap,
    /// Full-resolution pixels per pixel of the image the footprints were cast for.
    step_scale: f32,
    /// Pose uncertainty, full-resolution pixels.
    margin_px: f32,
    /// Full-resolution focal length, pixels.
    focal_full: f32,
    /// TIN error (metres) per manifest cell.
    cell_error: &'a [f32],
}

impl<'a> PhotoSamples<'a> {
    /// Prepares `image` (cast with a camera of focal lengths `fx`, `fy` pixels) with
    /// `transform` (applied to sRGB values) and the feather of `params`, decoding into `space`.
    pub fn new(
        image: &'a RgbImage,
        focal_px: [f64; 2],
        transform: &ColourTransform,
        params: &ConfidenceParams,
        space: ColourSpace,
    ) -> PhotoSamples<'a> {
        let lut = std::array::from_fn(|k| {
            std::array::from_fn(|v| {
                let mut rgb = [0.0; 3];
                rgb[k] = v as f32 / 255.0;
                space.decode(transform.apply(rgb)[k])
            })
        });
        let f = (focal_px[0] * focal_px[1]).sqrt();
        let pixel_angle = if f.is_finite() && f > 0.0 {
            (1.0 / f) as f32
        } else {
            0.0
        };
        PhotoSamples {
            image,
            lut,
            feather: params.border_feather(image.width(), image.height()),
            pixel_angle,
            occlusion: None,
            mask: None,
            min_distance: 0.0,
        }
    }
}

impl<'a> PhotoSamples<'a> {
    /// Adds the occlusion margin of `params` (`crate::photo::splatting::occlusion`): `map` of this photo,
    /// the image these samples are of being `step_scale` times smaller per side than the
    /// full-resolution photo of focal length `focal_full` pixels; `cell_error[c]` the TIN
    /// error (metres) of manifest cell `c`. No change when the margin is 0.
    pub fn with_occlusion(
        mut self,
        map: &'a OcclusionMap,
        step_scale: f32,
        focal_full: f64,
        cell_error: &'a [f32],
        params: &ConfidenceParams,
    ) -> PhotoSamples<'a> {
        if params.occlusion_margin_px > 0.0 {
            self.occlusion = Some(OcclusionTerm {
                map,
                step_scale,
                margin_px: params.occlusion_margin_px as f32,
                focal_full: focal_full as f32,
                cell_error,
            });
        }
        self
    }

    /// Leaves out the pixels `mask` marks (a mask of this image's size; another size leaves
    /// every pixel out).
    pub fn with_mask(mut self, mask: Option<&'a PixelMask>) -> PhotoSamples<'a> {
        self.mask = mask;
        self
    }

    /// Leaves out surface points nearer to the camera than `metres` (foreground objects).
    pub fn with_min_distance(mut self, metres: f64) -> PhotoSamples<'a> {
        self.min_distance = metres.max(0.0) as f32;
        self
    }

    /// Why footprint `fp`'s pixel is left out, if it is.
    #[inline]
    pub fn excluded(&self, fp: &PixelFootprint) -> Option<Exclusion> {
        if let Some(m) = self.mask
            && ((m.width, m.height) != self.image.dimensions() || m.is_masked(fp.pixel))
        {
            return Some(Exclusion::Masked);
        }
        (fp.distance < self.min_distance).then_some(Exclusion::Near)
    }

    /// The occlusion weight of footprint `fp` (1 without the margin).
    #[inline]
    pub(in crate::photo) fn occlusion_weight(&self, fp: &PixelFootprint) -> f32 {
        let Some(o) = &self.occlusion else {
            return 1.0;
        };
        let eps = o.cell_error.get(fp.cell as usize).copied().unwrap_or(0.0);
        let margin = o.margin_px + o.focal_full * eps / fp.distance.max(1e-3);
        occlusion_weight(o.map.distance_px(fp.pixel, o.step_scale), margin)
    }
}
