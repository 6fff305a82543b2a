//! Measured patch files: ArgyllCMS CGATS `.ti3` (as `dispread` writes them) and plain CSV
//! `r,g,b,X,Y,Z` (drive values 0–1, XYZ in cd/m²).
//!
//! Facts about `.ti3` (ArgyllCMS documentation `doc/ti3_format.html`, and how `colprof`
//! reads display data): the file starts with the identifier `CTI3`; device values
//! `RGB_R RGB_G RGB_B` are percentages 0–100; for `DEVICE_CLASS "DISPLAY"` the XYZ values are
//! normalised so that the white has Y = 100 unless the keyword `NORMALIZED_TO_Y_100` is
//! `"NO"`, and the keyword `LUMINANCE_XYZ_CDM2 "X Y Z"` gives the white's absolute XYZ in
//! cd/m², so absolute = value × LUMINANCE_Y / 100. The first table holds the measurements;
//! dispread and DisplayCAL may append a second table with the identifier `CAL` and fields
//! `RGB_I RGB_R RGB_G RGB_B` (the video-card curves loaded while measuring, 0–1), which is
//! kept. Fields `SPEC_nnn` (a spectrometer's readings at nnn nm) are kept as spectra;
//! `SAMPLE_ID` and other fields are optional and ignored, keywords may come in any order.

use std::path::{Path, PathBuf};

mod calibration;
mod tokens;
mod write;

use calibration::calibration_table;
pub use calibration::CalibrationEntry;
use tokens::tokens;

pub use write::write_ti3;

use super::model::Sample;
use crate::color::Xyz;
use crate::numeric_csv::{CsvError, NumericCsv};

/// What is wrong with a measurement file; every variant names the file, most the line.
#[derive(Debug, thiserror::Error)]
pub enum MeasurementsError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Csv(#[from] CsvError),
    #[error("{file}:{line}: {message}")]
    Cgats {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{file}: {message}")]
    File { file: PathBuf, message: String },
}

/// A measurement file as read: the patches (absolute cd/m² when `absolute`) and how the
/// XYZ scale was established.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurements {
    pub patches: Vec<Sample>,
    /// False when a `.ti3` holds only white-relative XYZ (Y = 100 at white, no
    /// `LUMINANCE_XYZ_CDM2`): the values are then taken as if the white had 100 cd/m².
    pub absolute: bool,
    /// Spectral readings when the file has `SPEC_nnn` fields, one per patch, in file order.
    pub spectra: Option<Spectra>,
    /// The `CAL` table's video-card curves, when the file has one.
    pub calibration: Option<Vec<CalibrationEntry>>,
}

/// Spectra of the patches: values at `wavelengths_nm`, in the file's units.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectra {
    pub wavelengths_nm: Vec<f64>,
    /// One row per patch, one value per wavelength.
    pub values: Vec<Vec<f64>>,
}

/// Reads `.ti3` (CGATS) or `.csv` by extension; relative `.ti3` data are returned as if the
/// white were 100 cd/m² (use [`read_measurement_file`] to know).
pub fn read_measurements(path: &Path) -> Result<Vec<Sample>, MeasurementsError> {
    read_measurement_file(path).map(|m| m.patches)
}

/// Reads `.ti3` (CGATS) or `.csv` by extension and tells whether the XYZ are absolute.
pub fn read_measurement_file(path: &Path) -> Result<Measurements, MeasurementsError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext == "csv" {
        let table = NumericCsv::read(path, &["r", "g", "b", "X", "Y", "Z"])?;
        let mut patches = Vec::with_capacity(table.rows.len());
        for (line, v) in &table.rows {
            let rgb = [v[0], v[1], v[2]];
            if rgb.iter().any(|d| !(0.0..=1.0).contains(d)) {
                return Err(MeasurementsError::Cgats {
                    file: path.to_path_buf(),
                    line: *line,
                    message: format!(
                        "drive values must lie in 0–1, found r,g,b = {},{},{}",
                        v[0], v[1], v[2]
                    ),
                });
            }
            let xyz = Xyz::new(v[3], v[4], v[5]);
            metamer_color::check_xyz(xyz).map_err(|e| MeasurementsError::Cgats {
                file: path.to_path_buf(),
                line: *line,
                message: format!("not a measurement: {e}"),
            })?;
            patches.push(Sample { rgb, xyz });
        }
        return Ok(Measurements {
            patches,
            absolute: true,
            spectra: None,
            calibration: None,
        });
    }
    let text = metamer_color::text::read_text(path).map_err(|source| MeasurementsError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    parse_ti3(&text, path)
}

