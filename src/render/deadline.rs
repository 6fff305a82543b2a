//! A wall-clock limit the renderers' long loops check, so `--max-seconds` holds inside a
//! level or a batch and not only between them.

use std::time::{Duration, Instant};

/// When work must stop (None: never).
#[derive(Clone, Copy, Debug)]
pub struct Deadline(Option<Instant>);

impl Deadline {
    /// `seconds` from now; an infinite or overlong limit never passes.
    pub fn after(seconds: f64) -> Deadline {
        Deadline(
            Duration::try_from_secs_f64(seconds.max(0.0))
                .ok()
                .and_then(|d| Instant::now().checked_add(d)),
        )
    }

    pub fn never() -> Deadline {
        Deadline(None)
    }

    #[inline]
    pub fn passed(&self) -> bool {
        self.0.is_some_and(|t| Instant::now() >= t)
    }
}
