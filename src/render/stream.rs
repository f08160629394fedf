//! Background loading of cells and the non-blocking draw policy.
//!
//! [`Streamer`] runs loader threads (std::thread + channels) that turn cell indices into
//! loaded data; the frame only polls it. [`resolve_draw_list`] replaces cells that are not
//! loaded yet by their nearest loaded ancestor, so a frame never waits for the disk.

use std::collections::{BTreeSet, HashSet};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use super::lod::CellIndex;
use crate::error::Result;
use crate::store::CellRecord;

/// Loads cells on background threads. Requests are served first come, first served; a cell
/// is never requested twice while pending.
pub struct Streamer<T: Send + 'static> {
    requests: Option<Sender<usize>>,
    results: Receiver<(usize, Result<T>)>,
    pending: HashSet<usize>,
    workers: Vec<JoinHandle<()>>,
}

impl<T: Send + 'static> Streamer<T> {
    /// Starts `threads` (at least 1) loader threads running `load(cell_index)`.
    pub fn new<F>(threads: usize, load: F) -> Streamer<T>
    where
        F: Fn(usize) -> Result<T> + Send + Sync + 'static,
    {
        let (req_tx, req_rx) = channel::<usize>();
        let (res_tx, res_rx) = channel();
        let req_rx = Arc::new(Mutex::new(req_rx));
        let load = Arc::new(load);
        let workers = (0..threads.max(1))
            .map(|_| {
                let (rx, tx, load) = (Arc::clone(&req_rx), res_tx.clone(), Arc::clone(&load));
                std::thread::spawn(move || {
                    loop {
                        let next = match rx.lock() {
                            Ok(guard) => guard.recv(),
                            Err(_) => return,
                        };
                        let Ok(i) = next else { return };
                        if tx.send((i, load(i))).is_err() {
                            return;
                        }
                    }
                })
            })
            .collect();
        Streamer {
            requests: Some(req_tx),
            results: res_rx,
            pending: HashSet::new(),
            workers,
        }
    }

    /// Asks for cell `i`; returns false if it is already pending.
    pub fn request(&mut self, i: usize) -> bool {
        if !self.pending.insert(i) {
            return false;
        }
        if let Some(tx) = &self.requests {
            let _ = tx.send(i);
        }
        true
    }

    /// True if `i` was requested and its result not yet returned by a poll.
    pub fn is_pending(&self, i: usize) -> bool {
        self.pending.contains(&i)
    }

    /// Number of pending requests.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Finished loads, without waiting.
    pub fn poll(&mut self) -> Vec<(usize, Result<T>)> {
        let out: Vec<_> = self.results.try_iter().collect();
        for (i, _) in &out {
            self.pending.remove(i);
        }
        out
    }

    /// Waits for the next finished load; `None` if nothing is pending.
    pub fn wait_one(&mut self) -> Option<(usize, Result<T>)> {
        if self.pending.is_empty() {
            return None;
        }
        let r = self.results.recv().ok()?;
        self.pending.remove(&r.0);
        Some(r)
    }
}

impl<T: Send + 'static> Drop for Streamer<T> {
    fn drop(&mut self) {
        self.requests = None;
        // Drain so that workers blocked on send can finish, then join them.
        while self.results.try_recv().is_ok() {}
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}

/// What a frame draws.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawList {
    /// Cells to draw (sorted ascending, loaded, no cell together with its ancestor).
    pub draw: Vec<usize>,
    /// Selected cells that are not loaded (to request), sorted ascending.
    pub missing: Vec<usize>,
    /// Selected cells drawn through a coarser loaded ancestor.
    pub substituted: usize,
    /// Selected cells with no loaded ancestor either (a hole this frame).
    pub holes: usize,
}

/// Resolves an LOD selection against what is loaded: loaded cells are drawn; a missing cell
/// is replaced by its nearest loaded ancestor (and loaded cells under a drawn ancestor are
/// dropped, so nothing is drawn twice).
pub fn resolve_draw_list(
    selected: &[usize],
    cells: &[CellRecord],
    index: &CellIndex,
    is_loaded: impl Fn(usize) -> bool,
) -> DrawList {
    let mut out = DrawList::default();
    let mut set = BTreeSet::new();
    for &i in selected {
        if is_loaded(i) {
            set.insert(i);
            continue;
        }
        out.missing.push(i);
        match index.ancestor_where(cells[i].key(), &is_loaded) {
            Some(a) => {
                out.substituted += 1;
                set.insert(a);
            }
            None => out.holes += 1,
        }
    }
    out.draw = set
        .iter()
        .copied()
        .filter(|&i| {
            index
                .ancestor_where(cells[i].key(), |a| set.contains(&a))
                .is_none()
        })
        .collect();
    out.missing.sort_unstable();
    out
}
