//! IES LM-63 photometric files (the North American format): written as LM-63-2019, read
//! from any version.
//!
//! The layout (sources in `src/light/README.md`): a version line (`IES:LM-63-2019`;
//! `IESNA:LM-63-2002`, `IESNA:LM-63-1995` and `IESNA91` before it), keyword lines
//! `[KEYWORD] text` in any order (2019 requires `[TEST]`, `[TESTLAB]`, `[ISSUEDATE]`,
//! `[MANUFAC]`), the line `TILT=NONE` (or `TILT=INCLUDE` followed by the tilt table, or
//! `TILT=<file>`), then numbers separated by blanks, commas or line breaks: lamps, lumens
//! per lamp (−1 for absolute photometry), candela multiplier, number of vertical and of
//! horizontal angles, photometric type (1 = C), units (1 = feet, 2 = metres), width, length
//! and height of the luminous opening, ballast factor, file generation type (2019; "future
//! use" before), input watts, the vertical angles, the horizontal angles, and the candela
//! values, one horizontal angle after another.
//!
//! In type C the vertical angle is γ and the horizontal angle is C. The horizontal angles
//! also say the symmetry: a single 0° is rotationally symmetric, 0…90° symmetric in each
//! quadrant, 0…180° symmetric about the 0–180° plane, 90…270° symmetric about the 90–270°
//! plane, 0…360° none. We write the opening's width along the 90–270° axis (our panel's
//! `height_m`, along `edge_v`) and its length along 0–180° (`width_m`, along `edge_u`); the
//! reader uses only their product, the area.
//!
//! A fitted table past the last reading is the model's extrapolation, and the candela
//! values cannot say so: a written file says it in the keyword block, in `[OTHER]` (the
//! keyword LM-63 keeps for information no other keyword holds) and in a user keyword,
//! `[_MEASURED_GAMMA]` (LM-63 lets a file define its own keywords, each beginning with an
//! underscore), both as described in the LM-63-2002 text the module's sources name.

use std::path::Path;

use metamer_color::text::{echo, strip_bom};

use super::cgamma::CGammaTable;
use super::fit::Extrapolation;
use super::numbers::{tokens, Numbers};
use super::photometry::{
    candela_grid, decode_text, finish, format_sig, mirror_planes, Opening, Panel, Photometry,
    PhotometryError,
};

/// Text for the keyword lines of a written file.
#[derive(Clone, Debug)]
pub struct IesInfo {
    /// `[TEST]`: a report or run identifier.
    pub test: String,
    /// `[ISSUEDATE]`, e.g. 2026-12-01.
    pub issue_date: String,
    /// `[LUMINAIRE]`.
    pub luminaire: String,
    /// `[FILEGENINFO]`: how the file was made.
    pub generation: String,
    /// Where the table is extrapolated past the readings: said in an `[OTHER]` line and
    /// in the user keyword `[_MEASURED_GAMMA]` (last angle read per half-plane).
    pub extrapolation: Option<Extrapolation>,
}

/// File generation type of LM-63-2019 for a computer-generated (simulated) distribution.
const FILE_GENERATION_SIMULATION: &str = "1.00010";
const PER_LINE: usize = 10;

