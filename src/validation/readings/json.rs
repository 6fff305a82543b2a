//! The JSON forms of readings `validate` takes: a session journal, `metamer spot --json`
//! lines (written here too, by [`spot_line`]) and `metamer render spots --json`.

use metamer_drivers::spec::model_named;
use metamer_drivers::Reading;

use super::*;

impl Parsed {
    /// A session journal: entries whose step data carry a ColorChecker patch.
    pub(super) fn journal(&mut self, text: &str) -> Result<(), ReadingsError> {
        let mut kind = String::new();
        let mut skipped = 0;
        let lines: Vec<&str> = text.lines().collect();
        let ends_with_newline = text.ends_with('\n');
        for (i, raw) in lines.iter().enumerate() {
            let line = i + 1;
            if raw.trim().is_empty() {
                continue;
            }
            let v: Value = match serde_json::from_str(raw) {
                Ok(v) => v,
                // The journal moves a torn last line aside only when resumed; a reader
                // should not fail on what a crash left.
                Err(_) if i + 1 == lines.len() && !ends_with_newline => {
                    self.notes.push(format!(
                        "line {line}: a torn last line (cut off mid-write) was ignored"
                    ));
                    continue;
                }
                Err(e) => {
                    return Err(self.bad(
                        line,
                        format!("not a JSON line: {}", echo_message(&e.to_string())),
                    ))
                }
            };
            match v["type"].as_str() {
                Some("header") => {
                    kind = v["kind"].as_str().unwrap_or_default().to_string();
                    if let Some(instruments) = v["data"]["instruments"].as_object() {
                        for (role, record) in instruments {
                            let model = record["info"]["model"].as_str().unwrap_or(role);
                            let serial = record["info"]["serial"].as_str().unwrap_or_default();
                            let name = if serial.is_empty() {
                                format!("{role}: {model}")
                            } else {
                                format!("{role}: {model} #{serial}")
                            };
                            self.note_instrument(&name);
                        }
                    }
                }
                Some("entry") => {
                    let Some(patch) = journal_patch(&kind, &v) else {
                        skipped += 1;
                        continue;
                    };
                    let xyz = self.xyz_of(&v["reading"], "xyz", line)?;
                    let emissive = v["mode"].as_str().is_none_or(|m| m == "emissive");
                    self.rows.push(Row {
                        instrument: v["reading"]["instrument"]
                            .as_str()
                            .filter(|_| emissive)
                            .map(String::from),
                        out_of_gamut: v["data"]["out_of_gamut"].as_bool().unwrap_or(false),
                        ..Row::reading(line, patch, xyz)
                    });
                }
                Some("calibration") => {}
                _ => return Err(self.bad(line, "expected a header, entry or calibration line")),
            }
        }
        if skipped > 0 {
            self.notes.push(format!(
                "{skipped} journal entries name no ColorChecker patch and were left out"
            ));
        }
        Ok(())
    }