/// Parses the first table of a CGATS `.ti3` text; `path` names it in errors.
pub fn parse_ti3(text: &str, path: &Path) -> Result<Measurements, MeasurementsError> {
    let text = metamer_color::text::strip_bom(text);
    let file = path.to_path_buf();
    // Messages quote fields of the file; any of them may be huge.
    let err = |(line, message): (usize, String)| MeasurementsError::Cgats {
        file: file.clone(),
        line,
        message: metamer_color::text::echo_message(&message),
    };
    let mut table = Table::default();
    let mut seen_identifier = false;
    let mut end_data = None;
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let toks = tokens(raw).map_err(|m| err((line, m)))?;
        if toks.is_empty() {
            continue;
        }
        if !seen_identifier {
            if toks[0] != "CTI3" {
                return Err(err((
                    line,
                    format!(
                        "not an ArgyllCMS .ti3 file: it must start with 'CTI3', found '{}'",
                        toks[0]
                    ),
                )));
            }
            seen_identifier = true;
            continue;
        }
        if table.line(line, &toks).map_err(err)? {
            end_data = Some(index);
            break;
        }
    }
    if !seen_identifier {
        return Err(MeasurementsError::File {
            file,
            message: "the file is empty".into(),
        });
    }
    let last = text.lines().count().max(1);
    let end_line = table.complete(end_data, last).map_err(err)?;
    let (scale, absolute) = table.scale().map_err(err)?;
    let patches = table.patches(scale).map_err(err)?;
    Ok(Measurements {
        patches,
        absolute,
        spectra: (!table.spectral.is_empty()).then(|| Spectra {
            wavelengths_nm: table.spectral.iter().map(|&(_, nm)| nm).collect(),
            values: table.spectra,
        }),
        calibration: calibration_table(text, end_line + 1).map_err(err)?,
    })
}

/// Where a `.ti3`'s first table is being read: CGATS puts keywords, then the field names
/// between `BEGIN_DATA_FORMAT` and `END_DATA_FORMAT`, then the rows up to `END_DATA`.
#[derive(Default)]
enum Section {
    #[default]
    Header,
    Format,
    Data,
}

/// A line's problem: its number and what is wrong.
type LineError = (usize, String);

/// What the first table's lines say, gathered line by line.
#[derive(Default)]
struct Table {
    section: Section,
    /// Keyword, value and line.
    keywords: Vec<(String, String, usize)>,
    fields: Vec<String>,
    /// `NUMBER_OF_FIELDS` and `NUMBER_OF_SETS` with their lines.
    declared_fields: Option<(usize, usize)>,
    declared_sets: Option<(usize, usize)>,
    /// Columns of RGB_R, RGB_G, RGB_B, XYZ_X, XYZ_Y, XYZ_Z; set at `BEGIN_DATA`.
    columns: Option<[usize; 6]>,
    rows: Vec<(usize, [f64; 6])>,
    /// Columns and wavelengths of the `SPEC_nnn` fields, and each row's values there.
    spectral: Vec<(usize, f64)>,
    spectra: Vec<Vec<f64>>,
}

impl Table {
    /// Reads one line after the identifier; true at `END_DATA`.
    fn line(&mut self, line: usize, toks: &[String]) -> Result<bool, LineError> {
        match self.section {
            Section::Header => self.header_line(line, toks)?,
            Section::Format => {
                if toks[0] == "END_DATA_FORMAT" {
                    self.section = Section::Header;
                } else {
                    self.fields.extend(toks.iter().cloned());
                }
            }
            Section::Data => {
                if toks[0] == "END_DATA" {
                    return Ok(true);
                }
                self.row(line, toks)?;
            }
        }
        Ok(false)
    }

