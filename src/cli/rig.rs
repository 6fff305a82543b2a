//! The refusals shared by the commands that open a rig (`measure-box`, `experiment`,
//! `spot`, `characterize`), said with their flags.

use metamer::measure_box::setup::{mixed_rig, BoxLightError};
use metamer::session::NobodyAtTheRig;

use super::CliError;

fn usage(e: impl std::fmt::Display) -> CliError {
    CliError::Usage(e.to_string())
}

/// Instruments and a `--scenario` that make no box rig, in the words of the command line.
/// `default_spot` is the spot meter the command takes when `--spot` is not given: a
/// refusal of it says so, as the user never wrote it.
pub(super) fn box_light_refusal(e: BoxLightError, default_spot: Option<&str>) -> CliError {
    match e {
        BoxLightError::Mixed(rig) => {
            let (spectral, spot) = (&rig.spectral, &rig.spot);
            let note = if default_spot == Some(spot.as_str()) {
                " (the default when --spot is not given)"
            } else {
                ""
            };
            usage(mixed_rig(["--spectral", "--spot"], spectral, spot, note))
        }
        BoxLightError::RealRig => usage(
            "--scenario sets the light of the simulated box; real instruments (--spectral/--spot not sim:…) measure the real box under its own light",
        ),
    }
}

/// A real rig with nobody to ask, refused in the words of the command line.
pub(super) fn nobody_at_the_rig(e: NobodyAtTheRig) -> CliError {
    usage(format!(
        "{e}. Run the command at a terminal, or add --unattended if the rig may measure without anyone at it; nothing was measured"
    ))
}
