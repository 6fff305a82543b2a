//! `metamer light`'s jobs as library calls: [`fit`] fits the light distribution to a
//! fall-off table and writes the fit, its chart and the IES/EULUMDAT files; [`show`] reads
//! a photometric file by its extension. The command line only parses, calls and prints.
//!
//! The fit reports as it goes through a [`FitEvent`] callback rather than only in a report
//! returned at the end: the fit's table and each file written are shown before a later
//! file can fail, and a report returned at the end would lose them on error.

use std::path::{Path, PathBuf};

use super::cgamma::CGammaTable;
use super::chart::ldc_chart_svg;
use super::fit::{fit as fit_falloff, Falloff, LdcError, LdcFit, ModelChoice};
use super::ies::{self, IesInfo};
use super::ldt::{self, LdtInfo};
use super::photometry::{flux_beyond_lm, flux_lm, Panel, Photometry, PhotometryError};
use crate::output::{OutputError, OutputPolicy};

/// Why a light job did not finish.
#[derive(Debug, thiserror::Error)]
pub enum LightError {
    /// The request itself is wrong (a missing panel size, two outputs on one file,
    /// relative readings without a luminance): the caller can fix it by asking
    /// differently; the command line calls it a usage error.
    #[error("{0}")]
    BadRequest(String),
    /// Light files asked for, or one side of the panel given, without both its sides.
    #[error("the light files need the panel's size: both its width and its height")]
    PanelSize,
    /// The light files need an absolute luminance the relative readings do not carry.
    #[error("the readings are relative (1 at the normal): the panel's luminance is needed")]
    NoLuminance,
    /// The fall-off file could not be read.
    #[error(transparent)]
    Read(LdcError),
    /// The fall-off readings cannot be fitted; named by their file.
    #[error("{}: {source}", file.display())]
    Fit { file: PathBuf, source: LdcError },
    /// The fit's chart could not be drawn.
    #[error(transparent)]
    Chart(LdcError),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Photometry(#[from] PhotometryError),
}

impl LightError {
    /// Whether the request, not the data or the machine, is at fault.
    pub fn is_bad_request(&self) -> bool {
        matches!(
            self,
            LightError::BadRequest(_) | LightError::PanelSize | LightError::NoLuminance
        )
    }
}

/// What `light fit` is asked to do.
#[derive(Clone, Debug)]
pub struct FitRequest {
    /// CSV `angle_deg,horizontal,vertical`.
    pub falloff: PathBuf,
    pub model: ModelChoice,
    /// The fit, its scores and its C-γ table (JSON).
    pub output: PathBuf,
    pub ies: Option<PathBuf>,
    pub ldt: Option<PathBuf>,
    pub chart: Option<PathBuf>,
    /// The panel's extent along its edge_u and edge_v, metres: needed for the IES/LDT
    /// files' candela.
    pub width_m: Option<f64>,
    pub height_m: Option<f64>,
    /// Luminance along the normal, cd/m²; `None` takes the readings' own, when absolute.
    pub luminance: Option<f64>,
    /// Replace output files that exist.
    pub force: bool,
}

/// A file [`fit`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightFile {
    Fit,
    Chart,
    Ies,
    Ldt,
}

/// What [`fit`] reports while it works.
#[derive(Debug)]
pub enum FitEvent<'a> {
    /// The distribution is fitted; nothing is written yet.
    Fitted(&'a LdcFit),
    /// A file is written.
    Written(LightFile, &'a Path),
    /// The panel the light files describe, before they are written, with its flux and the
    /// part of it the model extrapolates past the readings (see [`LdcFit::extrapolation`]).
    Panel {
        panel: &'a Panel,
        flux_lm: f64,
        extrapolated: Option<ExtrapolatedFlux>,
    },
}

/// The flux emitted where the table is extrapolated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtrapolatedFlux {
    /// γ above which at least one half-plane is extrapolated.
    pub beyond_deg: f64,
    pub flux_lm: f64,
}

