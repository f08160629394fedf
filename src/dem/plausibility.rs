//! Heights that cannot be terrain: missing data stored as a height (0 m cells in a
//! mountain DEM, a collar of a fill value), seen as walls between neighbouring samples that
//! no real surface has. Takes the decoded grid; returns a message for a warning.

use crate::georef::GridGeoref;

/// A step between neighbouring samples larger than this (metres) may be a wall...
pub const WALL_MIN_STEP_M: f64 = 500.0;

/// ...when it is also steeper than this many metres per metre of sample spacing (87.1°): no
/// cliff keeps such a slope over a sample spacing where the step exceeds
/// [`WALL_MIN_STEP_M`].
pub const WALL_MIN_GRADIENT: f64 = 20.0;

/// A warning naming how many neighbouring pairs of non-void samples (row and column
/// neighbours) step by more than [`WALL_MIN_STEP_M`] at a gradient above
/// [`WALL_MIN_GRADIENT`], where the first lies, and the value most of the low sides share
/// (the likely missing-data marker); `None` when there is no such step.
pub fn implausible_walls(
    width: usize,
    height: usize,
    heights: &[f32],
    void: &[bool],
    georef: &GridGeoref,
) -> Option<String> {
    let mut count = 0u64;
    let mut first: Option<(usize, usize, usize, usize)> = None;
    let mut low_values: std::collections::BTreeMap<u32, u64> = Default::default();
    let mut check = |a: usize, b: usize, spacing: f64| {
        if void[a] || void[b] {
            return;
        }
        let (ha, hb) = (heights[a] as f64, heights[b] as f64);
        let step = (ha - hb).abs();
        if step > WALL_MIN_STEP_M && step / spacing > WALL_MIN_GRADIENT {
            count += 1;
            first.get_or_insert((a / width, a % width, b / width, b % width));
            let low = if ha < hb { heights[a] } else { heights[b] };
            *low_values.entry(low.to_bits()).or_default() += 1;
        }
    };
    for r in 0..height {
        for c in 0..width {
            let i = r * width + c;
            if c + 1 < width {
                check(i, i + 1, georef.spacing_x);
            }
            if r + 1 < height {
                check(i, i + width, georef.spacing_y);
            }
        }
    }
    let (r0, c0, r1, c1) = first?;
    let at = |r: usize, c: usize| heights[r * width + c];
    let mut msg = format!(
        "{count} pairs of neighbouring samples step by more than {WALL_MIN_STEP_M} m at over \
         {WALL_MIN_GRADIENT} m per metre (no terrain is that steep), e.g. {} m at row {r0}, \
         column {c0} beside {} m at row {r1}, column {c1}: missing data stored as heights?",
        at(r0, c0),
        at(r1, c1)
    );
    if let Some((bits, n)) = low_values.iter().max_by_key(|(_, n)| **n)
        && *n * 2 > count
    {
        let v = f32::from_bits(*bits);
        msg.push_str(&format!(
            " The lower side is {v} m in {n} of them: if {v} marks missing data pass --nodata {v}"
        ));
    }
    Some(msg)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Vec<f32> {
        (0..w * h).map(|i| f(i / w, i % w)).collect()
    }

    #[test]
    fn a_block_of_zeros_in_a_mountain_is_a_wall_and_a_cliff_is_not() {
        let g = GridGeoref::new(0.0, 0.0, 4.0);
        let (w, h) = (20, 10);
        // 2000-m mountain with a 3x3 block of 0 m cells
        let hs = grid(w, h, |r, c| {
            if (3..6).contains(&r) && (5..8).contains(&c) {
                0.0
            } else {
                2000.0 + r as f32
            }
        });
        let m = implausible_walls(w, h, &hs, &vec![false; w * h], &g).unwrap();
        assert!(m.contains("12 pairs") && m.contains("--nodata 0"), "{m}");
        // the same block marked void: nothing
        let void: Vec<bool> = (0..w * h)
            .map(|i| (3..6).contains(&(i / w)) && (5..8).contains(&(i % w)))
            .collect();
        assert_eq!(implausible_walls(w, h, &hs, &void, &g), None);
        // a 60-m cliff between neighbours at 4 m spacing (86°) is terrain
        let cliff = grid(w, h, |_, c| if c < 10 { 1000.0 } else { 1060.0 });
        assert_eq!(
            implausible_walls(w, h, &cliff, &vec![false; w * h], &g),
            None
        );
        // a 600-m step over 100-m samples (80°) too
        let coarse = GridGeoref::new(0.0, 0.0, 100.0);
        let step = grid(w, h, |_, c| if c < 10 { 1000.0 } else { 1600.0 });
        assert_eq!(
            implausible_walls(w, h, &step, &vec![false; w * h], &coarse),
            None
        );
    }
}
