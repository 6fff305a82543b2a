//! Spot readings with the calibration negotiated through an [`Operator`]: before each
//! reading the instrument is asked what calibration is due, the operator is asked to set
//! it up (the instrument's own words), and a reading refused because a calibration expired
//! meanwhile is negotiated again and repeated. For a simulated instrument the simulated
//! world plays the operator's hands: confirming "place the instrument on its white tile"
//! puts it on the tile, and after the calibration it goes back to the target.
//!
//! [`run`] is `metamer spot`'s whole job as one call: the instrument opened and set up,
//! the readings made, the spectra written.

use std::path::PathBuf;
use std::sync::Arc;

use metamer_color::{colorchecker, ColorCheckerSet};
use metamer_drivers::i1pro::emulator::default_light;
use metamer_drivers::{
    CalibrationCondition, CalibrationOutcome, DriverError, Instrument, InstrumentInfo, MeasureMode,
    OpenOptions, Reading, Request, SharedWorld, Spec, Speed, View, World,
};

use crate::output::{OutputError, OutputPolicy};
use crate::session::{attendance, Answer, Heartbeat, NobodyAtTheRig, Operator, OperatorError};

/// A spot reading that could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error(transparent)]
    Driver(#[from] DriverError),
    #[error(transparent)]
    Operator(#[from] OperatorError),
    /// The operator declined to set up a calibration.
    #[error("stopped: the operator declined to {0}")]
    Declined(String),
    /// The instrument kept asking for calibrations (a driver that never answers Done).
    #[error("the {instrument} still asks for a calibration after {rounds} rounds; giving up")]
    Endless { instrument: String, rounds: usize },
}

/// Where a simulated instrument is: the world it sees and the target it is aimed at or
/// placed on between calibrations.
#[derive(Clone)]
pub struct SimulatedHands {
    pub world: Arc<SharedWorld>,
    pub target: View,
}

impl SimulatedHands {
    fn place(&self, condition: &CalibrationCondition) {
        self.world.set(match condition {
            CalibrationCondition::OnWhiteTile => View::WhiteTile,
            CalibrationCondition::SensorCapped => View::Capped,
            _ => self.target.clone(),
        });
    }

    fn back(&self) {
        self.world.set(self.target.clone());
    }
}

/// At most this many calibration rounds before one reading.
const MAX_ROUNDS: usize = 8;

/// Negotiates every calibration `mode` needs now: each condition is shown to `operator`,
/// then the instrument calibrates.
pub fn calibrate(
    instrument: &mut dyn Instrument,
    mode: MeasureMode,
    operator: &mut dyn Operator,
    hands: Option<&SimulatedHands>,
) -> Result<(), ReadError> {
    let mut next = instrument.calibration_needed(mode)?;
    let mut rounds = 0;
    while let Some(condition) = next {
        rounds += 1;
        if rounds > MAX_ROUNDS {
            return Err(ReadError::Endless {
                instrument: instrument.info().model,
                rounds: MAX_ROUNDS,
            });
        }
        let prompt = format!("{}: {}", instrument.info().model, condition.prompt());
        if operator.ask(&prompt)? == Answer::Abort {
            return Err(ReadError::Declined(condition.prompt()));
        }
        if let Some(h) = hands {
            h.place(&condition);
        }
        let beat = Heartbeat::start(format!(
            "the {} calibrates for {mode} readings",
            instrument.info().model
        ));
        let outcome = instrument.calibrate(mode, &condition);
        drop(beat);
        if let Some(h) = hands {
            h.back();
        }
        next = match outcome? {
            CalibrationOutcome::Done => instrument.calibration_needed(mode)?,
            CalibrationOutcome::Needs(c) => Some(c),
        };
    }
    Ok(())
}

/// One reading in `mode`, calibrating first where needed and again when a calibration
/// expires before the reading.
pub fn read(
    instrument: &mut dyn Instrument,
    mode: MeasureMode,
    operator: &mut dyn Operator,
    hands: Option<&SimulatedHands>,
) -> Result<Reading, ReadError> {
    let request = Request { mode };
    for _ in 0..MAX_ROUNDS {
        calibrate(instrument, mode, operator, hands)?;
        let beat = Heartbeat::start(format!("the {} measures", instrument.info().model));
        let measured = instrument.measure(&request);
        drop(beat);
        match measured {
            Err(DriverError::NeedsCalibration { .. }) => continue,
            r => return Ok(r?),
        }
    }
    Err(ReadError::Endless {
        instrument: instrument.info().model,
        rounds: MAX_ROUNDS,
    })
}

/// The spectra of several readings as the colour core's spectral CSV: a `#` line saying what
/// they are, `nm` and one column per reading (`reading1`, …), one row per wavelength.
/// Values are written in Rust's shortest round-trip form, so reading the file back gives
/// the very numbers the instrument reported. None when no reading has a spectrum or their
/// wavelengths differ.
pub fn spectra_csv(readings: &[Reading]) -> Option<String> {
    let spectra: Vec<_> = readings
        .iter()
        .map(|r| r.spectrum.as_ref())
        .collect::<Option<_>>()?;
    let first = spectra.first()?;
    if spectra
        .iter()
        .any(|s| s.wavelengths_nm() != first.wavelengths_nm())
    {
        return None;
    }
    let unit = first.quantity().map(|q| q.unit()).unwrap_or("unknown unit");
    let mut out = format!(
        "# {} readings of the {}, {unit}\nnm",
        readings.len(),
        readings[0].instrument
    );
    for i in 1..=readings.len() {
        out.push_str(&format!(",reading{i}"));
    }
    out.push('\n');
    for (k, nm) in first.wavelengths_nm().iter().enumerate() {
        out.push_str(&nm.to_string());
        for s in &spectra {
            out.push_str(&format!(",{}", s.values()[k]));
        }
        out.push('\n');
    }
    Some(out)
}

/// What `metamer spot` is asked to do.
#[derive(Clone, Debug)]
pub struct SpotRequest {
    /// The instrument's spec (`cs100a:PORT`, `i1pro`, `replay:FILE`, `sim:…`).
    pub instrument: Spec,
    pub mode: MeasureMode,
    /// Response speed, for instruments that have one; `None` keeps the instrument's.
    pub speed: Option<Speed>,
    /// Integration time in seconds or `auto`, for instruments that have one.
    pub integration: Option<String>,
    /// Number of readings, at least 1.
    pub count: u32,
    /// Write the readings' spectra to this CSV (see [`spectra_csv`]).
    pub spectrum: Option<PathBuf>,
    /// Replace the spectrum file if it exists.
    pub force: bool,
    /// Record the exchange with the instrument to this new transcript.
    pub record: Option<PathBuf>,
    /// Nobody is at the instrument: calibrate and read without asking.
    pub unattended: bool,
}

/// Why [`run`] did not finish.
#[derive(Debug, thiserror::Error)]
pub enum SpotRunError {
    /// The request itself is wrong (from here to [`SpotRunError::BadIntegration`]): the
    /// command line calls it a usage error.
    #[error("the count of readings must be at least 1")]
    Count,
    #[error("{}: exists; a recording is never overwritten, choose another file name", .0.display())]
    RecordingExists(PathBuf),
    /// The instrument spec names no instrument that can be opened this way.
    #[error(transparent)]
    Spec(DriverError),
    /// A spectrum was asked of an instrument that measures none (a colorimeter).
    #[error("the {model} measures no spectrum (a colorimeter)")]
    NotSpectral { model: String },
    #[error("the {model} returned readings without a spectrum")]
    NoSpectrum { model: String },
    #[error("the {instrument} has no integration time to set")]
    NoIntegration { instrument: String },
    #[error("integration time {value}: {message}")]
    BadIntegration { value: String, message: String },
    /// A real instrument with nobody to place it.
    #[error(transparent)]
    Nobody(#[from] NobodyAtTheRig),
    #[error(transparent)]
    Driver(#[from] DriverError),
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The caller's handling of an event failed (e.g. its output closed).
    #[error(transparent)]
    Event(#[from] std::io::Error),
}

impl SpotRunError {
    /// Whether the request, not the data or the machine, is at fault.
    pub fn is_bad_request(&self) -> bool {
        matches!(
            self,
            SpotRunError::Count
                | SpotRunError::RecordingExists(_)
                | SpotRunError::Spec(_)
                | SpotRunError::NotSpectral { .. }
                | SpotRunError::NoSpectrum { .. }
                | SpotRunError::NoIntegration { .. }
                | SpotRunError::BadIntegration { .. }
        )
    }
}

/// What [`run`] reports while it works.
#[derive(Debug)]
pub enum SpotEvent<'a> {
    /// Something to say before the instrument opens: a simulation that keeps a real
    /// instrument's pace (its calibration alone may take seconds).
    Note(String),
    /// The instrument is open and set up.
    Opened(&'a InstrumentInfo),
    /// Reading number `n` (from 1) arrived; later ones may still fail.
    Reading { n: u32, reading: &'a Reading },
    /// The operator declined a calibration: `done` of `of` readings were made.
    Stopped { done: usize, of: u32 },
}

/// The readings made and the instrument that made them.
#[derive(Debug)]
pub struct SpotReport {
    pub instrument: InstrumentInfo,
    pub readings: Vec<Reading>,
}

/// `metamer spot`: opens the instrument, sets it up, makes `request.count` readings with
/// their calibrations negotiated ([`read`]) and writes their spectra. Everything that can be
/// refused without measuring is refused first. A simulated instrument is aimed at 100 cd/m²
/// of CIE LED-RGB1 for light, at the ColorChecker's white 9.5 for a surface.
///
/// # Examples
///
/// ```
/// use metamer::spot::{run, SpotRequest};
/// use metamer_drivers::MeasureMode;
///
/// let request = SpotRequest {
///     instrument: "sim:cs100a?time_scale=0&noise=off".into(),
///     mode: MeasureMode::Emissive,
///     speed: None,
///     integration: None,
///     count: 2,
///     spectrum: None,
///     force: false,
///     record: None,
///     unattended: true,
/// };
/// let report = run(&request, &mut |_| Ok(())).unwrap();
/// assert_eq!(report.readings.len(), 2);
/// // The simulated meter sees the default light: 100 cd/m².
/// assert!((report.readings[0].xyy[2] - 100.0).abs() < 0.5);
/// ```
pub fn run(
    request: &SpotRequest,
    events: &mut dyn FnMut(SpotEvent) -> std::io::Result<()>,
) -> Result<SpotReport, SpotRunError> {
    if request.count == 0 {
        return Err(SpotRunError::Count);
    }
    if let Some(path) = request.record.as_ref().filter(|p| p.exists()) {
        return Err(SpotRunError::RecordingExists(path.clone()));
    }
    let spec = &request.instrument;
    let mut policy = OutputPolicy::new(request.force);
    policy.inputs(
        spec.replay_file()
            .into_iter()
            .chain(request.record.as_deref()),
    );
    if let Some(path) = &request.spectrum {
        // Before measuring: a refused output is found while nothing is lost.
        policy.check(path)?;
    }
    // Before the instrument is opened: a real one with nobody to place it is refused.
    let attended = attendance(&[spec], request.unattended)?;
    let hands = spec
        .is_simulated()
        .then(|| simulated_target(request.mode))
        .transpose()?;
    if let Some(pace) = crate::session::pace_note(&[spec]) {
        events(SpotEvent::Note(pace))?;
    }
    let mut instrument = open(request, spec, hands.as_ref())?;
    let info = instrument.info();
    events(SpotEvent::Opened(&info))?;
    let mut operator = attended.operator();
    let mut readings = Vec::new();
    for n in 1..=request.count {
        let reading = match read(
            instrument.as_mut(),
            request.mode,
            operator.as_mut(),
            hands.as_ref(),
        ) {
            Ok(r) => r,
            Err(ReadError::Declined(_)) => {
                events(SpotEvent::Stopped {
                    done: readings.len(),
                    of: request.count,
                })?;
                break;
            }
            Err(e) => return Err(e.into()),
        };
        events(SpotEvent::Reading {
            n,
            reading: &reading,
        })?;
        readings.push(reading);
    }
    if let Some(path) = request.spectrum.as_ref().filter(|_| !readings.is_empty()) {
        let Some(csv) = spectra_csv(&readings) else {
            return Err(SpotRunError::NoSpectrum { model: info.model });
        };
        policy.write(path, csv.as_bytes())?;
    }
    Ok(SpotReport {
        instrument: info,
        readings,
    })
}

/// The instrument of `request`, opened and set up; refused before any reading when it
/// cannot do what is asked.
fn open(
    request: &SpotRequest,
    spec: &Spec,
    hands: Option<&SimulatedHands>,
) -> Result<Box<dyn Instrument>, SpotRunError> {
    let options = OpenOptions {
        stimulus: hands.map(|h| h.world.clone() as Arc<dyn World>),
        record: request.record.clone(),
    };
    let mut instrument = spec.open_with(&options).map_err(|e| match e {
        e if e.is_spec() => SpotRunError::Spec(e),
        e => e.into(),
    })?;
    // Before measuring: a colorimeter's readings would be taken and then have no spectrum.
    if request.spectrum.is_some() && !instrument.capabilities().spectral {
        return Err(SpotRunError::NotSpectral {
            model: instrument.info().model,
        });
    }
    if let Some(speed) = request.speed {
        instrument.set_option("speed", speed.name())?;
    }
    if let Some(t) = &request.integration {
        instrument
            .set_option("integration_s", t)
            .map_err(|e| match e {
                DriverError::UnknownOption { instrument, .. } => {
                    SpotRunError::NoIntegration { instrument }
                }
                DriverError::BadOption { message, .. } => SpotRunError::BadIntegration {
                    value: t.clone(),
                    message,
                },
                e => e.into(),
            })?;
    }
    Ok(instrument)
}

/// What a simulated instrument is aimed at or placed on: 100 cd/m² of CIE LED-RGB1 for
/// light, the ColorChecker's white 9.5 for a surface.
fn simulated_target(mode: MeasureMode) -> Result<SimulatedHands, DriverError> {
    let target = match mode {
        MeasureMode::Reflective => {
            View::surface(colorchecker(ColorCheckerSet::BabelColorAverage)[18].clone())?
        }
        _ => View::radiance(default_light())?,
    };
    Ok(SimulatedHands {
        world: Arc::new(SharedWorld::new(target.clone())),
        target,
    })
}
