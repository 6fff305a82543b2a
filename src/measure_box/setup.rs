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
    /// The instruments and the light asked for make no rig ([`box_light`]).
    #[error(transparent)]
    Light(#[from] BoxLightError),
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
        matches!(self, RigError::Light(_)) || matches!(self, RigError::Open(e) if e.is_spec())
    }
}

/// What a spec names, in a word for a message.
fn kind(s: &Spec) -> &'static str {
    if s.is_simulated() {
        "simulated"
    } else if s.replay_file().is_some() {
        "a replayed transcript"
    } else {
        "real"
    }
}

/// Why `spectral` and `spot` make no rig (one is simulated and the other is not), naming
/// them as the caller does: `names` are what it calls the two (`the spot meter`, or a
/// command's flags), `spot_note` says more of the spot meter's spec where the user did not
/// write it (a default). When only the spot meter is simulated, says how its model is
/// named on real hardware.
pub fn mixed_rig(names: [&str; 2], spectral: &Spec, spot: &Spec, spot_note: &str) -> String {
    let [spectral_is, spot_is] = names;
    let mut s = format!(
        "{spectral_is} {spectral} is {} and {spot_is} {spot}{spot_note} is {}: both must be \
         simulated (sim:…) or neither, as a simulated instrument sees only the simulated box",
        kind(spectral),
        kind(spot)
    );
    if let (true, Some(model)) = (spot.is_simulated(), spot.model()) {
        if let Some(real) = model.real_spec() {
            s.push_str(&format!("; a real {} is named {real}", model.title));
        }
    }
    s
}

/// The two instruments of a rig, one simulated and the other not.
#[derive(Debug)]
pub struct MixedRig {
    pub spectral: Spec,
    pub spot: Spec,
}

/// Instruments and a light that make no box rig.
#[derive(Debug, thiserror::Error)]
pub enum BoxLightError {
    /// One instrument is simulated and the other is not.
    #[error("{}", mixed_rig(["the spectral instrument", "the spot meter"], &.0.spectral, &.0.spot, ""))]
    Mixed(Box<MixedRig>),
    /// The simulated box's light was asked of a real rig.
    #[error("a real rig measures the real box under its own light; only the simulated box's light can be chosen")]
    RealRig,
}

/// The box the instruments measure, and its light: the simulated box (both instruments
/// simulated: a simulated instrument sees only that box) under `light` or the default
/// light, or the real box (both real), which has its own light, so none may be asked of
/// it. `measure-box`, the experiment's checks and [`open`] decide it here, before anything
/// is opened; None is the real box.
pub fn box_light(
    spectral: &Spec,
    spot: &Spec,
    light: Option<Scenario>,
) -> Result<Option<Scenario>, BoxLightError> {
    match (spectral.is_simulated(), spot.is_simulated(), light) {
        (true, true, light) => Ok(Some(light.unwrap_or_default())),
        (false, false, None) => Ok(None),
        (false, false, Some(_)) => Err(BoxLightError::RealRig),
        _ => Err(BoxLightError::Mixed(Box::new(MixedRig {
            spectral: spectral.clone(),
            spot: spot.clone(),
        }))),
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
    /// The simulated box's light (None: the default); refused on a real rig ([`box_light`]).
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
    let mut rig_options = BTreeMap::new();
    let Some(light) = box_light(request.spectral, request.spot, request.light)? else {
        return Ok(BoxRig {
            spectral: request.spectral.open(None)?,
            spot: request.spot.open(None)?,
            operator: operator(),
            rig_options,
            simulated: false,
        });
    };
    let seed = request.seed;
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
        simulated: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rig_is_simulated_only_as_a_whole_and_only_the_simulated_box_takes_a_light() {
        let sim = Spec::new("sim:cs100a");
        let real = Spec::new("cs100a:/dev/ttyUSB0");
        let replayed = Spec::new("replay:spots.jsonl");
        let led = Some(Scenario::LedRgb1);
        assert_eq!(
            box_light(&sim, &sim, None).unwrap(),
            Some(Scenario::default())
        );
        assert_eq!(box_light(&sim, &sim, led).unwrap(), led);
        assert_eq!(box_light(&real, &replayed, None).unwrap(), None);
        assert!(matches!(
            box_light(&real, &replayed, led),
            Err(BoxLightError::RealRig)
        ));
        for light in [None, led] {
            assert_eq!(
                box_light(&sim, &real, light).unwrap_err().to_string(),
                "the spectral instrument sim:cs100a is simulated and the spot meter \
                 cs100a:/dev/ttyUSB0 is real: both must be simulated (sim:…) or neither, as a \
                 simulated instrument sees only the simulated box"
            );
            assert_eq!(
                box_light(&replayed, &sim, light).unwrap_err().to_string(),
                "the spectral instrument replay:spots.jsonl is a replayed transcript and the \
                 spot meter sim:cs100a is simulated: both must be simulated (sim:…) or \
                 neither, as a simulated instrument sees only the simulated box; a real \
                 Konica Minolta CS-100A is named cs100a:PORT"
            );
        }
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
        assert!(matches!(e, RigError::Light(BoxLightError::RealRig)), "{e}");
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
