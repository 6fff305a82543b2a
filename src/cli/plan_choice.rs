//! The display characterization's plan, as `characterize`, `experiment` and `lab` take it:
//! the paper's fixed patches, or the adaptive plan and its rule; and the box's plan, as
//! `measure-box`, `experiment` and `lab` take it.

use clap::ValueEnum;
use metamer::display::characterize::adaptive::Rule;
use metamer::display::ModelKind;
use metamer::experiment::display_spots::SpotsShown;
use metamer::experiment::measuring::{MeasuringChoices, MeasuringPlan, DEFAULT_MEASURING};

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
/// is the box's). A figure not given is the default rule's (`characterize`) or the
/// measuring plan's (`experiment`, `lab`).
#[derive(clap::Args, Clone, Debug)]
pub struct RuleArgs {
    /// adaptive only: stop when the predicted ΔE*ab at every target is below this
    /// (default 1; experiment and lab: their --measuring plan's, lean 2).
    #[arg(long, value_name = "ΔE")]
    pub stop_de: Option<f64>,
    /// adaptive only: the cap on fit readings, the first pass included (default 120;
    /// experiment and lab: their --measuring plan's, lean 56).
    #[arg(long, value_name = "N")]
    pub max_readings: Option<usize>,
    /// adaptive only: patches per batch (default 8).
    #[arg(long, value_name = "N")]
    pub batch: Option<usize>,
    /// adaptive only: held-out patches read after the fit, one near each of this many
    /// targets, those the candidate models agree on least (default: one near every
    /// target; experiment and lab: their --measuring plan's, lean 12).
    #[arg(long, value_name = "N")]
    pub held_out: Option<usize>,
}

impl RuleArgs {
    /// The adaptive rule for `plan`, or None for the fixed plan; its numbers checked in
    /// the words of these flags.
    pub fn rule(&self, plan: PlanKind) -> Result<Option<Rule>, CliError> {
        self.check()?;
        if plan == PlanKind::Fixed {
            return Ok(None);
        }
        let base = Rule::default();
        Ok(Some(Rule {
            stop_de: self.stop_de.unwrap_or(base.stop_de),
            max_readings: self.max_readings.unwrap_or(base.max_readings),
            batch: self.batch.unwrap_or(base.batch),
            held_out: self.held_out,
            ..base
        }))
    }

    /// The figures given, checked in the words of these flags.
    pub fn check(&self) -> Result<(), CliError> {
        if let Some(stop_de) = self.stop_de.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(CliError::Usage(format!(
                "--stop-de must be a ΔE*ab above 0, got {stop_de}"
            )));
        }
        if self.batch == Some(0) {
            return Err(CliError::Usage("--batch must be at least 1".into()));
        }
        if self.held_out == Some(0) {
            return Err(CliError::Usage("--held-out must be at least 1".into()));
        }
        Ok(())
    }
}

/// The measuring plan's flags `experiment` and `lab` share: the plan by name and each of
/// its options, which, given, replaces the plan's own.
#[derive(clap::Args, Clone, Debug)]
pub struct MeasuringArgs {
    /// Which readings to take: paper (the paper's fixed plan: every box tile, fall-off angle
    /// and spot 5 times; the display's ramps, grid and 48 held-out colours; every display
    /// spot --repeats times) or lean (what the verdicts need: the box's tiles and fall-off
    /// adaptively and its spots 3 times, pooled; the display adaptively, --stop-de 2
    /// --max-readings 56 --held-out 12; each display spot twice, pooled, --until-decided 0
    /// --repeats 2, the image slid under the meter, --display-spots under-meter).
    /// Every flag below replaces its part of the plan.
    #[arg(long, value_name = "PLAN", default_value_t = DEFAULT_MEASURING)]
    pub measuring: MeasuringPlan,
    /// The box's tiles and fall-off: fixed (every tile and angle, the paper's) or adaptive
    /// (a subset first, then where the spatial and distribution models leave the spots
    /// most in doubt, up to a cap). Default: the measuring plan's.
    #[arg(long, value_enum)]
    pub box_plan: Option<BoxPlanKind>,
    /// The display's characterization: fixed (the paper's patches) or adaptive (patches
    /// where the candidate models disagree at the rendered colours). Default: the
    /// measuring plan's.
    #[arg(long, value_enum)]
    pub display_plan: Option<PlanKind>,
    #[command(flatten)]
    pub rule: RuleArgs,
    /// Spot readings averaged per patch on the display, with --until-decided the most
    /// (default 3).
    #[arg(long, value_name = "K")]
    pub repeats: Option<usize>,
    /// Read each patch on the display until its ΔE*ab against the box is decided at 95 %
    /// with this margin beyond the JND (ΔE*ab 2.3), at least twice and at most --repeats
    /// times (e.g. 0.1); default: the measuring plan's (paper: every patch read --repeats
    /// times; lean: 0).
    #[arg(long, value_name = "ΔE")]
    pub until_decided: Option<f64>,
    /// How each patch is put in front of the meter on the display: aimed (the paper's: the
    /// image shown whole, the meter re-aimed at every patch), under-meter (the image slid
    /// so each patch in turn lies under the meter, aimed once at the middle of the screen)
    /// or full-screen (each patch's drive values over the whole screen). Default: the
    /// measuring plan's (paper: aimed; lean: under-meter).
    #[arg(long, value_name = "HOW")]
    pub display_spots: Option<SpotsShown>,
}

impl MeasuringArgs {
    /// The options given in place of the plan's, their figures checked in the words of
    /// these flags.
    pub fn choices(&self) -> Result<MeasuringChoices, CliError> {
        self.rule.check()?;
        let adaptive = |p: Option<PlanKind>| p.map(|p| p == PlanKind::Adaptive);
        Ok(MeasuringChoices {
            box_adaptive: self.box_plan.map(BoxPlanKind::adaptive),
            box_spot_rule: None,
            display_adaptive: adaptive(self.display_plan),
            stop_de: self.rule.stop_de,
            max_readings: self.rule.max_readings,
            batch: self.rule.batch,
            held_out: self.rule.held_out,
            repeats: self.repeats,
            until_decided: self.until_decided,
            spots_shown: self.display_spots,
        })
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
