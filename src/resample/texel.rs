//! What the per-texel kernels share ([`super::kernel`] and [`super::subtexel`]): a texel's
//! resulting colour, the running area-weighted sum, per-row scratch space and the bilinear
//! fallback for collapsed footprints.

use super::footprint::Footprint;
use super::{SrcView, bilinear};

/// Below this total intersection area (source pixels²) the footprint counts as collapsed.
pub const MIN_FOOTPRINT_AREA: f64 = 0.1;

/// Result of one texel.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TexelColour {
    /// RGB in 0..=255 (meaningless unless `known`).
    pub rgb: [f64; 3],
    /// A known source colour contributed.
    pub known: bool,
    /// The bilinear fallback was used.
    pub fallback: bool,
}

/// The running area-weighted colour of one texel: `Σ Aᵢ` over every overlapped pixel inside
/// the image, and `Σ Aᵢ`, `Σ Aᵢ Cᵢ` over the known ones.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct AreaSum {
    rgb: [f64; 3],
    known: f64,
    total: f64,
}

impl AreaSum {
    /// Adds overlap `a` (> 0) with a pixel of colour `px` (`None`: unknown).
    #[inline]
    // indexed loops: each index serves more than one array or lookup
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn add(&mut self, a: f64, px: Option<[u8; 3]>) {
        self.total += a;
        if let Some(px) = px {
            self.known += a;
            for k in 0..3 {
                self.rgb[k] += a * px[k] as f64;
            }
        }
    }

    /// The texel's colour, or `None` if the total overlap is below [`MIN_FOOTPRINT_AREA`]
    /// (the caller then falls back to bilinear filtering).
    #[inline]
    pub(crate) fn colour(&self) -> Option<TexelColour> {
        if self.total < MIN_FOOTPRINT_AREA {
            return None;
        }
        Some(if self.known > 0.0 {
            TexelColour {
                rgb: self.rgb.map(|v| v / self.known),
                known: true,
                fallback: false,
            }
        } else {
            TexelColour::default()
        })
    }
}

/// Reusable per-row scratch space (no allocation per texel).
#[derive(Default)]
pub(crate) struct Scratch {
    /// For each source column of the current footprint's bounding box, the row extent of
    /// the footprint within that column.
    pub col_ranges: Vec<(f64, f64)>,
    /// Likewise per source row, the column extent (subtexel kernel).
    pub row_ranges: Vec<(f64, f64)>,
}

pub(crate) fn bilinear_at(src: &SrcView, fp: &Footprint, fallback: bool) -> TexelColour {
    let c = fp.centre();
    match bilinear::sample(src, c[0], c[1]) {
        Some(rgb) => TexelColour {
            rgb,
            known: true,
            fallback,
        },
        None => TexelColour {
            rgb: [0.0; 3],
            known: false,
            fallback,
        },
    }
}
