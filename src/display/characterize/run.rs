//! One characterization from start to finish on the session engine: the plan's drive
//! colours as session steps, shown and measured with every reading journalled, then the
//! fit, verification and files ([`super::finish`]). The command line and the simulated lab
//! both come through [`run`].

use std::path::{Path, PathBuf};
use std::time::Duration;

use metamer_drivers::{Instrument, Spec};
use serde::{Deserialize, Serialize};

use super::finish::{files, finish, FinishError, MeasuredBy, Summary};
use super::plan::{DriveStep, Plan, PlanError, PlanOptions, METER};
use crate::display::ModelKind;
use crate::output::{OutputError, OutputPolicy};
use crate::rig::Screen;
use crate::session::budget::{srgb_assumption, srgb_luminance, SRGB_WHITE_CD_M2};
use crate::session::plan::{Prepare, Step};
use crate::session::{
    Cost, CostReport, InstrumentRecord, Meter, Operator, OperatorError, ProgressSink, Rig, RunEnd,
    RunOptions, Session, SessionError,
};

/// The journal's file name inside the output directory.
pub const LOG_FILE: &str = "log.jsonl";

/// What the journal's header says about a characterization besides its plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LogDetails {
    /// The display as named on the command line (`virtual:ips-lcd`, `window:0`).
    pub display: String,
    pub display_description: String,
    /// The instrument as named on the command line (`sim:cs100a?time_scale=0`).
    pub instrument: String,
}

/// What to characterize and how.
#[derive(Clone, Debug)]
pub struct Options {
    /// Output directory: the journal, profile, `.ti3`, report and summary.
    pub dir: PathBuf,
    pub plan: PlanOptions,
    pub model: ModelKind,
    /// The instrument as named by the user, for the files' provenance.
    pub instrument: Spec,
    /// Wait between showing a colour and measuring it; None: the display's default.
    pub settle: Option<Duration>,
    /// Continue the journal in `dir` instead of refusing it.
    pub resume: bool,
    /// Replace a profile, `.ti3`, report or summary already in `dir`. Without it they are
    /// replaced only when the journal being resumed holds readings (they are its own).
    pub force: bool,
    pub run: RunOptions,
}

/// Where a characterization ended.
#[derive(Debug)]
pub enum Outcome {
    /// Measured, fitted and verified; every file written.
    Finished(Box<Summary>),
    /// Not every reading is taken yet; the journal holds the others.
    Incomplete {
        end: RunEnd,
        done: usize,
        total: usize,
        log: PathBuf,
    },
}

impl Outcome {
    /// Whether the session was interrupted (Ctrl-C, a signal): a failure to the caller,
    /// though every reading taken is safe.
    pub fn is_interrupted(&self) -> bool {
        matches!(self, Outcome::Incomplete { end, .. } if end.is_interrupted())
    }
}

