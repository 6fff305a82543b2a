//! What a validation report shows, as data: the comparisons and the optional sections a
//! caller fills (the experiment fills them all, `validate` what its files hold). The report
//! draws a [`ReportInput`] (`super::report`); the experiment gathers its stages' files into
//! [`Sections`] (`experiment::report_input`), which the validation turns into one.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::assess::Assessment;
pub use super::cost_curve::CostCurve;
use super::readings::{ReadingSet, UncertaintySource};

/// Everything a report can show. `display_vs_box` is the paper's result and always there;
/// the rest is drawn when given. The comparisons are named test first, as everywhere; two
/// keep their older serialized names (`box_vs_display`, `box_vs_simulation`), which
/// `validation.json` has always used.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ReportInput {
    pub title: String,
    /// How CIELAB's white was chosen (for the reader).
    pub white_source: String,
    /// Fig. 4 and 5: the display showing the rendering, tested against the box.
    #[serde(rename = "box_vs_display")]
    pub display_vs_box: Option<Assessment>,
    /// Fig. 6: the simulation tested against the box.
    #[serde(rename = "box_vs_simulation")]
    pub simulation_vs_box: Option<Assessment>,
    /// The display tested against the simulation.
    pub display_vs_simulation: Option<Assessment>,
    pub display_model: Option<DisplayModelSection>,
    pub light_fit: Option<LightFitSection>,
    pub render_confidence: Option<RenderConfidenceSection>,
    pub instruments: Vec<InstrumentUsed>,
    /// 1-based patches whose colour the display cannot show (beyond what the readings say).
    pub out_of_gamut: Vec<usize>,
    /// The input files and what they held.
    pub inputs: Vec<InputFile>,
    /// What each side's interval contains, by side ("box", "simulation", "display");
    /// a side not named here is described from its readings' uncertainty source.
    #[serde(default)]
    pub uncertainty: Vec<(String, String)>,
    /// Each measuring stage's budget before its first reading and what it took.
    #[serde(default)]
    pub measuring_cost: Vec<StageCost>,
    /// Each side's accuracy against its readings and minutes, this run's and the compared
    /// run's (`validation::cost_curve`).
    #[serde(default)]
    pub cost_curves: Vec<CostCurve>,
    /// Another run, made with another plan on the same rig, whose cost the report sets
    /// beside this one's.
    #[serde(default)]
    pub compared_cost: Option<ComparedCost>,
    pub notes: Vec<String>,
}

/// Another run's measuring cost, from its saved folder.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ComparedCost {
    /// How the report names it (its folder's name).
    pub run: String,
    pub stages: Vec<StageCost>,
}

/// One measuring stage's cost as the report shows it: the budget made before its first
/// reading and, once it ran, what it took (the instrument's time at its real pace, whatever
/// a simulation's time scale; the wall time as the clock ran).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageCost {
    pub stage: String,
    pub budget: CostFigures,
    pub taken: Option<CostFigures>,
}

/// Counts and seconds of a budget or of what a stage took.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CostFigures {
    pub readings: usize,
    pub placements: usize,
    pub calibrations: usize,
    pub instrument_s: f64,
    /// Instrument, operator and settle time: the session's length at the rig (what was
    /// taken counts the instrument at its real pace here too, so a simulation at another
    /// time scale shows what a real rig would have taken, but the operator's waits).
    pub rig_s: f64,
}

/// The display's characterization: the model, its diagnostics and its verification.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DisplayModelSection {
    pub model: String,
    /// The fit's verdict in words ("PLCC's assumptions hold within ΔE00 0.5 …").
    pub verdict: String,
    /// Diagnostics as (what, value) rows.
    pub diagnostics: Vec<(String, String)>,
    /// Held-out verification ΔE00 (mean, p95, max) and the patch count.
    pub verification_de00: Option<[f64; 3]>,
    pub verification_patches: usize,
}

/// The light distribution (LDC) fit.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LightFitSection {
    pub summary: Vec<(String, String)>,
    /// An SVG chart of the fit, drawn inline (scripts are removed).
    pub chart_svg: Option<String>,
}

/// The renderer's confidence.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RenderConfidenceSection {
    pub method: String,
    /// The target 95 % ΔE*ab half-width.
    pub target_de: Option<f64>,
    /// Per patch: (patch, 95 % ΔE*ab half-width or bound).
    pub per_patch: Vec<(usize, f64)>,
    /// What the per-patch numbers are ("95 % half-width", "error bound").
    #[serde(default)]
    pub measure: String,
    /// Whether every patch reached the target.
    #[serde(default)]
    pub converged: Option<bool>,
    /// Wall time of the render, seconds.
    #[serde(default)]
    pub seconds: Option<f64>,
}

/// An instrument used, with its calibrations.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InstrumentUsed {
    pub role: String,
    pub model: String,
    /// Serial number and firmware where the instrument reports them.
    #[serde(default)]
    pub serial: Option<String>,
    #[serde(default)]
    pub firmware: Option<String>,
    /// How it was connected (`/dev/ttyUSB0`, `sim:cs100a`, …).
    #[serde(default)]
    pub connection: Option<String>,
    /// Each calibration with its time ("2026-12-01T22:54:03Z emissive, on_white_tile").
    pub calibrations: Vec<String>,
}

/// An input file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InputFile {
    pub role: String,
    pub path: String,
    pub format: String,
    pub patches: usize,
    /// SHA-256 of its bytes (hex), where known.
    #[serde(default)]
    pub sha256: Option<String>,
}

/// The sections a caller gathers beside the readings (the experiment from its earlier
/// stages' files), each missing one noted.
#[derive(Clone, Debug, Default)]
pub struct Sections {
    pub display_model: Option<DisplayModelSection>,
    pub light_fit: Option<LightFitSection>,
    pub render_confidence: Option<RenderConfidenceSection>,
    /// The simulation's per-patch uncertainty, to enter the comparisons' intervals.
    pub render_uncertainty: Option<RenderUncertainty>,
    pub instruments: Vec<InstrumentUsed>,
    pub inputs: Vec<InputFile>,
    pub measuring_cost: Vec<StageCost>,
    pub cost_curves: Vec<CostCurve>,
    pub compared_cost: Option<ComparedCost>,
    pub notes: Vec<String>,
}

/// The simulation's uncertainty per patch, to enter the comparisons' intervals.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderUncertainty {
    /// Patch → per-axis CIELAB standard uncertainty.
    pub sigma_lab: BTreeMap<usize, f64>,
    /// What it is, for the report.
    pub description: String,
}

impl RenderUncertainty {
    /// Gives each simulated patch of `set` the render's uncertainty (its XYZ carry none
    /// of their own: the stage writes one rendered value per patch).
    pub fn apply(&self, set: &mut ReadingSet) {
        for (k, p) in set.patches.iter_mut() {
            if let Some(s) = self.sigma_lab.get(k) {
                p.u_lab = (p.u_lab.powi(2) + s.powi(2)).sqrt();
                if p.u_factors.is_empty() {
                    p.source = UncertaintySource::Render;
                }
            }
        }
    }
}
