//! Each photo's pixels to leave out, per pyramid step: its mask file (the photo list's
//! `"mask"`) and, when on, its uniform borders ([`crate::photo::uniform_border`]), halved
//! with the photo (a coarse pixel is left out when any of its full-resolution pixels is).

use crate::photo::{BorderSide, PhotoInput, PixelMask, uniform_border};
use crate::store::PhotoReport;

/// A photo's masks by pyramid step (empty: nothing left out) and what they hold.
pub(crate) struct PhotoMasks {
    steps: Vec<PixelMask>,
    /// What the automatic border mask took, per side.
    border: Vec<BorderSide>,
}

impl PhotoMasks {
    /// The masks of `photo` for pyramid steps `0..=steps` (`borders`: add its uniform
    /// borders to its mask file's).
    pub(crate) fn of(photo: &PhotoInput, steps: usize, borders: bool) -> PhotoMasks {
        let (border_mask, border) = if borders {
            uniform_border(&photo.image)
        } else {
            (PixelMask::none(0, 0), Vec::new())
        };
        let full = match (&photo.mask, border.is_empty()) {
            (None, true) => None,
            (Some(m), true) => Some(m.clone()),
            (None, false) => Some(border_mask),
            (Some(m), false) => {
                let mut m = m.clone();
                m.union(&border_mask);
                Some(m)
            }
        };
        let mut out = Vec::new();
        if let Some(full) = full {
            out.push(full);
            while out.len() <= steps {
                match out.last().and_then(PixelMask::halved) {
                    Some(m) => out.push(m),
                    None => break,
                }
            }
        }
        for s in &border {
            tracing::info!(
                "photo {}: a uniform border left out on the {} (colour {:?}, {} pixels)",
                photo.name,
                s.side,
                s.colour,
                s.pixels
            );
        }
        PhotoMasks { steps: out, border }
    }

    /// The mask of pyramid step `step`, if any pixel is left out.
    pub(crate) fn at(&self, step: usize) -> Option<&PixelMask> {
        self.steps.get(step)
    }

    /// Records the automatic border mask in the photo's report.
    pub(crate) fn report(&self, r: &mut PhotoReport) {
        r.border_masked = self
            .border
            .iter()
            .map(|s| format!("{}: {} pixels of colour {:?}", s.side, s.pixels, s.colour))
            .collect();
    }
}
