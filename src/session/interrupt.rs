//! Ctrl-C for a measuring session: the first SIGINT sets a flag the runner checks before
//! every step (what is measured is on disk already); a second one ends the process at once.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

static INTERRUPTED: OnceLock<Arc<AtomicBool>> = OnceLock::new();

extern "C" fn on_sigint(_: libc::c_int) {
    if let Some(flag) = INTERRUPTED.get() {
        flag.store(true, Ordering::SeqCst);
    }
    // SAFETY: signal() is async-signal-safe (POSIX.1-2008 §2.4.3); SIG_DFL is always valid.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

/// Installs the SIGINT handler and returns the flag it sets (shared by every caller in the
/// process; it is not cleared, since the process is meant to end after an interrupt).
pub fn on_ctrl_c() -> Arc<AtomicBool> {
    let flag = INTERRUPTED
        .get_or_init(|| Arc::new(AtomicBool::new(false)))
        .clone();
    // SAFETY: the handler only stores to an atomic and resets the disposition, both
    // async-signal-safe; the flag is initialised before the handler is installed.
    unsafe {
        libc::signal(
            libc::SIGINT,
            on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
    }
    flag
}
