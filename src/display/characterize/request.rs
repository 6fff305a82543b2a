//! A whole characterization as one call: what `metamer characterize` and the experiment's
//! display stage ask for ([`Request`]), from the plan's check to the finished profile
//! ([`characterize`]). Where the two callers differ, the difference is a field of the
//! request ([`Request::attend`], [`Request::simulated_meter`], [`Request::virtual_white_cd_m2`])
//! so that it is visible in one place rather than in two copies of the same steps.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use metamer_drivers::{Instrument, Spec, Speed, World};

use super::adaptive::rule::Adaptive;
use super::adaptive::run::first_pass;
use super::finish::files;
use super::hands::{Hands, HandsOperator};
use super::meter::meter_sees;
use super::plan::{plan_advice, Plan, PlanOptions};
use super::run::{log_path, run, CharacterizeError, Options, Outcome};
use crate::display::ModelKind;
use crate::output::OutputPolicy;
use crate::rig::{OpenError, Screen, ScreenSpec, VirtualDisplay, VirtualPanel};
use crate::session::{
    attendance, refuse_existing, Attendance, Operator, ProgressSink, RunOptions, ScriptedOperator,
    SessionError, TerminalOperator,
};

/// Who answers the session's requests (aim the meter, calibrate it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Attend {
    /// `metamer characterize`: the person at the terminal. With no terminal nobody answers,
    /// and a physical instrument is refused before anything is opened unless `unattended`
    /// (nobody could aim it, and it would measure wherever it points).
    Terminal { unattended: bool },
    /// The experiment's display stage: nobody when `unattended` or the screen is simulated
    /// (a simulated meter sees a simulated monitor without being aimed); otherwise the
    /// terminal, without the refusal (the experiment's preflight checks its rig).
    Stage { unattended: bool },
}

/// What happens when a simulated meter is put in front of a real screen, where it cannot
/// see what the screen shows and reads its own fixed light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimulatedMeter {
    /// `metamer characterize`: measure anyway and say so (a dry run of a real window).
    Warn,
    /// The experiment's display stage: refused before the meter is opened, since its
    /// readings would flow into the validation as if they were the screen's.
    Refuse,
}

/// One characterization: the screen, the meter, the plan and what to do on the way.
#[derive(Clone, Debug)]
pub struct Request {
    /// Output directory: the journal, profile, `.ti3`, report and summary.
    pub out: PathBuf,
    pub screen: ScreenSpec,
    /// A simulated monitor's full-white luminance (cd/m²): the experiment sets it so that
    /// the rendering fits without tone mapping. None: the preset's own. A real screen is
    /// measured as it is.
    pub virtual_white_cd_m2: Option<f64>,
    /// The meter, as the user named it (its text goes into the files' provenance).
    pub instrument: Spec,
    /// The meter's response speed, for instruments that have one; None: its default.
    pub speed: Option<Speed>,
    pub plan: PlanOptions,
    /// None: the fixed plan of `plan`. Some: the adaptive plan ([`super::adaptive`]), whose
    /// first pass takes `plan`'s ramps and repeats.
    pub adaptive: Option<Adaptive>,
    pub model: ModelKind,
    /// Wait between showing a colour and measuring it; None: the screen's default.
    pub settle: Option<Duration>,
    /// Continue the journal in `out` instead of refusing it.
    pub resume: bool,
    /// Replace a profile, `.ti3`, report or summary already in `out`.
    pub force: bool,
    pub attend: Attend,
    pub simulated_meter: SimulatedMeter,
    pub run: RunOptions,
}

/// What a characterization tells its caller on the way, besides its session's progress.
pub trait Listener {
    /// Advice on the plan (e.g. too few patches for the model).
    fn note(&mut self, text: &str);
    /// Something the user should know before trusting the readings (the screen's own
    /// warnings, a simulated meter on a real screen).
    fn warning(&mut self, text: &str);
    /// Where the session reports its progress; `attended`: somebody is at the rig.
    fn progress(&mut self, attended: bool) -> &mut dyn ProgressSink;
}