/// The IES text of `table` for `panel` (absolute candela, I = L₀·A·f·cos γ).
pub fn to_string(table: &CGammaTable, panel: &Panel, info: &IesInfo) -> String {
    let mut out = String::new();
    let line = |out: &mut String, s: &str| {
        out.push_str(s);
        out.push_str("\r\n");
    };
    line(&mut out, "IES:LM-63-2019");
    line(&mut out, &format!("[TEST] {}", one_line(&info.test)));
    line(
        &mut out,
        "[TESTLAB] none: fitted to measurements by metamer",
    );
    line(
        &mut out,
        &format!("[ISSUEDATE] {}", one_line(&info.issue_date)),
    );
    line(&mut out, "[MANUFAC] metamer");
    line(
        &mut out,
        &format!("[LUMINAIRE] {}", one_line(&info.luminaire)),
    );
    line(
        &mut out,
        &format!("[FILEGENINFO] {}", one_line(&info.generation)),
    );
    if let Some(e) = &info.extrapolation {
        line(&mut out, &format!("[OTHER] {}", e.sentence()));
        let m = e.measured_to_deg;
        line(
            &mut out,
            &format!(
                "[_MEASURED_GAMMA] C0 0-{} C90 0-{} C180 0-{} C270 0-{}",
                m[0], m[1], m[2], m[3]
            ),
        );
    }
    line(&mut out, "TILT=NONE");
    let gammas = table.gamma_deg();
    // A full circle is closed with 360° (= the 0° plane), as the format expects.
    let mut horizontal: Vec<f64> = table.c_deg().to_vec();
    let mut candela = candela_grid(table, panel);
    if horizontal.len() > 1 {
        horizontal.push(360.0);
        candela.push(candela[0].clone());
    }
    line(
        &mut out,
        &format!(
            "1 -1 1 {} {} 1 2 {} {} 0",
            gammas.len(),
            horizontal.len(),
            format_sig(panel.height_m, 6),
            format_sig(panel.width_m, 6)
        ),
    );
    line(&mut out, &format!("1 {FILE_GENERATION_SIMULATION} 0"));
    let mut block = |values: &mut dyn Iterator<Item = String>| {
        let v: Vec<String> = values.collect();
        for chunk in v.chunks(PER_LINE) {
            line(&mut out, &chunk.join(" "));
        }
    };
    block(&mut gammas.iter().map(|g| format_sig(*g, 8)));
    block(&mut horizontal.iter().map(|c| format_sig(*c, 8)));
    for row in &candela {
        block(&mut row.iter().map(|v| format_sig(*v, 7)));
    }
    out
}

fn one_line(s: &str) -> String {
    s.replace(['\r', '\n'], " ")
}

