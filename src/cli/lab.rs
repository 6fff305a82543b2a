//! `metamer lab`: the experiment on the simulated rig, nothing to connect and nobody at it.

use std::path::PathBuf;

use metamer::display::gamut::GamutMapping;
use metamer::display::ModelKind;
use metamer::experiment::lab::{run_lab, LabError, LabOptions, LabSummary, LAB_FILE};
use metamer::rig::{Scenario, ScreenSpec};
use metamer::session::{on_ctrl_c, RunOptions};

use super::experiment::{print_cost, print_outcomes, refusal, StageProgress};
use super::plan_choice::{BoxPlanKind, PlanKind, RuleArgs};
use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory: the experiment's stage directories (box/, simulation/, display/,
    /// reproduction/, display-spots/, validation/ with report.html) and lab.json.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// The box's light: display-white (the ips-lcd display's white, as the paper's box was
    /// lit by an LCD) or led-rgb1 (CIE LED-RGB1, a warm light whose saturated colours no
    /// virtual display can show).
    #[arg(long, default_value = "display-white", value_name = "LIGHT")]
    scenario: Scenario,
    /// The simulated monitor, named as `experiment --display` names it: virtual:ideal-crt,
    /// virtual:ips-lcd or virtual:wide-gamut-ccfl (the preset's name alone is taken too).
    #[arg(long, default_value = "virtual:ips-lcd", value_name = "DISPLAY")]
    display: ScreenSpec,
    /// Display model: lut (3D LUT, for displays where PLCC's assumptions fail, as the
    /// simulated LCDs'), plcc (paper Eq. 9), plcc-gamma, gog, gogo, matrix-lsq.
    #[arg(long, default_value = "lut", value_name = "MODEL")]
    model: ModelKind,
    /// Out-of-gamut colours: nearest-lab (least ΔE*ab the display can show) or clip.
    #[arg(long, default_value = "nearest-lab", value_name = "MAPPING")]
    gamut: GamutMapping,
    /// The simulation's accuracy: 95 % half-width of every patch's ΔE*ab.
    #[arg(long, default_value_t = 0.1, value_name = "ΔE")]
    target_de: f64,
    /// Spot readings averaged per patch on the display.
    #[arg(long, default_value_t = 3, value_name = "K")]
    repeats: usize,
    /// Read each patch on the display until its ΔE*ab against the box is decided at 95 %
    /// with this margin beyond the JND (ΔE*ab 2.3), at least twice and at most --repeats
    /// times (e.g. 0.1); without it every patch is read --repeats times.
    #[arg(long, value_name = "ΔE")]
    until_decided: Option<f64>,
    /// Another run's folder (an experiment's or `lab`'s, measured with another plan on the
    /// same rig), whose measuring cost and accuracy the report's cost section sets beside
    /// this run's; read from its saved files, nothing measured again.
    #[arg(long, value_name = "DIR")]
    compare_with: Option<PathBuf>,
    /// The box measurement plan (see `metamer measure-box --help`), e.g. a spot rule;
    /// default: the paper's.
    #[arg(long, value_name = "PLAN.json")]
    plan: Option<PathBuf>,
    /// Readings of each tile and spot in the box (default: the box plan's 5).
    #[arg(long, value_name = "N")]
    box_repeats: Option<usize>,
    /// The box's tiles and fall-off: fixed (every tile and angle, the paper's) or adaptive
    /// (a subset first, then where the spatial and distribution models leave the spots
    /// most in doubt, up to a cap).
    #[arg(long, value_enum, default_value = "fixed")]
    box_plan: BoxPlanKind,
    /// Seed of the simulated box and of its instruments' noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The simulated instruments' pace: 1 = their real pace (the CS-100A ≈100 ms per reading), 0 = at once.
    #[arg(long, default_value_t = 0.0, value_name = "F")]
    time_scale: f64,
    /// The camera image's side in pixels (the paper's 1014), reproduced and shown whole on
    /// the simulated monitor for the spot readings; 0: none, each patch shown full-screen.
    #[arg(long, default_value_t = 1014, value_name = "PIXELS")]
    image_size: usize,
    /// Continue an interrupted measuring stage from its journal.
    #[arg(long)]
    resume: bool,
    /// The operator's time per placement the budget printed before the first reading
    /// assumes, seconds (default 30: a person's half minute to place, aim and confirm).
    #[arg(long, value_name = "S", value_parser = super::parse_placement_seconds)]
    placement_seconds: Option<f64>,
    /// Run every stage again, even those whose inputs are unchanged (earlier measurements
    /// are moved aside, never deleted).
    #[arg(long)]
    force: bool,
    /// The display's characterization: fixed (the paper's patches) or adaptive (patches
    /// where the candidate models disagree at the 24 rendered colours).
    #[arg(long, value_enum, default_value = "fixed")]
    display_plan: PlanKind,
    #[command(flatten)]
    rule: RuleArgs,
}

pub fn run(args: Args) -> CliResult {
    let adaptive = args.rule.rule(args.display_plan)?;
    let ScreenSpec::Virtual(display) = args.display else {
        return Err(CliError::Usage(format!(
            "--display {}: the lab's monitor is simulated; name it virtual:PRESET",
            args.display
        )));
    };
    let options = LabOptions {
        scenario: args.scenario,
        display,
        model: args.model,
        gamut: args.gamut,
        target_de: args.target_de,
        repeats: args.repeats,
        until_decided: args.until_decided,
        compare_with: args.compare_with,
        plan: args.plan,
        box_repeats: args.box_repeats,
        box_adaptive: args.box_plan.adaptive(),
        seed: args.seed,
        time_scale: args.time_scale,
        image_size: args.image_size,
        adaptive,
    };
    let run = RunOptions {
        stop_after: None,
        interrupt: Some(on_ctrl_c()),
        placement_s: args.placement_seconds,
    };
    let shown = StageProgress::default();
    let summary = run_lab(&args.out, &options, args.resume, args.force, run, &|p| {
        shown.show(p)
    });
    shown.finish();
    let (outcomes, summary) = summary.map_err(|e| match e {
        LabError::Request(e) => refusal(e),
        e => CliError::from(e),
    })?;
    print_outcomes(&outcomes, None)?;
    print_cost(&summary.budget_total)?;
    print_summary(&summary)?;
    outln!(
        "report: {}; summary: {}",
        args.out.join(&summary.report).display(),
        args.out.join(LAB_FILE).display()
    )?;
    Ok(())
}

fn print_summary(s: &LabSummary) -> CliResult {
    outln!(
        "box lit by {}; display virtual:{}, model {}; {} of 24 simulated colours out of its gamut{}",
        s.options.scenario,
        s.options.display.name(),
        s.options.model,
        s.out_of_gamut_patches.len(),
        if s.out_of_gamut_patches.is_empty() {
            String::new()
        } else {
            format!(
                " (patches {}; {} mapping)",
                s.out_of_gamut_patches
                    .iter()
                    .map(|p| p.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                s.options.gamut
            )
        }
    )?;
    for c in [
        &s.display_vs_box,
        &s.simulation_vs_box,
        &s.display_vs_simulation,
    ] {
        outln!("{}", c.summary)?;
    }
    outln!("total {:.1} s", s.seconds)?;
    Ok(())
}
