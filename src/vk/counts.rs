//! How many pipeline barriers and dispatches the program has recorded: every barrier goes through
//! `vk::barrier`, every dispatch counts itself, and a frame reports the difference across its
//! recording (`Frame::barriers`, `--timings`, `bench --json`).

use std::sync::atomic::{AtomicU64, Ordering};

#[derive(Debug, Default)]
pub struct CommandCounts {
    barriers: AtomicU64,
    dispatches: AtomicU64,
}

/// The counts at one moment, or their difference over a span of recording.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counted {
    pub barriers: u64,
    pub dispatches: u64,
}

impl CommandCounts {
    pub fn barrier(&self) {
        self.barriers.fetch_add(1, Ordering::Relaxed);
    }

    pub fn dispatch(&self) {
        self.dispatches.fetch_add(1, Ordering::Relaxed);
    }

    pub fn now(&self) -> Counted {
        Counted { barriers: self.barriers.load(Ordering::Relaxed), dispatches: self.dispatches.load(Ordering::Relaxed) }
    }
}

impl Counted {
    /// What was recorded between `earlier` and `self`.
    pub fn since(self, earlier: Counted) -> Counted {
        Counted {
            barriers: self.barriers.saturating_sub(earlier.barriers),
            dispatches: self.dispatches.saturating_sub(earlier.dispatches),
        }
    }
}