/// Reads an IES file: the distribution as a C-γ table (front hemisphere) and its photometry.
/// Text that is not UTF-8 is read as Windows-1252 (see [`decode_text`]).
pub fn read(path: &Path) -> Result<(CGammaTable, Photometry), PhotometryError> {
    let bytes = metamer_color::text::read_bytes(path).map_err(|source| PhotometryError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    let (text, encoding) = decode_text(&bytes);
    let (table, mut photometry) = parse(&text, path)?;
    photometry.text_encoding = encoding.map(String::from);
    Ok((table, photometry))
}

/// The keyword lines before `TILT=` as (keyword, text); `[MORE]` continues the line before.
fn keywords(lines: &[&str]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for l in lines {
        let l = l.trim();
        let Some(rest) = l.strip_prefix('[') else {
            continue;
        };
        let Some((key, text)) = rest.split_once(']') else {
            continue;
        };
        let (key, text) = (key.trim().to_ascii_uppercase(), echo(text.trim()));
        match out.last_mut() {
            Some(last) if key == "MORE" => {
                last.1.push(' ');
                last.1.push_str(&text);
            }
            _ => out.push((key, text)),
        }
    }
    out
}

/// A comma inside a value on a line that separates values by blanks: LM-63 separates
/// values by blanks or commas and writes decimals with a point, so "10 5,5 0,0" is either
/// decimal commas (10, 5.5, 0.0) or two values each (10, 5, 5, 0, 0), and the counts can
/// come out right either way. A line whose values are all separated by commas (with or
/// without blanks) is the format's own. The first such value and its line, if any.
fn ambiguous_comma(text: &str, first_line: usize) -> Option<(usize, String)> {
    let inner_comma = |w: &str| {
        let b = w.as_bytes();
        (1..b.len().saturating_sub(1))
            .any(|k| b[k] == b',' && b[k - 1].is_ascii_digit() && b[k + 1].is_ascii_digit())
    };
    text.lines().enumerate().find_map(|(i, l)| {
        let words: Vec<&str> = l.split_whitespace().collect();
        let blank_separated = words
            .windows(2)
            .any(|w| !w[0].ends_with(',') && !w[1].starts_with(','));
        if !blank_separated {
            return None;
        }
        words
            .iter()
            .find(|w| inner_comma(w))
            .map(|w| (first_line + i, w.to_string()))
    })
}

/// [`read`] on text; `source` names the file in errors.
pub fn parse(text: &str, source: &Path) -> Result<(CGammaTable, Photometry), PhotometryError> {
    let lines: Vec<&str> = strip_bom(text).lines().collect();
    let header = Header::read(&lines, source)?;
    let rest = lines[header.tilt + 1..].join("\n");
    let first_value_line = header.tilt + 2;
    let mut values = Numbers::new(tokens(&rest, first_value_line), source, lines.len());
    if let Some((line, word)) = ambiguous_comma(&rest, first_value_line) {
        return Err(values.error(
            line,
            format!(
                "'{}': a comma inside a value on a line of blank-separated values — a \
                 decimal comma, or two values? LM-63 writes decimals with a point and \
                 separates values by blanks or commas",
                echo(&word)
            ),
        ));
    }
    if header.tilt_value == "INCLUDE" {
        skip_tilt_table(&mut values)?;
    }
    let photometric = PhotometricLine::read(&mut values)?;
    let (_, gammas) = values.take(photometric.n_vertical, "the vertical angles")?;
    let (h_line, horizontal) = values.take(photometric.n_horizontal, "the horizontal angles")?;
    let rows = candela_table(&mut values, &horizontal, &photometric)?;
    let (symmetry, planes) = unfold(&values, h_line, horizontal, rows)?;
    let (table, mut photometry) = finish(
        header.version,
        symmetry.into(),
        photometric.n_horizontal,
        photometric.opening(),
        planes,
        &gammas,
    )
    .map_err(|message| PhotometryError::Content {
        file: source.to_path_buf(),
        message,
    })?;
    photometry.labels = keywords(&lines[..header.tilt]);
    Ok((table, photometry))
}

/// The lines before the numbers: the version and where the `TILT=` line is.
struct Header {
    version: String,
    /// Index of the `TILT=` line.
    tilt: usize,
    /// What follows `TILT=`, upper case.
    tilt_value: String,
}

impl Header {
    fn read(lines: &[&str], source: &Path) -> Result<Header, PhotometryError> {
        let first = lines.iter().position(|l| !l.trim().is_empty()).unwrap_or(0);
        let version = lines
            .get(first)
            .map(|l| l.trim())
            .filter(|l| l.to_ascii_uppercase().starts_with("IES"))
            .map(|l| l.to_string())
            .unwrap_or_else(|| "IES LM-63-1986".into());
        let Some(tilt) = lines
            .iter()
            .position(|l| l.trim_start().to_ascii_uppercase().starts_with("TILT="))
        else {
            return Err(PhotometryError::Format {
                file: source.to_path_buf(),
                line: lines.len().max(1),
                message: "no TILT= line: not an IES LM-63 file".into(),
            });
        };
        let tilt_value = lines[tilt].trim_start()[5..].trim().to_ascii_uppercase();
        Ok(Header {
            version,
            tilt,
            tilt_value,
        })
    }
}

/// Reads past a `TILT=INCLUDE` table, checking its form. Lamp-to-luminaire geometry, the
/// number of tilt angles, the angles, the factors: they scale the lamp's output with its
/// tilt, which a fixed panel does not have.
fn skip_tilt_table(values: &mut Numbers) -> Result<(), PhotometryError> {
    values.next("the tilt geometry")?;
    let (count_line, n) = values.next("the number of tilt angles")?;
    if n.is_nan() || n < 0.0 || n.fract() != 0.0 {
        return Err(values.error(
            count_line,
            format!("the number of tilt angles {n} is not a count"),
        ));
    }
    let mut last = (count_line, f64::NEG_INFINITY);
    for k in 0..(n as usize).saturating_mul(2) {
        let (line, v) = values.next("the TILT=INCLUDE table")?;
        if (k as f64) < n && v <= last.1 {
            return Err(values.error(
                line,
                format!(
                    "the TILT=INCLUDE table's angles must increase: {}° then {v}° (its \
                     count on line {count_line} says {n} angles, then {n} factors)",
                    last.1
                ),
            ));
        }
        last = (line, v);
    }
    // The line of lamps, lumens, multiplier, … starts a line of its own: a table that
    // ends in the middle of a line has more or fewer values than its count says, and
    // every number after it would be read as the wrong field.
    if let Some((line, t)) = values.peek().filter(|(l, _)| *l == last.0) {
        return Err(values.error(
            *line,
            format!(
                "the TILT=INCLUDE table ends in the middle of line {line}, before '{}': its \
                 count on line {count_line} says {n} angles and {n} factors, but the \
                 values do not end with a line (one too few or too many?)",
                echo(t)
            ),
        ));
    }
    Ok(())
}

/// The thirteen numbers after the tilt: what the rest of the file is made of.
struct PhotometricLine {
    multiplier: f64,
    n_vertical: usize,
    n_horizontal: usize,
    /// Metres per unit of the opening's dimensions.
    metres: f64,
    width: f64,
    length: f64,
}

impl PhotometricLine {
    fn read(values: &mut Numbers) -> Result<PhotometricLine, PhotometryError> {
        let count = |values: &Numbers, (line, v): (usize, f64), what: &str| {
            if v >= 1.0 && v.fract() == 0.0 {
                Ok(v as usize)
            } else {
                Err(values.error(line, format!("{what} {v} is not a positive count")))
            }
        };
        values.next("the number of lamps")?;
        values.next("the lumens per lamp")?;
        let multiplier = values.value("the candela multiplier")?;
        let what = "the number of vertical angles";
        let read = values.next(what)?;
        let n_vertical = count(values, read, what)?;
        let what = "the number of horizontal angles";
        let read = values.next(what)?;
        let n_horizontal = count(values, read, what)?;
        let (line, kind) = values.next("the photometric type")?;
        if kind != 1.0 {
            return Err(values.error(
                line,
                format!("photometric type {kind}: only type C (1) describes a panel by C-planes"),
            ));
        }
        let (line, units) = values.next("the units type")?;
        let metres = match units as i64 {
            1 if units == 1.0 => 0.3048,
            2 if units == 2.0 => 1.0,
            _ => {
                return Err(values.error(
                    line,
                    format!("units type {units}: expected 1 (feet) or 2 (metres)"),
                ))
            }
        };
        let width = values.value("the opening's width")?;
        let length = values.value("the opening's length")?;
        values.next("the opening's height")?;
        values.next("the ballast factor")?;
        values.next("the file generation type")?;
        values.next("the input watts")?;
        Ok(PhotometricLine {
            multiplier,
            n_vertical,
            n_horizontal,
            metres,
            width,
            length,
        })
    }

    /// The luminous opening in metres.
    fn opening(&self) -> Opening {
        let (w, l) = (self.width * self.metres, self.length * self.metres);
        // Negative dimensions describe round openings (a circle or an ellipse).
        let area = if w < 0.0 && l < 0.0 {
            std::f64::consts::PI / 4.0 * w * l
        } else {
            (w * l).max(0.0)
        };
        Opening {
            width_m: l.abs(),
            height_m: w.abs(),
            area_m2: area,
        }
    }
}

/// The candela values, one row per horizontal angle, times the multiplier; then the end of
/// the file.
fn candela_table(
    values: &mut Numbers,
    horizontal: &[f64],
    photometric: &PhotometricLine,
) -> Result<Vec<Vec<f64>>, PhotometryError> {
    let mut rows = Vec::new();
    for &c in horizontal {
        let what = format!("the candela values of C-plane {c}°");
        let (_, row) = values.take(photometric.n_vertical, &what)?;
        rows.push(
            row.into_iter()
                .map(|v| v * photometric.multiplier)
                .collect(),
        );
    }
    // Every value the counts call for is read; more numbers mean a count or a value is
    // wrong, and the table read would be shifted (a DOS end-of-file mark is not a value).
    let extra: Vec<&(usize, String)> = values
        .remaining()
        .iter()
        .filter(|(_, t)| !t.chars().all(char::is_control))
        .collect();
    if let Some((line, t)) = extra.first() {
        return Err(values.error(
            *line,
            format!(
                "{} value(s) after the last candela value, from '{}' on: the counts \
                 ({} vertical × {} horizontal angles) do not match the numbers in the file",
                extra.len(),
                echo(t),
                photometric.n_vertical,
                photometric.n_horizontal
            ),
        ));
    }
    Ok(rows)
}

/// C-planes as (C, candela at each vertical angle).
type Planes = Vec<(f64, Vec<f64>)>;

/// The symmetry the horizontal angles say, and the stored planes mirrored into the full
/// circle by it. `h_line` is the line of the first horizontal angle.
fn unfold(
    values: &Numbers,
    h_line: usize,
    horizontal: Vec<f64>,
    rows: Vec<Vec<f64>>,
) -> Result<(&'static str, Planes), PhotometryError> {
    let n_horizontal = horizontal.len();
    let first_c = horizontal[0];
    let last_c = horizontal[n_horizontal - 1];
    if let Some(w) = horizontal
        .windows(2)
        .find(|w| w[1].is_nan() || w[1] <= w[0])
    {
        return Err(values.error(
            h_line,
            format!(
                "the horizontal angles must increase: {}° then {}°",
                w[0], w[1]
            ),
        ));
    }
    let stored: Vec<(f64, Vec<f64>)> = horizontal.into_iter().zip(rows).collect();
    type Mirror = fn(f64) -> f64;
    let (symmetry, mirrors): (&str, Vec<Mirror>) = if n_horizontal == 1 && first_c == 0.0 {
        ("rotationally symmetric", vec![])
    } else if first_c == 0.0 && last_c == 90.0 {
        (
            "symmetric in each quadrant",
            vec![|c| 180.0 - c, |c| 180.0 + c, |c| 360.0 - c],
        )
    } else if first_c == 0.0 && last_c == 180.0 {
        ("symmetric about the 0–180° plane", vec![|c| 360.0 - c])
    } else if first_c == 90.0 && last_c == 270.0 {
        ("symmetric about the 90–270° plane", vec![|c| 180.0 - c])
    } else if first_c == 0.0 && last_c > 180.0 && last_c <= 360.0 {
        ("none", vec![])
    } else {
        return Err(values.error(
            h_line,
            format!(
                "horizontal angles {first_c}…{last_c}°: type C files run 0, 0…90, 0…180, \
                 90…270 or 0…360"
            ),
        ));
    };
    let planes = if n_horizontal == 1 {
        stored
    } else {
        mirror_planes(stored, &mirrors)
    };
    Ok((symmetry, planes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_quadrant_symmetric_file_with_wrapped_values_and_keywords_in_any_order() {
        // A Lambertian 0.5 m × 0.2 m panel of 100 cd/m² (I₀ = 10 cd), in feet.
        let ft = 1.0 / 0.3048;
        let text = format!(
            "IESNA:LM-63-2002\n[MANUFAC] x\n[TEST] t\nTILT=NONE\n1 -1 2 3 2 1 1 {} {} 0\n\
             1 1 0\n0 45\n90\n0 90\n5 3.5355339\n0\n5 3.5355339 0\n",
            0.2 * ft,
            0.5 * ft
        );
        let (t, p) = parse(&text, Path::new("a.ies")).unwrap();
        assert_eq!(t.c_deg(), &[0.0, 90.0, 180.0, 270.0]);
        assert!((p.normal_intensity_cd - 10.0).abs() < 1e-12);
        assert!((p.area_m2 - 0.1).abs() < 1e-12);
        assert!((p.normal_luminance_cd_m2().unwrap() - 100.0).abs() < 1e-9);
        assert!((t.at(200.0, 45.0) - 1.0).abs() < 1e-7);
        assert_eq!(p.symmetry, "symmetric in each quadrant");
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let e = parse(
            "IES:LM-63-2019\nTILT=NONE\n1 -1 1 2 1 3 2\n",
            Path::new("b.ies"),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "b.ies:3: photometric type 3: only type C (1) describes a panel by C-planes"
        );
        let e = parse("IES:LM-63-2019\n[TEST] x\n", Path::new("c.ies")).unwrap_err();
        assert!(e.to_string().contains("no TILT= line"), "{e}");
        let e = parse(
            "IES:LM-63-2019\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n10 x\n",
            Path::new("d.ies"),
        )
        .unwrap_err();
        assert!(
            e.to_string().starts_with("d.ies:7: the candela values"),
            "{e}"
        );
    }
}
