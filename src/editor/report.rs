//! The energy report of the editor's material, computed off the UI thread (nothing slow runs on
//! the UI thread): the readouts of the tool panel and the curve of its albedo plot
//! ([`crate::brdf::energy::AlbedoCurve`]), one measurement. A stroke or slider edit asks for a new report and goes on at once; one worker
//! thread measures the newest material asked for (older requests still queued are skipped), and the
//! panel shows the newest finished report, marked as updating while it is not the current
//! material's. No window or GPU here: `on_done` (the editor passes a redraw request) is how the
//! window learns a report is ready.
//!
//! The worker and its thread pool run in the idle scheduling class ([`yield_to_rendering`]): on
//! lavapipe the GPU is these same CPU cores, and a report measured beside a frame at normal
//! priority takes half of them, which slows the interaction frames about as much
//! (docs/performance.md, The editor's frame). Idle, the report waits
//! for the frames: while strokes keep both cores busy it is marked as updating, and it finishes in the
//! first idle moment. On a machine whose GPU is not its CPU nothing changes.

use std::sync::mpsc::{channel, Receiver, Sender};
use std::thread::JoinHandle;

use crate::brdf::energy::Report;
use crate::brdf::Material;

/// Monte Carlo samples per view and reciprocity pairs of the editor's report (the paper model's
/// measured albedo; the reciprocal model's bound is exact and quadrature-based).
pub const SAMPLES: usize = 2_000;
pub const PAIRS: usize = 20_000;

pub struct ReportWorker {
    requests: Option<Sender<Material>>,
    done: Receiver<(Material, Report)>,
    thread: Option<JoinHandle<()>>,
    /// The newest finished report and the material it describes.
    latest: Option<(Material, Report)>,
    /// The material most recently asked for.
    asked: Option<Material>,
}

impl ReportWorker {
    /// Starts the worker; `on_done` runs on the worker thread after each report.
    pub fn new(on_done: impl Fn() + Send + 'static) -> ReportWorker {
        let (req_tx, req_rx) = channel::<Material>();
        let (done_tx, done) = channel();
        let thread = std::thread::Builder::new()
            .name("brdf-shop energy report".into())
            .spawn(move || {
                yield_to_rendering();
                // A pool of its own, so that its threads can yield too (the global pool is shared).
                let pool = rayon::ThreadPoolBuilder::new()
                    .thread_name(|i| format!("brdf-shop energy report {i}"))
                    .start_handler(|_| yield_to_rendering())
                    .build()
                    .ok();
                while let Ok(mut m) = req_rx.recv() {
                    // Only the newest request matters.
                    while let Ok(newer) = req_rx.try_recv() {
                        m = newer;
                    }
                    let measure = || Report::measure(&m, SAMPLES, PAIRS);
                    let report = match &pool {
                        Some(p) => p.install(measure),
                        None => measure(),
                    };
                    if done_tx.send((m, report)).is_err() {
                        return;
                    }
                    on_done();
                }
            })
            .ok();
        ReportWorker { requests: Some(req_tx), done, thread, latest: None, asked: None }
    }

    /// Asks for the report of `m` unless it is the one asked for last; returns at once.
    pub fn request(&mut self, m: &Material) {
        if self.asked.as_ref() == Some(m) {
            return;
        }
        self.asked = Some(m.clone());
        let sent = self.requests.as_ref().is_some_and(|tx| tx.send(m.clone()).is_ok());
        if !sent {
            // No worker thread (it could not be started): measure here rather than show nothing.
            self.latest = Some((m.clone(), Report::measure(m, SAMPLES, PAIRS)));
        }
    }

    /// The newest finished report, and whether it is `current`'s (false while an update is pending).
    pub fn latest(&mut self, current: &Material) -> Option<(&Report, bool)> {
        while let Ok(r) = self.done.try_recv() {
            self.latest = Some(r);
        }
        self.latest.as_ref().map(|(m, r)| (r, m == current))
    }
}

impl Drop for ReportWorker {
    fn drop(&mut self) {
        // Closing the request channel ends the worker after the report it is measuring; nobody
        // waits for that. The worker runs only on cores nothing else wants: when other programs keep
        // them busy, joining it would hold the editor's exit until they stop (a `--quit` session
        // beside two busy processes on 2 cores would wait minutes). The thread holds no GPU object and
        // writes nothing; it ends with its report, or with the process.
        self.requests = None;
        drop(self.thread.take());
    }
}

/// Moves the calling thread to the idle scheduling class (`SCHED_IDLE`: it runs only when no other
/// thread wants the core, and gives way at once when one does); where that is refused, to the
/// lowest nice value. Where both fail the thread keeps its priority: the report is then only slower
/// to leave room, never wrong.
fn yield_to_rendering() {
    #[cfg(target_os = "linux")]
    {
        let param = libc::sched_param { sched_priority: 0 };
        // SAFETY: sched_setscheduler, gettid and setpriority take plain integers and a pointer to a
        // live `sched_param`; pid 0 and the calling thread's own id change only this thread.
        unsafe {
            if libc::sched_setscheduler(0, libc::SCHED_IDLE, &param) != 0 {
                let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
                libc::setpriority(libc::PRIO_PROCESS, tid, 19);
            }
        }
    }
}
