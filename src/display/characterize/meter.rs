//! Whether a meter can see a screen, decided from their names: a simulated meter sees only
//! a simulated screen.

use metamer_drivers::Spec;

use crate::rig::ScreenSpec;

/// A simulated meter put before a real screen: it cannot see what the screen shows and
/// reads its own fixed light.
#[derive(Debug, thiserror::Error)]
#[error("the simulated meter {meter} cannot see the real screen {screen}; use a real meter, or a virtual display")]
pub struct SimulatedMeterOnRealScreen {
    pub meter: String,
    pub screen: String,
}

/// Whether `meter` can see `screen`: a simulated meter sees only a simulated screen. Asked
/// of the names, so the experiment refuses the pair before its first reading, and
/// `characterize` and the experiment's stages ask the same question when they open them.
pub fn meter_sees(meter: &Spec, screen: &ScreenSpec) -> Result<(), SimulatedMeterOnRealScreen> {
    if meter.is_simulated() && !matches!(screen, ScreenSpec::Virtual(_)) {
        return Err(SimulatedMeterOnRealScreen {
            meter: meter.to_string(),
            screen: screen.canonical(),
        });
    }
    Ok(())
}
