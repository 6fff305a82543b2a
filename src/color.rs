//! The colour core, which lives in the `metamer-color` crate so the instrument drivers
//! compute XYZ with the same code and the same CIE tables; re-exported here so the library
//! keeps one `color` path.
//!
//! `metamer color`'s jobs are here as library calls: [`spectra_xyz`] (XYZ, xyY and CIELAB
//! of a spectral CSV's columns) and [`pair_differences`] (ΔE of Lab pairs).

use std::path::{Path, PathBuf};

pub use metamer_color::*;

use crate::numeric_csv::{CsvError, NumericCsv};

/// Why a colour job did not finish.
#[derive(Debug, thiserror::Error)]
pub enum ColorJobError {
    /// The illuminant is neither a known name nor a file: the command line calls it a usage
    /// error.
    #[error("unknown illuminant '{0}': use D65, D50, A, FL11, LED-RGB1, LED-B3 or a CSV file")]
    UnknownIlluminant(String),
    #[error(transparent)]
    Color(#[from] ColorError),
    #[error(transparent)]
    Csv(#[from] CsvError),
    /// The caller's handling of a column failed (e.g. its output closed).
    #[error(transparent)]
    Event(#[from] std::io::Error),
    /// One row is a single wavelength: a sum over Δλ (CIE 15:2018 §7.1) needs at least
    /// two, and reading one sample as a 1 nm line or as a flat spectrum would be a guess.
    #[error(
        "{}:{line}: the spectrum has one row ({nm} nm): XYZ is a sum over wavelength steps \
         (CIE 15:2018 §7.1), so give at least two rows; for a single line, give the samples \
         either side of it as 0",
        file.display()
    )]
    OneSample { file: PathBuf, line: usize, nm: f64 },
    /// No sample lies where the colour-matching functions are summed, so the result would
    /// be zero, or (a reflectance held at its end values) a flat spectrum nobody measured.
    /// The range is `method`'s.
    #[error(
        "{}:{first_line}: column '{}': its samples ({first_nm}–{last_nm} nm) lie outside \
         {start_nm}–{end_nm} nm, the wavelengths the colour-matching functions are summed \
         over",
        file.display(), text::echo(column)
    )]
    OutsideSummation {
        file: PathBuf,
        first_line: usize,
        column: String,
        first_nm: f64,
        last_nm: f64,
        start_nm: i32,
        end_nm: i32,
        method: Integration,
    },
    /// A column's result overflowed.
    #[error(
        "{}: column '{}': the result is not a finite number (XYZ {xyz:?}): the values are too \
         large to integrate, or the white has no luminance",
        file.display(), text::echo(column)
    )]
    NotFinite {
        file: PathBuf,
        column: String,
        xyz: [f64; 3],
    },
    /// A pair's difference overflowed.
    #[error(
        "{}:{line}: the colour difference is not a finite number (ΔE*ab {de76}, ΔE00 {de00}): \
         L*a*b* values of real colours lie within a few hundred",
        file.display()
    )]
    PairNotFinite {
        file: PathBuf,
        line: usize,
        de76: f64,
        de00: f64,
    },
}

/// How a spectrum's samples are integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integration {
    /// CIE 15:2018's standard method: a grid coarser than 1 nm is interpolated to 1 nm by
    /// Sprague, held at its end values beyond its range and summed over 360–830 nm; a
    /// spectrum at 1 nm is summed as given, over 380–780 nm.
    Cie15,
    /// Linear interpolation to 1 nm, a radiance zero and a reflectance held outside its
    /// table, summed over 380–780 nm (paper Eq. 8; what the renderer does).
    Linear,
}

/// What `color xyz` is asked to do.
#[derive(Clone, Debug)]
pub struct XyzRequest {
    /// Spectral CSV: '#' comments, header 'nm,…', rows of wavelength and values.
    pub spectrum: PathBuf,
    /// Radiance (absolute XYZ in cd/m²) or reflectance (Y = 100 for white, the end values
    /// held outside the table's range).
    pub quantity: Quantity,
    /// D65, D50, A, FL11, LED-RGB1, LED-B3, or a spectral CSV file.
    pub illuminant: String,
    pub observer: ObserverKind,
    /// Reference white for CIELAB (default for reflectance: the illuminant's white).
    pub white: Option<Xyz>,
    /// Only this column.
    pub column: Option<String>,
    pub method: Integration,
}

/// One column's colour.
#[derive(Clone, Debug)]
pub struct ColumnColor {
    pub name: String,
    /// Whether the output names the column: a chosen one, or one of several.
    pub named: bool,
    pub description: Description,
}

