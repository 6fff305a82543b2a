//! Where a session reports how far it is: a sink trait, a terminal progress bar for the
//! command line, and closures for callers that only count.

use std::io::IsTerminal;
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use metamer_drivers::spec::Spec;
use metamer_drivers::{MeasureMode, Reading};

use super::repeats::Deviation;

/// One step as it is done.
#[derive(Clone, Copy, Debug)]
pub struct StepProgress<'a> {
    /// Entries in the journal once this reading is kept, this one included.
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
    /// (k, n): reading k (1-based) of the n its placement is for; None for a step the
    /// operator does not set up (a colour shown on a screen).
    pub placement: Option<(usize, usize)>,
    /// How the reading differs from its placement's earlier ones, when by more than the
    /// instrument repeats.
    pub deviation: Option<&'a Deviation>,
}

/// Which part of a longer measurement a session is: stage `number` of `of`, `name`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StageOf {
    pub number: usize,
    pub of: usize,
    pub name: String,
}

/// Receives a session's progress.
pub trait ProgressSink {
    /// The run begins with `done` of `total` steps already in the journal.
    fn start(&mut self, done: usize, total: usize) {
        let _ = (done, total);
    }
    /// The session about to run is this stage of a longer measurement.
    fn stage(&mut self, stage: &StageOf) {
        let _ = stage;
    }
    /// A reading was taken: reported before it is journalled, so a reading the instrument
    /// did not repeat can be shown before the operator is asked about it.
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

/// A reading's luminance (four significant digits, as the meters send) with its unit, and
/// its chromaticity: `Y 101.2 cd/m² · xy 0.3127 0.3290`.
pub fn reading_summary(mode: MeasureMode, r: &Reading) -> String {
    let [x, y, lum] = r.xyy;
    let lum = if lum.is_finite() { lum } else { r.xyz[1] };
    let digits = if lum == 0.0 || !lum.is_finite() {
        0
    } else {
        (3 - lum.abs().log10().floor() as i32).clamp(0, 6) as usize
    };
    let unit = match mode {
        MeasureMode::Emissive => " cd/m²",
        MeasureMode::Ambient => " lx",
        MeasureMode::Reflective => " (white 100)",
    };
    let xy = if x.is_finite() && y.is_finite() {
        format!("{x:.4} {y:.4}")
    } else {
        "—".into()
    };
    format!("Y {lum:.digits$}{unit} · xy {xy}")
}

/// The line shown after a reading: `reading 3/5 · stage 1/4 · Y 101.2 cd/m² · xy 0.3127
/// 0.3290`, with what makes it doubtful appended; a step outside a placement is counted
/// among all the session's (`patch 12/44`, with `noun`).
pub fn reading_line(p: &StepProgress<'_>, stage: Option<&StageOf>, noun: &str) -> String {
    let mut line = match p.placement {
        Some((k, n)) => format!("reading {k}/{n}"),
        None => format!("{noun} {}/{}", p.done, p.total),
    };
    if let Some(s) = stage {
        line.push_str(&format!(" · stage {}/{} {}", s.number, s.of, s.name));
    }
    line.push_str(&format!(" · {}", reading_summary(p.mode, p.reading)));
    if let Some(d) = p.deviation {
        line.push_str(&format!(" · differs: {d}"));
    }
    line
}

/// How often a wait shows it is alive: a real i1Pro's dark calibration alone takes about
/// 20 s, and a line every few seconds tells a log reader the command has not hung.
pub const HEARTBEAT: Duration = Duration::from_secs(5);

/// While an instrument works on one slow request (a calibration, a reading), a line on
/// stderr every [`HEARTBEAT`] saying what it waits for and since when. Nothing is printed
/// for a wait shorter than that (a simulation at `time_scale=0` never prints). The line
/// stops when the value is dropped.
pub struct Heartbeat {
    stop: Option<mpsc::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl Heartbeat {
    /// Starts the lines for `what` ("the spectral instrument (i1pro) calibrates").
    pub fn start(what: String) -> Heartbeat {
        Heartbeat::every(what, HEARTBEAT)
    }

    pub fn every(what: String, period: Duration) -> Heartbeat {
        let (stop, stopped) = mpsc::channel::<()>();
        let start = Instant::now();
        let thread = std::thread::spawn(move || {
            while let Err(mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(period) {
                crate::output::console::reported_at_exit(crate::output::console::err_fmt(
                    format_args!("  … {what}: {} s so far", start.elapsed().as_secs()),
                ));
            }
        });
        Heartbeat {
            stop: Some(stop),
            thread: Some(thread),
        }
    }
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The first thing a command with simulated instruments should say when they keep a real
/// instrument's pace (their default): that the wait is on purpose, and how to skip it.
/// None when every simulation among `specs` answers at once.
pub fn pace_note(specs: &[&Spec]) -> Option<String> {
    let paced: Vec<(String, f64)> = specs
        .iter()
        .filter_map(|s| Some((s.as_str().to_string(), s.sim_time_scale()?)))
        .filter(|(_, scale)| *scale > 0.0)
        .collect();
    let (_, scale) = paced.first()?;
    let names: Vec<&str> = paced.iter().map(|(n, _)| n.as_str()).collect();
    let same = paced.iter().all(|(_, s)| s == scale);
    let pace = if same && *scale == 1.0 {
        "at their real pace, as long as real ones take".to_string()
    } else if same {
        format!("at {scale} times their real pace")
    } else {
        let scales: Vec<String> = paced.iter().map(|(_, s)| format!("{s}")).collect();
        format!("at {} times their real pace", scales.join(", "))
    };
    Some(format!(
        "the simulated instruments ({}) run {pace}; `?time_scale=0` in a spec (or \
         METAMER_SIM_TIME_SCALE=0) makes them answer at once",
        names.join(", ")
    ))
}

/// A progress bar on stderr, for the command line; notes are printed above it. Attended,
/// every reading of a placement also gets a line of its own above the bar, so the
/// operator sees each value (the bar is cleared whenever a request waits for them).
pub struct BarProgress {
    bar: indicatif::ProgressBar,
    /// What a step is called in the bar (`patch`, `reading`).
    noun: &'static str,
    stage: Option<StageOf>,
    lines: bool,
    /// Where stderr is no terminal (a log, a pipe), the bar is not drawn: a line then says
    /// how far the session is, at most once per [`HEARTBEAT`]; when the last one was.
    logged: Option<Instant>,
}

impl BarProgress {
    pub fn new(noun: &'static str) -> BarProgress {
        BarProgress {
            bar: indicatif::ProgressBar::hidden(),
            noun,
            stage: None,
            lines: false,
            logged: None,
        }
    }

    /// A line per reading of a placement: somebody is at the rig, watching.
    pub fn attended(mut self, attended: bool) -> BarProgress {
        self.lines = attended;
        self
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
        if std::io::stderr().is_terminal() {
            // Elapsed time and the estimate move while an instrument works.
            self.bar.enable_steady_tick(Duration::from_secs(1));
        } else {
            self.logged = Some(Instant::now());
        }
    }

    fn stage(&mut self, stage: &StageOf) {
        self.stage = Some(stage.clone());
    }

    fn step(&mut self, p: &StepProgress<'_>) {
        let line = reading_line(p, self.stage.as_ref(), self.noun);
        if (self.lines && p.placement.is_some()) || p.deviation.is_some() {
            self.note(&format!("  {line}"));
        }
        self.bar.set_message(format!(
            "{} → {}",
            p.label,
            reading_summary(p.mode, p.reading)
        ));
        self.bar.set_position(p.done as u64);
        if self
            .logged
            .is_some_and(|t| t.elapsed() >= HEARTBEAT || p.done == p.total)
        {
            crate::output::console::reported_at_exit(crate::output::console::err_fmt(
                format_args!(
                    "{line} · {} s elapsed, about {} s left",
                    p.elapsed.as_secs(),
                    p.remaining.as_secs()
                ),
            ));
            self.logged = Some(Instant::now());
        }
    }

    fn note(&mut self, text: &str) {
        if self.bar.is_hidden() {
            // A note cannot fail the reading it comes with; a failed write is remembered
            // and the command reports it when it ends.
            crate::output::console::reported_at_exit(crate::output::console::err_fmt(
                format_args!("{text}"),
            ));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reading_line_says_where_the_session_is_and_what_was_read() {
        let r = Reading::from_yxy(101.234, 0.31271, 0.32902, "cs100a");
        let mut p = StepProgress {
            done: 13,
            total: 125,
            index: 12,
            label: "tile 0,2 #3",
            mode: MeasureMode::Emissive,
            reading: &r,
            elapsed: Duration::ZERO,
            remaining: Duration::ZERO,
            placement: Some((3, 5)),
            deviation: None,
        };
        let stage = StageOf {
            number: 1,
            of: 4,
            name: "tiles".into(),
        };
        assert_eq!(
            reading_line(&p, Some(&stage), "reading"),
            "reading 3/5 · stage 1/4 tiles · Y 101.2 cd/m² · xy 0.3127 0.3290"
        );
        p.placement = None;
        p.mode = MeasureMode::Reflective;
        assert_eq!(
            reading_line(&p, None, "patch"),
            "patch 13/125 · Y 101.2 (white 100) · xy 0.3127 0.3290"
        );
        let dark = Reading::from_yxy(0.0123, f64::NAN, f64::NAN, "cs100a");
        assert_eq!(
            reading_summary(MeasureMode::Emissive, &dark),
            "Y 0.01230 cd/m² · xy —"
        );
    }

    #[test]
    fn a_paced_simulation_is_named_and_an_instant_or_real_one_is_not() {
        let instant = Spec::new("sim:cs100a?time_scale=0");
        let real = Spec::new("cs100a:/dev/ttyUSB0");
        let paced = Spec::new("sim:i1pro?time_scale=1");
        let slow = Spec::new("sim:cs100a?time_scale=2");
        assert_eq!(pace_note(&[&instant, &real]), None);
        assert_eq!(
            pace_note(&[&paced, &instant]).as_deref(),
            Some(
                "the simulated instruments (sim:i1pro?time_scale=1) run at their real pace, as \
                 long as real ones take; `?time_scale=0` in a spec (or METAMER_SIM_TIME_SCALE=0) \
                 makes them answer at once"
            )
        );
        assert!(pace_note(&[&paced, &slow])
            .unwrap()
            .contains("(sim:i1pro?time_scale=1, sim:cs100a?time_scale=2) run at 1, 2 times"));
    }
}
