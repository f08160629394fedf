//! Bilinear lookup in the source image, ignoring unknown (alpha 0) and out-of-image taps.

use super::SrcView;
use crate::fastmath::floor_i;

/// Bilinear colour (RGB, 0..=255) at fractional pixel coordinates `(col, row)` (pixel
/// centres at integers). Taps outside the image or with alpha 0 are dropped and the rest
/// renormalised; `None` if no tap with positive weight is known.
pub(crate) fn sample(src: &SrcView, col: f64, row: f64) -> Option<[f64; 3]> {
    if !(col.is_finite() && row.is_finite())
        || col < -1.0
        || row < -1.0
        || col > src.w as f64
        || row > src.h as f64
    {
        return None;
    }
    let (c0, r0) = (floor_i(col), floor_i(row));
    let (fx, fy) = (col - c0 as f64, row - r0 as f64);
    let mut acc = [0.0; 3];
    let mut wsum = 0.0;
    for (dc, dr, w) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        if w <= 0.0 {
            continue;
        }
        if let Some(px) = src.get(c0 + dc, r0 + dr) {
            for k in 0..3 {
                acc[k] += w * px[k] as f64;
            }
            wsum += w;
        }
    }
    (wsum > 1e-12).then(|| acc.map(|v| v / wsum))
}
