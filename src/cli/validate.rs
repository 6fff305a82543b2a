//! `metamer validate`: the box's readings against the display's (and the simulation's) in
//! CIELAB relative to the display's white, with uncertainty; prints the per-patch table
//! and writes `validation.json`, `validation.csv` and `report.html`.

use std::path::PathBuf;

use clap::ValueEnum;
use metamer::validation::export::{comparisons, to_json};
use metamer::validation::job::{
    read_sides, validate, Context, Coverage, Outcome, ReadingFiles, Request, White,
};
use metamer::validation::{AssessOptions, Assessment, Propagation, ValidationError};

use super::{parse_triple, CliError, CliResult};

#[derive(Clone, Copy, ValueEnum)]
enum PropagationArg {
    /// Seeded Monte Carlo draws of the readings' noise, the interval by inverting the test
    /// of each true difference (bias-aware; right near ΔE = 0 too).
    MonteCarlo,
    /// ΔE ± 1.96 σ by first-order propagation.
    Linear,
}

/// Most Monte Carlo draws per patch.
const MAX_DRAWS: usize = 10_000_000;
/// Largest model term: CIELAB's whole gamut spans a few hundred ΔE*ab.
const MAX_MODEL_TERM: f64 = 1000.0;

#[derive(clap::Args)]
pub struct Args {
    /// The box's readings: a session journal (.jsonl), `metamer spot --json` output, or a
    /// CSV patch,X,Y,Z[,sd_X,sd_Y,sd_Z[,cov_XY,cov_XZ,cov_YZ]][,n][,u_lab][,out_of_gamut].
    #[arg(long, value_name = "READINGS")]
    reference: PathBuf,
    /// The display's readings of the rendering (same formats).
    #[arg(long, value_name = "READINGS")]
    test: PathBuf,
    /// The simulation's readings (also `metamer render spots --json` output): adds box vs
    /// simulation (Fig. 6) and display vs simulation.
    #[arg(long, value_name = "READINGS")]
    simulation: Option<PathBuf>,
    /// CIELAB's white: X,Y,Z, or `test` / `reference` for that file's `white` reading (else
    /// its brightest reading). Default: test, the display's white.
    #[arg(long, default_value = "test", value_name = "X,Y,Z|test|reference")]
    white: String,
    /// Output directory for validation.json, validation.csv and report.html.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// Replace report files already in DIR.
    #[arg(long)]
    force: bool,
    /// Print validation.json to stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// How uncertainty reaches ΔE.
    #[arg(long, value_enum, default_value = "monte-carlo")]
    propagation: PropagationArg,
    /// Monte Carlo draws per patch.
    #[arg(long, default_value_t = 4000, value_name = "N")]
    draws: usize,
    /// Monte Carlo seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// A standard uncertainty in ΔE*ab for the display model (e.g. its RMS verification
    /// error), added to every display reading.
    #[arg(long, default_value_t = 0.0, value_name = "DE")]
    model_term: f64,
    /// Patches the display cannot show (comma-separated numbers), besides those the
    /// readings mark; marked in the comparisons with the display on one side.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    out_of_gamut: Vec<usize>,
    /// The report's title.
    #[arg(long, default_value = "Validation: box, display and simulation")]
    title: String,
}

pub fn run(args: Args) -> CliResult {
    check_numbers(&args)?;
    let readings = ReadingFiles {
        box_readings: &args.reference,
        display: &args.test,
        simulation: args.simulation.as_deref(),
    };
    let white = match args.white.as_str() {
        "test" => White::Display,
        "reference" => White::Box,
        s => match parse_triple(s) {
            Ok(v) => White::Given(v.into()),
            // A file that cannot be read is said before a malformed white.
            Err(e) => {
                read_sides(&readings, true)?;
                return Err(CliError::Usage(format!("--white: {e}")));
            }
        },
    };
    let propagation = match args.propagation {
        PropagationArg::MonteCarlo => Propagation::MonteCarlo {
            draws: args.draws,
            seed: args.seed,
        },
        PropagationArg::Linear => Propagation::Linear,
    };
    let outcome = validate(&Request {
        readings,
        white,
        options: AssessOptions {
            propagation,
            model_term_de: args.model_term,
        },
        out_of_gamut: args.out_of_gamut.clone(),
        coverage: Coverage::Shared,
        check_readings: true,
        context: Context::Files,
        point_files: false,
        title: args.title.clone(),
        out: &args.out,
        force: args.force,
    })
    .map_err(refusal)?;
    print(&outcome, args.json)
}

