//! `metamer color …`: spectra to XYZ/xyY/CIELAB, and colour differences of Lab pairs.

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use metamer::color::{
    delta_e2000, delta_e76, describe, Illuminant, Lab, ObserverKind, Outside, Quantity,
    SpectralTable, Spectrum, Xyz,
};
use metamer::numeric_csv::NumericCsv;

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

fn load_illuminant(name: &str) -> Result<Spectrum, CliError> {
    if let Ok(known) = name.parse::<Illuminant>() {
        return Ok(known.spectrum());
    }
    let path = PathBuf::from(name);
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
        || path.exists()
    {
        return Ok(SpectralTable::read(&path)?.first());
    }
    Err(CliError::Usage(format!(
        "unknown illuminant '{name}': use D65, D50, A, FL11, LED-RGB1, LED-B3 or a CSV file"
    )))
}

fn xyz(a: XyzArgs) -> CliResult {
    let table = SpectralTable::read(&a.spectrum)?;
    let illuminant = load_illuminant(&a.illuminant)?;
    let (quantity, outside) = match a.quantity {
        QuantityArg::Radiance => (Quantity::Radiance, Outside::Zero),
        QuantityArg::Reflectance => (Quantity::Reflectance, Outside::HoldEnds),
    };
    let columns: Vec<(String, Spectrum)> = match &a.column {
        Some(name) => vec![(name.clone(), table.column(name)?)],
        None => table
            .columns
            .iter()
            .cloned()
            .zip(table.all(Outside::Zero))
            .collect(),
    };
    let white = a.white.map(Xyz::from_array);
    // A chosen column is named in the output, as every column of a file with several is.
    let named = columns.len() > 1 || a.column.is_some();
    for (name, spectrum) in columns {
        let spectrum = match a.method {
            MethodArg::Cie15 => spectrum.with_outside(outside).as_measured(),
            MethodArg::Linear => spectrum.with_outside(outside),
        };
        let d = describe(&spectrum, quantity, &illuminant, a.observer, white);
        let mut numbers: Vec<f64> = d.xyz.to_array().into();
        numbers.extend(d.xyy.to_array());
        numbers.extend(d.lab.map(|l| l.to_array()).into_iter().flatten());
        if numbers.iter().any(|v| !v.is_finite()) {
            return Err(CliError::Failed(
                format!(
                    "{}: column '{}': the result is not a finite number (XYZ {:?}): the \
                     values are too large to integrate, or the white has no luminance",
                    a.spectrum.display(),
                    metamer::color::text::echo(&name),
                    d.xyz.to_array()
                )
                .into(),
            ));
        }
        if a.json {
            let mut obj = serde_json::json!({
                "XYZ": d.xyz.to_array(),
                "xyY": d.xyy.to_array(),
            });
            if let Some(lab) = d.lab {
                obj["Lab"] = serde_json::json!(lab.to_array());
            }
            if named {
                obj["column"] = serde_json::json!(name);
            }
            println!("{obj}");
        } else {
            let lab = d
                .lab
                .map(|l| format!("  L*a*b* {:8.3} {:8.3} {:8.3}", l.l, l.a, l.b))
                .unwrap_or_default();
            println!(
                "{name:<24} XYZ {:10.4} {:10.4} {:10.4}  xyY {:.5} {:.5} {:10.4}{lab}",
                d.xyz.x, d.xyz.y, d.xyz.z, d.xyy.x, d.xyy.y, d.xyy.luminance
            );
        }
    }
    Ok(())
}

fn delta_e(a: DeltaEArgs) -> CliResult {
    let csv = NumericCsv::read(&a.pairs, &["L1", "a1", "b1", "L2", "a2", "b2"])?;
    let mut results: Vec<(f64, f64)> = Vec::with_capacity(csv.rows.len());
    for (line, v) in &csv.rows {
        let p = Lab::new(v[0], v[1], v[2]);
        let q = Lab::new(v[3], v[4], v[5]);
        let (d76, d00) = (delta_e76(p, q), delta_e2000(p, q));
        // Finite Lab values far beyond any colour (1e308) overflow the formulas.
        if !d76.is_finite() || !d00.is_finite() {
            return Err(CliError::Failed(
                format!(
                    "{}:{line}: the colour difference is not a finite number (ΔE*ab {d76}, \
                     ΔE00 {d00}): L*a*b* values of real colours lie within a few hundred",
                    a.pairs.display()
                )
                .into(),
            ));
        }
        results.push((d76, d00));
    }
    if a.json {
        let arr: Vec<_> = results
            .iter()
            .map(|(d76, d00)| serde_json::json!({"de76": d76, "de00": d00}))
            .collect();
        println!("{}", serde_json::Value::Array(arr));
    } else {
        println!("{:>5} {:>10} {:>10}", "row", "dE76", "dE00");
        for (i, (d76, d00)) in results.iter().enumerate() {
            println!("{:>5} {d76:>10.4} {d00:>10.4}", i + 1);
        }
    }
    Ok(())
}
