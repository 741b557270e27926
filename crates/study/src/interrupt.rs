//! Interrupt requests. The program's signal handlers (Ctrl-C's SIGINT and the SIGTERM batch
//! schedulers and `kill` send) or a binding's own signal check call [`request`]; the results
//! folder checks at every sample, frame and analysis start ([`check`]), so a run stops within
//! one output step, keeps what it wrote, and its summary says `interrupted` with the signal.
//!
//! The handlers only set atomics ([`flag`], [`signal`], registered with `signal_hook`), which
//! is all a signal handler may safely do; everything else happens at the next check.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

static REQUESTED: OnceLock<Arc<AtomicBool>> = OnceLock::new();
static SIGNAL: OnceLock<Arc<AtomicUsize>> = OnceLock::new();

/// The flag itself, for a signal handler that sets it (the program's `signal_hook::flag`).
pub fn flag() -> Arc<AtomicBool> {
    REQUESTED.get_or_init(|| Arc::new(AtomicBool::new(false))).clone()
}

/// The number of the signal that asked for the stop (0: none, or a stop asked for by a
/// call of [`request`]), for a handler that stores it (`signal_hook::flag::register_usize`).
pub fn signal() -> Arc<AtomicUsize> {
    SIGNAL.get_or_init(|| Arc::new(AtomicUsize::new(0))).clone()
}

/// SIGINT's number (Ctrl-C) on the platforms `signal_hook` serves.
pub const SIGINT: usize = 2;
/// SIGTERM's number (a batch scheduler's stop, `kill`).
pub const SIGTERM: usize = 15;

/// The run was interrupted: by Ctrl-C, by SIGTERM, or by its caller.
#[derive(Debug, thiserror::Error)]
#[error("interrupted by {by}; the results written so far are kept")]
pub struct Interrupted {
    /// What asked for the stop: `the user (Ctrl-C)`, `SIGTERM (...)`, `the caller`.
    pub by: &'static str,
}

/// Asks the running study to stop at its next check.
pub fn request() {
    flag().store(true, Ordering::SeqCst);
}

/// Whether a stop was asked for.
pub fn requested() -> bool {
    flag().load(Ordering::SeqCst)
}

/// Clears a request (before a new run in the same process).
pub fn clear() {
    flag().store(false, Ordering::SeqCst);
    signal().store(0, Ordering::SeqCst);
}

/// [`Interrupted`] when a stop was asked for, naming the signal that asked.
pub fn check() -> Result<(), crate::error::BoxError> {
    if !requested() {
        return Ok(());
    }
    let by = match signal().load(Ordering::SeqCst) {
        SIGTERM => "SIGTERM (a batch scheduler's stop or `kill`)",
        SIGINT => "the user (Ctrl-C)",
        _ => "a request to stop",
    };
    Err(Box::new(Interrupted { by }))
}
