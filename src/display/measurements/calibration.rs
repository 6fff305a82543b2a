//! The `CAL` table that dispread and DisplayCAL append to a `.ti3`: the video-card curves
//! loaded while the patches were measured (fields `RGB_I RGB_R RGB_G RGB_B`, 0–1).

use super::tokens::tokens;

/// One row of a `CAL` table: input level and the output of each channel's curve, 0–1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibrationEntry {
    pub input: f64,
    pub rgb: [f64; 3],
}

/// The `CAL` table after line index `from` (0-based), if any; errors carry the 1-based line.
pub(super) fn calibration_table(
    text: &str,
    from: usize,
) -> Result<Option<Vec<CalibrationEntry>>, (usize, String)> {
    let mut lines = text.lines().enumerate().skip(from);
    if !cal_table_follows(&mut lines) {
        return Ok(None);
    }
    let mut fields: Vec<String> = Vec::new();
    let mut in_format = false;
    let mut columns: Option<[usize; 4]> = None;
    let mut out = Vec::new();
    for (index, raw) in lines {
        let line = index + 1;
        let toks = tokens(raw).map_err(|m| (line, m))?;
        let Some(first) = toks.first() else { continue };
        if in_format {
            if first == "END_DATA_FORMAT" {
                in_format = false;
            } else {
                fields.extend(toks.iter().cloned());
            }
            continue;
        }
        match (first.as_str(), columns) {
            ("BEGIN_DATA_FORMAT", _) => {
                in_format = true;
                fields.extend(toks[1..].iter().cloned());
            }
            ("BEGIN_DATA", _) => columns = Some(cal_columns(&fields, line)?),
            ("END_DATA", Some(_)) => return Ok(Some(out)),
            (_, Some(cols)) => out.push(cal_row(&toks, &fields, cols, line)?),
            _ => {}
        }
    }
    if columns.is_none() {
        // A CAL header without a table holds no curves.
        return Ok(None);
    }
    Err((
        text.lines().count().max(1),
        "the CAL table's END_DATA is missing: the file is cut short".into(),
    ))
}

/// Reads up to the identifier `CAL`; false at the end of the text or at another table's
/// identifier, after which nothing more is read.
fn cal_table_follows<'a>(lines: &mut impl Iterator<Item = (usize, &'a str)>) -> bool {
    for (_, raw) in lines {
        match tokens(raw).ok().and_then(|t| t.first().cloned()) {
            Some(t) if t == "CAL" => return true,
            Some(t)
                if t.chars()
                    .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit())
                    && !t.contains('_')
                    && raw.trim() == t =>
            {
                return false
            }
            _ => {}
        }
    }
    false
}

/// The columns of `RGB_I RGB_R RGB_G RGB_B` among the CAL table's fields.
fn cal_columns(fields: &[String], line: usize) -> Result<[usize; 4], (usize, String)> {
    let names = ["RGB_I", "RGB_R", "RGB_G", "RGB_B"];
    let mut cols = [0; 4];
    for (c, n) in cols.iter_mut().zip(names) {
        *c = fields.iter().position(|f| f == n).ok_or_else(|| {
            (
                line,
                format!(
                    "the CAL table lacks the field {n} (found: {})",
                    fields.join(" ")
                ),
            )
        })?;
    }
    Ok(cols)
}

/// One row of the CAL table: each value a number in 0–1.
fn cal_row(
    toks: &[String],
    fields: &[String],
    cols: [usize; 4],
    line: usize,
) -> Result<CalibrationEntry, (usize, String)> {
    if toks.len() != fields.len() {
        return Err((
            line,
            format!(
                "the CAL table expects {} values, found {}",
                fields.len(),
                toks.len()
            ),
        ));
    }
    let v: Vec<f64> = cols
        .iter()
        .map(|&c| {
            toks[c]
                .parse::<f64>()
                .ok()
                .filter(|x| (0.0..=1.0).contains(x))
                .ok_or_else(|| {
                    (
                        line,
                        format!(
                            "CAL field {} ('{}') is not a number in 0–1",
                            fields[c], toks[c]
                        ),
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    Ok(CalibrationEntry {
        input: v[0],
        rgb: [v[1], v[2], v[3]],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::measurements::{parse_ti3, read_measurement_file};
    use std::path::Path;

    /// A file in the shape DisplayCAL writes from a spectrometer: CRLF line ends, tabs, no
    /// SAMPLE_ID, keywords after the data format, SPEC_nnn fields and a CAL table after the
    /// measurements.
    #[test]
    fn reads_spectra_and_the_calibration_table() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/displaycal_spectral_cal.ti3");
        let m = read_measurement_file(&path).unwrap();
        assert!(m.absolute);
        assert_eq!(m.patches.len(), 3);
        // 50 % red, 25 % green; Y 10 of a 100 normalised to an 80 cd/m² white = 8 cd/m².
        assert_eq!(m.patches[2].rgb, [0.5, 0.25, 0.0]);
        assert!((m.patches[2].xyz[1] - 8.0).abs() < 1e-12);
        let s = m.spectra.unwrap();
        assert_eq!(s.wavelengths_nm, vec![450.0, 550.0, 650.0]);
        assert_eq!(s.values[2], vec![0.05, 0.20, 0.35]);
        let cal = m.calibration.unwrap();
        assert_eq!(cal.len(), 3);
        assert_eq!(
            cal[1],
            CalibrationEntry {
                input: 0.5,
                rgb: [0.48, 0.5, 0.52]
            }
        );
    }

    #[test]
    fn a_broken_calibration_table_names_its_line() {
        let text = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/displaycal_spectral_cal.ti3"),
        )
        .unwrap();
        let bad = text.replace("0.5 0.48 0.5 0.52", "0.5 0.48 0.5");
        let e = parse_ti3(&bad, Path::new("c.ti3")).unwrap_err().to_string();
        assert_eq!(e, "c.ti3:48: the CAL table expects 4 values, found 3");
        let cut: String = text.lines().take(48).collect::<Vec<_>>().join("\n");
        let e = parse_ti3(&cut, Path::new("c.ti3")).unwrap_err().to_string();
        assert!(e.contains("CAL table's END_DATA is missing"), "{e}");
        let bad = text.replace("SPEC_550", "SPEC_x");
        let e = parse_ti3(&bad, Path::new("c.ti3")).unwrap_err().to_string();
        assert!(e.starts_with("c.ti3:26: spectral field SPEC_x"), "{e}");
    }
}