    fn header_line(&mut self, line: usize, toks: &[String]) -> Result<(), LineError> {
        match toks[0].as_str() {
            "BEGIN_DATA_FORMAT" => {
                self.section = Section::Format;
                self.fields.extend(toks[1..].iter().cloned());
            }
            "NUMBER_OF_FIELDS" | "NUMBER_OF_SETS" => {
                let n = toks
                    .get(1)
                    .and_then(|t| t.parse::<usize>().ok())
                    .ok_or_else(|| (line, format!("{} needs a whole number", toks[0])))?;
                if toks[0] == "NUMBER_OF_FIELDS" {
                    self.declared_fields = Some((n, line));
                } else {
                    self.declared_sets = Some((n, line));
                }
            }
            "BEGIN_DATA" => {
                let cols = find_columns(&self.fields).map_err(|m| (line, m))?;
                if let Some((n, l)) = self.declared_fields {
                    if n != self.fields.len() {
                        return Err((
                            l,
                            format!(
                                "NUMBER_OF_FIELDS is {n} but the data format lists {} fields",
                                self.fields.len()
                            ),
                        ));
                    }
                }
                self.columns = Some(cols);
                self.spectral = spectral_columns(&self.fields).map_err(|m| (line, m))?;
                self.section = Section::Data;
            }
            "KEYWORD" => {}
            name => {
                let value = toks[1..].join(" ");
                self.keywords.push((name.to_string(), value, line));
            }
        }
        Ok(())
    }

    /// One data row: the device values and XYZ checked, the spectrum kept.
    fn row(&mut self, line: usize, toks: &[String]) -> Result<(), LineError> {
        let cols = self.columns.expect("set when the data began");
        if toks.len() != self.fields.len() {
            return Err((
                line,
                format!(
                    "expected {} values ({}), found {}",
                    self.fields.len(),
                    self.fields.join(" "),
                    toks.len()
                ),
            ));
        }
        let mut v = [0.0; 6];
        for (k, &c) in cols.iter().enumerate() {
            v[k] = self.number(line, toks, c)?;
        }
        for (k, name) in ["RGB_R", "RGB_G", "RGB_B"].iter().enumerate() {
            if !(0.0..=100.0).contains(&v[k]) {
                return Err((line, format!("{name} = {} is outside 0–100", v[k])));
            }
        }
        metamer_color::check_xyz(Xyz::new(v[3], v[4], v[5]))
            .map_err(|e| (line, format!("not a measurement: {e}")))?;
        if !self.spectral.is_empty() {
            let row = self
                .spectral
                .iter()
                .map(|&(c, _)| self.number(line, toks, c))
                .collect::<Result<Vec<f64>, LineError>>()?;
            self.spectra.push(row);
        }
        self.rows.push((line, v));
        Ok(())
    }

    /// Field `c` of a row as a finite number.
    fn number(&self, line: usize, toks: &[String], c: usize) -> Result<f64, LineError> {
        toks[c]
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| {
                (
                    line,
                    format!("field {} ('{}') is not a number", self.fields[c], toks[c]),
                )
            })
    }

    /// The table as a whole, once its lines are read (`end_data`: the index of its
    /// `END_DATA` line, `last`: the file's last line); returns `end_data`.
    fn complete(&self, end_data: Option<usize>, last: usize) -> Result<usize, LineError> {
        if self.columns.is_none() {
            return Err((last, "no BEGIN_DATA: the file holds no measurements".into()));
        }
        let Some(end_data) = end_data else {
            return Err((last, "END_DATA is missing: the file is cut short".into()));
        };
        if self.rows.is_empty() {
            return Err((last, "the data table has no rows".into()));
        }
        if let Some((n, l)) = self.declared_sets {
            if n != self.rows.len() {
                return Err((
                    l,
                    format!(
                        "NUMBER_OF_SETS is {n} but the data table has {} rows",
                        self.rows.len()
                    ),
                ));
            }
        }
        Ok(end_data)
    }

    fn keyword(&self, name: &str) -> Option<&(String, String, usize)> {
        self.keywords.iter().find(|(k, _, _)| k == name)
    }

    /// The factor from the file's XYZ to cd/m², and whether the result is absolute, from
    /// the keywords (`DEVICE_CLASS`, `NORMALIZED_TO_Y_100`, `LUMINANCE_XYZ_CDM2`).
    fn scale(&self) -> Result<(f64, bool), LineError> {
        if let Some((_, class, l)) = self.keyword("DEVICE_CLASS") {
            if class != "DISPLAY" {
                return Err((
                    *l,
                    format!("DEVICE_CLASS is \"{class}\"; display measurements need \"DISPLAY\""),
                ));
            }
        }
        let normalised = self
            .keyword("NORMALIZED_TO_Y_100")
            .is_none_or(|(_, v, _)| v != "NO");
        Ok(match (normalised, self.keyword("LUMINANCE_XYZ_CDM2")) {
            (false, _) => (1.0, true),
            (true, Some((_, value, l))) => {
                let xyz: Vec<f64> = value
                    .split_whitespace()
                    .filter_map(|t| t.parse::<f64>().ok())
                    .collect();
                if xyz.len() != 3
                    || xyz[1] <= 0.0
                    || metamer_color::check_xyz(Xyz::new(xyz[0], xyz[1], xyz[2])).is_err()
                {
                    return Err((
                        *l,
                        format!("LUMINANCE_XYZ_CDM2 must be three numbers X Y Z with Y > 0, found \"{value}\""),
                    ));
                }
                (xyz[1] / 100.0, true)
            }
            (true, None) => (1.0, false),
        })
    }

    /// The rows as patches: drive 0–1, XYZ times `scale`.
    fn patches(&self, scale: f64) -> Result<Vec<Sample>, LineError> {
        let mut patches = Vec::with_capacity(self.rows.len());
        for &(line, v) in &self.rows {
            let xyz = Xyz::new(v[3] * scale, v[4] * scale, v[5] * scale);
            // Each row passed alone; the white's luminance can still scale it past belief.
            metamer_color::check_xyz(xyz)
                .map_err(|e| (line, format!("not a measurement once scaled to cd/m²: {e}")))?;
            patches.push(Sample {
                rgb: [v[0] / 100.0, v[1] / 100.0, v[2] / 100.0],
                xyz,
            });
        }
        Ok(patches)
    }
}

