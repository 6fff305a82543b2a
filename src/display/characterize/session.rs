//! Showing and measuring the plan: each patch is shown, left to settle, measured, and its
//! reading appended to the durable log before the next one is shown. Resuming measures
//! only what the log lacks.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use metamer_drivers::{DriverError, Instrument, InstrumentInfo, Reading, Request};

use super::log::{LogError, LogHeader, LogReading, SessionLog, LOG_FILE};
use super::plan::{Plan, PlannedPatch};
use crate::rig::screen::{Screen, ScreenError};

/// A measurement could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum MeasureFailure {
    #[error(transparent)]
    Display(#[from] ScreenError),
    #[error(transparent)]
    Instrument(#[from] DriverError),
    #[error(transparent)]
    Log(#[from] LogError),
}

/// The session could not start or go on.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    #[error("creating the output directory {}: {source}", dir.display())]
    Dir {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Log(#[from] LogError),
    #[error("patch {} of {} ({}, RGB {:?}): {source}\n  {done} of {total} readings are safe in {}; fix the cause and run the same command with --resume", index + 1, total, label, rgb, log.display())]
    Measure {
        index: usize,
        label: String,
        rgb: [u8; 3],
        done: usize,
        total: usize,
        log: PathBuf,
        source: Box<MeasureFailure>,
    },
}

/// How to measure.
#[derive(Clone, Debug, Default)]
pub struct MeasureOptions {
    /// Wait between showing a patch and measuring it.
    pub settle: Duration,
    pub request: Request,
    /// Stop after this many new readings (an interruption on purpose, for tests and for
    /// splitting a long session).
    pub stop_after: Option<usize>,
    /// Set from elsewhere (a Ctrl-C handler) to stop before the next patch.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// Where measuring ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measured {
    /// Every planned reading is in the log.
    Complete,
    /// Stopped by [`MeasureOptions::stop_after`] with this many readings still missing.
    Stopped { missing: usize },
    /// Stopped by [`MeasureOptions::interrupt`] with this many readings still missing.
    Interrupted { missing: usize },
}

/// One reading as it arrives, for progress displays.
pub struct Progress<'a> {
    /// Readings in the log now, this one included.
    pub done: usize,
    pub total: usize,
    pub patch: &'a PlannedPatch,
    pub reading: &'a Reading,
}

/// A characterization session bound to its output directory and log.
pub struct Session {
    plan: Plan,
    log: SessionLog,
    readings: Vec<Option<LogReading>>,
    /// Readings found in the log when the session was resumed.
    pub recovered: usize,
    /// Bytes of a torn last line set aside on resuming (0 if none).
    pub torn_bytes: usize,
}

impl Session {
    /// Starts a session in `dir` (created if missing). With `resume`, an existing log
    /// there is continued; without it an existing log is an error and is left alone.
    pub fn open(
        dir: &Path,
        plan: Plan,
        display: &str,
        instrument: &str,
        instrument_info: InstrumentInfo,
        resume: bool,
    ) -> Result<Session, SessionError> {
        std::fs::create_dir_all(dir).map_err(|source| SessionError::Dir {
            dir: dir.to_path_buf(),
            source,
        })?;
        let header = LogHeader::new(&plan, display, instrument, instrument_info);
        let mut readings = vec![None; plan.patches.len()];
        let (log, recovered, torn_bytes) = if resume && dir.join(LOG_FILE).exists() {
            let (log, rec) = SessionLog::resume(dir, &plan, &header)?;
            let n = rec.readings.len();
            for r in rec.readings {
                let i = r.index;
                readings[i] = Some(r);
            }
            (log, n, rec.torn_bytes)
        } else {
            (SessionLog::create(dir, &header)?, 0, 0)
        };
        Ok(Session {
            plan,
            log,
            readings,
            recovered,
            torn_bytes,
        })
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    pub fn log_path(&self) -> &Path {
        self.log.path()
    }

    /// Readings in the log.
    pub fn done(&self) -> usize {
        self.readings.iter().filter(|r| r.is_some()).count()
    }

    /// Shows and measures every planned patch the log lacks, in plan order.
    pub fn measure(
        &mut self,
        display: &mut dyn Screen,
        instrument: &mut dyn Instrument,
        options: &MeasureOptions,
        progress: &mut dyn FnMut(Progress<'_>),
    ) -> Result<Measured, SessionError> {
        let total = self.plan.patches.len();
        let mut done = self.done();
        let mut new = 0;
        for patch in &self.plan.patches {
            if self.readings[patch.index].is_some() {
                continue;
            }
            if options
                .interrupt
                .as_ref()
                .is_some_and(|i| i.load(Ordering::SeqCst))
            {
                return Ok(Measured::Interrupted {
                    missing: total - done,
                });
            }
            if options.stop_after.is_some_and(|n| new >= n) {
                return Ok(Measured::Stopped {
                    missing: total - done,
                });
            }
            let log_path = self.log.path().to_path_buf();
            let fail = |source: MeasureFailure| SessionError::Measure {
                index: patch.index,
                label: patch.label.clone(),
                rgb: patch.rgb,
                done,
                total,
                log: log_path.clone(),
                source: Box::new(source),
            };
            display
                .show(patch.rgb)
                .map_err(|e| fail(MeasureFailure::from(e)))?;
            std::thread::sleep(options.settle);
            let reading = instrument
                .measure(&options.request)
                .map_err(|e| fail(MeasureFailure::from(e)))?;
            let entry = LogReading {
                index: patch.index,
                rgb: patch.rgb,
                label: patch.label.clone(),
                reading,
            };
            self.log
                .append(&entry)
                .map_err(|e| fail(MeasureFailure::from(e)))?;
            done += 1;
            new += 1;
            progress(Progress {
                done,
                total,
                patch,
                reading: &entry.reading,
            });
            self.readings[patch.index] = Some(entry);
        }
        Ok(Measured::Complete)
    }

    /// Every reading with its planned patch, in plan order; None until all are measured.
    pub fn complete_readings(&self) -> Option<Vec<(&PlannedPatch, &Reading)>> {
        self.plan
            .patches
            .iter()
            .zip(&self.readings)
            .map(|(p, r)| r.as_ref().map(|r| (p, &r.reading)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::characterize::plan::PlanOptions;
    use crate::rig::virtual_display::{Preset, VirtualDisplay};

    fn tempdir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("metamer-session-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn run(dir: &Path, resume: bool, stop_after: Option<usize>) -> (Measured, Session) {
        let plan = Plan::new(PlanOptions {
            ramp_steps: 3,
            repeats: 2,
            grid_steps: 0,
        })
        .unwrap();
        let mut display = VirtualDisplay::preset(Preset::IpsLcd);
        let mut meter = metamer_drivers::open_instrument(
            "sim:cs100a?time_scale=0&noise=off",
            display.stimulus(),
        )
        .unwrap();
        let mut session = Session::open(
            dir,
            plan,
            "virtual:ips-lcd",
            "sim:cs100a",
            meter.info(),
            resume,
        )
        .unwrap();
        let options = MeasureOptions {
            stop_after,
            ..MeasureOptions::default()
        };
        let mut seen = Vec::new();
        let outcome = session
            .measure(&mut display, meter.as_mut(), &options, &mut |p| {
                seen.push((p.done, p.patch.index))
            })
            .unwrap();
        // Progress counts up from what the log held, one per new reading.
        for (k, (done, _)) in seen.iter().enumerate() {
            assert_eq!(*done, session.recovered + k + 1);
        }
        (outcome, session)
    }

    #[test]
    fn an_interrupted_session_resumes_to_the_same_readings() {
        let whole = tempdir("whole");
        let (outcome, straight) = run(&whole, false, None);
        assert_eq!(outcome, Measured::Complete);
        let n = straight.plan().patches.len();
        assert_eq!(n, 2 * (5 + 4 + 48));

        let split = tempdir("split");
        let (outcome, first) = run(&split, false, Some(10));
        assert_eq!(outcome, Measured::Stopped { missing: n - 10 });
        assert!(first.complete_readings().is_none());
        drop(first);
        let (outcome, second) = run(&split, true, Some(40));
        assert_eq!(second.recovered, 10);
        assert_eq!(outcome, Measured::Stopped { missing: n - 50 });
        drop(second);
        let (outcome, third) = run(&split, true, None);
        assert_eq!((outcome, third.recovered), (Measured::Complete, 50));

        // Same patches in the same order; noise is off, so the same XYZ too.
        let a = straight.complete_readings().unwrap();
        let b = third.complete_readings().unwrap();
        for ((pa, ra), (pb, rb)) in a.iter().zip(&b) {
            assert_eq!(pa, pb);
            assert_eq!(ra.xyz, rb.xyz, "{}", pa.label);
        }
        // The log holds each planned patch exactly once.
        let text = std::fs::read_to_string(split.join(LOG_FILE)).unwrap();
        let mut indices: Vec<usize> = text
            .lines()
            .skip(1)
            .map(|l| {
                serde_json::from_str::<serde_json::Value>(l).unwrap()["index"]
                    .as_u64()
                    .unwrap() as usize
            })
            .collect();
        indices.sort_unstable();
        assert_eq!(indices, (0..n).collect::<Vec<_>>());
        // Resuming a complete log measures nothing.
        let (outcome, again) = run(&split, true, None);
        assert_eq!((outcome, again.recovered), (Measured::Complete, n));
        std::fs::remove_dir_all(&whole).unwrap();
        std::fs::remove_dir_all(&split).unwrap();
    }

    #[test]
    fn an_interrupt_stops_before_the_next_patch() {
        let dir = tempdir("interrupt");
        let plan = Plan::new(PlanOptions::default()).unwrap();
        let n = plan.patches.len();
        let mut display = VirtualDisplay::preset(Preset::IdealCrt);
        let mut meter =
            metamer_drivers::open_instrument("sim:cs100a?time_scale=0", display.stimulus())
                .unwrap();
        let mut session = Session::open(
            &dir,
            plan,
            "virtual:ideal-crt",
            "sim:cs100a",
            meter.info(),
            false,
        )
        .unwrap();
        let flag = Arc::new(AtomicBool::new(false));
        let options = MeasureOptions {
            interrupt: Some(flag.clone()),
            ..MeasureOptions::default()
        };
        let outcome = session
            .measure(&mut display, meter.as_mut(), &options, &mut |p| {
                if p.done == 5 {
                    flag.store(true, Ordering::SeqCst);
                }
            })
            .unwrap();
        assert_eq!(outcome, Measured::Interrupted { missing: n - 5 });
        assert_eq!(session.done(), 5);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failing_instrument_says_what_is_safe() {
        let dir = tempdir("fail");
        let plan = Plan::new(PlanOptions::default()).unwrap();
        let mut display = VirtualDisplay::preset(Preset::IdealCrt);
        // A replay of nothing: the driver cannot talk to it at all, so use a meter that
        // measures light far beyond its range instead: ER10 is an instrument error.
        let blinding = std::sync::Arc::new(metamer_drivers::SharedWorld::new([1e7; 3]));
        let mut meter =
            metamer_drivers::open_instrument("sim:cs100a?time_scale=0", Some(blinding)).unwrap();
        let mut session = Session::open(
            &dir,
            plan,
            "virtual:ideal-crt",
            "sim:cs100a",
            meter.info(),
            false,
        )
        .unwrap();
        let e = session
            .measure(
                &mut display,
                meter.as_mut(),
                &MeasureOptions::default(),
                &mut |_| {},
            )
            .unwrap_err();
        let text = e.to_string();
        assert!(
            text.starts_with("patch 1 of 86 (black, RGB [0, 0, 0]): "),
            "{text}"
        );
        assert!(
            text.contains("0 of 86 readings are safe in") && text.contains("--resume"),
            "{text}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
