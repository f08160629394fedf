//! Progress of long steps, reported through a callback the caller supplies.
//!
//! Library stages take a [`ProgressSink`] in their options (default: none, nothing
//! reported) and open one [`ProgressTask`] per long step (`cells`, `reparam`, one per photo
//! of a projection, …), which they advance from any thread. The command-line interface
//! implements [`Progress`] with terminal bars; a library user may implement it for a log, a
//! GUI or nothing at all. Progress never changes what a stage computes.

use std::sync::Arc;

/// Something that shows progress: opens a task of `len` steps titled `title`.
pub trait Progress: Send + Sync {
    /// A task of `len` steps titled `title` begins.
    fn task(&self, len: u64, title: &str) -> Box<dyn ProgressTask>;
}

/// One running task of a [`Progress`]; advanced from any thread.
pub trait ProgressTask: Send + Sync {
    /// `n` more steps are done.
    fn inc(&self, n: u64);
    /// The task is over (a bar is cleared).
    fn finish(&self) {}
}

/// Where a stage reports progress: a shared [`Progress`], or nowhere (the default).
/// Compares equal to every other sink, so options that hold one keep their equality.
#[derive(Clone, Default)]
pub struct ProgressSink(Option<Arc<dyn Progress>>);

/// A task that shows nothing.
struct Silent;

impl ProgressTask for Silent {
    fn inc(&self, _n: u64) {}
}

impl ProgressSink {
    /// Reports to `progress`.
    pub fn new(progress: Arc<dyn Progress>) -> ProgressSink {
        ProgressSink(Some(progress))
    }

    /// Reports nowhere.
    pub fn none() -> ProgressSink {
        ProgressSink(None)
    }

    /// A task of `len` steps titled `title` (one that shows nothing when the sink is none).
    pub fn task(&self, len: u64, title: &str) -> Box<dyn ProgressTask> {
        match &self.0 {
            Some(p) => p.task(len, title),
            None => Box::new(Silent),
        }
    }
}

impl std::fmt::Debug for ProgressSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.is_some() {
            "ProgressSink(some)"
        } else {
            "ProgressSink(none)"
        })
    }
}

impl PartialEq for ProgressSink {
    fn eq(&self, _other: &ProgressSink) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    struct Count(Arc<AtomicU64>);
    impl Progress for Count {
        fn task(&self, _len: u64, _title: &str) -> Box<dyn ProgressTask> {
            Box::new(CountTask(self.0.clone()))
        }
    }
    struct CountTask(Arc<AtomicU64>);
    impl ProgressTask for CountTask {
        fn inc(&self, n: u64) {
            self.0.fetch_add(n, Ordering::Relaxed);
        }
    }

    #[test]
    fn a_sink_forwards_steps_and_none_drops_them() {
        let n = Arc::new(AtomicU64::new(0));
        let sink = ProgressSink::new(Arc::new(Count(n.clone())));
        let t = sink.task(3, "x");
        t.inc(2);
        t.inc(1);
        t.finish();
        assert_eq!(n.load(Ordering::Relaxed), 3);
        ProgressSink::none().task(3, "x").inc(5);
        assert_eq!(n.load(Ordering::Relaxed), 3);
        assert_eq!(sink, ProgressSink::none());
    }
}
