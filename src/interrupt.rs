//! Ctrl-C for long work (`check`, `reference`, the reports): [`install`] makes SIGINT and SIGTERM
//! set a flag that the long loops poll ([`requested`]) and end cleanly on — nothing half-written,
//! exit status [`EXIT_STATUS`] with one line. A second signal ends the program at once (the handler
//! restores the default action after the first).
//!
//! Owns the process's signal handlers and nothing else; imports nothing of the GPU.

use std::sync::atomic::{AtomicBool, Ordering};

/// The exit status of a command ended by Ctrl-C: 128 + SIGINT, what a shell reports for a program
/// the signal killed.
pub const EXIT_STATUS: u8 = 130;

static REQUESTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(sig: libc::c_int) {
    REQUESTED.store(true, Ordering::SeqCst);
    // SAFETY: `signal` is async-signal-safe (POSIX); restoring the default lets a second Ctrl-C end
    // the program at once.
    unsafe { libc::signal(sig, libc::SIG_DFL) };
}

/// Installs the handlers (SIGINT, SIGTERM). Only commands whose long loops poll [`requested`]
/// install them (`check`, `reference`); every other command keeps the default action, so Ctrl-C
/// still ends it at once (its outputs are written atomically, so nothing half-written is left).
pub fn install() {
    for sig in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: `on_signal` only stores to an atomic and calls `signal`, both async-signal-safe;
        // the `sigaction` struct is fully initialised (zeroed, then the handler and flags set).
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(sig, &action, std::ptr::null_mut());
        }
    }
}

/// Whether Ctrl-C (or SIGTERM) was received since the start.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// The error a command returns when it stopped on Ctrl-C: the binary maps it to [`EXIT_STATUS`].
#[derive(Debug, thiserror::Error)]
#[error("interrupted (Ctrl-C): stopped before writing anything")]
pub struct Interrupted;
