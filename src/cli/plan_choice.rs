//! The display characterization's plan, as `characterize`, `experiment` and `lab` take it:
//! the paper's fixed patches, or the adaptive plan and its rule.

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
