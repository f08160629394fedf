//! Colour encodings: the sRGB transfer function (IEC 61966-2-1) and averaging colours in
//! linear light or in sRGB values.
//!
//! Cameras and the eye integrate light, so a pixel that covers two surfaces of different
//! brightness shows the mean of their *linear* intensities; averaging sRGB-encoded values
//! instead darkens high-contrast detail. [`ColourSpace::Linear`] decodes 8-bit sRGB before
//! averaging and encodes the mean again ([`encode_u8`] rounds exactly: it returns the 8-bit
//! value whose decoded interval contains the mean).

use std::sync::LazyLock;

/// The space colours are averaged in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColourSpace {
    /// Linear light: 8-bit sRGB decoded before averaging, the mean encoded again.
    #[default]
    Linear,
    /// sRGB-encoded values averaged as they are (cliffmap before 2026-12).
    Srgb,
}

impl ColourSpace {
    /// The name used on the command line and in the manifest: "linear" or "srgb".
    pub fn name(self) -> &'static str {
        match self {
            ColourSpace::Linear => "linear",
            ColourSpace::Srgb => "srgb",
        }
    }

    /// The working value (0..1) of the 8-bit sRGB value `v`.
    #[inline]
    pub fn decode_u8(self, v: u8) -> f32 {
        match self {
            ColourSpace::Linear => SRGB8_TO_LINEAR[v as usize],
            ColourSpace::Srgb => v as f32 / 255.0,
        }
    }

    /// The working value (0..1) of the sRGB value `v` in [0, 1].
    #[inline]
    pub fn decode(self, v: f32) -> f32 {
        match self {
            ColourSpace::Linear => srgb_to_linear(v as f64) as f32,
            ColourSpace::Srgb => v,
        }
    }

    /// The sRGB value in [0, 1] of the working value `v` (clamped to [0, 1]).
    #[inline]
    pub fn encode(self, v: f32) -> f32 {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        match self {
            ColourSpace::Linear => linear_to_srgb(v as f64) as f32,
            ColourSpace::Srgb => v,
        }
    }

    /// The 8-bit sRGB value of the working value `v` (clamped to [0, 1]; NaN gives 0),
    /// rounded to nearest in the sRGB encoding.
    #[inline]
    pub fn encode_u8(self, v: f32) -> u8 {
        match self {
            ColourSpace::Linear => encode_u8(v),
            ColourSpace::Srgb => crate::fastmath::to_u8(v as f64 * 255.0),
        }
    }
}

/// Linear intensity in [0, 1] of the sRGB value `c` in [0, 1].
#[inline]
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB value in [0, 1] of the linear intensity `l` in [0, 1].
#[inline]
pub fn linear_to_srgb(l: f64) -> f64 {
    if l <= 0.003_130_8 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear intensity of each 8-bit sRGB value.
static SRGB8_TO_LINEAR: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|v| srgb_to_linear(v as f64 / 255.0) as f32));

/// `THRESHOLDS[k]`: the linear intensity of the sRGB value `(k + 0.5) / 255`, the boundary
/// between 8-bit values `k` and `k + 1`.
static THRESHOLDS: LazyLock<[f32; 255]> =
    LazyLock::new(|| std::array::from_fn(|k| srgb_to_linear((k as f64 + 0.5) / 255.0) as f32));

/// Entries of [`ENCODE_START`]: the linear range [0, 1] in equal bins.
const ENCODE_BINS: usize = 1 << 16;

/// Per bin of the linear range, the 8-bit value of the bin's lower end. Adjacent value
/// boundaries are at least 3·10⁻⁴ apart and a bin is 1.5·10⁻⁵ wide, so at most one boundary
/// lies in a bin: a value's code is the bin's, or one more if it is at or past that boundary.
static ENCODE_START: LazyLock<Vec<u8>> = LazyLock::new(|| {
    let t = &*THRESHOLDS;
    let mut k = 0usize;
    (0..ENCODE_BINS)
        .map(|i| {
            let l = i as f32 / ENCODE_BINS as f32;
            while k < t.len() && t[k] <= l {
                k += 1;
            }
            k as u8
        })
        .collect()
});

/// The 8-bit sRGB value of the linear intensity `l` (rounded in the sRGB encoding: the
/// number of value boundaries below `l`); NaN and values below 0 give 0, above 1 give 255.
#[inline]
pub fn encode_u8(l: f32) -> u8 {
    if !(l > 0.0) {
        return 0;
    }
    if l >= 1.0 {
        return 255;
    }
    let k = ENCODE_START[((l * ENCODE_BINS as f32) as usize).min(ENCODE_BINS - 1)];
    // (THRESHOLDS has 255 entries: index 255 stands for "no further boundary")
    match THRESHOLDS.get(k as usize) {
        Some(&t) if t <= l => k + 1,
        _ => k,
    }
}

/// Linear intensity of the 8-bit sRGB value `v`.
#[inline]
pub fn decode_u8(v: u8) -> f32 {
    SRGB8_TO_LINEAR[v as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_rounds_like_the_encoding() {
        for v in 0..=255u8 {
            assert_eq!(encode_u8(decode_u8(v)), v, "{v}");
            assert_eq!(
                ColourSpace::Srgb.encode_u8(ColourSpace::Srgb.decode_u8(v)),
                v
            );
            let s = linear_to_srgb(srgb_to_linear(v as f64 / 255.0));
            assert!((s * 255.0 - v as f64).abs() < 1e-9);
        }
        // against direct rounding of the encoded value, on a fine grid
        for i in 0..=20_000 {
            let l = i as f32 / 20_000.0;
            let want = (linear_to_srgb(l as f64) * 255.0).round() as i32;
            let got = encode_u8(l) as i32;
            assert!(
                (got - want).abs() <= 1
                    && (got == want || (linear_to_srgb(l as f64) * 255.0).fract().abs() > 0.499),
                "{l}"
            );
        }
        // the table walk agrees with a full count of the boundaries below the value
        for i in 0..=100_000 {
            let l = i as f32 / 100_000.0;
            assert_eq!(
                encode_u8(l) as usize,
                THRESHOLDS.iter().filter(|&&t| t <= l).count(),
                "{l}"
            );
        }
        // and on the f32 values next to every boundary
        for &t in THRESHOLDS.iter() {
            let mut l = t;
            for _ in 0..4 {
                l = f32::from_bits(l.to_bits() - 1);
            }
            for _ in 0..9 {
                assert_eq!(
                    encode_u8(l) as usize,
                    THRESHOLDS.iter().filter(|&&b| b <= l).count(),
                    "{l}"
                );
                l = f32::from_bits(l.to_bits() + 1);
            }
        }
        assert_eq!(encode_u8(f32::NAN), 0);
        assert_eq!(encode_u8(-1.0), 0);
        assert_eq!(encode_u8(2.0), 255);
        // the mean of black and white is 50 % intensity, sRGB 188, not 128
        assert_eq!(encode_u8(0.5 * (decode_u8(0) + decode_u8(255))), 188);
    }
}
