//! An indexed max-heap of faces keyed by their worst error.
//!
//! Each face index is in the heap at most once and its key is updated in place when the
//! face is rescanned, so the heap never holds stale entries (edge flips reuse triangle
//! slots; every reused slot is rescanned). Ties break on the larger face index, so the
//! order is deterministic.

const ABSENT: u32 = u32::MAX;

/// Children per node: a node's four children are adjacent (64 bytes), half the depth of a
/// binary heap.
const ARITY: usize = 4;

/// 4-ary max-heap of `(key, face)` with O(log n) insert, update and removal by face index.
#[derive(Default)]
pub(crate) struct FaceHeap {
    heap: Vec<(f64, u32)>,
    pos: Vec<u32>,
}

impl FaceHeap {
    /// An empty heap with room for faces `0..n`.
    pub fn with_capacity(n: usize) -> FaceHeap {
        FaceHeap {
            heap: Vec::with_capacity(n / 2),
            pos: vec![ABSENT; n],
        }
    }

    #[inline]
    fn above(a: (f64, u32), b: (f64, u32)) -> bool {
        a.0 > b.0 || (a.0 == b.0 && a.1 > b.1)
    }

    /// Removes every entry.
    pub fn clear(&mut self) {
        for &(_, f) in &self.heap {
            self.pos[f as usize] = ABSENT;
        }
        self.heap.clear();
    }

    /// The face with the largest key, and that key.
    pub fn peek(&self) -> Option<(f64, u32)> {
        self.heap.first().copied()
    }

    /// Sets the key of `face` (inserting it if absent), or removes it for `None`.
    pub fn set(&mut self, face: u32, key: Option<f64>) {
        let f = face as usize;
        if f >= self.pos.len() {
            self.pos.resize((f + 1).max(self.pos.len() * 2), ABSENT);
        }
        let p = self.pos[f];
        match (p, key) {
            (ABSENT, None) => {}
            (ABSENT, Some(k)) => {
                self.heap.push((k, face));
                let i = self.heap.len() - 1;
                self.pos[f] = i as u32;
                self.sift_up(i);
            }
            (p, Some(k)) => {
                let old = self.heap[p as usize].0;
                self.heap[p as usize].0 = k;
                if k > old {
                    self.sift_up(p as usize)
                } else {
                    self.sift_down(p as usize)
                }
            }
            (p, None) => {
                let p = p as usize;
                self.pos[f] = ABSENT;
                let last = self.heap.pop().unwrap_or((0.0, face));
                if p < self.heap.len() {
                    self.heap[p] = last;
                    self.pos[last.1 as usize] = p as u32;
                    self.sift_up(p);
                    let q = self.pos[last.1 as usize] as usize;
                    self.sift_down(q);
                }
            }
        }
    }

    fn sift_up(&mut self, mut i: usize) {
        let e = self.heap[i];
        while i > 0 {
            let parent = (i - 1) / ARITY;
            if !Self::above(e, self.heap[parent]) {
                break;
            }
            self.heap[i] = self.heap[parent];
            self.pos[self.heap[i].1 as usize] = i as u32;
            i = parent;
        }
        self.heap[i] = e;
        self.pos[e.1 as usize] = i as u32;
    }

    fn sift_down(&mut self, mut i: usize) {
        let n = self.heap.len();
        let e = self.heap[i];
        loop {
            let first = ARITY * i + 1;
            if first >= n {
                break;
            }
            let mut c = first;
            for k in first + 1..(first + ARITY).min(n) {
                if Self::above(self.heap[k], self.heap[c]) {
                    c = k;
                }
            }
            if !Self::above(self.heap[c], e) {
                break;
            }
            self.heap[i] = self.heap[c];
            self.pos[self.heap[i].1 as usize] = i as u32;
            i = c;
        }
        self.heap[i] = e;
        self.pos[e.1 as usize] = i as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_a_sorted_model() {
        let mut h = FaceHeap::default();
        let mut model: Vec<Option<f64>> = vec![None; 200];
        let mut seed = 99u64;
        let mut rnd = |m: u64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) % m
        };
        for step in 0..20000 {
            let f = rnd(200) as usize;
            let key = if rnd(4) == 0 {
                None
            } else {
                Some(rnd(50) as f64)
            };
            h.set(f as u32, key);
            model[f] = key;
            let best = model
                .iter()
                .enumerate()
                .filter_map(|(i, k)| k.map(|k| (k, i as u32)))
                .max_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(h.peek(), best, "step {step}");
            if step % 5000 == 0 {
                h.clear();
                model.iter_mut().for_each(|k| *k = None);
            }
        }
    }
}
