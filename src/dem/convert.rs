//! Turns decoded samples (in the file's own units) into heights in metres and a void mask,
//! checking every value. Shared by all DEM readers.
//!
//! Per sample: if the reader marks it void (no-data value or transparent pixel) it is a
//! void; otherwise `h = value * z_scale + z_offset` in f64, which must be finite and within
//! ±[`MAX_ABS_HEIGHT`] m, then stored as f32.

use std::path::Path;

use crate::error::{Error, Result};

/// Heights beyond this magnitude (metres, after scaling) are refused as implausible.
pub const MAX_ABS_HEIGHT: f64 = 1e5;

/// A stored sample type and how the no-data value is matched in it: like GDAL, the
/// no-data value is converted to the sample type; integers match only an integral in-range
/// value, floats match after rounding to their own precision, NaN matches NaN.
pub(crate) trait Sample: Copy {
    /// The value as f64 (exact for all types except u64/i64 beyond 2^53).
    fn to_f64(self) -> f64;
    /// Whether this sample equals the declared no-data value `nd`.
    fn is_nodata(self, nd: f64) -> bool;
}

macro_rules! int_sample {
    ($($t:ty),*) => {$(
        impl Sample for $t {
            #[inline]
            fn to_f64(self) -> f64 { self as f64 }
            #[inline]
            fn is_nodata(self, nd: f64) -> bool {
                nd.fract() == 0.0 && nd >= <$t>::MIN as f64 && nd <= <$t>::MAX as f64 && self as f64 == nd
            }
        }
    )*};
}
int_sample!(u8, i8, u16, i16, u32, i32, u64, i64);

impl Sample for f32 {
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn is_nodata(self, nd: f64) -> bool {
        if nd.is_nan() {
            self.is_nan()
        } else {
            self == nd as f32
        }
    }
}

impl Sample for f64 {
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn is_nodata(self, nd: f64) -> bool {
        if nd.is_nan() {
            self.is_nan()
        } else {
            self == nd
        }
    }
}

/// Values commonly stored for missing data without a declared no-data value: −9999 (ESRI
/// ASCII grids and many exports), −32768 (SRTM and other i16 grids), the lowest f32
/// (−3.4028235e38, GDAL's and ArcGIS's float default) and its rounded form −3.4e38, and NaN.
/// Without `--nodata` and without a no-data tag a reader takes them as no-data
/// (`DemLoadOptions::nodata_sentinels`); `--nodata none` turns this off.
pub const NODATA_SENTINELS: [f64; 5] = [-9999.0, -32768.0, f32::MIN as f64, -3.4e38, f64::NAN];

/// How a reader tells no-data samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum VoidRule {
    /// The declared value (option or file tag) and nothing else.
    Declared(f64),
    /// None declared: the common sentinels ([`NODATA_SENTINELS`]).
    Sentinels,
    /// None declared and sentinels off: every value is a height.
    Off,
}

impl VoidRule {
    /// The rule for a declared value (the option, else the file's tag) and whether
    /// undeclared sentinels count.
    pub fn new(declared: Option<f64>, sentinels: bool) -> VoidRule {
        match declared {
            Some(nd) => VoidRule::Declared(nd),
            None if sentinels => VoidRule::Sentinels,
            None => VoidRule::Off,
        }
    }

    /// Whether a value was declared (for the hints of errors).
    pub fn declared(self) -> bool {
        matches!(self, VoidRule::Declared(_))
    }

    /// Which no-data value `v` is: `Some(k)` for the declared value (k = 0) or the k-th
    /// sentinel, `None` for a height.
    #[inline]
    pub fn matches<T: Sample>(self, v: T) -> Option<usize> {
        match self {
            VoidRule::Declared(nd) => v.is_nodata(nd).then_some(0),
            VoidRule::Sentinels => NODATA_SENTINELS.iter().position(|&s| v.is_nodata(s)),
            VoidRule::Off => None,
        }
    }
}

/// Per sentinel, how many samples a reader took as no-data by [`VoidRule::Sentinels`].
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct SentinelCounts(pub [u64; NODATA_SENTINELS.len()]);

impl SentinelCounts {
    /// Counts match `k` of `rule` (only sentinel matches count) and says whether it is void.
    #[inline]
    pub fn note(&mut self, rule: VoidRule, k: Option<usize>) -> bool {
        if let (VoidRule::Sentinels, Some(k)) = (rule, k) {
            self.0[k] += 1;
        }
        k.is_some()
    }

