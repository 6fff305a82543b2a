//! Opening the box rig: the instruments and operator a session measures with — the
//! simulated truth box when both instruments are simulated, the real box otherwise.
//! [`super::job::measure`], the one call of `measure-box` and of the experiment's box
//! stage, opens its rig here, so both measure the same box the same way.

use std::collections::BTreeMap;
use std::sync::Arc;

use metamer_drivers::{DriverError, Instrument, SharedWorld, Spec, View};

use super::plan::BoxPlan;
use super::simulated_box::{BoxOperator, SimulatedBox, SimulatedBoxError};
use crate::rig::Scenario;
use crate::session::Operator;

/// The rig could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// One instrument is simulated and the other is not ([`mixed_rig`] names both).
    #[error("{0}")]
    Mixed(String),
    /// A simulated box's light was asked of a real rig.
    #[error("the light '{0}' is the simulated box's; real instruments measure the real box, lit by its own light")]
    LightOnRealBox(Scenario),
    /// The simulated box could not be made.
    #[error(transparent)]
    Truth(#[from] SimulatedBoxError),
    /// An instrument could not be opened.
    #[error(transparent)]
    Open(#[from] DriverError),
}

impl RigError {
    /// Whether the request itself is wrong (a misnamed instrument or a mixed or mislit
    /// rig), as opposed to something that failed while opening what was asked for.
    pub fn is_request(&self) -> bool {
        matches!(self, RigError::Mixed(_) | RigError::LightOnRealBox(_))
            || matches!(self, RigError::Open(e) if e.is_spec())
    }
}

/// Why `spectral` and `spot` make no rig: one is simulated and the other is not. `spot_is`
/// says more of the spot meter's spec where the user did not write it (a default). When
/// only the spot meter is simulated, says how its model is named on real hardware.
pub fn mixed_rig(spectral: &Spec, spot: &Spec, spot_is: &str) -> String {
    let kind = |s: &Spec| {
        if s.is_simulated() {
            "simulated"
        } else if s.replay_file().is_some() {
            "a replayed transcript"
        } else {
            "real"
        }
    };
    let mut s = format!(
        "--spectral {spectral} is {} and --spot {spot}{spot_is} is {}: both must be simulated \
         (sim:…) or neither, as a simulated instrument sees only the simulated box",
        kind(spectral),
        kind(spot)
    );
    if let (true, Some(real)) = (
        spot.is_simulated(),
        spot.model().and_then(|m| m.real_spec()),
    ) {
        s.push_str(&format!("; name the real spot meter with --spot {real}"));
    }
    s
}

/// A light asked of the box that it cannot have.
#[derive(Debug, thiserror::Error)]
pub enum BoxLightError {
    /// No simulated box light has this name.
    #[error("{0}")]
    Unknown(String),
    /// The simulated box's light was asked of a real rig.
    #[error("a real rig measures the real box under its own light; only the simulated box's light can be chosen")]
    RealRig,
}

/// The simulated box's light named `name`, checked against the rig: a real rig is lit
/// by whatever light it has. Checked before anything is opened.
pub fn box_light(name: Option<&str>, simulated: bool) -> Result<Option<Scenario>, BoxLightError> {
    match (name, simulated) {
        (None, _) => Ok(None),
        (Some(n), true) => n.parse().map(Some).map_err(BoxLightError::Unknown),
        (Some(_), false) => Err(BoxLightError::RealRig),
    }
}

/// Whether the rig is the simulated box: a simulated instrument sees only that box, and
/// a real one only the real box, so the two must agree.
pub fn is_simulated(spectral: &Spec, spot: &Spec) -> Result<bool, RigError> {
    match (spectral.is_simulated(), spot.is_simulated()) {
        (a, b) if a == b => Ok(a),
        _ => Err(RigError::Mixed(mixed_rig(spectral, spot, ""))),
    }
}

/// What the box is measured with.
pub struct BoxRig {
    pub spectral: Box<dyn Instrument>,
    pub spot: Box<dyn Instrument>,
    /// Who places and aims the instruments: the simulated box itself, or the caller's.
    pub operator: Box<dyn Operator>,
    /// What the journals record of the rig and check on resuming (a simulated box's seed
    /// and light; nothing for a real box).
    pub rig_options: BTreeMap<String, String>,
    pub simulated: bool,
}

/// What to open: the instruments as named, and for a simulated box its seed and light.
pub struct RigRequest<'a> {
    pub plan: &'a BoxPlan,
    pub spectral: &'a Spec,
    pub spot: &'a Spec,
    /// Seeds the simulated box; its spectral instrument draws noise from this seed and its
    /// spot meter from the next, unless their specs name their own.
    pub seed: u64,
    /// The simulated box's light (None: the default); refused on a real rig.
    pub light: Option<Scenario>,
}

