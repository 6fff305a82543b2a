//! `metamer light`: fit the light distribution curve to a fall-off table and export it as
//! IES/EULUMDAT; show what a photometric file holds.

use std::path::PathBuf;

use clap::Subcommand;

use super::{CliError, CliResult};
use metamer::light::chart::ldc_chart_svg;
use metamer::light::fit::{HalfPlane, Plane};
use metamer::light::ies::{self, IesInfo};
use metamer::light::ldt::{self, LdtInfo};
use metamer::light::{fit, flux_lm, CGammaTable, Falloff, LdcFit, ModelChoice, Panel, Photometry};
use metamer::output::{OutputError, OutputPolicy};

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

fn run_fit(a: FitArgs) -> CliResult {
    let exports = a.ies.is_some() || a.ldt.is_some();
    let panel_size = match (a.width_m, a.height_m) {
        (Some(w), Some(h)) => Some((w, h)),
        (None, None) if !exports => None,
        _ => {
            return Err(CliError::Usage(
                "--ies and --ldt need the panel's size: give both --width-m and --height-m".into(),
            ))
        }
    };
    let mut policy = OutputPolicy::new(a.force);
    policy.input(&a.falloff);
    let outputs = [
        Some(&a.output),
        a.ies.as_ref(),
        a.ldt.as_ref(),
        a.chart.as_ref(),
    ];
    let outputs: Vec<&PathBuf> = outputs.into_iter().flatten().collect();
    for (i, out) in outputs.iter().enumerate() {
        // Two outputs on one path: the second would be refused as existing, after the
        // first was written over it.
        if outputs[..i].iter().any(|o| same_path(o, out)) {
            return Err(CliError::Usage(format!(
                "{} is given for two outputs; each needs its own file",
                out.display()
            )));
        }
        policy.check(out).map_err(output_error)?;
    }
    let falloff = Falloff::read_csv(&a.falloff)?;
    // The panel and its luminance are checked before anything is fitted or written, so a
    // bad --width-m does not leave the fit written and the light files missing.
    let panel = match panel_size {
        None => None,
        Some((w, h)) => {
            let l0 = match a.luminance {
                Some(l) => l,
                None => {
                    let normal = falloff.validate().map_err(|e| {
                        CliError::Failed(format!("{}: {e}", a.falloff.display()).into())
                    })?;
                    let l0 = (normal[0] + normal[1]) / 2.0;
                    if l0 == 1.0 {
                        return Err(CliError::Usage(
                            "the readings are relative (1 at the normal): give the panel's \
                             luminance with --luminance CD_M2"
                                .into(),
                        ));
                    }
                    l0
                }
            };
            Some(Panel::new(w, h, l0).map_err(|e| CliError::Usage(e.to_string()))?)
        }
    };
    let fit = fit(&falloff, a.model)
        .map_err(|e| CliError::Failed(format!("{}: {e}", a.falloff.display()).into()))?;
    print_fit(&a.falloff, &fit);
    let json = serde_json::to_string_pretty(&fit)?;
    policy
        .write(&a.output, json.as_bytes())
        .map_err(output_error)?;
    println!("fit written to {}", a.output.display());
    if let Some(chart) = &a.chart {
        let svg = ldc_chart_svg(&fit)?;
        policy.write(chart, svg.as_bytes()).map_err(output_error)?;
        println!("chart written to {}", chart.display());
    }
    if let Some(panel) = panel {
        let (w, h, l0) = (panel.width_m, panel.height_m, panel.normal_luminance_cd_m2);
        let flux = flux_lm(&fit.table, &panel);
        println!(
            "panel {w} m × {h} m at {l0} cd/m²: I₀ = {:.4} cd, flux {:.4} lm",
            panel.normal_intensity_cd(),
            flux
        );
        let date = today();
        let luminaire = format!(
            "flat panel {w} m x {h} m, {} light distribution fitted to {}",
            fit.model,
            a.falloff.display()
        );
        if let Some(path) = &a.ies {
            let info = IesInfo {
                test: format!("metamer light fit {}", a.falloff.display()),
                issue_date: date.clone(),
                luminaire: luminaire.clone(),
                generation: format!("metamer light fit, model {}", fit.model),
            };
            let text = ies::to_string(&fit.table, &panel, &info);
            policy.write(path, text.as_bytes()).map_err(output_error)?;
            println!("IES written to {}", path.display());
        }
        if let Some(path) = &a.ldt {
            let info = LdtInfo {
                luminaire,
                file_name: path
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                date_user: format!("{date} metamer"),
            };
            let text = ldt::to_string(&fit.table, &panel, &info);
            policy.write(path, text.as_bytes()).map_err(output_error)?;
            println!("EULUMDAT written to {}", path.display());
        }
    }
    Ok(())
}

