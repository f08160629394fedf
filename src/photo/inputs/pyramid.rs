//! Photo pyramids: the photo box-filtered by 2 per step, with the matching camera, so that
//! a coarser quadtree level (texels twice as large) sees photo pixels twice as large and
//! footprint/texel ratios, and so the filtering, stay the same on every level.

use image::RgbImage;
use rayon::prelude::*;

use crate::camera::CameraModel;
use crate::colour::ColourSpace;

/// Halves an image: pixel `(i, j)` is the mean (rounded) of pixels `(2i..2i+2, 2j..2j+2)`;
/// an odd last column or row is cropped. `None` if a side is below 2 pixels.
pub fn downsample2(img: &RgbImage) -> Option<RgbImage> {
    downsample2_in(img, ColourSpace::Srgb)
}

/// [`downsample2`] averaging in `space` (linear light: the four values decoded, averaged
/// and encoded again, rounded in the encoding).
pub fn downsample2_in(img: &RgbImage, space: ColourSpace) -> Option<RgbImage> {
    let (w, h) = (img.width() / 2, img.height() / 2);
    if w == 0 || h == 0 {
        return None;
    }
    let src = img.as_raw();
    let sw = img.width() as usize;
    let mut out = vec![0u8; w as usize * h as usize * 3];
    out.par_chunks_exact_mut(w as usize * 3)
        .enumerate()
        .for_each(|(j, row)| {
            // the two source rows, cropped to an even width
            let (a, b) = (
                &src[2 * j * sw * 3..][..6 * w as usize],
                &src[(2 * j + 1) * sw * 3..][..6 * w as usize],
            );
            for ((o, a), b) in row
                .chunks_exact_mut(3)
                .zip(a.chunks_exact(6))
                .zip(b.chunks_exact(6))
            {
                for k in 0..3 {
                    o[k] = match space {
                        ColourSpace::Srgb => {
                            let s = a[k] as u32 + a[k + 3] as u32 + b[k] as u32 + b[k + 3] as u32;
                            ((s + 2) / 4) as u8
                        }
                        ColourSpace::Linear => {
                            let d = crate::colour::decode_u8;
                            crate::colour::encode_u8(
                                0.25 * (d(a[k]) + d(a[k + 3]) + d(b[k]) + d(b[k + 3])),
                            )
                        }
                    };
                }
            }
        });
    RgbImage::from_raw(w, h, out)
}

/// The camera of [`downsample2`]'s result: the camera of the image cropped to even sides
/// (same intrinsics, the crop removes the last column/row), resized by exactly 1/2.
pub fn half_camera(camera: &CameraModel) -> CameraModel {
    let (w, h) = (camera.width / 2, camera.height / 2);
    CameraModel {
        width: 2 * w,
        height: 2 * h,
        ..*camera
    }
    .resized(w, h)
}

/// A photo and its successive halvings with their cameras; step 0 is the photo itself.
#[derive(Clone, Debug)]
pub struct PhotoPyramid<'a> {
    full: &'a RgbImage,
    camera: CameraModel,
    /// Steps 1.. (images and cameras).
    coarser: Vec<(RgbImage, CameraModel)>,
}

impl<'a> PhotoPyramid<'a> {
    /// Builds `steps` halvings (fewer if the image becomes smaller than 2 pixels), each
    /// averaging 2 × 2 pixels as sRGB values.
    pub fn new(image: &'a RgbImage, camera: CameraModel, steps: usize) -> PhotoPyramid<'a> {
        PhotoPyramid::new_in(image, camera, steps, ColourSpace::Srgb)
    }

    /// [`PhotoPyramid::new`] averaging in `space`.
    pub fn new_in(
        image: &'a RgbImage,
        camera: CameraModel,
        steps: usize,
        space: ColourSpace,
    ) -> PhotoPyramid<'a> {
        let mut coarser: Vec<(RgbImage, CameraModel)> = Vec::new();
        for _ in 0..steps {
            let (img, cam) = coarser.last().map_or((image, &camera), |(i, c)| (i, c));
            let Some(next) = downsample2_in(img, space) else {
                break;
            };
            let cam = half_camera(cam);
            coarser.push((next, cam));
        }
        PhotoPyramid {
            full: image,
            camera,
            coarser,
        }
    }

    /// Halvings available (images after step 0).
    pub fn steps(&self) -> usize {
        self.coarser.len()
    }

    /// Image and camera after `step` halvings (the coarsest available if fewer exist).
    pub fn level(&self, step: usize) -> (&RgbImage, CameraModel) {
        match step.min(self.coarser.len()) {
            0 => (self.full, self.camera),
            k => (&self.coarser[k - 1].0, self.coarser[k - 1].1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn halves_images_and_cameras_consistently() {
        let img = RgbImage::from_fn(5, 4, |x, y| image::Rgb([(x * 10) as u8, (y * 20) as u8, 7]));
        let half = downsample2(&img).unwrap();
        assert_eq!(half.dimensions(), (2, 2));
        assert_eq!(half.get_pixel(1, 1).0, [25, 50, 7]);
        assert!(downsample2(&RgbImage::new(1, 8)).is_none());
        let r = crate::camera::rotation_look_at(DVec3::ZERO, DVec3::X).unwrap();
        let cam = CameraModel::with_fov(DVec3::ZERO, r, 5, 4, 0.8);
        let hc = half_camera(&cam);
        assert_eq!((hc.width, hc.height), (2, 2));
        // a world point projects to half the (pixel-edge) coordinates
        let p = DVec3::new(10.0, 0.7, -0.4);
        let (a, b) = (cam.project(p).unwrap(), hc.project(p).unwrap());
        for k in 0..2 {
            assert!(((b[k] + 0.5) - 0.5 * (a[k] + 0.5)).abs() < 1e-9);
        }
        let pyr = PhotoPyramid::new(&img, cam, 5);
        assert_eq!(pyr.level(0).0.dimensions(), (5, 4));
        assert_eq!(pyr.level(1).0.dimensions(), (2, 2));
        assert_eq!(pyr.level(9).0.dimensions(), (1, 1));
    }
}
