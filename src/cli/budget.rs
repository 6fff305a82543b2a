//! `metamer budget`: display models' reproduction error against measured patches on the
//! simulated monitors (the patch-count chart).

use std::path::PathBuf;

use metamer::display::budget::{run_budget_study, write_budget, RAMP_STEPS};
use metamer::display::ModelKind;
use metamer::rig::Preset;

use super::{CliError, CliResult};
use metamer::output::OutputPolicy;

#[derive(clap::Args)]
pub struct Args {
    /// Output directory: budget.csv and budget-PRESET.svg per monitor.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// Simulated monitors to study (repeatable; default all: ideal-crt, ips-lcd,
    /// wide-gamut-ccfl).
    #[arg(long = "display", value_name = "PRESET")]
    displays: Vec<String>,
    /// Models to study (repeatable; default all).
    #[arg(long = "model", value_name = "MODEL")]
    models: Vec<String>,
    /// Fresh sets of readings per budget (the errors are pooled over them).
    #[arg(long, default_value_t = 5)]
    trials: usize,
    /// Seed of the meter noise and of the verification colours.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Replace budget.csv and the charts if they exist.
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> CliResult {
    // Options that cannot work are refused before minutes of fitting.
    if args.trials == 0 {
        return Err(CliError::Usage(
            "--trials must be at least 1: each trial is one fresh set of readings".into(),
        ));
    }
    if args.out.exists() && !args.out.is_dir() {
        return Err(CliError::Usage(format!(
            "-o {}: is a file, but budget writes budget.csv and one chart per display into a \
             directory",
            args.out.display()
        )));
    }
    let presets: Vec<Preset> = if args.displays.is_empty() {
        Preset::ALL.to_vec()
    } else {
        args.displays
            .iter()
            .map(|s| s.parse())
            .collect::<Result<_, String>>()
            .map_err(CliError::Usage)?
    };
    let models: Vec<ModelKind> = if args.models.is_empty() {
        ModelKind::ALL.to_vec()
    } else {
        args.models
            .iter()
            .map(|s| s.parse())
            .collect::<Result<_, String>>()
            .map_err(CliError::Usage)?
    };
    let out = OutputPolicy::new(args.force);
    // Before the study, which takes minutes: a refused output is found now.
    out.dir(&args.out)?;
    out.check(&args.out.join("budget.csv"))?;
    for p in &presets {
        out.check(&args.out.join(format!("budget-{}.svg", p.name())))?;
    }
    let total = presets.len() * models.len() * RAMP_STEPS.len();
    let bar = indicatif::ProgressBar::new(total as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} fit {pos}/{len} · about {eta} left")
            .expect("valid template"),
    );
    let points = run_budget_study(&presets, &models, args.trials, args.seed, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let points = points?;
    write_budget(&args.out, &points, &out)?;
    println!("preset            model                   patches  mean ΔE00  p95 ΔE00  max ΔE00");
    for p in &points {
        println!(
            "{:<17} {:<23} {:>7}  {:>9.3}  {:>8.3}  {:>8.3}",
            p.preset, p.model, p.patches, p.mean_de00, p.p95_de00, p.max_de00
        );
    }
    println!("wrote {}", args.out.display());
    Ok(())
}
