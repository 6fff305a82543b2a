//! `metamer light`: fit the light distribution curve to a fall-off table and export it as
//! IES/EULUMDAT; show what a photometric file holds.

use std::path::PathBuf;

use clap::Subcommand;

use super::{CliError, CliResult};
use metamer::light::fit::{HalfPlane, Plane};
use metamer::light::job::{self, FitEvent, FitRequest, LightError, LightFile};
use metamer::light::{CGammaTable, LdcFit, ModelChoice, Photometry};
use metamer::output::OutputError;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: LightCommand,
}

#[derive(Subcommand)]
enum LightCommand {
    /// Fit the light distribution curve to luminance readings off the normal.
    Fit(FitArgs),
    /// Summarise an IES (.ies) or EULUMDAT (.ldt) file.
    Show(ShowArgs),
}

#[derive(clap::Args)]
struct FitArgs {
    /// Readings: CSV `angle_deg,horizontal,vertical` (signed angles; either plane alone).
    #[arg(long, value_name = "FILE.csv")]
    falloff: PathBuf,
    /// lambertian, cos-power, cos-poly, lobes, series, spline, or auto (leave-one-out
    /// cross-validation picks the simplest model that predicts held-out angles as well as
    /// the best).
    #[arg(long, default_value = "auto")]
    model: ModelChoice,
    /// The fit, its scores and its C-γ table (JSON).
    #[arg(short = 'o', long = "output", value_name = "LIGHT.json")]
    output: PathBuf,
    /// Also write an IES LM-63-2019 file (needs --width-m and --height-m).
    #[arg(long, value_name = "OUT.ies")]
    ies: Option<PathBuf>,
    /// Also write a EULUMDAT file (needs --width-m and --height-m).
    #[arg(long, value_name = "OUT.ldt")]
    ldt: Option<PathBuf>,
    /// Also draw the readings and every model's curve (SVG).
    #[arg(long, value_name = "OUT.svg")]
    chart: Option<PathBuf>,
    /// The panel's extent along its edge_u (the horizontal plane), metres.
    #[arg(long, value_name = "W")]
    width_m: Option<f64>,
    /// The panel's extent along its edge_v (the vertical plane), metres.
    #[arg(long, value_name = "H")]
    height_m: Option<f64>,
    /// Luminance along the normal, cd/m², for the candela of IES/LDT (default: the
    /// readings' normal luminance, when they are absolute).
    #[arg(long, value_name = "CD_M2")]
    luminance: Option<f64>,
    /// Replace output files that exist.
    #[arg(long)]
    force: bool,
}

#[derive(clap::Args)]
struct ShowArgs {
    /// An IES (.ies) or EULUMDAT (.ldt) file.
    #[arg(value_name = "FILE")]
    file: PathBuf,
}

pub fn run(args: Args) -> CliResult {
    match args.command {
        LightCommand::Fit(a) => run_fit(a),
        LightCommand::Show(a) => run_show(a),
    }
}

fn output_error(e: OutputError) -> CliError {
    if e.needs_force() {
        CliError::Usage(format!("{e} (add --force to replace it)"))
    } else {
        CliError::from(e)
    }
}

fn light_error(e: LightError) -> CliError {
    match e {
        LightError::BadRequest(message) => CliError::Usage(message),
        LightError::PanelSize => CliError::Usage(
            "--ies and --ldt need the panel's size: give both --width-m and --height-m".into(),
        ),
        LightError::NoLuminance => CliError::Usage(
            "the readings are relative (1 at the normal): give the panel's luminance with \
             --luminance CD_M2"
                .into(),
        ),
        LightError::Output(e) => output_error(e),
        LightError::Fit { .. } => CliError::Failed(e.to_string().into()),
        e => CliError::from(e),
    }
}

fn run_fit(a: FitArgs) -> CliResult {
    let request = FitRequest {
        falloff: a.falloff,
        model: a.model,
        output: a.output,
        ies: a.ies,
        ldt: a.ldt,
        chart: a.chart,
        width_m: a.width_m,
        height_m: a.height_m,
        luminance: a.luminance,
        force: a.force,
    };
    job::fit(&request, &|event| match event {
        FitEvent::Fitted(fit) => super::console::reported_at_exit(print_fit(&request.falloff, fit)),
        FitEvent::Written(file, path) => {
            let what = match file {
                LightFile::Fit => "fit",
                LightFile::Chart => "chart",
                LightFile::Ies => "IES",
                LightFile::Ldt => "EULUMDAT",
            };
            super::console::reported_at_exit(outln!("{what} written to {}", path.display()));
        }
        FitEvent::Panel {
            panel,
            flux_lm,
            extrapolated,
        } => {
            super::console::reported_at_exit(outln!(
                "panel {} m × {} m at {} cd/m²: I₀ = {:.4} cd, flux {:.4} lm",
                panel.width_m,
                panel.height_m,
                panel.normal_luminance_cd_m2,
                panel.normal_intensity_cd(),
                flux_lm
            ));
            if let Some(e) = extrapolated {
                super::console::reported_at_exit(outln!(
                    "  of which {:.4} lm ({:.1} %) above γ = {}°, where the table is extrapolated",
                    e.flux_lm,
                    100.0 * e.flux_lm / flux_lm,
                    e.beyond_deg
                ));
            }
        }
    })
    .map_err(light_error)?;
    Ok(())
}