/// Fits the light distribution curve to `request.falloff` and writes the files asked for.
/// Every output is checked, and the panel with it, before anything is fitted or written.
///
/// # Examples
///
/// ```
/// use metamer::light::job::{fit, FitRequest};
/// use metamer::light::ModelChoice;
///
/// let dir = std::env::temp_dir().join(format!("metamer-doc-light-fit-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let request = FitRequest {
///     falloff: concat!(env!("CARGO_MANIFEST_DIR"), "/data/light_falloff_9_angles.csv").into(),
///     model: ModelChoice::Auto,
///     output: dir.join("light.json"),
///     ies: Some(dir.join("light.ies")),
///     ldt: Some(dir.join("light.ldt")),
///     chart: None,
///     width_m: Some(0.3),
///     height_m: Some(0.3),
///     luminance: Some(1000.0),
///     force: true,
/// };
/// let fitted = fit(&request, &|_| {}).unwrap();
/// assert_eq!(fitted.normal_luminance, 1.0);
/// // The IES file reads back as the panel it was written for: 1000 cd/m² × 0.09 m².
/// let (_, photometry) = metamer::light::job::show(&dir.join("light.ies")).unwrap();
/// assert!((photometry.normal_intensity_cd - 90.0).abs() < 1e-3);
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn fit(request: &FitRequest, events: &dyn Fn(FitEvent)) -> Result<LdcFit, LightError> {
    let policy = check_outputs(request)?;
    let falloff = Falloff::read_csv(&request.falloff).map_err(LightError::Read)?;
    // The panel and its luminance are checked before anything is fitted or written, so a
    // bad width does not leave the fit written and the light files missing.
    let panel = panel(request, &falloff)?;
    let fit = fit_falloff(&falloff, request.model).map_err(|source| LightError::Fit {
        file: request.falloff.clone(),
        source,
    })?;
    events(FitEvent::Fitted(&fit));
    let json = serde_json::to_string_pretty(&fit)?;
    policy.write(&request.output, json.as_bytes())?;
    events(FitEvent::Written(LightFile::Fit, &request.output));
    if let Some(chart) = &request.chart {
        let svg = ldc_chart_svg(&fit).map_err(LightError::Chart)?;
        policy.write(chart, svg.as_bytes())?;
        events(FitEvent::Written(LightFile::Chart, chart));
    }
    if let Some(panel) = panel {
        let flux_lm = flux_lm(&fit.table, &panel);
        let extrapolated = fit.extrapolation().map(|e| ExtrapolatedFlux {
            beyond_deg: e.beyond_deg,
            flux_lm: flux_beyond_lm(&fit.table, &panel, e.beyond_deg),
        });
        events(FitEvent::Panel {
            panel: &panel,
            flux_lm,
            extrapolated,
        });
        write_light_files(request, &policy, &fit, &panel, events)?;
    }
    Ok(fit)
}

/// The output policy with every output checked: the panel size the light files need, no
/// two outputs on one file, none existing unless forced.
fn check_outputs(request: &FitRequest) -> Result<OutputPolicy, LightError> {
    let exports = request.ies.is_some() || request.ldt.is_some();
    if exports && (request.width_m.is_none() || request.height_m.is_none())
        || request.width_m.is_some() != request.height_m.is_some()
    {
        return Err(LightError::PanelSize);
    }
    let mut policy = OutputPolicy::new(request.force);
    policy.input(&request.falloff);
    let outputs = [
        Some(&request.output),
        request.ies.as_ref(),
        request.ldt.as_ref(),
        request.chart.as_ref(),
    ];
    let outputs: Vec<&PathBuf> = outputs.into_iter().flatten().collect();
    for (i, out) in outputs.iter().enumerate() {
        // Two outputs on one path: the second would be refused as existing, after the
        // first was written over it.
        if outputs[..i].iter().any(|o| same_path(o, out)) {
            return Err(LightError::BadRequest(format!(
                "{} is given for two outputs; each needs its own file",
                out.display()
            )));
        }
        policy.check(out)?;
    }
    Ok(policy)
}

