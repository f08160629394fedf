//! Void filling: gives every no-data sample a height for geometry, deterministically.
//!
//! Rule (front propagation of neighbour means): let *known* be the valid samples. In each
//! pass, every void sample that has at least one known sample among its 8 neighbours gets
//! the arithmetic mean (computed in f64) of those known neighbours' heights, **all using
//! the heights known at the start of the pass**; then they all become known. Passes repeat
//! until no void is left. A hole is thus filled from its border inwards, one ring per
//! pass, and the result does not depend on visiting order or thread count. Filled heights
//! always lie within the range of the valid heights (each is a mean of known values).
//! The caller keeps `void[i] = true` for filled samples so textures can mark them unknown.
//!
//! Cost: each sample is visited O(1) times (only the current front is examined), so the
//! fill is linear in the number of samples.

/// Fills `heights[i]` for every `void[i]` as described in the module doc. Requires at
/// least one non-void sample (returns `false`, changing nothing, if there is none).
pub fn fill_voids(width: usize, height: usize, heights: &mut [f32], void: &[bool]) -> bool {
    let n = width * height;
    debug_assert!(heights.len() == n && void.len() == n);
    if !void.iter().any(|&v| !v) {
        return false;
    }
    let mut known: Vec<bool> = void.iter().map(|&v| !v).collect();
    // `queued[i]` is the pass number + 1 in which i was put on a front (0 = never).
    let mut queued = vec![0u32; n];
    let neighbours = |i: usize| {
        let (r, c) = ((i / width) as isize, (i % width) as isize);
        (-1isize..=1)
            .flat_map(move |dr| (-1isize..=1).map(move |dc| (r + dr, c + dc)))
            .filter(move |&(rr, cc)| {
                (rr, cc) != (r, c)
                    && rr >= 0
                    && cc >= 0
                    && (rr as usize) < height
                    && (cc as usize) < width
            })
            .map(move |(rr, cc)| rr as usize * width + cc as usize)
    };

    let mut front: Vec<usize> = (0..n)
        .filter(|&i| !known[i] && neighbours(i).any(|j| known[j]))
        .collect();
    for &i in &front {
        queued[i] = 1;
    }
    let mut pass = 1u32;
    let mut updates: Vec<(usize, f32)> = Vec::new();
    while !front.is_empty() {
        updates.clear();
        for &i in &front {
            let (mut sum, mut count) = (0.0f64, 0u32);
            for j in neighbours(i) {
                if known[j] {
                    sum += heights[j] as f64;
                    count += 1;
                }
            }
            // Every front sample has a known neighbour by construction.
            updates.push((i, (sum / count.max(1) as f64) as f32));
        }
        for &(i, h) in &updates {
            heights[i] = h;
            known[i] = true;
        }
        pass += 1;
        let mut next = Vec::new();
        for &(i, _) in &updates {
            for j in neighbours(i) {
                if !known[j] && queued[j] == 0 {
                    queued[j] = pass;
                    next.push(j);
                }
            }
        }
        next.sort_unstable();
        front = next;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fills_ring_by_ring_with_neighbour_means() {
        // 5x5, valid border of height 10 except one corner at 20, 3x3 hole in the middle.
        let (w, h) = (5, 5);
        let mut hs = vec![10.0f32; 25];
        hs[0] = 20.0;
        let mut void = vec![false; 25];
        for r in 1..4 {
            for c in 1..4 {
                void[r * w + c] = true;
                hs[r * w + c] = -1.0; // garbage that must be overwritten
            }
        }
        assert!(fill_voids(w, h, &mut hs, &void));
        // (1,1) has known neighbours (0,0),(0,1),(0,2),(1,0),(2,0): mean (20+10*4)/5 = 12
        assert_eq!(hs[w + 1], 12.0);
        // (1,2) has (0,1),(0,2),(0,3): 10
        assert_eq!(hs[w + 2], 10.0);
        // centre (2,2) is filled in pass 2 from its 8 ring neighbours (pass-1 values).
        let ring: Vec<f64> = [
            (1, 1),
            (1, 2),
            (1, 3),
            (2, 1),
            (2, 3),
            (3, 1),
            (3, 2),
            (3, 3),
        ]
        .iter()
        .map(|&(r, c)| hs[r * w + c] as f64)
        .collect();
        assert_eq!(hs[2 * w + 2], (ring.iter().sum::<f64>() / 8.0) as f32);
        assert!(hs.iter().all(|&x| (10.0..=20.0).contains(&x)));
    }

    #[test]
    fn large_hole_is_filled_and_deterministic() {
        let (w, h) = (60, 40);
        let base: Vec<f32> = (0..w * h)
            .map(|i| ((i % w) as f32 * 0.7 + (i / w) as f32 * 1.3).sin() * 50.0)
            .collect();
        let void: Vec<bool> = (0..w * h).map(|i| (i % w) > 3 || (i / w) > 30).collect();
        let mut a = base.clone();
        let mut b = base.clone();
        assert!(fill_voids(w, h, &mut a, &void));
        assert!(fill_voids(w, h, &mut b, &void));
        assert_eq!(a, b);
        let (lo, hi) = base
            .iter()
            .zip(&void)
            .filter(|(_, v)| !**v)
            .fold((f32::MAX, f32::MIN), |(l, u), (&x, _)| (l.min(x), u.max(x)));
        assert!(a.iter().all(|&x| x.is_finite() && x >= lo && x <= hi));
        // valid samples untouched
        assert!(
            a.iter()
                .zip(&base)
                .zip(&void)
                .all(|((x, y), v)| *v || x == y)
        );
    }

    #[test]
    fn all_void_is_refused() {
        let mut hs = vec![0.0f32; 4];
        assert!(!fill_voids(2, 2, &mut hs, &[true; 4]));
    }
}
