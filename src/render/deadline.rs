//! A wall-clock limit the renderers' long loops check, so `--max-seconds` holds inside a
//! level or a batch and not only between them, and a caller's stop flag (the experiment's
//! Ctrl-C) that ends them the same way.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

thread_local! {
    /// The stop flag of the render running on this thread ([`cancellable`]).
    static STOP: Cell<Option<&'static AtomicBool>> = const { Cell::new(None) };
}

/// When work must stop (None: never), and the flag that stops it early.
#[derive(Clone, Copy, Debug)]
pub struct Deadline {
    at: Option<Instant>,
    stop: Option<&'static AtomicBool>,
}

impl Deadline {
    /// `seconds` from now; an infinite or overlong limit never passes. Inside
    /// [`cancellable`], it also passes once that call's flag is set.
    pub fn after(seconds: f64) -> Deadline {
        Deadline {
            at: Duration::try_from_secs_f64(seconds.max(0.0))
                .ok()
                .and_then(|d| Instant::now().checked_add(d)),
            stop: STOP.with(Cell::get),
        }
    }

    pub fn never() -> Deadline {
        Deadline {
            at: None,
            stop: None,
        }
    }

    #[inline]
    pub fn passed(&self) -> bool {
        self.at.is_some_and(|t| Instant::now() >= t)
            || self.stop.is_some_and(|s| s.load(Ordering::Relaxed))
    }
}

/// Runs `work` with every [`Deadline::after`] made on this thread meanwhile also passing
/// once `stop` is set: a render stops at its next check as it does at its time limit, and
/// the caller, who set the flag, knows its result is cut short. The renderers take their
/// deadlines from their options' time limits deep inside; the flag reaches them here
/// without every options type carrying it. The flag is kept for the rest of the process
/// (one per call, a pointer's size), so a deadline copied into a worker thread can hold it
/// by reference.
pub fn cancellable<T>(stop: Option<&Arc<AtomicBool>>, work: impl FnOnce() -> T) -> T {
    let Some(stop) = stop else {
        return work();
    };
    let flag: &'static AtomicBool = Box::leak(Box::new(stop.clone()));
    let before = STOP.with(|s| s.replace(Some(flag)));
    let result = work();
    STOP.with(|s| s.set(before));
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_flag_passes_the_deadlines_made_inside_only() {
        let stop = Arc::new(AtomicBool::new(false));
        let (early, late) = cancellable(Some(&stop), || {
            let early = Deadline::after(3600.0);
            stop.store(true, Ordering::SeqCst);
            (early, Deadline::after(3600.0))
        });
        assert!(early.passed() && late.passed());
        assert!(!Deadline::after(3600.0).passed());
        assert!(Deadline::after(0.0).passed());
        assert!(!Deadline::never().passed());
    }
}
