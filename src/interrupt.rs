//! Interruption (Ctrl-C): one process-wide flag. [`install`] makes SIGINT set it; the long
//! loops (photon tracing batches, image rows) poll [`requested`] and stop early, and the render
//! pipeline then returns an error instead of writing anything, so an earlier output file is
//! left untouched. A second Ctrl-C while the first is being honoured exits at once (status
//! 130); even then no output is half-written, since every file is written atomically. Owns the
//! flag only; what stopping means is up to each caller.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();

/// Installs the Ctrl-C handler (once per process; later calls return the first call's result).
pub fn install() -> Result<(), String> {
    INSTALLED
        .get_or_init(|| {
            ctrlc::set_handler(|| {
                if REQUESTED.swap(true, Ordering::SeqCst) {
                    eprintln!("\ninterrupted twice; exiting now");
                    std::process::exit(130);
                }
                eprintln!("\ninterrupt: stopping (press Ctrl-C again to exit at once)");
            })
            .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))
        })
        .clone()
}

/// Whether an interruption was requested (and not [`reset`] since).
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// Requests an interruption, as Ctrl-C does (for tests and embedding programs).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Clears the flag, so a later run in the same process is not interrupted.
pub fn reset() {
    REQUESTED.store(false, Ordering::SeqCst);
}
