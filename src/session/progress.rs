//! Where a session reports how far it is: a sink trait, a terminal progress bar for the
//! command line, and closures for callers that only count.

use std::time::Duration;

use metamer_drivers::{MeasureMode, Reading};

/// One step as it is done.
#[derive(Clone, Copy, Debug)]
pub struct StepProgress<'a> {
    /// Entries in the journal now, this one included.
    pub done: usize,
    pub total: usize,
    /// The step's plan index.
    pub index: usize,
    pub label: &'a str,
    pub mode: MeasureMode,
    pub reading: &'a Reading,
    /// Since this run (not the first run of a resumed session) started.
    pub elapsed: Duration,
    /// The steps still to take at the mean pace of this run's steps so far.
    pub remaining: Duration,
}

/// Receives a session's progress.
pub trait ProgressSink {
    /// The run begins with `done` of `total` steps already in the journal.
    fn start(&mut self, done: usize, total: usize) {
        let _ = (done, total);
    }
    fn step(&mut self, progress: &StepProgress<'_>);
    /// Something the operator should read (resuming, a calibration done).
    fn note(&mut self, text: &str) {
        let _ = text;
    }
    /// Runs `ask` (a question to the operator) with the progress display out of its way.
    fn suspend(&mut self, ask: &mut dyn FnMut()) {
        ask()
    }
    /// The run ended, for whatever reason.
    fn finish(&mut self) {}
}

/// Reports nothing.
#[derive(Debug, Default)]
pub struct NoProgress;

impl ProgressSink for NoProgress {
    fn step(&mut self, _: &StepProgress<'_>) {}
}

impl<F: FnMut(&StepProgress<'_>)> ProgressSink for F {
    fn step(&mut self, progress: &StepProgress<'_>) {
        self(progress)
    }
}

/// A progress bar on stderr, for the command line; notes are printed above it.
pub struct BarProgress {
    bar: indicatif::ProgressBar,
    /// What a step is called in the bar (`patch`, `step`).
    noun: &'static str,
}

impl BarProgress {
    pub fn new(noun: &'static str) -> BarProgress {
        BarProgress {
            bar: indicatif::ProgressBar::hidden(),
            noun,
        }
    }
}

impl ProgressSink for BarProgress {
    fn start(&mut self, done: usize, total: usize) {
        self.bar = indicatif::ProgressBar::new(total as u64);
        let template = format!(
            "{{bar:30}} {} {{pos}}/{{len}} · {{msg}} · {{elapsed}} elapsed, about {{eta}} left",
            self.noun
        );
        if let Ok(style) = indicatif::ProgressStyle::with_template(&template) {
            self.bar.set_style(style);
        }
        self.bar.set_position(done as u64);
        self.bar.reset_eta();
    }

    fn step(&mut self, p: &StepProgress<'_>) {
        self.bar
            .set_message(format!("{} → Y {:.3}", p.label, p.reading.xyz[1]));
        self.bar.set_position(p.done as u64);
    }

    fn note(&mut self, text: &str) {
        if self.bar.is_hidden() {
            eprintln!("{text}");
        } else {
            self.bar.println(text);
        }
    }

    fn suspend(&mut self, ask: &mut dyn FnMut()) {
        self.bar.suspend(ask)
    }

    fn finish(&mut self) {
        self.bar.finish_and_clear();
    }
}