/// XYZ, xyY and CIELAB of every column of `request.spectrum` (or the one asked for), each
/// handed to `each` as it is computed: a later column that overflows does not hide the
/// earlier ones.
///
/// # Examples
///
/// ```
/// use metamer::color::{spectra_xyz, Integration, ObserverKind, Quantity, XyzRequest};
///
/// let request = XyzRequest {
///     spectrum: concat!(env!("CARGO_MANIFEST_DIR"), "/data/paper_white_reflectance.csv").into(),
///     quantity: Quantity::Reflectance,
///     illuminant: "D65".into(),
///     observer: ObserverKind::Cie1931,
///     white: None,
///     column: None,
///     method: Integration::Cie15,
/// };
/// let mut columns = Vec::new();
/// spectra_xyz(&request, &mut |c| {
///     columns.push(c);
///     Ok(())
/// })
/// .unwrap();
/// // A white paper under D65: Y near 100, and a CIELAB against D65's white.
/// let d = &columns[0].description;
/// assert!(d.xyz.y > 50.0 && d.xyz.y <= 110.0);
/// assert!(d.lab.is_some());
/// ```
pub fn spectra_xyz(
    request: &XyzRequest,
    each: &mut dyn FnMut(ColumnColor) -> std::io::Result<()>,
) -> Result<(), ColorJobError> {
    let table = SpectralTable::read(&request.spectrum)?;
    let illuminant = load_illuminant(&request.illuminant)?;
    let outside = match request.quantity {
        Quantity::Reflectance => Outside::HoldEnds,
        _ => Outside::Zero,
    };
    let columns: Vec<(String, Spectrum)> = match &request.column {
        Some(name) => vec![(name.clone(), table.column(name)?)],
        None => table
            .columns
            .iter()
            .cloned()
            .zip(table.all(Outside::Zero))
            .collect(),
    };
    if let ([nm], [line]) = (&table.wavelengths_nm[..], &table.lines[..]) {
        return Err(ColorJobError::OneSample {
            file: request.spectrum.clone(),
            line: *line,
            nm: *nm,
        });
    }
    let white = request.white;
    let named = columns.len() > 1 || request.column.is_some();
    for (name, spectrum) in columns {
        let spectrum = match request.method {
            Integration::Cie15 => spectrum.with_outside(outside).as_measured(),
            Integration::Linear => spectrum.with_outside(outside),
        };
        let range = summation_range(&spectrum);
        let (first_nm, last_nm) = spectrum.range_nm();
        if last_nm < f64::from(*range.start()) || first_nm > f64::from(*range.end()) {
            return Err(ColorJobError::OutsideSummation {
                file: request.spectrum.clone(),
                first_line: table.lines[0],
                column: name,
                first_nm,
                last_nm,
                start_nm: *range.start(),
                end_nm: *range.end(),
                method: request.method,
            });
        }
        let d = describe(
            &spectrum,
            request.quantity,
            &illuminant,
            request.observer,
            white,
        );
        let mut numbers: Vec<f64> = d.xyz.to_array().into();
        numbers.extend(d.xyy.to_array());
        numbers.extend(d.lab.map(|l| l.to_array()).into_iter().flatten());
        if numbers.iter().any(|v| !v.is_finite()) {
            return Err(ColorJobError::NotFinite {
                file: request.spectrum.clone(),
                column: name,
                xyz: d.xyz.to_array(),
            });
        }
        each(ColumnColor {
            name,
            named,
            description: d,
        })?;
    }
    Ok(())
}

/// A named illuminant, or the first column of a spectral CSV.
fn load_illuminant(name: &str) -> Result<Spectrum, ColorJobError> {
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
    Err(ColorJobError::UnknownIlluminant(name.to_string()))
}

/// ΔE*ab 1976 and CIEDE2000 of each pair of a CSV with the header `L1,a1,b1,L2,a2,b2`,
/// in row order.
///
/// # Examples
///
/// ```
/// let file = std::env::temp_dir().join(format!("metamer-doc-pairs-{}.csv", std::process::id()));
/// std::fs::write(&file, "L1,a1,b1,L2,a2,b2\n50,2.6772,-79.7751,50,0,-82.7485\n").unwrap();
/// let d = metamer::color::pair_differences(&file).unwrap();
/// // Sharma, Wu and Dalal's first pair: ΔE00 = 2.0425.
/// assert!((d[0].1 - 2.0425).abs() < 1e-4);
/// # std::fs::remove_file(&file).unwrap();
/// ```
pub fn pair_differences(pairs: &Path) -> Result<Vec<(f64, f64)>, ColorJobError> {
    let csv = NumericCsv::read(pairs, &["L1", "a1", "b1", "L2", "a2", "b2"])?;
    let mut results: Vec<(f64, f64)> = Vec::with_capacity(csv.rows.len());
    for (line, v) in &csv.rows {
        let p = Lab::new(v[0], v[1], v[2]);
        let q = Lab::new(v[3], v[4], v[5]);
        let (de76, de00) = (delta_e76(p, q), delta_e2000(p, q));
        // Finite Lab values far beyond any colour (1e308) overflow the formulas.
        if !de76.is_finite() || !de00.is_finite() {
            return Err(ColorJobError::PairNotFinite {
                file: pairs.to_path_buf(),
                line: *line,
                de76,
                de00,
            });
        }
        results.push((de76, de00));
    }
    Ok(results)
}