/// Characterizes `request.screen` with `request.instrument` into `request.out`: checks the plan
/// and what is already in `out` before anything is opened, opens the screen and the
/// meter, measures what the journal lacks, then fits, verifies and writes the profile,
/// `.ti3`, report and summary.
///
/// # Examples
///
/// A simulated monitor measured by a simulated CS-100A that takes no time per reading:
///
/// ```
/// use metamer::display::characterize::{
///     characterize, Attend, Listener, Outcome, PlanOptions, Request, SimulatedMeter,
/// };
/// use metamer::display::ModelKind;
/// use metamer::rig::ScreenSpec;
/// use metamer::session::{NoProgress, ProgressSink, RunOptions};
///
/// struct Quiet(NoProgress);
/// impl Listener for Quiet {
///     fn note(&mut self, _: &str) {}
///     fn warning(&mut self, _: &str) {}
///     fn progress(&mut self, _: bool) -> &mut dyn ProgressSink {
///         &mut self.0
///     }
/// }
///
/// let out = std::env::temp_dir().join(format!("metamer-doc-characterize-{}", std::process::id()));
/// # let _ = std::fs::remove_dir_all(&out);
/// let request = Request {
///     out: out.clone(),
///     screen: ScreenSpec::parse("virtual:ideal-crt")?,
///     virtual_white_cd_m2: None,
///     instrument: "sim:cs100a?time_scale=0".into(),
///     speed: None,
///     plan: PlanOptions { ramp_steps: 3, repeats: 1, grid_steps: 0 },
///     adaptive: None,
///     model: ModelKind::Plcc,
///     settle: None,
///     resume: false,
///     force: false,
///     attend: Attend::Terminal { unattended: true },
///     simulated_meter: SimulatedMeter::Warn,
///     run: RunOptions::default(),
/// };
/// let Outcome::Finished(summary) = characterize(&request, &mut Quiet(NoProgress))? else {
///     panic!("nothing stops a simulated session");
/// };
/// assert!(summary.files.profile.is_file());
/// assert!(summary.verification.de00.mean < 1.0, "ΔE00 {}", summary.verification.de00.mean);
/// # std::fs::remove_dir_all(&out)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn characterize(
    request: &Request,
    listener: &mut dyn Listener,
) -> Result<Outcome, CharacterizeError> {
    let out = request.out.as_path();
    let plan = Plan::new(request.plan)?;
    if let Some(adaptive) = &request.adaptive {
        adaptive.check(first_pass(request.plan)?.len())?;
    }
    let attended = match request.attend {
        Attend::Terminal { unattended } => {
            attendance(&[&request.instrument], unattended)? == Attendance::Terminal
        }
        Attend::Stage { unattended } => {
            !unattended && !matches!(request.screen, ScreenSpec::Virtual(_))
        }
    };
    if !request.resume {
        // Before a full-screen window or an instrument is opened for nothing.
        refuse_existing(&log_path(out)).map_err(SessionError::Journal)?;
        // Files another session left in the directory (a new directory has none).
        if out.is_dir() {
            let policy = OutputPolicy::new(request.force);
            for f in files(out, &log_path(out)).outputs() {
                policy.check(f)?;
            }
        }
    }
    if let Some(pace) = crate::session::pace_note(&[&request.instrument]) {
        listener.note(&pace);
    }
    // After every refusal: a note on what the plan can judge is no answer to a command
    // that will not run.
    if let Some(advice) = plan_advice(&plan).filter(|_| request.adaptive.is_none()) {
        listener.note(&advice);
    }
    let mut display = open_screen(&request.screen, request.virtual_white_cd_m2)
        .map_err(CharacterizeError::OpenScreen)?;
    for warning in display.warnings() {
        listener.warning(&warning);
    }
    // A simulated monitor's meter is moved onto its tile for calibrations and back.
    let hands = display.stimulus().map(Hands::new);
    let seen = hands.clone().map(|h| h as Arc<dyn World>);
    let mut instrument = open_meter(request, seen, listener)?;
    let options = Options {
        dir: out.to_path_buf(),
        plan: request.plan,
        model: request.model,
        instrument: request.instrument.clone(),
        settle: request.settle,
        resume: request.resume,
        force: request.force,
        run: request.run.clone(),
    };
    let mut operator: Box<dyn Operator> = match (request.attend, attended) {
        (Attend::Terminal { .. }, true) => Attendance::Terminal.operator(),
        (Attend::Terminal { .. }, false) => Attendance::Unattended.operator(),
        (Attend::Stage { .. }, true) => Box::new(TerminalOperator),
        (Attend::Stage { .. }, false) => Box::new(ScriptedOperator::confirming()),
    };
    let mut moved;
    let operator: &mut dyn Operator = match hands {
        Some(hands) => {
            moved = HandsOperator {
                hands,
                inner: operator.as_mut(),
            };
            &mut moved
        }
        None => operator.as_mut(),
    };
    match &request.adaptive {
        Some(adaptive) => super::adaptive::run(
            &options,
            adaptive,
            display.as_mut(),
            instrument.as_mut(),
            operator,
            listener.progress(attended),
        ),
        None => run(
            &options,
            display.as_mut(),
            instrument.as_mut(),
            operator,
            listener.progress(attended),
        ),
    }
}

/// The screen `spec` names; a simulated monitor set to `virtual_white_cd_m2` when given.
pub fn open_screen(
    spec: &ScreenSpec,
    virtual_white_cd_m2: Option<f64>,
) -> Result<Box<dyn Screen>, OpenError> {
    Ok(match (spec, virtual_white_cd_m2) {
        (ScreenSpec::Virtual(p), Some(w)) => Box::new(VirtualDisplay::new(
            VirtualPanel::preset(*p).with_white_luminance(w),
        )),
        _ => spec.open()?,
    })
}

/// The request's meter, aimed at `display` (a simulated meter sees `seen`), at the
/// requested speed.
fn open_meter(
    request: &Request,
    seen: Option<Arc<dyn World>>,
    listener: &mut dyn Listener,
) -> Result<Box<dyn Instrument>, CharacterizeError> {
    let blind = match meter_sees(&request.instrument, &request.screen) {
        Err(e) if request.simulated_meter == SimulatedMeter::Refuse => {
            return Err(CharacterizeError::SimulatedMeterOnRealScreen(e))
        }
        seen => seen.is_err(),
    };
    let mut instrument = request
        .instrument
        .open(seen)
        .map_err(CharacterizeError::Instrument)?;
    if blind {
        listener.warning(
            "a simulated instrument cannot see a real screen; it measures its own fixed light",
        );
    }
    if let Some(speed) = request.speed {
        instrument
            .set_option("speed", speed.name())
            .map_err(CharacterizeError::Speed)?;
    }
    Ok(instrument)
}
