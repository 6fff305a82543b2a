//! The display characterization's plan, as `characterize`, `experiment` and `lab` take it:
//! the paper's fixed patches, or the adaptive plan and its rule; and the box's plan, as
//! `measure-box`, `experiment` and `lab` take it.

use clap::ValueEnum;
use metamer::display::characterize::adaptive::{
    Rule, DEFAULT_BATCH, DEFAULT_MAX_READINGS, DEFAULT_STOP_DE,
};
use metamer::display::ModelKind;

use super::CliError;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PlanKind {
    /// The paper's fixed patches: ramps, the model's grid, 48 held-out colours.
    Fixed,
    /// A first pass, then batches where the candidate models disagree at the colours to
    /// reproduce, until the predicted ΔE*ab there is below --stop-de or --max-readings.
    Adaptive,
}

/// The box's tiles and fall-off: the two plans have their own words in `--help`, so the box
/// flag does not describe the display's patches. The library's plan takes the choice
/// (`BoxPlan::choose_adaptive`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BoxPlanKind {
    /// The paper's: every tile of the light and every fall-off angle of the plan.
    Fixed,
    /// The tiles' centre, corners and edge midpoints and the fall-off's normal and outer
    /// angles first, then one tile or angle a round where the spatial and distribution
    /// models leave the spots most in doubt, up to the rule's caps.
    Adaptive,
}

impl BoxPlanKind {
    /// Whether the box is read adaptively (the library's request field).
    pub fn adaptive(self) -> bool {
        self == BoxPlanKind::Adaptive
    }
}

/// The adaptive plan's rule; the plan itself is chosen by each command's own flag
/// (`characterize --plan`, `experiment` and `lab --display-plan`: the experiment's `--plan`
/// is the box's).
#[derive(clap::Args, Clone, Debug)]
pub struct RuleArgs {
    /// adaptive only: stop when the predicted ΔE*ab at every target is below this.
    #[arg(long, value_name = "ΔE", default_value_t = DEFAULT_STOP_DE)]
    pub stop_de: f64,
    /// adaptive only: the cap on fit readings, the first pass included.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_READINGS)]
    pub max_readings: usize,
    /// adaptive only: patches per batch.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_BATCH)]
    pub batch: usize,
}

impl RuleArgs {
    /// The adaptive rule for `plan`, or None for the fixed plan; its numbers checked in
    /// the words of these flags.
    pub fn rule(&self, plan: PlanKind) -> Result<Option<Rule>, CliError> {
        if plan == PlanKind::Fixed {
            return Ok(None);
        }
        if !(self.stop_de.is_finite() && self.stop_de > 0.0) {
            return Err(CliError::Usage(format!(
                "--stop-de must be a ΔE*ab above 0, got {}",
                self.stop_de
            )));
        }
        if self.batch == 0 {
            return Err(CliError::Usage("--batch must be at least 1".into()));
        }
        Ok(Some(Rule {
            stop_de: self.stop_de,
            max_readings: self.max_readings,
            batch: self.batch,
            ..Rule::default()
        }))
    }
}

/// A model by name, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum ModelChoice {
    Auto,
    Kind(ModelKind),
}

impl std::str::FromStr for ModelChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(ModelChoice::Auto);
        }
        s.parse::<ModelKind>()
            .map(ModelChoice::Kind)
            .map_err(|e| format!("{e}, or auto"))
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// One flag's block of a command's long help, from its line to the next flag's, its
    /// lines as the terminal's width wrapped them joined by single spaces.
    fn block(help: &str, flag: &str) -> String {
        let start = help
            .find(&format!("      {flag} "))
            .unwrap_or_else(|| panic!("{flag} is not in the help"));
        let rest = &help[start + flag.len() + 6..];
        let end = [rest.find("\n      --"), rest.find("\n  -")]
            .into_iter()
            .flatten()
            .min()
            .unwrap_or(rest.len());
        rest[..end].split_whitespace().collect::<Vec<_>>().join(" ")
    }

    /// `--box-plan` describes the box's tiles and fall-off, `--display-plan` the display's
    /// patches, in `lab`, `experiment` and `measure-box` (which has the box's only).
    #[test]
    fn the_box_plan_and_the_display_plan_are_described_in_their_own_words() {
        let mut cli = super::super::Cli::command();
        for name in ["lab", "experiment", "measure-box"] {
            let help = cli
                .find_subcommand_mut(name)
                .unwrap_or_else(|| panic!("no {name} command"))
                .render_long_help()
                .to_string();
            let boxed = block(&help, "--box-plan");
            for words in ["every tile of the light", "fall-off angle", "adaptive:"] {
                assert!(boxed.contains(words), "{name} --box-plan: {boxed}");
            }
            for words in ["ramps", "held-out", "--stop-de", "candidate models"] {
                assert!(!boxed.contains(words), "{name} --box-plan: {boxed}");
            }
            if name == "measure-box" {
                assert!(!help.contains("--display-plan"), "{help}");
                continue;
            }
            let display = block(&help, "--display-plan");
            for words in ["ramps", "48 held-out colours", "--stop-de"] {
                assert!(display.contains(words), "{name} --display-plan: {display}");
            }
            assert!(
                !display.contains("tile"),
                "{name} --display-plan: {display}"
            );
        }
    }
}
