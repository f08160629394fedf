//! The photos of one `register` run, decoded once and shared while memory allows.
//!
//! A photo can be needed many times in one run: as the photo being registered, as the
//! anchor of ties and resections, and (with `--textures best`) as a label source for every
//! other photo in both passes, so a run over `n` photos would otherwise decode up to about
//! `n²` images. [`DecodedPhotos`] keeps each decoded image (RGB8, as
//! [`PhotoSpec::load`] gives it, with the same checks and errors) while the kept images
//! stay within a byte budget, dropping the least recently used first; an image dropped
//! and needed again is decoded again. The images are the same either way, so results do
//! not depend on the budget.

use std::cell::RefCell;
use std::sync::Arc;

use image::RgbImage;

use crate::error::Result;
use crate::photo::PhotoSpec;

/// Decoded images kept by default: 1 GiB (about 27 photos of 12 MP).
pub const DEFAULT_BUDGET_BYTES: usize = 1 << 30;

/// Decoded images of a photo list, by index in the list (module docs).
pub struct DecodedPhotos<'a> {
    specs: &'a [PhotoSpec],
    budget: usize,
    state: RefCell<State>,
}

#[derive(Default)]
struct State {
    /// Per photo: its image if kept, and when it was last asked for.
    kept: Vec<(Option<Arc<RgbImage>>, u64)>,
    clock: u64,
    bytes: usize,
    decodes: usize,
}

impl<'a> DecodedPhotos<'a> {
    /// Nothing decoded yet; at most `budget` bytes of images kept at once (0 keeps none
    /// beyond the one returned).
    pub fn new(specs: &'a [PhotoSpec], budget: usize) -> DecodedPhotos<'a> {
        DecodedPhotos {
            specs,
            budget,
            state: RefCell::new(State {
                kept: vec![(None, 0); specs.len()],
                ..State::default()
            }),
        }
    }

    /// The image of photo `i` (decoded now unless kept). Errors as [`PhotoSpec::load`],
    /// naming the file; panics only for `i` outside the list (a caller's bug).
    pub fn get(&self, i: usize) -> Result<Arc<RgbImage>> {
        let mut s = self.state.borrow_mut();
        s.clock += 1;
        let now = s.clock;
        if let Some(img) = &s.kept[i].0 {
            let img = Arc::clone(img);
            s.kept[i].1 = now;
            return Ok(img);
        }
        let img = Arc::new(self.specs[i].load()?.image);
        s.decodes += 1;
        let size = img.as_raw().len();
        // drop the least recently used images until this one fits
        while s.bytes + size > self.budget {
            let oldest = s
                .kept
                .iter()
                .enumerate()
                .filter(|(_, (k, _))| k.is_some())
                .min_by_key(|(_, (_, t))| *t)
                .map(|(j, _)| j);
            let Some(j) = oldest else { break };
            if let Some(old) = s.kept[j].0.take() {
                s.bytes -= old.as_raw().len();
            }
        }
        if s.bytes + size <= self.budget {
            s.bytes += size;
            s.kept[i] = (Some(Arc::clone(&img)), now);
        }
        Ok(img)
    }

    /// How many images have been decoded so far.
    #[cfg(test)]
    pub fn decodes(&self) -> usize {
        self.state.borrow().decodes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;

    fn specs(dir: &std::path::Path, n: usize) -> Vec<PhotoSpec> {
        (0..n)
            .map(|k| {
                let path = dir.join(format!("p{k}.png"));
                RgbImage::from_pixel(8, 6, image::Rgb([k as u8 * 40, 7, 9]))
                    .save(&path)
                    .unwrap();
                PhotoSpec {
                    mask_path: None,
                    name: format!("p{k}.png"),
                    image_path: path,
                    camera: CameraModel::pinhole(
                        glam::DVec3::ZERO,
                        glam::DMat3::IDENTITY,
                        8,
                        6,
                        10.0,
                    ),
                    unregistered: None,
                }
            })
            .collect()
    }

    #[test]
    fn images_are_decoded_once_within_the_budget_and_again_after_eviction() {
        let dir = tempfile::tempdir().unwrap();
        let specs = specs(dir.path(), 3);
        let one = 8 * 6 * 3;
        let all = DecodedPhotos::new(&specs, 3 * one);
        for _ in 0..3 {
            for i in 0..3 {
                assert_eq!(all.get(i).unwrap().get_pixel(0, 0).0[0], i as u8 * 40);
            }
        }
        assert_eq!(all.decodes(), 3);
        // room for two: 0, 1, 2 (drops 0), 1 (kept), 0 (drops 2), 2 again
        let two = DecodedPhotos::new(&specs, 2 * one);
        for i in [0, 1, 2, 1, 0, 2] {
            assert_eq!(two.get(i).unwrap().get_pixel(0, 0).0[0], i as u8 * 40);
        }
        assert_eq!(two.decodes(), 5);
        let none = DecodedPhotos::new(&specs, 0);
        for i in [1, 1] {
            assert_eq!(none.get(i).unwrap().get_pixel(0, 0).0[0], 40);
        }
        assert_eq!(none.decodes(), 2);
    }

    #[test]
    fn a_bad_image_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let mut specs = specs(dir.path(), 1);
        std::fs::write(&specs[0].image_path, b"not a png").unwrap();
        specs[0].name = "broken.png".into();
        let cache = DecodedPhotos::new(&specs, DEFAULT_BUDGET_BYTES);
        let e = cache.get(0).unwrap_err().to_string();
        assert!(e.contains("p0.png"), "{e}");
    }
}
