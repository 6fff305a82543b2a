//! `metamer color …`: spectra to XYZ/xyY/CIELAB, and colour differences of Lab pairs.

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use metamer::color::{
    pair_differences, spectra_xyz, ColorJobError, Integration, ObserverKind, Quantity, XyzRequest,
};

use super::{parse_triple, CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: ColorCommand,
}

#[derive(Subcommand)]
enum ColorCommand {
    /// XYZ, xyY and CIELAB of a spectrum (every value column of the CSV).
    Xyz(XyzArgs),
    /// ΔE*ab 1976 and CIEDE2000 of Lab pairs.
    DeltaE(DeltaEArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum QuantityArg {
    /// W·sr⁻¹·m⁻²·nm⁻¹, giving absolute XYZ in cd/m² (K_m = 683 lm/W).
    Radiance,
    /// Reflectance factor 0–1 under --illuminant, giving Y = 100 for white; the end values
    /// are held outside the table's range.
    Reflectance,
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    /// CIE 15:2018's standard method: a spectrum on an even grid coarser than 1 nm (5 nm,
    /// an i1Pro's 10 nm) is interpolated to 1 nm by Sprague (CIE 167:2005), held at its end
    /// values beyond its range and summed over 360–830 nm; a spectrum at 1 nm is summed as
    /// given, over 380–780 nm.
    Cie15,
    /// Linear interpolation to 1 nm, a radiance zero and a reflectance held outside its
    /// table, summed over 380–780 nm (paper Eq. 8; what the renderer and the validation box
    /// do with their tables).
    Linear,
}

#[derive(clap::Args)]
struct XyzArgs {
    /// Spectral CSV: '#' comments, header 'nm,…', rows of wavelength and values.
    spectrum: PathBuf,
    #[arg(long, value_enum, default_value = "radiance")]
    quantity: QuantityArg,
    /// D65, D50, A, FL11, LED-RGB1, LED-B3, or a spectral CSV file.
    #[arg(long, default_value = "D65")]
    illuminant: String,
    /// Colour-matching functions: 1931 (2°) or 1964 (10°).
    #[arg(long, default_value = "1931", value_parser = parse_observer)]
    observer: ObserverKind,
    /// Reference white X,Y,Z for CIELAB (default for reflectance: the illuminant's white).
    #[arg(long, value_parser = parse_triple)]
    white: Option<[f64; 3]>,
    /// Only this column (its header name, or the number before ':' in ColorChecker files).
    #[arg(long)]
    column: Option<String>,
    /// How the samples are integrated (protocols/color/README.md compares the two with
    /// ArgyllCMS and colour-science).
    #[arg(long, value_enum, default_value = "cie15")]
    method: MethodArg,
    /// JSON: one object per column, one per line.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct DeltaEArgs {
    /// CSV with the header 'L1,a1,b1,L2,a2,b2' and one pair per row.
    #[arg(long)]
    pairs: PathBuf,
    /// JSON: an array of {"de76":…,"de00":…} in row order.
    #[arg(long)]
    json: bool,
}

fn parse_observer(s: &str) -> Result<ObserverKind, String> {
    s.parse()
        .map_err(|e: metamer::color::ColorError| e.to_string())
}

pub fn run(args: Args) -> CliResult {
    match args.command {
        ColorCommand::Xyz(a) => xyz(a),
        ColorCommand::DeltaE(a) => delta_e(a),
    }
}

fn color_error(e: ColorJobError) -> CliError {
    match e {
        ColorJobError::UnknownIlluminant(_) => CliError::Usage(e.to_string()),
        // The range summed over is the method's: the flag that chose it is named.
        ColorJobError::OutsideSummation {
            method: Integration::Linear,
            ..
        } => CliError::Failed(format!("{e} with --method linear").into()),
        ColorJobError::NotFinite { .. }
        | ColorJobError::PairNotFinite { .. }
        | ColorJobError::OneSample { .. }
        | ColorJobError::OutsideSummation { .. } => CliError::Failed(e.to_string().into()),
        ColorJobError::Color(e) => CliError::from(e),
        ColorJobError::Csv(e) => CliError::from(e),
        ColorJobError::Event(e) => CliError::from(e),
    }
}

fn xyz(a: XyzArgs) -> CliResult {
    let request = XyzRequest {
        spectrum: a.spectrum,
        quantity: match a.quantity {
            QuantityArg::Radiance => Quantity::Radiance,
            QuantityArg::Reflectance => Quantity::Reflectance,
        },
        illuminant: a.illuminant,
        observer: a.observer,
        white: a.white.map(Into::into),
        column: a.column,
        method: match a.method {
            MethodArg::Cie15 => Integration::Cie15,
            MethodArg::Linear => Integration::Linear,
        },
    };
    spectra_xyz(&request, &mut |c| {
        let d = &c.description;
        if a.json {
            let mut obj = serde_json::json!({
                "XYZ": d.xyz.to_array(),
                "xyY": d.xyy.to_array(),
            });
            if let Some(lab) = d.lab {
                obj["Lab"] = serde_json::json!(lab.to_array());
            }
            if c.named {
                obj["column"] = serde_json::json!(c.name);
            }
            outln!("{obj}")?;
        } else {
            let lab = d
                .lab
                .map(|l| format!("  L*a*b* {:8.3} {:8.3} {:8.3}", l.l, l.a, l.b))
                .unwrap_or_default();
            outln!(
                "{:<24} XYZ {:10.4} {:10.4} {:10.4}  xyY {:.5} {:.5} {:10.4}{lab}",
                c.name,
                d.xyz.x,
                d.xyz.y,
                d.xyz.z,
                d.xyy.x,
                d.xyy.y,
                d.xyy.luminance
            )?;
        }
        Ok(())
    })
    .map_err(color_error)
}

fn delta_e(a: DeltaEArgs) -> CliResult {
    let results = pair_differences(&a.pairs).map_err(color_error)?;
    if a.json {
        let arr: Vec<_> = results
            .iter()
            .map(|(d76, d00)| serde_json::json!({"de76": d76, "de00": d00}))
            .collect();
        outln!("{}", serde_json::Value::Array(arr))?;
    } else {
        outln!("{:>5} {:>10} {:>10}", "row", "dE76", "dE00")?;
        for (i, (d76, d00)) in results.iter().enumerate() {
            outln!("{:>5} {d76:>10.4} {d00:>10.4}", i + 1)?;
        }
    }
    Ok(())
}