/// The panel the light files describe, if a size is given: at `request.luminance`, or the
/// readings' own normal luminance when they are absolute.
fn panel(request: &FitRequest, falloff: &Falloff) -> Result<Option<Panel>, LightError> {
    let (Some(w), Some(h)) = (request.width_m, request.height_m) else {
        return Ok(None);
    };
    let l0 = match request.luminance {
        Some(l) => l,
        None => {
            let normal = falloff.validate().map_err(|source| LightError::Fit {
                file: request.falloff.clone(),
                source,
            })?;
            let l0 = (normal[0] + normal[1]) / 2.0;
            if l0 == 1.0 {
                return Err(LightError::NoLuminance);
            }
            l0
        }
    };
    Panel::new(w, h, l0)
        .map(Some)
        .map_err(|e| LightError::BadRequest(e.to_string()))
}

/// The IES and EULUMDAT files of `fit` for `panel`, those asked for.
fn write_light_files(
    request: &FitRequest,
    policy: &OutputPolicy,
    fit: &LdcFit,
    panel: &Panel,
    events: &dyn Fn(FitEvent),
) -> Result<(), LightError> {
    let date = today();
    let luminaire = format!(
        "flat panel {} m x {} m, {} light distribution fitted to {}",
        panel.width_m,
        panel.height_m,
        fit.model,
        request.falloff.display()
    );
    if let Some(path) = &request.ies {
        let info = IesInfo {
            test: format!("metamer light fit {}", request.falloff.display()),
            issue_date: date.clone(),
            luminaire: luminaire.clone(),
            generation: format!("metamer light fit, model {}", fit.model),
            extrapolation: fit.extrapolation(),
        };
        let text = ies::to_string(&fit.table, panel, &info);
        policy.write(path, text.as_bytes())?;
        events(FitEvent::Written(LightFile::Ies, path));
    }
    if let Some(path) = &request.ldt {
        let info = LdtInfo {
            luminaire,
            file_name: path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            date_user: format!("{date} metamer"),
            extrapolation: fit.extrapolation(),
        };
        let text = ldt::to_string(&fit.table, panel, &info);
        policy.write(path, text.as_bytes())?;
        events(FitEvent::Written(LightFile::Ldt, path));
    }
    Ok(())
}

/// Whether two output paths name one file: spelled alike, or (when it exists) the same
/// file by another name.
fn same_path(a: &Path, b: &Path) -> bool {
    a == b
        || matches!(
            (std::fs::canonicalize(a), std::fs::canonicalize(b)),
            (Ok(x), Ok(y)) if x == y
        )
}

/// Today's date (UTC) as YYYY-MM-DD, for the files' issue date.
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let (y, m, d) = crate::calendar::civil_from_days((secs / 86_400) as i64);
    format!("{y:04}-{m:02}-{d:02}")
}

/// Reads an IES (`.ies`) or EULUMDAT (`.ldt`) file, chosen by its extension: the
/// distribution and its photometry.
///
/// # Examples
///
/// ```
/// use metamer::light::job::show;
///
/// // A rotationally symmetric Lambertian 0.5 m × 0.2 m panel of 100 cd/m² (I₀ = 10 cd).
/// let file = std::env::temp_dir().join(format!("metamer-doc-show-{}.ies", std::process::id()));
/// let text = "IES:LM-63-2019\nTILT=NONE\n1 -1 1 3 1 1 2 0.2 0.5 0\n1 1 0\n0 45 90\n0\n\
///             10 7.0710678 0\n";
/// std::fs::write(&file, text).unwrap();
/// let (table, photometry) = show(&file).unwrap();
/// assert_eq!(photometry.symmetry, "rotationally symmetric");
/// assert!((photometry.normal_luminance_cd_m2().unwrap() - 100.0).abs() < 1e-9);
/// assert!((table.at(90.0, 45.0) - 1.0).abs() < 1e-7);
/// # std::fs::remove_file(&file).unwrap();
/// ```
pub fn show(file: &Path) -> Result<(CGammaTable, Photometry), LightError> {
    let ext = file
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "ies" => Ok(ies::read(file)?),
        "ldt" => Ok(ldt::read(file)?),
        _ => Err(LightError::BadRequest(format!(
            "{}: expected a .ies or .ldt file",
            file.display()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use crate::calendar::civil_from_days;

    #[test]
    fn dates_from_day_counts() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        // 2000-03-01 is day 11017; 2024-02-29 is day 19782 (a leap day).
        assert_eq!(civil_from_days(11_017), (2000, 3, 1));
        assert_eq!(civil_from_days(19_782), (2024, 2, 29));
    }
}