/// Opens the rig `request` names. On a simulated rig `note` hears which box is simulated
/// before the instruments open; on a real one `operator` is who will be asked to place
/// and aim them.
pub fn open(
    request: &RigRequest<'_>,
    operator: impl FnOnce() -> Box<dyn Operator>,
    note: &dyn Fn(String),
) -> Result<BoxRig, RigError> {
    let simulated = is_simulated(request.spectral, request.spot)?;
    let mut rig_options = BTreeMap::new();
    if !simulated {
        if let Some(light) = request.light {
            return Err(RigError::LightOnRealBox(light));
        }
        return Ok(BoxRig {
            spectral: request.spectral.open(None)?,
            spot: request.spot.open(None)?,
            operator: operator(),
            rig_options,
            simulated,
        });
    }
    let (seed, light) = (request.seed, request.light.unwrap_or_default());
    rig_options.insert("seed".to_string(), seed.to_string());
    rig_options.insert("light".to_string(), light.name().to_string());
    note(format!("simulating the box (seed {seed}, lit by {light})"));
    let truth = SimulatedBox::new(request.plan, seed, light)?;
    let world = Arc::new(SharedWorld::new(View::Capped));
    let spectral = request
        .spectral
        .with_seed_unless_set(seed)
        .open(Some(world.clone()))?;
    let spot = request
        .spot
        .with_seed_unless_set(seed.wrapping_add(1))
        .open(Some(world.clone()))?;
    Ok(BoxRig {
        spectral,
        spot,
        operator: Box::new(BoxOperator::new(truth, world)),
        rig_options,
        simulated,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rig_is_simulated_only_as_a_whole() {
        let sim = Spec::new("sim:cs100a");
        let real = Spec::new("cs100a:/dev/ttyUSB0");
        let replayed = Spec::new("replay:spots.jsonl");
        assert!(is_simulated(&sim, &sim).unwrap());
        assert!(!is_simulated(&real, &replayed).unwrap());
        assert_eq!(
            is_simulated(&sim, &real).unwrap_err().to_string(),
            "--spectral sim:cs100a is simulated and --spot cs100a:/dev/ttyUSB0 is real: both \
             must be simulated (sim:…) or neither, as a simulated instrument sees only the \
             simulated box"
        );
        assert_eq!(
            is_simulated(&replayed, &sim).unwrap_err().to_string(),
            "--spectral replay:spots.jsonl is a replayed transcript and --spot sim:cs100a is \
             simulated: both must be simulated (sim:…) or neither, as a simulated instrument \
             sees only the simulated box; name the real spot meter with --spot cs100a:PORT"
        );
    }

    #[test]
    fn a_simulated_rig_records_its_seed_and_light_and_seeds_its_meter_apart() {
        let plan = BoxPlan::default();
        let spectral = Spec::new("sim:i1pro?time_scale=0");
        let spot = Spec::new("sim:cs100a?time_scale=0");
        let notes = std::cell::RefCell::new(Vec::new());
        let request = RigRequest {
            plan: &plan,
            spectral: &spectral,
            spot: &spot,
            seed: 4,
            light: None,
        };
        let rig = open(
            &request,
            || unreachable!("a simulated box answers for itself"),
            &|n| notes.borrow_mut().push(n),
        )
        .unwrap();
        assert!(rig.simulated);
        assert_eq!(rig.rig_options["seed"], "4");
        assert_eq!(rig.rig_options["light"], Scenario::default().name());
        assert_eq!(
            notes.into_inner(),
            [format!(
                "simulating the box (seed 4, lit by {})",
                Scenario::default()
            )]
        );
        assert_eq!(rig.spectral.info().model, "i1pro");
        assert_eq!(rig.spot.info().model, "cs100a");
    }

    #[test]
    fn a_real_rig_refuses_the_simulated_light_before_opening_anything() {
        let plan = BoxPlan::default();
        // A port that cannot exist: reaching the open would fail differently.
        let spectral = Spec::new("replay:/nonexistent/spectral.jsonl");
        let spot = Spec::new("cs100a:/nonexistent/tty");
        let request = RigRequest {
            plan: &plan,
            spectral: &spectral,
            spot: &spot,
            seed: 1,
            light: Some(Scenario::default()),
        };
        let e = open(&request, || unreachable!(), &|_| {}).err().unwrap();
        assert!(matches!(e, RigError::LightOnRealBox(_)), "{e}");
        assert!(e.is_request());
        let e = open(
            &RigRequest {
                light: None,
                ..request
            },
            || unreachable!(),
            &|_| {},
        )
        .err()
        .unwrap();
        assert!(matches!(e, RigError::Open(_)) && !e.is_request(), "{e}");
    }
}
