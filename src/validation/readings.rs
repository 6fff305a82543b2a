//! Readings of the ColorChecker patches as `validate` takes them: a session journal, the
//! output of `metamer spot --json`, the output of `metamer render spots --json`, or a CSV
//! `patch,X,Y,Z` with optional columns (see [`csv`]): `sd_X,sd_Y,sd_Z` and
//! `cov_XY,cov_XZ,cov_YZ` (one reading's covariance), `n`, `u_lab` (a renderer's CIELAB
//! standard uncertainty) and `out_of_gamut`. The format is sniffed from the content; every
//! error names the file and the line.
//!
//! Each patch ends with one mean XYZ and the full covariance of that mean, the degrees of
//! freedom of the covariance where it was estimated from repeats, and where it came from,
//! so a report can say how far it may be trusted.
//!
//! The experiment's stages build the same [`PatchReading`] from what they measured or
//! rendered and write it with [`write_readings`] (see [`write`]); this reader is the one
//! that reads those files back, in the validation and in the checks before a run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_color::text::{echo, echo_message, strip_bom};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::covariance::{self, Cov3};
use super::uncertain::render_lab_sigma;
pub use super::uncertain::CHI3_95;
use crate::color::{Xyz, COLORCHECKER_NAMES};
use crate::render::spot::Uncertainty;

/// The number of patches of the chart.
pub const PATCHES: usize = 24;

/// Which file format the readings were in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    Journal,
    SpotJson,
    RenderJson,
    Csv,
}

impl Format {
    pub fn name(self) -> &'static str {
        match self {
            Format::Journal => "session journal",
            Format::SpotJson => "metamer spot --json",
            Format::RenderJson => "metamer render spots --json",
            Format::Csv => "CSV",
        }
    }
}

/// Where a patch's uncertainty comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum UncertaintySource {
    /// The scatter of repeated readings (the covariance of their mean).
    Repeats,
    /// Standard deviations (and covariances) given with the readings.
    Given,
    /// One reading, with the instrument's stated repeatability in Y and x, y.
    Instrument,
    /// The renderer's confidence (standard error of its estimate, or its 95 % ΔE bound).
    Render,
    /// One reading and nothing said about it: its uncertainty is unknown (taken as 0).
    Unknown,
}

/// One patch's readings reduced to a mean and its uncertainty.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchReading {
    /// Mean XYZ, in the readings' units (cd/m² from a meter).
    pub xyz: Xyz,
    /// Standard uncertainty of the mean in X, Y and Z.
    pub u_xyz: [f64; 3],
    /// The uncertainty of the mean as independent standard-normal factors, each moving XYZ
    /// along its vector (Σ f fᵀ is the mean's covariance): from repeats, each reading's
    /// deviation / √(k(k−1)), which keeps the correlation of X, Y and Z (a meter's repeats
    /// mostly move luminance and chromaticity, not one axis); from a given or stated
    /// covariance, its eigenvectors.
    pub u_factors: Vec<[f64; 3]>,
    /// Degrees of freedom of that covariance where it was estimated from the readings'
    /// scatter (k − 1 for k repeats); None where it is known (stated, rendered).
    #[serde(default)]
    pub dof: Option<usize>,
    /// An extra per-axis standard uncertainty in CIELAB (from a renderer's ΔE bound), 0 if
    /// none.
    pub u_lab: f64,
    /// The renderer's own ΔE*ab statement for the patch (its 95 % half-width or error
    /// bound), as the input gave it.
    #[serde(default)]
    pub render_de95: Option<f64>,
    /// Readings averaged.
    pub n: usize,
    pub source: UncertaintySource,
    /// The input marks this colour as outside the display's gamut.
    pub out_of_gamut: bool,
    /// Line of the first reading of this patch; 0 for a patch built from readings taken
    /// here ([`PatchReading::stated`]) rather than read from a file.
    pub line: usize,
    /// The covariance of one reading, where a single row or reading states it (a CSV row's
    /// sd and cov columns, an instrument's stated repeatability) or a stage estimated it
    /// from its repeats: with [`PatchReading::n`] it is what a readings file's row holds
    /// ([`write_readings`]). None where the readings were combined from several rows or
    /// say nothing per reading.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reading_cov: Option<Cov3>,
    /// The most readings the rule that read this patch could have taken, where it stopped
    /// on what the readings said (a verdict rule, [`super::sequential`]): the comparison's
    /// ΔE*ab interval is then the repeated one, valid whatever the count. None for a fixed
    /// count, or one fixed before the patch's mean was seen.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub most: Option<usize>,
}

