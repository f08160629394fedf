//! Floor and ceiling without libm calls (the x86-64 baseline has no rounding instruction,
//! so `f64::floor` is a function call in the hot loops of resampling and splatting).

/// `floor(x)` for |x| < 2^51 in plain arithmetic (exact: adding and subtracting
/// 1.5 · 2^52 rounds to an integer, corrected downwards). Beyond that range the result is
/// within one unit in the last place of `x` (which is an integer there anyway).
#[inline(always)]
pub(crate) fn floor_f(x: f64) -> f64 {
    const M: f64 = 6_755_399_441_055_744.0;
    let r = (x + M) - M;
    if r > x { r - 1.0 } else { r }
}

/// `ceil(x)` for |x| < 2^51 (see [`floor_f`]).
#[inline(always)]
pub(crate) fn ceil_f(x: f64) -> f64 {
    -floor_f(-x)
}

/// `floor(v)` as an integer (exact for |v| < 2^63; saturates beyond, 0 for NaN).
#[inline]
pub(crate) fn floor_i(v: f64) -> i64 {
    let t = v as i64;
    t - i64::from((t as f64) > v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_and_ceil_match_libm() {
        for x in [
            -3.5,
            -3.0,
            -2.999_999_999,
            -0.5,
            -0.0,
            0.0,
            1e-300,
            0.5,
            0.999_999_999_999,
            1.0,
            2.5,
            1e9 + 0.5,
            4.5e15,
        ] {
            assert_eq!(floor_f(x), x.floor(), "{x}");
            assert_eq!(ceil_f(x), x.ceil(), "{x}");
            assert_eq!(floor_i(x), x.floor() as i64, "{x}");
        }
    }
}