/// Columns and wavelengths of `SPEC_nnn` fields, which must rise in wavelength.
fn spectral_columns(fields: &[String]) -> Result<Vec<(usize, f64)>, String> {
    let mut out: Vec<(usize, f64)> = Vec::new();
    for (c, f) in fields.iter().enumerate() {
        if let Some(nm) = f.strip_prefix("SPEC_") {
            let nm = nm
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("spectral field {f} does not end in a wavelength in nm"))?;
            if out.last().is_some_and(|&(_, last)| nm <= last) {
                return Err(format!(
                    "spectral field {f} does not follow a shorter wavelength"
                ));
            }
            out.push((c, nm));
        }
    }
    Ok(out)
}

fn find_columns(fields: &[String]) -> Result<[usize; 6], String> {
    let names = ["RGB_R", "RGB_G", "RGB_B", "XYZ_X", "XYZ_Y", "XYZ_Z"];
    let mut out = [0; 6];
    let missing: Vec<&str> = names
        .iter()
        .filter(|n| !fields.iter().any(|f| f == *n))
        .copied()
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "the data format lacks the field(s) {} (found: {})",
            missing.join(" "),
            fields.join(" ")
        ));
    }
    for (o, n) in out.iter_mut().zip(names) {
        *o = fields.iter().position(|f| f == n).expect("checked above");
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DISPREAD: &str = r#"CTI3   

DESCRIPTOR "Argyll Calibration Target chart information 3"

ORIGINATOR "Argyll dispread"

CREATED "Wed Jan 10 12:00:00 2024"
KEYWORD "DEVICE_CLASS"
DEVICE_CLASS "DISPLAY"
KEYWORD "COLOR_REP"
COLOR_REP "RGB_XYZ"
KEYWORD "LUMINANCE_XYZ_CDM2"
LUMINANCE_XYZ_CDM2 "190.10 200.00 217.76"
KEYWORD "NORMALIZED_TO_Y_100"
NORMALIZED_TO_Y_100 "YES"

NUMBER_OF_FIELDS 7
BEGIN_DATA_FORMAT
SAMPLE_ID RGB_R RGB_G RGB_B XYZ_X XYZ_Y XYZ_Z 
END_DATA_FORMAT

NUMBER_OF_SETS 2
BEGIN_DATA
1 100.00 100.00 100.00 95.05 100.00 108.88 
2 50.000 0.0000 0.0000 10.000 5.0000 0.5000 
END_DATA

CAL    

DESCRIPTOR "Argyll Device Calibration State"
"#;

    #[test]
    fn dispread_layout_is_scaled_to_absolute_by_luminance_y() {
        let m = parse_ti3(DISPREAD, Path::new("d.ti3")).unwrap();
        assert!(m.absolute);
        // absolute = value × 200 / 100
        assert_eq!(m.patches[0].rgb, [1.0, 1.0, 1.0]);
        assert!((m.patches[0].xyz[1] - 200.0).abs() < 1e-9);
        assert!((m.patches[0].xyz[0] - 190.1).abs() < 1e-9);
        assert_eq!(m.patches[1].rgb, [0.5, 0.0, 0.0]);
        assert!((m.patches[1].xyz[0] - 20.0).abs() < 1e-9);
        assert!((m.patches[1].xyz[2] - 1.0).abs() < 1e-9);
    }

    #[test]
    fn unnormalised_and_relative_files() {
        let abs = DISPREAD.replace("NORMALIZED_TO_Y_100 \"YES\"", "NORMALIZED_TO_Y_100 \"NO\"");
        let m = parse_ti3(&abs, Path::new("d.ti3")).unwrap();
        assert!(m.absolute);
        assert!((m.patches[0].xyz[1] - 100.0).abs() < 1e-12);
        let rel = DISPREAD.replace("LUMINANCE_XYZ_CDM2 \"190.10 200.00 217.76\"", "");
        let m = parse_ti3(&rel, Path::new("d.ti3")).unwrap();
        assert!(!m.absolute);
        assert!((m.patches[0].xyz[1] - 100.0).abs() < 1e-12);
    }

    #[test]
    fn bad_files_name_file_and_line() {
        let p = Path::new("bad.ti3");
        let msg = |t: &str| parse_ti3(t, p).unwrap_err().to_string();
        assert_eq!(
            msg(&DISPREAD.replace("2 50.000 0.0000", "2 50.000 x0.0")),
            "bad.ti3:25: field RGB_G ('x0.0') is not a number"
        );
        assert_eq!(
            msg(&DISPREAD.replace("2 50.000 0.0000 0.0000 10.000", "2 50.000 0.0000 10.000")),
            "bad.ti3:25: expected 7 values (SAMPLE_ID RGB_R RGB_G RGB_B XYZ_X XYZ_Y XYZ_Z), found 6"
        );
        assert_eq!(
            msg(&DISPREAD.replace("NUMBER_OF_SETS 2", "NUMBER_OF_SETS 3")),
            "bad.ti3:22: NUMBER_OF_SETS is 3 but the data table has 2 rows"
        );
        assert!(msg(&DISPREAD.replace("XYZ_Y", "LAB_L"))
            .contains("bad.ti3:23: the data format lacks the field(s) XYZ_Y"));
        assert!(msg(&DISPREAD.replace("CTI3", "CGATS.17"))
            .starts_with("bad.ti3:1: not an ArgyllCMS .ti3"));
        let cut: String = DISPREAD.lines().take(24).collect::<Vec<_>>().join("\n");
        assert!(msg(&cut).contains("END_DATA is missing"));
        assert!(
            msg(&DISPREAD.replace("2 50.000", "2 150.00")).starts_with("bad.ti3:25: RGB_R = 150")
        );
        assert!(
            msg(&DISPREAD.replace("\"190.10 200.00 217.76\"", "\"190.10\""))
                .starts_with("bad.ti3:13: LUMINANCE_XYZ_CDM2")
        );
    }

    #[test]
    fn csv_rows_and_errors() {
        let dir = std::env::temp_dir().join(format!("metamer-mcsv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.csv");
        std::fs::write(&path, "r,g,b,X,Y,Z\n1,1,1,95,100,108\n0.5,0,0,10,5,0.5\n").unwrap();
        let p = read_measurements(&path).unwrap();
        assert_eq!(
            p[1],
            Sample {
                rgb: [0.5, 0.0, 0.0],
                xyz: Xyz::new(10.0, 5.0, 0.5)
            }
        );
        std::fs::write(&path, "r,g,b,X,Y,Z\n1,1,1,95,100,108\n2,0,0,10,5,0.5\n").unwrap();
        let e = read_measurements(&path).unwrap_err().to_string();
        assert!(
            e.ends_with("m.csv:3: drive values must lie in 0–1, found r,g,b = 2,0,0"),
            "{e}"
        );
        std::fs::write(&path, "r,g,b,X,Y\n").unwrap();
        let e = read_measurements(&path).unwrap_err().to_string();
        assert!(
            e.contains("m.csv:1: expected the header 'r,g,b,X,Y,Z'"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
