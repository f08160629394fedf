//! Progress bars on the terminal: the CLI's [`Progress`] (hidden with `--quiet` or
//! when stderr is not a terminal).

use std::sync::Arc;

use cliffmap::progress::{Progress, ProgressSink, ProgressTask};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

/// Bars drawn together on stderr, one per task.
struct Bars {
    multi: MultiProgress,
}

struct Bar(ProgressBar);

impl ProgressTask for Bar {
    fn inc(&self, n: u64) {
        self.0.inc(n);
    }

    fn finish(&self) {
        self.0.finish_and_clear();
    }
}

impl Progress for Bars {
    fn task(&self, len: u64, title: &str) -> Box<dyn ProgressTask> {
        let pb = ProgressBar::new(len);
        if let Ok(style) =
            ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
        {
            pb.set_style(style.progress_chars("=> "));
        }
        pb.set_message(title.to_string());
        Box::new(Bar(self.multi.add(pb)))
    }
}

/// Where a command reports progress: terminal bars, or nowhere when `quiet`.
pub(crate) fn progress_sink(quiet: bool) -> ProgressSink {
    if quiet {
        ProgressSink::none()
    } else {
        ProgressSink::new(Arc::new(Bars {
            multi: MultiProgress::new(),
        }))
    }
}
