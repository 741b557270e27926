//! Interrupt requests. The program's Ctrl-C handler (or a binding's own signal check) calls
//! [`request`]; the results folder checks at every sample, frame and analysis start
//! ([`check`]), so a run stops within one output step, keeps what it wrote, and its summary
//! says `interrupted`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

static REQUESTED: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// The flag itself, for a signal handler that sets it (the program's `signal_hook::flag`).
pub fn flag() -> Arc<AtomicBool> {
    REQUESTED.get_or_init(|| Arc::new(AtomicBool::new(false))).clone()
}

/// The run was interrupted by the user.
#[derive(Debug, thiserror::Error)]
#[error("interrupted by the user (Ctrl-C); the results written so far are kept")]
pub struct Interrupted;

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
}

/// [`Interrupted`] when a stop was asked for.
pub fn check() -> Result<(), crate::error::BoxError> {
    if requested() {
        Err(Box::new(Interrupted))
    } else {
        Ok(())
    }
}
