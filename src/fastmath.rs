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

/// `x.round()` (halves away from zero, the sign of zero kept) for |x| < 2^51 without a
/// libm call; NaN and infinities as `round`.
#[inline(always)]
pub(crate) fn round_f(x: f64) -> f64 {
    let a = x.abs();
    let f = floor_f(a);
    // (a − f is exact below 2^51)
    let r = if a - f >= 0.5 { f + 1.0 } else { f };
    r.copysign(x)
}

/// `round_f(v)` clamped to 0..=255, as a byte (0 for NaN).
#[inline(always)]
pub(crate) fn to_u8(v: f64) -> u8 {
    round_f(v).clamp(0.0, 255.0) as u8
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

    #[test]
    fn round_matches_libm() {
        let near_half = 0.5f64.next_down();
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            2.5,
            -2.5,
            near_half,
            -near_half,
            254.5,
            255.49999999999997,
            1e15 + 0.5,
        ];
        xs.extend([f64::NAN, f64::INFINITY, f64::NEG_INFINITY]);
        let mut seed = 5u64;
        for _ in 0..100_000 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let v = (seed >> 11) as f64 / (1u64 << 53) as f64;
            xs.push((v - 0.3) * 400.0);
            xs.push((v * 512.0).floor() * 0.5); // exact halves
        }
        for x in xs {
            let (a, b) = (round_f(x), x.round());
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{x}: {a} vs {b}"
            );
            assert_eq!(to_u8(x), x.round().clamp(0.0, 255.0) as u8, "{x}");
        }
    }
}
