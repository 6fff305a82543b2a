//! `metamer measure-box`: the guided, resumable measurement of the validation box.

use std::path::PathBuf;

use metamer::measure_box::job::{self, MeasureBoxJobError, MeasureBoxRequest};
use metamer::measure_box::run::advice::JournalConflict;
use metamer::measure_box::{BoxPlanError, Outcome, Summary};
use metamer::rig::Scenario;
use metamer::session::{on_ctrl_c, BarProgress, RunOptions};
use metamer_drivers::Spec;

use super::plan_choice::BoxPlanKind;
use super::rig::{box_light_refusal, nobody_at_the_rig};
use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory: the stage journals, scene.json, light.json/.svg/.ies/.ldt,
    /// summary.json.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// The spectral instrument: i1pro, i1pro:SERIAL, replay:FILE.jsonl or sim:i1pro.
    #[arg(long, value_name = "SPEC")]
    spectral: Spec,
    /// The spot meter: cs100a:PORT, replay:FILE.jsonl or sim:cs100a.
    #[arg(long, value_name = "SPEC")]
    spot: Spec,
    /// A plan file (JSON) changing counts, angles and geometry; default the paper's plan.
    #[arg(long, value_name = "FILE.json")]
    plan: Option<PathBuf>,
    /// The tiles and the fall-off: fixed (every tile and angle, the paper's) or adaptive (a
    /// subset first, then where the spatial and distribution models leave the spots most
    /// in doubt, up to a cap: the plan file's `adaptive` rule, or the default one). A plan
    /// file with an `adaptive` rule is read adaptively either way.
    #[arg(long, value_enum, default_value = "fixed")]
    box_plan: BoxPlanKind,
    /// Readings of each tile and each spot (default 5, or the plan file's).
    #[arg(long, value_name = "N")]
    repeats: Option<usize>,
    /// Continue the journals in DIR (after a crash, Ctrl-C or kill).
    #[arg(long)]
    resume: bool,
    /// Run only this stage (again from the start, the earlier journal set aside, unless
    /// --resume): tiles, falloff, materials or spots.
    #[arg(long, value_name = "STAGE")]
    stage: Option<String>,
    /// Seed of the simulated box's truth and of its instruments' noise (sim: only).
    #[arg(long, default_value_t = 1, value_name = "N")]
    seed: u64,
    /// The simulated box's light (sim: only; default display-white): display-white (the
    /// ips-lcd display's white, as the paper's box was lit by an LCD) or led-rgb1 (CIE
    /// LED-RGB1, a warm light whose saturated colours no virtual display can show).
    #[arg(long, value_name = "LIGHT")]
    scenario: Option<Scenario>,
    /// Replace an existing scene.json, light.json/.svg/.ies/.ldt or summary.json in DIR.
    #[arg(long)]
    force: bool,
    /// Nobody is at the rig: take every reading without asking anyone to place, aim or
    /// calibrate the instruments. Real instruments without a terminal on stdin need it.
    #[arg(long)]
    unattended: bool,
    /// The operator's time per placement the budget printed before the first reading
    /// assumes, seconds (default 30: a person's half minute to place, aim and confirm).
    #[arg(long, value_name = "S", value_parser = super::parse_placement_seconds)]
    placement_seconds: Option<f64>,
    /// Stop after N new readings, as if interrupted (tests; splitting a long session).
    #[arg(long, value_name = "N", hide = true)]
    stop_after: Option<usize>,
}

fn usage(e: impl std::fmt::Display) -> CliError {
    CliError::Usage(e.to_string())
}

pub fn run(args: Args) -> CliResult {
    let request = MeasureBoxRequest {
        out: args.out,
        spectral: args.spectral,
        spot: args.spot,
        plan: args.plan,
        repeats: args.repeats,
        resume: args.resume,
        stage: args.stage,
        seed: args.seed,
        scenario: args.scenario,
        force: args.force,
        unattended: args.unattended,
        run: RunOptions {
            stop_after: args.stop_after,
            interrupt: Some(on_ctrl_c()),
            placement_s: args.placement_seconds,
        },
        // Asked as the flags and the terminal say; the spots stay in summary.json.
        attendance: None,
        spot_readings: false,
        adaptive: args.box_plan.adaptive(),
        // The plan file's rule and white, as measure-box has no measuring plan.
        spot_rule: None,
        spot_white: None,
    };
    let outcome = job::measure(
        &request,
        &|n| super::console::reported_at_exit(errln!("{n}…")),
        &mut |shown| Box::new(BarProgress::new("reading").attended(shown)),
    )
    .map_err(refusal)?;
    report(outcome)
}

