//! The refusals shared by the commands that open a rig (`measure-box`, `experiment`,
//! `spot`, `characterize`), said with their flags.

use metamer::rig::Scenario;
use metamer::session::NobodyAtTheRig;

use super::CliError;

fn usage(e: impl std::fmt::Display) -> CliError {
    CliError::Usage(e.to_string())
}

/// The simulated box's light named by `--scenario`; refused with real instruments, whose
/// box is lit by whatever light it has.
pub(super) fn box_light(name: Option<&str>, simulated: bool) -> Result<Option<Scenario>, CliError> {
    match (name, simulated) {
        (None, _) => Ok(None),
        (Some(n), true) => n.parse().map(Some).map_err(usage),
        (Some(_), false) => Err(usage(
            "--scenario sets the light of the simulated box; real instruments (--spectral/--spot not sim:…) measure the real box under its own light",
        )),
    }
}

/// A real rig with nobody to ask, refused in the words of the command line.
pub(super) fn nobody_at_the_rig(e: NobodyAtTheRig) -> CliError {
    usage(format!(
        "{e}. Run the command at a terminal, or add --unattended if the rig may measure without anyone at it; nothing was measured"
    ))
}