/// A characterization failed.
#[derive(Debug, thiserror::Error)]
pub enum CharacterizeError {
    #[error(transparent)]
    Plan(#[from] PlanError),
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error(transparent)]
    Finish(#[from] FinishError),
    #[error(transparent)]
    Operator(#[from] OperatorError),
    #[error("showing white to aim the instrument: {0}")]
    Aim(#[source] crate::rig::ScreenError),
    #[error("{0}")]
    Output(#[from] OutputError),
    /// A physical meter with nobody at the rig ([`super::Attend::Terminal`]).
    #[error(transparent)]
    NobodyAtTheRig(#[from] crate::session::NobodyAtTheRig),
    #[error(transparent)]
    OpenScreen(crate::rig::OpenError),
    /// The meter could not be opened (its spec, its port, its transcript).
    #[error(transparent)]
    Instrument(metamer_drivers::DriverError),
    /// The meter refused the requested response speed.
    #[error(transparent)]
    Speed(metamer_drivers::DriverError),
    #[error(transparent)]
    SimulatedMeterOnRealScreen(super::meter::SimulatedMeterOnRealScreen),
    /// An adaptive plan's rule or targets make no plan.
    #[error(transparent)]
    Adaptive(#[from] super::adaptive::rule::AdaptiveError),
}

/// The journal of a characterization in `dir`.
pub fn log_path(dir: &Path) -> PathBuf {
    dir.join(LOG_FILE)
}

/// Characterizes `display` with `instrument`: measures what the journal in
/// `options.dir` lacks (all of it for a new session), then fits, verifies and writes the
/// profile, `.ti3`, report and summary. On a real screen the operator is first asked to aim
/// the instrument at white.
pub fn run(
    options: &Options,
    display: &mut dyn Screen,
    instrument: &mut dyn Instrument,
    operator: &mut dyn Operator,
    progress: &mut dyn ProgressSink,
) -> Result<Outcome, CharacterizeError> {
    let plan = Plan::new(options.plan)?;
    let settle = options.settle.unwrap_or_else(|| display.default_settle());
    let display_name = display.spec();
    let details = LogDetails {
        display: display_name.clone(),
        display_description: display.describe(),
        instrument: options.instrument.to_string(),
    };
    let instruments = [(METER.to_string(), InstrumentRecord::of(instrument))].into();
    let mut session: Session<LogDetails, DriveStep> = Session::open(
        &log_path(&options.dir),
        plan.session_plan(&display_name, settle),
        details.clone(),
        instruments,
        options.resume,
    )?;
    let total = session.plan().steps.len();
    if let Some(aside) = &session.set_aside {
        progress.note(&format!(
            "{} held no session; it was set aside as {} and a new session started",
            session.journal_path().display(),
            aside.display()
        ));
    }
    let mut out = OutputPolicy::new(options.force || session.recovered > 0);
    out.input(session.journal_path());
    // Before anything is measured: a profile that may not be replaced is found now.
    for f in files(&options.dir, session.journal_path()).outputs() {
        out.check(f)?;
    }
    if let Some(note) = resuming_note(&session) {
        progress.note(&note);
    }
    let incomplete = |session: &Session<LogDetails, DriveStep>, end| Outcome::Incomplete {
        end,
        done: session.done(),
        total,
        log: session.journal_path().to_path_buf(),
    };
    // A real screen: the operator aims the instrument at its white once, before the first
    // patch; that is the session's one placement.
    let aim = session.done() < total && display.stimulus().is_none();
    let mut cost = CostReport {
        estimate: estimate(&session, display, &*instrument, options, aim),
        actual: None,
    };
    if session.done() < total {
        progress.note(&cost.estimate.before("the display's patches"));
    }
    let Some(aimed) = aim_at_white(aim, display, operator)? else {
        let missing = total - session.done();
        return Ok(incomplete(&session, RunEnd::Aborted { missing }));
    };
    let end = {
        let mut rig = Rig {
            screen: Some(display),
            instruments: vec![(METER.to_string(), &mut *instrument)],
            operator: &mut *operator,
        };
        session.run(&mut rig, &options.run, progress)?
    };
    let mut spent = session.spent().clone();
    spent.add(&aimed);
    progress.note(&spent.after("the display's patches", &cost.estimate));
    cost.actual = Some(spent);
    if end != RunEnd::Complete {
        return Ok(incomplete(&session, end));
    }
    let Some(entries) = session.complete_entries() else {
        let missing = total - session.done();
        return Ok(incomplete(&session, RunEnd::Stopped { missing }));
    };
    let readings: Vec<_> = entries.iter().map(|e| (&e.data, &e.reading)).collect();
    let info = &instrument.info();
    let summary = finish(
        &options.dir,
        session.journal_path(),
        &readings,
        options.model,
        &MeasuredBy {
            display: &details.display,
            display_description: &details.display_description,
            instrument: &details.instrument,
            instrument_info: info,
            cost: &cost,
        },
        &out,
        None,
    )?;
    Ok(Outcome::Finished(Box::new(summary)))
}

/// Has the operator aim the instrument at the white of a real screen (`aim`): the
/// placement and the time it took (nothing without `aim`), or None when the operator
/// declined.
fn aim_at_white(
    aim: bool,
    display: &mut dyn Screen,
    operator: &mut dyn Operator,
) -> Result<Option<Cost>, CharacterizeError> {
    if !aim {
        return Ok(Some(Cost::default()));
    }
    display.show([255; 3]).map_err(CharacterizeError::Aim)?;
    let prompt = format!(
        "aim the instrument at the middle of the white {}",
        display.describe()
    );
    Ok(Cost::ask_placement(operator, &prompt)?)
}

/// The budget of the patches the journal of `session` lacks: each patch's luminance as the
/// screen knows it (a simulated monitor), else as an sRGB display of the standard's 80 cd/m²
/// white would give it; with the operator's aim at the white of a real screen (`aim`).
pub(crate) fn estimate(
    session: &Session<LogDetails, DriveStep>,
    display: &dyn Screen,
    instrument: &dyn Instrument,
    options: &Options,
    aim: bool,
) -> Cost {
    let placement_s = options.run.placement_s();
    let meters = [(METER.to_string(), Meter::of(instrument))].into();
    let known = display.expected_cd_m2([255; 3]).is_some();
    let rgb = |step: &Step<DriveStep>| match step.prepare {
        Prepare::Show { rgb } => rgb,
        _ => step.data.rgb,
    };
    let light = |step: &Step<DriveStep>| {
        let rgb = rgb(step);
        display
            .expected_cd_m2(rgb)
            .unwrap_or_else(|| srgb_luminance(rgb, SRGB_WHITE_CD_M2))
    };
    let assumption = if known {
        format!(
            "a patch's luminance as the simulated {} shows it",
            display.spec()
        )
    } else {
        srgb_assumption(SRGB_WHITE_CD_M2)
    };
    let mut cost = session.estimate(&meters, &light, &assumption, placement_s);
    if aim {
        cost.placements += 1;
        cost.operator_s += placement_s;
        cost.wall_s += placement_s;
    }
    cost
}

/// What resuming `session` found in its journal (readings, a torn last line set aside),
/// if it resumed one.
pub(super) fn resuming_note(session: &Session<LogDetails, DriveStep>) -> Option<String> {
    if session.recovered == 0 && session.torn_bytes == 0 {
        return None;
    }
    let torn = if session.torn_bytes > 0 {
        format!(
            " ({} bytes of a reading cut off by the interruption were set aside in {})",
            session.torn_bytes,
            crate::session::torn_path(session.journal_path()).display()
        )
    } else {
        String::new()
    };
    Some(format!(
        "resuming: {} of {} readings in {}{torn}",
        session.recovered,
        session.plan().steps.len(),
        session.journal_path().display()
    ))
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    use super::*;
    use crate::rig::{Preset, VirtualDisplay};
    use crate::session::{NoProgress, ScriptedOperator, StepProgress};

    fn options(tag: &str, resume: bool, run: RunOptions) -> Options {
        let dir =
            std::env::temp_dir().join(format!("metamer-charrun-{tag}-{}", std::process::id()));
        if !resume {
            let _ = std::fs::remove_dir_all(&dir);
        }
        Options {
            dir,
            plan: PlanOptions {
                ramp_steps: 3,
                repeats: 2,
                grid_steps: 0,
            },
            model: ModelKind::Plcc,
            instrument: "sim:cs100a".into(),
            settle: None,
            resume,
            force: false,
            run,
        }
    }

    fn characterize(o: &Options, progress: &mut dyn ProgressSink) -> Outcome {
        let mut display = VirtualDisplay::preset(Preset::IdealCrt);
        let mut meter = metamer_drivers::open_instrument(
            "sim:cs100a?time_scale=0&noise=off",
            display.stimulus(),
        )
        .unwrap();
        run(
            o,
            &mut display,
            meter.as_mut(),
            &mut ScriptedOperator::confirming(),
            progress,
        )
        .unwrap()
    }

    #[test]
    fn a_split_session_finishes_with_the_straight_one_s_numbers() {
        let straight = options("straight", false, RunOptions::default());
        let Outcome::Finished(a) = characterize(&straight, &mut NoProgress) else {
            panic!("a straight run finishes")
        };
        let stop = |n| RunOptions {
            stop_after: Some(n),
            ..RunOptions::default()
        };
        let first = options("split", false, stop(10));
        let n = 2 * (5 + 4 + 48);
        match characterize(&first, &mut NoProgress) {
            Outcome::Incomplete {
                end, done, total, ..
            } => assert_eq!(
                (end, done, total),
                (RunEnd::Stopped { missing: n - 10 }, 10, n)
            ),
            Outcome::Finished(_) => panic!("stopped after 10"),
        }
        let Outcome::Finished(b) = characterize(
            &options("split", true, RunOptions::default()),
            &mut NoProgress,
        ) else {
            panic!("the resumed run finishes")
        };
        // Noise is off: the same readings, so the same fit and verification.
        assert_eq!(a.readings, b.readings);
        assert_eq!(a.verification.de00.mean, b.verification.de00.mean);
        assert_eq!(a.verification.de00.max, b.verification.de00.max);
        std::fs::remove_dir_all(&straight.dir).unwrap();
        std::fs::remove_dir_all(&first.dir).unwrap();
    }

    /// Each reading's XYZ by plan index, from the journal in `dir`.
    fn logged_xyz(dir: &Path) -> Vec<(u64, Vec<f64>)> {
        let text = std::fs::read_to_string(log_path(dir)).unwrap();
        let mut v: Vec<(u64, Vec<f64>)> = text
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
            .filter(|l| l["type"] == "entry")
            .map(|l| {
                let xyz = l["reading"]["xyz"].as_array().unwrap();
                (
                    l["index"].as_u64().unwrap(),
                    xyz.iter().map(|c| c.as_f64().unwrap()).collect(),
                )
            })
            .collect();
        v.sort_by_key(|e| e.0);
        v
    }

    /// With the meter's noise on, a session interrupted and resumed in a new "process" (a
    /// fresh simulated meter) reads exactly the numbers of an uninterrupted one: the noise
    /// of reading k depends on the seed and k only.
    #[test]
    fn a_resumed_noisy_session_reads_the_uninterrupted_numbers() {
        let noisy = |o: &Options| {
            let mut display = VirtualDisplay::preset(Preset::IdealCrt);
            let mut meter = metamer_drivers::open_instrument(
                "sim:cs100a?time_scale=0&seed=7",
                display.stimulus(),
            )
            .unwrap();
            run(
                o,
                &mut display,
                meter.as_mut(),
                &mut ScriptedOperator::confirming(),
                &mut NoProgress,
            )
            .unwrap()
        };
        let straight = options("noisy-straight", false, RunOptions::default());
        assert!(matches!(noisy(&straight), Outcome::Finished(_)));
        let split = options(
            "noisy-split",
            false,
            RunOptions {
                stop_after: Some(37),
                ..RunOptions::default()
            },
        );
        assert!(matches!(
            noisy(&split),
            Outcome::Incomplete { done: 37, .. }
        ));
        let resumed = options("noisy-split", true, RunOptions::default());
        assert!(matches!(noisy(&resumed), Outcome::Finished(_)));
        let (a, b) = (logged_xyz(&straight.dir), logged_xyz(&split.dir));
        assert_eq!(a.len(), 114);
        assert_eq!(a, b);
        // The noise is there: the two readings of white (passes 1 and 2) differ.
        let white: Vec<&Vec<f64>> = {
            let plan = Plan::new(split.plan).unwrap();
            plan.patches
                .iter()
                .filter(|p| p.rgb == [255; 3])
                .map(|p| &a[p.index].1)
                .collect()
        };
        assert!(white.len() >= 2 && white[0] != white[1], "{white:?}");
        std::fs::remove_dir_all(&straight.dir).unwrap();
        std::fs::remove_dir_all(&split.dir).unwrap();
    }

    #[test]
    fn an_interrupt_stops_before_the_next_colour() {
        let flag = Arc::new(AtomicBool::new(false));
        let o = options(
            "interrupt",
            false,
            RunOptions {
                interrupt: Some(flag.clone()),
                ..RunOptions::default()
            },
        );
        let mut sink = |p: &StepProgress<'_>| {
            if p.done == 5 {
                flag.store(true, Ordering::SeqCst);
            }
        };
        match characterize(&o, &mut sink) {
            Outcome::Incomplete { end, done, .. } => {
                assert_eq!((end, done), (RunEnd::Interrupted { missing: 114 - 5 }, 5))
            }
            Outcome::Finished(_) => panic!("interrupted"),
        }
        std::fs::remove_dir_all(&o.dir).unwrap();
    }

    #[test]
    fn a_failing_instrument_says_what_is_safe() {
        let o = options("fail", false, RunOptions::default());
        let mut display = VirtualDisplay::preset(Preset::IdealCrt);
        // Light far beyond the meter's range: the CS-100A answers ER10, an instrument error.
        let blinding = Arc::new(metamer_drivers::SharedWorld::new([1e7; 3]));
        let mut meter =
            metamer_drivers::open_instrument("sim:cs100a?time_scale=0", Some(blinding)).unwrap();
        let e = run(
            &o,
            &mut display,
            meter.as_mut(),
            &mut ScriptedOperator::confirming(),
            &mut NoProgress,
        )
        .unwrap_err();
        let text = e.to_string();
        assert!(
            text.starts_with("step 1 of 114 (black, RGB [0, 0, 0]): "),
            "{text}"
        );
        assert!(
            text.contains("0 of 114 steps are safe in") && text.contains("resume the session"),
            "{text}"
        );
        std::fs::remove_dir_all(&o.dir).unwrap();
    }
}
