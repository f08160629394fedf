//! A least-recently-used cache with a byte budget (GPU memory of loaded cells).

use std::collections::HashMap;

/// Entries keyed by cell index, each with a size in bytes and the frame it was last used in.
/// Inserting evicts least-recently-used entries (ties: lowest key first) until the budget
/// holds, but never an entry used in the current frame; if those alone exceed the budget the
/// cache goes over budget rather than drop something being drawn.
#[derive(Debug)]
pub struct LruCache<V> {
    entries: HashMap<usize, Entry<V>>,
    budget: u64,
    used: u64,
    frame: u64,
}

#[derive(Debug)]
struct Entry<V> {
    value: V,
    bytes: u64,
    last_used: u64,
}

impl<V> LruCache<V> {
    /// An empty cache holding at most `budget_bytes` (except as described on the type).
    pub fn new(budget_bytes: u64) -> LruCache<V> {
        LruCache {
            entries: HashMap::new(),
            budget: budget_bytes,
            used: 0,
            frame: 0,
        }
    }

    /// Starts a new frame: entries used from now on are protected from eviction until the next call.
    pub fn begin_frame(&mut self) {
        self.frame += 1;
    }

    /// The value for `key`, marking it used in the current frame.
    pub fn get(&mut self, key: usize) -> Option<&V> {
        let frame = self.frame;
        self.entries.get_mut(&key).map(|e| {
            e.last_used = frame;
            &e.value
        })
    }

    /// The value for `key` without changing its recency.
    pub fn peek(&self, key: usize) -> Option<&V> {
        self.entries.get(&key).map(|e| &e.value)
    }

    /// True if `key` is cached.
    pub fn contains(&self, key: usize) -> bool {
        self.entries.contains_key(&key)
    }

    /// Inserts (or replaces) `key` as used in the current frame and returns the evicted
    /// entries in eviction order (least recently used first).
    pub fn insert(&mut self, key: usize, value: V, bytes: u64) -> Vec<(usize, V)> {
        if let Some(old) = self.entries.remove(&key) {
            self.used -= old.bytes;
        }
        let mut evicted = Vec::new();
        while self.used + bytes > self.budget {
            let victim = self
                .entries
                .iter()
                .filter(|(_, e)| e.last_used < self.frame)
                .min_by_key(|(k, e)| (e.last_used, **k))
                .map(|(k, _)| *k);
            let Some(k) = victim else { break };
            if let Some(e) = self.entries.remove(&k) {
                self.used -= e.bytes;
                evicted.push((k, e.value));
            }
        }
        self.used += bytes;
        self.entries.insert(
            key,
            Entry {
                value,
                bytes,
                last_used: self.frame,
            },
        );
        evicted
    }

    /// Bytes currently held.
    pub fn used_bytes(&self) -> u64 {
        self.used
    }

    /// The byte budget.
    pub fn budget_bytes(&self) -> u64 {
        self.budget
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True if empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}
