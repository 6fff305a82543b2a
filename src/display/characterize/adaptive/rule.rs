//! The adaptive plan's rule and targets: what it stops at, how many patches at a time, the
//! seed of its held-out offsets, and the colours to reproduce as a file reads them.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::color::Xyz;
use crate::display::characterize::plan::VERIFICATION_SEED;
use crate::numeric_csv::{CsvError, NumericCsv};

/// Default stopping figure: the predicted ΔE*ab at every target below it.
pub const DEFAULT_STOP_DE: f64 = 1.0;
/// Default cap on fit readings (the first pass included).
pub const DEFAULT_MAX_READINGS: usize = 120;
/// Default patches per batch.
pub const DEFAULT_BATCH: usize = 8;
/// Most targets a file may hold: each costs a fit's inverse per batch.
pub const MAX_TARGETS: usize = 1000;
/// The adaptive plan's rule: when to stop, how many at a time, and the seed of the
/// held-out patches' offsets.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rule {
    /// Stop when the predicted ΔE*ab at every target is below this.
    pub stop_de: f64,
    /// Stop choosing when this many fit readings are taken (the first pass included).
    pub max_readings: usize,
    /// Patches per batch.
    pub batch: usize,
    pub seed: u64,
    /// Held-out patches read after the fit, one near each of this many targets: those the
    /// fitted models leave least certain ([`super::choice::held_out_targets`]). None: one
    /// near every target. Left out of the fingerprint when None, so a plan made before the
    /// count could be set is the same plan.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out: Option<usize>,
}

impl Rule {
    /// The held-out patches read for `targets` target colours.
    pub fn held_out_count(&self, targets: usize) -> usize {
        self.held_out.map_or(targets, |n| n.min(targets))
    }
}

impl Default for Rule {
    fn default() -> Self {
        Rule {
            stop_de: DEFAULT_STOP_DE,
            max_readings: DEFAULT_MAX_READINGS,
            batch: DEFAULT_BATCH,
            seed: VERIFICATION_SEED,
            held_out: None,
        }
    }
}

/// An adaptive characterization: the rule, the colours to reproduce, and whether the
/// model is chosen by cross-validation (`auto`) rather than the request's.
#[derive(Clone, Debug, PartialEq)]
pub struct Adaptive {
    pub rule: Rule,
    /// Absolute XYZ, cd/m².
    pub targets: Vec<Xyz>,
    /// Choose the model as `fit --model auto` does, after every batch and at the end.
    pub auto: bool,
}

/// An adaptive plan that cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum AdaptiveError {
    #[error("reading the targets: {0}")]
    Targets(#[from] CsvError),
    #[error("{}:{line}: target X={x}, Y={y}, Z={z} is no colour a display shows (Y must be above 0, X and Z at least 0)", file.display())]
    NotAColour {
        file: PathBuf,
        line: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error("{}: {count} targets, more than the {MAX_TARGETS} an adaptive plan takes", file.display())]
    TooMany { file: PathBuf, count: usize },
    #[error("an adaptive plan needs at least one target colour")]
    NoTargets,
    #[error("the stopping figure must be a ΔE*ab above 0, got {0}")]
    StopDe(f64),
    #[error("a batch must hold at least 1 patch")]
    Batch,
    #[error("the held-out set must hold at least 1 patch")]
    HeldOut,
    #[error("the cap of {cap} readings is below the first pass's {first}")]
    Cap { cap: usize, first: usize },
}

/// Reads the colours to reproduce from a CSV file with the header `X,Y,Z` (cd/m²), the
/// format `reproduce` takes; each must be a colour (Y above 0, X and Z not negative).
pub fn read_targets(path: &Path) -> Result<Vec<Xyz>, AdaptiveError> {
    let csv = NumericCsv::read(path, &["X", "Y", "Z"])?;
    if csv.rows.len() > MAX_TARGETS {
        return Err(AdaptiveError::TooMany {
            file: path.to_path_buf(),
            count: csv.rows.len(),
        });
    }
    csv.rows
        .into_iter()
        .map(|(line, v)| {
            if v[1] > 0.0 && v[0] >= 0.0 && v[2] >= 0.0 {
                Ok(Xyz::new(v[0], v[1], v[2]))
            } else {
                Err(AdaptiveError::NotAColour {
                    file: path.to_path_buf(),
                    line,
                    x: v[0],
                    y: v[1],
                    z: v[2],
                })
            }
        })
        .collect()
}

impl Adaptive {
    /// Refuses a rule or targets that make no plan, before anything is opened.
    pub fn check(&self, first_pass: usize) -> Result<(), AdaptiveError> {
        let r = &self.rule;
        if !(r.stop_de.is_finite() && r.stop_de > 0.0) {
            return Err(AdaptiveError::StopDe(r.stop_de));
        }
        if r.batch == 0 {
            return Err(AdaptiveError::Batch);
        }
        if r.held_out == Some(0) {
            return Err(AdaptiveError::HeldOut);
        }
        if r.max_readings < first_pass {
            return Err(AdaptiveError::Cap {
                cap: r.max_readings,
                first: first_pass,
            });
        }
        if self.targets.is_empty() {
            return Err(AdaptiveError::NoTargets);
        }
        Ok(())
    }

    /// SHA-256 of the targets as text (17 significant digits each), for the fingerprint.
    pub fn targets_sha256(&self) -> String {
        let mut h = Sha256::new();
        for t in &self.targets {
            h.update(format!("{:.17e},{:.17e},{:.17e}\n", t.x, t.y, t.z).as_bytes());
        }
        format!("{:x}", h.finalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(tag: &str, text: &str) -> PathBuf {
        let p =
            std::env::temp_dir().join(format!("metamer-targets-{tag}-{}.csv", std::process::id()));
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn a_bad_targets_file_is_named_with_its_line() {
        let ok = file("ok", "X,Y,Z\n# the white\n95.0,100.0,108.9\n10,12,5\n");
        assert_eq!(
            read_targets(&ok).unwrap(),
            vec![Xyz::new(95.0, 100.0, 108.9), Xyz::new(10.0, 12.0, 5.0)]
        );
        let dark = file("dark", "X,Y,Z\n10,12,5\n1,0,1\n");
        let e = read_targets(&dark).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("{}:3: target X=1, Y=0, Z=1", dark.display())),
            "{e}"
        );
        let word = file("word", "X,Y,Z\n10,twelve,5\n");
        let e = read_targets(&word).unwrap_err().to_string();
        assert!(
            e.contains(&format!("{}:2:", word.display())) && e.contains("'twelve'"),
            "{e}"
        );
        let header = file("header", "R,G,B\n1,2,3\n");
        let e = read_targets(&header).unwrap_err().to_string();
        assert!(e.contains(&format!("{}:1:", header.display())), "{e}");
        for p in [ok, dark, word, header] {
            std::fs::remove_file(p).unwrap();
        }
    }
}