/// A failure in the command's words: its flags named where the request was wrong.
fn refusal(e: MeasureBoxJobError) -> CliError {
    match e {
        MeasureBoxJobError::Plan(e @ BoxPlanError::Io { .. }) => CliError::from(e),
        MeasureBoxJobError::Repeats(message) => usage(format!("--repeats {message}")),
        MeasureBoxJobError::Plan(e) => usage(e),
        MeasureBoxJobError::UnknownStage(message) => usage(message),
        MeasureBoxJobError::BoxLight(e) => box_light_refusal(e, None),
        MeasureBoxJobError::Nobody(e) => nobody_at_the_rig(e),
        MeasureBoxJobError::Rig(e) if e.is_request() => usage(e),
        MeasureBoxJobError::Rig(e) => CliError::from(e),
        // Not asked for by the command (`spot_readings: false`).
        MeasureBoxJobError::SpotReadings(e) => CliError::from(e),
        MeasureBoxJobError::Measure(e) => match (e.conflict(), e.advice()) {
            (Some(c @ JournalConflict::Earlier { stage, .. }), _) => CliError::Failed(
                format!(
                    "{c}: continue it with --resume, measure the stage again with --stage {stage}, or choose another output directory"
                )
                .into(),
            ),
            (Some(c @ JournalConflict::OtherSession { .. }), _) => CliError::Failed(
                format!(
                    "{c}; run with the same --plan/--box-plan/--repeats/--seed and --resume, or choose another output directory"
                )
                .into(),
            ),
            (None, Some(t)) => CliError::Failed(
                format!("{t}; fix the cause and run the same command with --resume").into(),
            ),
            (None, None) => CliError::from(e),
        },
    }
}

/// Where the session ended, and what is left to do, with the flags that go on.
fn report(outcome: Outcome) -> CliResult {
    let go_on = match &outcome {
        Outcome::StagesMissing(_) => " (--stage NAME, or the whole session with --resume)",
        _ => ": continue with --resume",
    };
    let left = outcome.left_to_do().map(|t| format!("{t}{go_on}"));
    match (&outcome, left) {
        (Outcome::Finished(summary), _) => print_summary(summary),
        (_, Some(text)) if outcome.is_interrupted() => Err(CliError::Failed(text.into())),
        (_, text) => {
            outln!("{}", text.unwrap_or_default())?;
            Ok(())
        }
    }
}

fn print_summary(s: &Summary) -> CliResult {
    let c = &s.render.comparison;
    outln!(
        "tiles: {} · fall-off: {} angles, {} LDC (rms {}) · materials: {} · spots: {}",
        s.tiles.len(),
        s.falloff.len(),
        s.light.model,
        s.provenance
            .distribution_fit
            .rms
            .map_or("n/a".into(), |r| format!("{r:.4}")),
        s.materials.len(),
        s.spots.len()
    )?;
    if let Some(a) = &s.adaptive {
        outln!(
            "adaptive plan: {} tiles read in {} round(s), {} predicted by the spatial model ({}); {} fall-off angles read in {} round(s) ({})",
            a.tiles_read.len(),
            a.tile_rounds,
            a.tiles_predicted.len(),
            a.tiles.why,
            a.falloff_read.len(),
            a.falloff_rounds,
            a.falloff.why
        )?;
    }
    let flagged = &s.provenance.outliers;
    if flagged.is_empty() {
        outln!("no outliers; every group's spread within the instruments' noise")?;
    }
    for f in flagged {
        outln!(
            "flagged: {} {}: outlier repeats {:?}{}",
            f.stage,
            f.what,
            f.outliers,
            if f.spread_exceeds_noise {
                format!(", spread {:.4} > 2 × noise {:.4}", f.sd_y, f.noise_y)
            } else {
                String::new()
            }
        )?;
    }
    outln!("measured scene rendered vs box spots: ΔE*ab mean {:.2}, max {:.2}; ΔE00 mean {:.2}, max {:.2}; {} of {} below the JND by point estimate",
        c.mean_de76,
        c.max_de76,
        c.mean_de00,
        c.max_de00,
        c.below_jnd_point,
        c.patches.len()
    )?;
    let f = &s.files;
    outln!(
        "wrote {}, {}, {}, {}, {}, {}",
        f.scene.display(),
        f.light.display(),
        f.light_chart.display(),
        f.ies.display(),
        f.ldt.display(),
        f.summary.display()
    )?;
    Ok(())
}