/// The numbers the library takes as given, checked as this command's options.
fn check_numbers(args: &Args) -> CliResult {
    if args.draws < 100 {
        return Err(CliError::Usage(
            "--draws must be at least 100 for a 95 % interval".into(),
        ));
    }
    // Draws are held in memory per patch; ten million already take minutes.
    if args.draws > MAX_DRAWS {
        return Err(CliError::Usage(format!(
            "--draws {}: at most {MAX_DRAWS} (10⁵ give the 95 % interval to a few per cent)",
            args.draws
        )));
    }
    if !(0.0..=MAX_MODEL_TERM).contains(&args.model_term) {
        return Err(CliError::Usage(format!(
            "--model-term {:?}: must be a ΔE*ab from 0 to {MAX_MODEL_TERM}",
            args.model_term
        )));
    }
    if let Some(bad) = args.out_of_gamut.iter().find(|k| !(1..=24).contains(*k)) {
        return Err(CliError::Usage(format!(
            "--out-of-gamut: patch {bad} is not 1–24"
        )));
    }
    Ok(())
}

/// The library's refusals of what this command's options gave, worded as such.
fn refusal(e: ValidationError) -> CliError {
    match e {
        ValidationError::GivenWhite(m) => CliError::Usage(format!("--white: {m}")),
        // A white that makes CIELAB meaningless is the user's input, not a data fault.
        ValidationError::BadWhite { .. } => CliError::Usage(format!("--white: {e}")),
        ValidationError::Output(o) if o.needs_force() => CliError::Usage(format!(
            "{o}: pass --force to replace the report, or choose another -o directory"
        )),
        e => CliError::from(e),
    }
}

fn print(outcome: &Outcome, json: bool) -> CliResult {
    let input = &outcome.report;
    if json {
        outln!("{}", to_json(input))?;
        return Ok(());
    }
    for note in &input.notes {
        errln!("note: {note}")?;
    }
    let white = outcome.white;
    outln!(
        "white X Y Z = {:.4} {:.4} {:.4} ({})",
        white.x,
        white.y,
        white.z,
        input.white_source
    )?;
    for (_, a) in comparisons(input) {
        print_table(a)?;
    }
    for f in &outcome.files {
        outln!("wrote {}", f.display())?;
    }
    Ok(())
}

fn print_table(a: &Assessment) -> CliResult {
    outln!()?;
    outln!(
        "{} vs {} (CIELAB of {} first, then of {})",
        a.test,
        a.reference,
        a.reference,
        a.test
    )?;
    outln!(
        "{:>3} {:<14} {:>7} {:>7} {:>7}  {:>7} {:>7} {:>7}  {:>7} {:>15}  {:>7} {:>15}  JND",
        "#",
        "patch",
        "L*",
        "a*",
        "b*",
        "L*",
        "a*",
        "b*",
        "ΔE*ab",
        "95 %",
        "ΔE00",
        "95 %"
    )?;
    for p in &a.patches {
        let [rl, ra, rb] = p.reference.lab;
        let [tl, ta, tb] = p.test.lab;
        outln!(
            "{:>3} {:<14} {rl:>7.2} {ra:>7.2} {rb:>7.2}  {tl:>7.2} {ta:>7.2} {tb:>7.2}  {:>7.2} {:>15}  {:>7.2} {:>15}  {}{}",
            p.patch,
            p.name,
            p.de76,
            format!("[{:.2}, {:.2}]", p.de76_interval.lo, p.de76_interval.hi),
            p.de00,
            format!("[{:.2}, {:.2}]", p.de00_interval.lo, p.de00_interval.hi),
            p.jnd.name(),
            if p.out_of_gamut { "  (out of gamut)" } else { "" }
        )?;
    }
    outln!("{}", a.summary())?;
    Ok(())
}