/// Whether two output paths name one file: spelled alike, or (when it exists) the same
/// file by another name.
fn same_path(a: &std::path::Path, b: &std::path::Path) -> bool {
    a == b
        || matches!(
            (std::fs::canonicalize(a), std::fs::canonicalize(b)),
            (Ok(x), Ok(y)) if x == y
        )
}

fn print_fit(source: &std::path::Path, fit: &LdcFit) {
    println!(
        "{}: normal luminance {} (horizontal {}, vertical {} at 0°)",
        source.display(),
        num(fit.normal_luminance),
        num(fit.normal_readings[0]),
        num(fit.normal_readings[1])
    );
    println!(
        "  {:<11} {:>5} {:>9} {:>9} {:>9}  parameters per half-plane",
        "model", "par.", "rms", "LOO rms", "LOO max"
    );
    let score = |v: Option<f64>| v.map_or("-".to_string(), num);
    for c in &fit.candidates {
        let mark = if c.model == fit.model { "*" } else { " " };
        println!(
            "{mark} {:<11} {:>5} {:>9} {:>9} {:>9}  {}",
            c.model.name(),
            c.parameters,
            score(c.rms),
            score(c.cv_rms),
            score(c.cv_max),
            c.note.as_deref().unwrap_or("")
        );
        if c.parameters > 0 {
            for h in &c.halves {
                println!("      {:<20} {}", h.half.to_string(), h.params.describe());
            }
        }
    }
    println!("chose {}", fit.why);
    println!("residuals (reading/normal − fitted):");
    for plane in [Plane::Horizontal, Plane::Vertical] {
        let cells: Vec<String> = fit
            .residuals
            .iter()
            .filter(|r| r.plane == plane)
            .map(|r| format!("{:+}°:{:+.4}", r.angle_deg, r.residual))
            .collect();
        println!("  {plane:<10} {}", cells.join(" "));
    }
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
    let ext = a
        .file
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let (table, p) = match ext.as_str() {
        "ies" => ies::read(&a.file)?,
        "ldt" => ldt::read(&a.file)?,
        _ => {
            return Err(CliError::Usage(format!(
                "{}: expected a .ies or .ldt file",
                a.file.display()
            )))
        }
    };
    print_photometry(&a.file, &table, &p);
    Ok(())
}

fn print_photometry(file: &std::path::Path, table: &CGammaTable, p: &Photometry) {
    println!("{}: {}", file.display(), p.format);
    if let Some(enc) = &p.text_encoding {
        println!("  text lines read as {enc} (not UTF-8)");
    }
    for (key, text) in &p.labels {
        println!("  {key:<11} {text}");
    }
    println!(
        "  C-planes: {} stored, symmetry {}; {} after expansion; γ 0…90° in {} steps",
        p.stored_planes,
        p.symmetry,
        table.c_deg().len(),
        table.gamma_deg().len() - 1
    );
    println!(
        "  candela: {} … {} cd (normal {} cd)",
        num(p.min_intensity_cd),
        num(p.max_intensity_cd),
        num(p.normal_intensity_cd)
    );
    match p.normal_luminance_cd_m2() {
        Some(l) => println!(
            "  luminous opening {} m × {} m ({} m²): normal luminance {} cd/m²",
            num(p.width_m),
            num(p.height_m),
            num(p.area_m2),
            num(l)
        ),
        None => println!("  no luminous opening given: luminance unknown"),
    }
    println!("  flux {} lm (front hemisphere)", num(p.flux_lm));
    if p.max_backward_cd > 0.0 {
        println!(
            "  up to {} cd behind the panel (γ > 90°), left out of the distribution",
            num(p.max_backward_cd)
        );
    }
    println!("  relative luminance f(C, γ):");
    let gammas = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0];
    let head: String = gammas
        .iter()
        .map(|g| format!(" {:>9}", format!("{g}°")))
        .collect();
    println!("    {:<6}{head}", "C \\ γ");
    for h in HalfPlane::ALL {
        let cells: String = gammas
            .iter()
            .map(|&g| format!(" {:>9}", num(table.at(h.c_deg(), g))))
            .collect();
        println!("    {:<6}{cells}", format!("C{}", h.c_deg()));
    }
}

/// Today's date (UTC) as YYYY-MM-DD, for the files' issue date.
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let (y, m, d) = civil_from_days((secs / 86_400) as i64);
    format!("{y:04}-{m:02}-{d:02}")
}

/// The proleptic Gregorian date of a day count since 1970-01-01 (eras of 400 years).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::civil_from_days;

    #[test]
    fn dates_from_day_counts() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        // 2000-03-01 is day 11017; 2024-02-29 is day 19782 (a leap day).
        assert_eq!(civil_from_days(11_017), (2000, 3, 1));
        assert_eq!(civil_from_days(19_782), (2024, 2, 29));
    }
}