    /// "1234 samples of -9999, 12 of NaN", or `None` if no sentinel was met.
    pub fn describe(&self) -> Option<String> {
        let parts: Vec<String> = NODATA_SENTINELS
            .iter()
            .zip(self.0)
            .filter(|(_, n)| *n > 0)
            .map(|(s, n)| format!("{n} samples of {}", num(*s)))
            .collect();
        (!parts.is_empty()).then(|| parts.join(", "))
    }
}

/// Formats a value compactly (scientific notation when huge) but exactly enough to be
/// passed back as `--nodata` (Rust's shortest round-trip representation).
fn num(v: f64) -> String {
    if v.abs() >= 1e9 {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// How stored values become heights.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scaling {
    /// Multiplier (finite, non-zero).
    pub scale: f64,
    /// Added after scaling (finite).
    pub offset: f64,
}

/// Converts `n = values.len()` samples of a grid `width` wide. `sample(i)` returns the
/// stored value in f64 and whether the reader already knows it is void. Errors name the
/// file, the row and the column of the first bad value and suggest `--nodata`/`--z-scale`.
pub(crate) fn to_heights(
    path: &Path,
    width: usize,
    n: usize,
    scaling: Scaling,
    nodata_declared: bool,
    mut sample: impl FnMut(usize) -> (f64, bool),
) -> Result<(Vec<f32>, Vec<bool>)> {
    let mut heights = Vec::with_capacity(n);
    let mut void = Vec::with_capacity(n);
    for i in 0..n {
        let (v, is_void) = sample(i);
        if is_void {
            heights.push(0.0);
            void.push(true);
            continue;
        }
        let (row, col) = (i / width, i % width);
        if !v.is_finite() {
            let hint = if v.is_nan() && !nodata_declared {
                "; if NaN marks missing data pass --nodata nan"
            } else if v.is_nan() {
                "; NaN is not the declared no-data value (pass --nodata nan to treat it as no-data)"
            } else {
                "; if it marks missing data pass --nodata with that value"
            };
            return Err(Error::bad_input(
                path,
                format!("height at row {row}, column {col} is {v} (not a finite number){hint}"),
            ));
        }
        let h = v * scaling.scale + scaling.offset;
        if !h.is_finite() || h.abs() > MAX_ABS_HEIGHT {
            let (h, v) = (num(h), num(v));
            return Err(Error::bad_input(
                path,
                format!(
                    "height {h} m at row {row}, column {col} is implausible (|h| > {MAX_ABS_HEIGHT} m); \
                     if {v} marks missing data pass --nodata {v}, otherwise check --z-scale/--z-offset"
                ),
            ));
        }
        heights.push(h as f32);
        void.push(false);
    }
    Ok((heights, void))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodata_matching_follows_sample_type() {
        assert!((-9999.0f32).is_nodata(-9999.0));
        assert!(f32::MIN.is_nodata(-3.4028234663852886e38));
        assert!(f32::NAN.is_nodata(f64::NAN));
        assert!(!f32::NAN.is_nodata(-9999.0));
        assert!(0u16.is_nodata(0.0));
        assert!(!0u16.is_nodata(0.5));
        assert!(!65535u16.is_nodata(65535.5));
        assert!(!0u8.is_nodata(-9999.0));
        assert!((-32768i16).is_nodata(-32768.0));
    }

    #[test]
    fn scaling_and_errors() {
        let s = Scaling {
            scale: 0.1,
            offset: 5.0,
        };
        let vals = [10.0, 20.0, -1.0, 30.0];
        let (h, v) = to_heights(Path::new("a.png"), 2, 4, s, false, |i| {
            (vals[i], vals[i] < 0.0)
        })
        .unwrap();
        assert_eq!(h, vec![6.0, 7.0, 0.0, 8.0]);
        assert_eq!(v, vec![false, false, true, false]);

        let vals = [1.0, 2.0, 3.0, f64::NAN];
        let e = to_heights(Path::new("n.tif"), 2, 4, s, false, |i| (vals[i], false))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("n.tif") && e.contains("row 1, column 1") && e.contains("--nodata nan"),
            "{e}"
        );

        let vals = [1.0, 2e6, 3.0, 4.0];
        let one = Scaling {
            scale: 1.0,
            offset: 0.0,
        };
        let e = to_heights(Path::new("b.f32"), 2, 4, one, false, |i| (vals[i], false))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("b.f32") && e.contains("row 0, column 1") && e.contains("--nodata"),
            "{e}"
        );
    }
}