fn print_fit(source: &std::path::Path, fit: &LdcFit) -> Result<(), super::console::ConsoleError> {
    outln!(
        "{}: normal luminance {} (horizontal {}, vertical {} at 0°)",
        source.display(),
        num(fit.normal_luminance),
        num(fit.normal_readings[0]),
        num(fit.normal_readings[1])
    )?;
    outln!(
        "  {:<11} {:>5} {:>9} {:>9} {:>9}  parameters per half-plane",
        "model",
        "par.",
        "rms",
        "LOO rms",
        "LOO max"
    )?;
    let score = |v: Option<f64>| v.map_or("-".to_string(), num);
    for c in &fit.candidates {
        let mark = if c.model == fit.model { "*" } else { " " };
        outln!(
            "{mark} {:<11} {:>5} {:>9} {:>9} {:>9}  {}",
            c.model.name(),
            c.parameters,
            score(c.rms),
            score(c.cv_rms),
            score(c.cv_max),
            c.note.as_deref().unwrap_or("")
        )?;
        if c.parameters > 0 {
            for h in &c.halves {
                outln!("      {:<20} {}", h.half.to_string(), h.params.describe())?;
            }
        }
    }
    outln!("chose {}", fit.why)?;
    if let Some(e) = fit.extrapolation() {
        outln!("note: {}", e.sentence())?;
    }
    outln!("residuals (reading/normal − fitted):")?;
    for plane in [Plane::Horizontal, Plane::Vertical] {
        let cells: Vec<String> = fit
            .residuals
            .iter()
            .filter(|r| r.plane == plane)
            .map(|r| format!("{:+}°:{:+.4}", r.angle_deg, r.residual))
            .collect();
        outln!("  {plane:<10} {}", cells.join(" "))?;
    }
    Ok(())
}

/// A number for a table: 5 significant digits in at most 9 characters, in exponent form
/// outside 0.001 … 99999 so that a tiny or a huge value keeps its column.
fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if !v.is_finite() {
        format!("{v}")
    } else if (1e-3..1e5).contains(&a) {
        let decimals = (4 - a.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

fn run_show(a: ShowArgs) -> CliResult {
    let (table, p) = job::show(&a.file).map_err(light_error)?;
    print_photometry(&a.file, &table, &p)
}

fn print_photometry(file: &std::path::Path, table: &CGammaTable, p: &Photometry) -> CliResult {
    outln!("{}: {}", file.display(), p.format)?;
    if let Some(enc) = &p.text_encoding {
        outln!("  text lines read as {enc} (not UTF-8)")?;
    }
    for (key, text) in &p.labels {
        outln!("  {key:<11} {text}")?;
    }
    outln!(
        "  C-planes: {} stored, symmetry {}; {} after expansion; γ 0…90° in {} steps",
        p.stored_planes,
        p.symmetry,
        table.c_deg().len(),
        table.gamma_deg().len() - 1
    )?;
    outln!(
        "  candela: {} … {} cd (normal {} cd)",
        num(p.min_intensity_cd),
        num(p.max_intensity_cd),
        num(p.normal_intensity_cd)
    )?;
    match p.normal_luminance_cd_m2() {
        Some(l) => outln!(
            "  luminous opening {} m × {} m ({} m²): normal luminance {} cd/m²",
            num(p.width_m),
            num(p.height_m),
            num(p.area_m2),
            num(l)
        ),
        None => outln!("  no luminous opening given: luminance unknown"),
    }?;
    outln!("  flux {} lm (front hemisphere)", num(p.flux_lm))?;
    if p.max_backward_cd > 0.0 {
        outln!(
            "  up to {} cd behind the panel (γ > 90°), left out of the distribution",
            num(p.max_backward_cd)
        )?;
    }
    outln!("  relative luminance f(C, γ):")?;
    let gammas = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0];
    let head: String = gammas
        .iter()
        .map(|g| format!(" {:>9}", format!("{g}°")))
        .collect();
    outln!("    {:<6}{head}", "C \\ γ")?;
    for h in HalfPlane::ALL {
        let cells: String = gammas
            .iter()
            .map(|&g| format!(" {:>9}", num(table.at(h.c_deg(), g))))
            .collect();
        outln!("    {:<6}{cells}", format!("C{}", h.c_deg()))?;
    }
    Ok(())
}