/// All patches of one file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReadingSet {
    pub file: PathBuf,
    pub format: Format,
    /// By 1-based ColorChecker patch number.
    pub patches: BTreeMap<usize, PatchReading>,
    /// A reading labelled `white` (the display's or box's white), if the file has one.
    pub white: Option<PatchReading>,
    /// Instruments named in the file (journal header, spot lines).
    pub instruments: Vec<String>,
    /// Things the reader should know (skipped entries, a torn last line).
    pub notes: Vec<String>,
    /// How the readings were taken when the file says they are not luminances (a journal
    /// of reflective-mode entries): see [`super::plausible`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured_as: Option<String>,
}

impl ReadingSet {
    /// The white this set offers as CIELAB's reference: its reading labelled `white`, else
    /// its brightest reading (largest Y; on a display showing the chart that is patch 19,
    /// white 9.5, which then gets L* = 100). Says which in words.
    pub fn white_or_brightest(&self) -> (crate::color::Xyz, String) {
        if let Some(w) = &self.white {
            return (
                w.xyz,
                format!("the white reading of {}", self.file.display()),
            );
        }
        let (k, p) = self
            .patches
            .iter()
            .max_by(|a, b| a.1.xyz[1].total_cmp(&b.1.xyz[1]))
            .expect("a reading set has at least one patch");
        (
            p.xyz,
            format!(
                "the brightest reading of {} (patch {k}, {}), which has no white reading",
                self.file.display(),
                COLORCHECKER_NAMES[k - 1]
            ),
        )
    }
}

/// What is wrong with a readings file.
#[derive(Debug, thiserror::Error)]
pub enum ReadingsError {
    #[error("{}: cannot read: {source}", file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}:{line}: {message}", file.display())]
    Bad {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{}: {message}", file.display())]
    Empty { file: PathBuf, message: String },
    /// The readings file could not be written.
    #[error("writing {}: {source}", file.display())]
    Write {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The output policy refused the readings file.
    #[error("{source}")]
    Output {
        file: PathBuf,
        #[source]
        source: crate::output::OutputError,
    },
}

impl ReadingsError {
    /// The file the error is about.
    pub fn file(&self) -> &Path {
        match self {
            ReadingsError::Io { file, .. }
            | ReadingsError::Bad { file, .. }
            | ReadingsError::Empty { file, .. }
            | ReadingsError::Write { file, .. }
            | ReadingsError::Output { file, .. } => file,
        }
    }
}

/// A patch as a row names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PatchId {
    Number(usize),
    White,
}

/// One reading or row before the repeats of a patch are combined.
#[derive(Clone, Debug)]
struct Row {
    line: usize,
    patch: PatchId,
    xyz: [f64; 3],
    /// Standard deviation of one reading, and how many readings the row averages.
    sd: Option<[f64; 3]>,
    /// The covariances XY, XZ, YZ of one reading (0 where not given).
    cov: [f64; 3],
    n: usize,
    /// A renderer's standard error of XYZ.
    stderr: Option<[f64; 3]>,
    /// A renderer's 95 % ΔE*ab half-width or bound.
    de95: Option<Uncertainty>,
    /// A renderer's per-axis CIELAB standard uncertainty.
    u_lab: Option<f64>,
    /// The degrees of freedom of the row's sd and cov as the row states them (`dof`
    /// column): None without the column, `Some(None)` for a cell that states them known.
    dof: Option<Option<usize>>,
    /// The `most` column: the readings the patch's rule could have taken.
    most: Option<usize>,
    /// The instrument that took the reading, when the input names it.
    instrument: Option<String>,
    out_of_gamut: bool,
}

impl Row {
    /// A plain reading: no spread, no render statement.
    fn reading(line: usize, patch: PatchId, xyz: [f64; 3]) -> Row {
        Row {
            line,
            patch,
            xyz,
            sd: None,
            cov: [0.0; 3],
            n: 1,
            stderr: None,
            de95: None,
            u_lab: None,
            dof: None,
            most: None,
            instrument: None,
            out_of_gamut: false,
        }
    }