    /// `metamer spot --json`: one reading per line, optionally with `"patch"`.
    pub(super) fn spot_lines(&mut self, text: &str) -> Result<(), ReadingsError> {
        let mut unnumbered = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let raw = raw.trim();
            if raw.is_empty() || raw.starts_with('#') {
                continue;
            }
            let v: Value = serde_json::from_str(raw).map_err(|e| {
                self.bad(
                    line,
                    format!("not a JSON line: {}", echo_message(&e.to_string())),
                )
            })?;
            let xyz = self.xyz_of(&v, "XYZ", line)?;
            if let Some(name) = v["instrument"].as_str() {
                self.note_instrument(name);
            }
            let patch = match v.get("patch") {
                None => None,
                Some(p) => Some(patch_id(p).ok_or_else(|| {
                    self.bad(
                        line,
                        format!(
                            "\"patch\": {} is not 1–24 or \"white\"",
                            echo(&p.to_string())
                        ),
                    )
                })?),
            };
            let row = Row {
                // A spot line does not say its mode: only a model that reads emitted light
                // alone (its registry row says so) is known to have taken an emissive
                // reading.
                instrument: v["instrument"]
                    .as_str()
                    .filter(|m| model_named(m).is_some_and(|row| row.reads_only_emitted_light()))
                    .map(String::from),
                out_of_gamut: v["out_of_gamut"].as_bool().unwrap_or(false),
                ..Row::reading(line, patch.unwrap_or(PatchId::Number(0)), xyz)
            };
            if patch.is_none() {
                unnumbered.push(self.rows.len());
            }
            self.rows.push(row);
        }
        if unnumbered.is_empty() {
            return Ok(());
        }
        if unnumbered.len() != self.rows.len() {
            let line = self.rows[unnumbered[0]].line;
            return Err(self.bad(
                line,
                "some readings carry \"patch\" and this one does not: number all or none",
            ));
        }
        // Without numbers, `spot --count k` per patch appended patch after patch gives k
        // consecutive readings of patch 1, then of patch 2, …
        let n = self.rows.len();
        let per_patch = if n <= PATCHES {
            1
        } else if n % PATCHES == 0 {
            n / PATCHES
        } else {
            return Err(ReadingsError::Empty {
                file: self.file.clone(),
                message: format!(
                    "{n} unnumbered readings: expected up to 24 (one per patch) or a multiple of 24 (the same number of repeats per patch), or a \"patch\" key on each line"
                ),
            });
        };
        for (k, row) in self.rows.iter_mut().enumerate() {
            row.patch = PatchId::Number(k / per_patch + 1);
        }
        if per_patch > 1 {
            self.notes.push(format!(
                "{n} unnumbered readings taken as {per_patch} consecutive repeats of each patch"
            ));
        }
        Ok(())
    }

    /// `metamer render spots --json`: `{"patches":[{"patch":k,"XYZ":…,"XYZ_stderr":…,
    /// "de_ci95"|"de_bound":…}]}`.
    pub(super) fn render(&mut self, whole: &Value) -> Result<(), ReadingsError> {
        let patches = whole["patches"]
            .as_array()
            .ok_or_else(|| self.bad(1, "\"patches\" must be an array"))?;
        self.note_instrument(&format!(
            "renderer ({})",
            whole["method"].as_str().unwrap_or("unknown method")
        ));
        for (i, p) in patches.iter().enumerate() {
            let what = format!("patches[{i}]");
            let patch = p
                .get("patch")
                .and_then(patch_id)
                .ok_or_else(|| self.bad(1, format!("{what}.patch must be 1–24")))?;
            let xyz = self
                .xyz_of(p, "XYZ", 1)
                .map_err(|e| self.bad(1, format!("{what}: {e}")))?;
            let stderr = match p.get("XYZ_stderr") {
                Some(_) => Some(self.xyz_of(p, "XYZ_stderr", 1)?),
                None => None,
            };
            let de95 = match (p["de_ci95"].as_f64(), p["de_bound"].as_f64()) {
                (Some(de), _) => Some(Uncertainty::HalfWidth95 { de, sampling: None }),
                (None, Some(de)) => Some(Uncertainty::Bound { de, regular: None }),
                (None, None) => None,
            };
            self.rows.push(Row {
                stderr,
                de95,
                ..Row::reading(1, patch, xyz)
            });
        }
        Ok(())
    }
}

/// One reading as a line of `metamer spot --json`, the form [`Parsed::spot_lines`] reads
/// back: `{"XYZ":[X,Y,Z],"xyY":[x,y,Y],"flags":[…],"instrument":"cs100a"}` and, from
/// spectral instruments, `"integration_s"` and `"spectrum":{"start_nm":380,"step_nm":10,
/// "values":[…]}`; values the instrument did not measure are null.
pub fn spot_line(r: &Reading) -> String {
    // A struct, not json!(), to keep the documented key order.
    #[derive(serde::Serialize)]
    struct Grid<'a> {
        start_nm: f64,
        step_nm: f64,
        values: &'a [f64],
    }
    #[derive(serde::Serialize)]
    struct Line<'a> {
        #[serde(rename = "XYZ")]
        xyz: Xyz,
        #[serde(rename = "xyY")]
        xyy: [f64; 3],
        flags: Vec<&'static str>,
        instrument: &'a str,
        #[serde(skip_serializing_if = "Option::is_none")]
        integration_s: Option<f64>,
        #[serde(skip_serializing_if = "Option::is_none")]
        spectrum: Option<Grid<'a>>,
    }
    let spectrum = r.spectrum.as_ref().and_then(|s| {
        let (start_nm, step_nm) = s.grid()?;
        Some(Grid {
            start_nm,
            step_nm,
            values: s.values(),
        })
    });
    let line = Line {
        xyz: r.xyz,
        xyy: r.xyy,
        flags: r.flags.iter().map(|f| f.name()).collect(),
        instrument: &r.instrument,
        integration_s: r.spectrum.as_ref().and(r.integration_s),
        spectrum,
    };
    // Numbers (a non-finite one is written null) and strings: nothing here can fail.
    serde_json::to_string(&line).expect("a reading serializes")
}
