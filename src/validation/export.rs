//! The report's numbers as JSON and CSV, and writing the three report files into a
//! directory under the output policy.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::output::OutputPolicy;

use super::assess::Assessment;
use super::error::ValidationError;
use super::report::{render_html, ReportInput};

/// The file names inside the output directory.
pub const JSON_FILE: &str = "validation.json";
pub const CSV_FILE: &str = "validation.csv";
pub const HTML_FILE: &str = "report.html";

/// `validation.json`: the report's input as data.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ValidationJson<'a> {
    pub format: &'a str,
    pub version: u32,
    #[serde(flatten)]
    pub report: &'a ReportInput,
}

/// The comparisons of `input`, display vs box, simulation vs box, display vs simulation,
/// each with the key `validation.csv` names it by (the first two keep their older,
/// reference-first keys).
pub fn comparisons(input: &ReportInput) -> Vec<(&'static str, &Assessment)> {
    [
        ("box_vs_display", &input.display_vs_box),
        ("box_vs_simulation", &input.simulation_vs_box),
        ("display_vs_simulation", &input.display_vs_simulation),
    ]
    .into_iter()
    .filter_map(|(k, a)| a.as_ref().map(|a| (k, a)))
    .collect()
}

/// `validation.json`'s text.
pub fn to_json(input: &ReportInput) -> String {
    let doc = ValidationJson {
        format: "metamer-validation",
        version: 1,
        report: input,
    };
    serde_json::to_string_pretty(&doc).expect("the report serializes")
}

/// One row per comparison and patch.
pub fn to_csv(input: &ReportInput) -> String {
    let mut s = String::from(
        "comparison,patch,name,X_ref,Y_ref,Z_ref,uX_ref,uY_ref,uZ_ref,X_test,Y_test,Z_test,uX_test,uY_test,uZ_test,L_ref,a_ref,b_ref,L_test,a_test,b_test,de76,de76_lo,de76_hi,de00,de00_lo,de00_hi,jnd,out_of_gamut\n",
    );
    for (key, a) in comparisons(input) {
        for p in &a.patches {
            let nums: Vec<String> = p
                .reference
                .xyz
                .into_iter()
                .chain(p.reference.u_xyz)
                .chain(p.test.xyz)
                .chain(p.test.u_xyz)
                .chain(p.reference.lab)
                .chain(p.test.lab)
                .chain([
                    p.de76,
                    p.de76_interval.lo,
                    p.de76_interval.hi,
                    p.de00,
                    p.de00_interval.lo,
                    p.de00_interval.hi,
                ])
                .map(|v| format!("{v:.6}"))
                .collect();
            s += &format!(
                "{key},{},{},{},{},{}\n",
                p.patch,
                p.name,
                nums.join(","),
                p.jnd.name(),
                u8::from(p.out_of_gamut)
            );
        }
    }
    s
}

/// Writes `validation.json`, `validation.csv` and `report.html` into `dir` (created if
/// missing) under `policy`: each atomically, never onto an input, existing files only when
/// forced. All three are checked before any is written, so a refusal leaves no mix of old
/// and new files. Returns the paths.
pub fn write_report_files(
    dir: &Path,
    input: &ReportInput,
    policy: &OutputPolicy,
) -> Result<Vec<PathBuf>, ValidationError> {
    policy.dir(dir)?;
    let files = [
        (JSON_FILE, to_json(input)),
        (CSV_FILE, to_csv(input)),
        (HTML_FILE, render_html(input)),
    ];
    for (name, _) in &files {
        policy.check(&dir.join(name))?;
    }
    files
        .iter()
        .map(|(name, text)| {
            let path = dir.join(name);
            policy.write(&path, text.as_bytes())?;
            Ok(path)
        })
        .collect()
}