    /// One reading's covariance as the row gives it.
    fn covariance(&self) -> Option<Cov3> {
        self.sd.map(|sd| covariance::from_parts(sd, self.cov))
    }
}

/// Reads `file`, sniffing its format.
pub fn read_readings(file: &Path) -> Result<ReadingSet, ReadingsError> {
    let text = metamer_color::text::read_text(file).map_err(|source| ReadingsError::Io {
        file: file.to_path_buf(),
        source,
    })?;
    parse_readings(&text, file)
}

/// Parses readings from `text`; `file` names it in errors.
pub fn parse_readings(text: &str, file: &Path) -> Result<ReadingSet, ReadingsError> {
    let text = strip_bom(text);
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .ok_or_else(|| ReadingsError::Empty {
            file: file.to_path_buf(),
            message: "the file holds no readings".into(),
        })?;
    let mut p = Parsed {
        file: file.to_path_buf(),
        rows: Vec::new(),
        instruments: Vec::new(),
        notes: Vec::new(),
    };
    let format = p.by_format(first, text)?;
    let mut set = p.finish(format)?;
    set.measured_as = not_luminance(text, format);
    Ok(set)
}

impl Parsed {
    /// Parses `text` in the format its first line `first` shows: a journal's header, a
    /// render's JSON document, `spot --json` lines, else CSV.
    fn by_format(&mut self, first: &str, text: &str) -> Result<Format, ReadingsError> {
        if !first.starts_with('{') {
            self.csv(text)?;
            return Ok(Format::Csv);
        }
        let head: Option<Value> = serde_json::from_str(first).ok();
        let is_journal = head
            .as_ref()
            .is_some_and(|v| v["type"] == "header" || v["format"] == "metamer-session-journal");
        if is_journal {
            self.journal(text)?;
            return Ok(Format::Journal);
        }
        match serde_json::from_str::<Value>(text) {
            Ok(whole) if whole.get("patches").is_some() => {
                self.render(&whole)?;
                Ok(Format::RenderJson)
            }
            _ => {
                self.spot_lines(text)?;
                Ok(Format::SpotJson)
            }
        }
    }
}

/// How readings in `text` (a journal) were taken, when not as light from the scene: the
/// first entry in reflective or ambient mode, with its line. Other formats do not say.
pub fn not_luminance(text: &str, format: Format) -> Option<String> {
    if format != Format::Journal {
        return None;
    }
    for (i, line) in text.lines().enumerate() {
        let Ok(v) = serde_json::from_str::<Value>(line) else {
            continue;
        };
        if v["type"] != "entry" {
            continue;
        }
        let mode = v["mode"].as_str().unwrap_or_default();
        let what = match mode {
            "reflective" => "of surfaces on the instrument's lamp (reflectance, white = 100)",
            "ambient" => "as illuminance through the instrument's diffuser (lux)",
            _ => continue,
        };
        return Some(format!("in {mode} mode, {what} (line {})", i + 1));
    }
    None
}

struct Parsed {
    file: PathBuf,
    rows: Vec<Row>,
    instruments: Vec<String>,
    notes: Vec<String>,
}

impl Parsed {
    fn bad(&self, line: usize, message: impl Into<String>) -> ReadingsError {
        ReadingsError::Bad {
            file: self.file.clone(),
            line,
            message: message.into(),
        }
    }

    fn xyz_of(&self, v: &Value, key: &str, line: usize) -> Result<[f64; 3], ReadingsError> {
        let arr = v
            .get(key)
            .and_then(Value::as_array)
            .filter(|a| a.len() == 3)
            .ok_or_else(|| self.bad(line, format!("expected \"{key}\": [X, Y, Z]")))?;
        let mut out = [0.0; 3];
        for (o, (x, name)) in out.iter_mut().zip(arr.iter().zip(["X", "Y", "Z"])) {
            *o = x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                self.bad(
                    line,
                    format!(
                        "{name} is {}: the instrument did not measure it (a reading without chromaticity cannot be compared)",
                        echo(&x.to_string())
                    ),
                )
            })?;
        }
        Ok(out)
    }

    fn note_instrument(&mut self, name: &str) {
        if !name.is_empty() && !self.instruments.iter().any(|i| i == name) {
            self.instruments.push(name.to_string());
        }
    }
}

/// The ColorChecker patch of a journal entry: the step data's `patch` (1-based ColorChecker
/// number or "white"), except in a `characterize` journal, where `patch` numbers drive
/// colours and a ColorChecker colour is known by its label ("ColorChecker dark skin").
fn journal_patch(kind: &str, entry: &Value) -> Option<PatchId> {
    let data = &entry["data"];
    if kind != "characterize" {
        if let Some(p) = data.get("patch").and_then(patch_id) {
            return Some(p);
        }
    }
    let label = data["label"]
        .as_str()
        .or_else(|| entry["label"].as_str())
        .unwrap_or_default();
    let name = label.strip_prefix("ColorChecker ")?;
    by_name(name)
}

fn by_name(name: &str) -> Option<PatchId> {
    if name.eq_ignore_ascii_case("white") {
        return Some(PatchId::White);
    }
    COLORCHECKER_NAMES
        .iter()
        .position(|n| n.eq_ignore_ascii_case(name))
        .map(|i| PatchId::Number(i + 1))
}

fn patch_id(v: &Value) -> Option<PatchId> {
    match v {
        Value::Number(n) => n
            .as_u64()
            .filter(|k| (1..=PATCHES as u64).contains(k))
            .map(|k| PatchId::Number(k as usize)),
        Value::String(s) => match s.trim().parse::<usize>() {
            Ok(k) if (1..=PATCHES).contains(&k) => Some(PatchId::Number(k)),
            Ok(_) => None,
            Err(_) => by_name(s.trim()),
        },
        _ => None,
    }
}

mod csv;
mod json;
mod rows;
pub mod write;

pub use json::spot_line;
pub use write::write_readings;

#[cfg(test)]
mod tests;
