//! `metamer fit` as one call: read measured patches, choose or take a display model, fit
//! it, save the profile and, when asked, an ICC profile read back against the model and
//! the selection chart. Every option that cannot work is refused, and every output that
//! may not be written is found, before the fit.

use std::path::{Path, PathBuf};

use crate::display::icc::{
    agreement, encode_icc, inverse_agreement, Agreement, IccError, IccReadError, IccSummary,
    IccVersion,
};
use crate::display::select_chart::selection_svg;
use crate::display::{
    fit_profile_with, read_measurement_file, select_model, FitError, FitOptions, MeasurementsError,
    ModelKind, Profile, ProfileError, Selection,
};
use crate::output::{OutputError, OutputPolicy};

/// What to fit and where to write it.
#[derive(Clone, Debug)]
pub struct Request {
    /// `.ti3` or CSV `r,g,b,X,Y,Z`.
    pub measurements: PathBuf,
    /// The model; None: chosen by cross-validation over the patches.
    pub model: Option<ModelKind>,
    /// Cross-validation folds when the model is chosen (at least 2).
    pub folds: usize,
    /// A fixed exponent (plcc-gamma only) and the instrument's noise.
    pub options: FitOptions,
    /// The profile (JSON).
    pub output: PathBuf,
    /// Replace outputs that exist (never one of the inputs).
    pub force: bool,
    /// Also an ICC profile, of this version (default 4).
    pub icc: Option<PathBuf>,
    pub icc_version: Option<IccVersion>,
    /// Also the model selection's chart (SVG); only when the model is chosen.
    pub chart: Option<PathBuf>,
}

/// What the fit says as it goes.
pub enum Event<'a> {
    /// Something to know about the measurements before trusting the fit.
    Warning(String),
    /// The model chosen, with every candidate's held-out error.
    Selected(&'a Selection),
    ChartWritten(&'a Path),
    /// The profile fitted to `patches` patches of `measurements` (written next).
    Fitted {
        patches: usize,
        measurements: &'a Path,
        profile: &'a Profile,
    },
    ProfileWritten(&'a Path),
}

/// The ICC profile written and how closely it follows the model.
#[derive(Clone, Debug)]
pub struct IccReport {
    pub path: PathBuf,
    pub summary: IccSummary,
    /// Its A2B0 (drive → PCS) against the model over the measured drives.
    pub forward: Agreement,
    /// Its B2A0 against the model's inverse; None when it could not be read back.
    pub inverse: Option<Agreement>,
}

/// What a fit made.
#[derive(Clone, Debug)]
pub struct Report {
    pub profile: Profile,
    pub icc: Option<IccReport>,
}

/// A fit was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{}: is a directory; give the profile file to write", .0.display())]
    OutputIsDirectory(PathBuf),
    #[error("a fixed gamma applies to the plcc-gamma model only")]
    GammaWithoutPlccGamma,
    #[error("the gamma must be a positive number, got {0}")]
    BadGamma(f64),
    #[error("an ICC version needs an ICC output")]
    IccVersionWithoutIcc,
    #[error("the selection chart needs the model chosen by cross-validation")]
    ChartWithoutSelection,
    #[error("the noise must be a non-negative number, got {0}")]
    BadNoise(f64),
    #[error("the folds must be at least 2, got {0}")]
    Folds(usize),
    #[error("cannot draw {}: {message}", path.display())]
    Chart { path: PathBuf, message: String },
    /// Not transparent: the caller finds the output error in the chain (to offer --force).
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error(transparent)]
    Measurements(#[from] MeasurementsError),
    #[error(transparent)]
    Fit(#[from] FitError),
    #[error(transparent)]
    Profile(#[from] ProfileError),
    #[error(transparent)]
    Icc(#[from] IccError),
    #[error(transparent)]
    IccRead(#[from] IccReadError),
}

/// Fits the request's model (or chooses one) to its measurements and writes the profile,
/// and the ICC profile and selection chart when asked.
///
/// # Examples
///
/// PLCC on a `.ti3` from the test data, with an ICC v4 profile:
///
/// ```
/// use metamer::display::job::fit::{run, Request};
/// use metamer::display::{FitOptions, ModelKind};
///
/// let dir = std::env::temp_dir().join(format!("metamer-doc-fit-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let request = Request {
///     measurements: concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/dispread_analytic.ti3").into(),
///     model: Some(ModelKind::Plcc),
///     folds: 5,
///     options: FitOptions::default(),
///     output: dir.join("profile.json"),
///     force: true,
///     icc: Some(dir.join("display.icc")),
///     icc_version: None,
///     chart: None,
/// };
/// let report = run(&request, &mut |_| {})?;
/// assert_eq!(report.profile.model, ModelKind::Plcc);
/// assert!(report.icc.unwrap().forward.max_de00 < 1.0);
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run(request: &Request, events: &mut dyn FnMut(Event<'_>)) -> Result<Report, Error> {
    let r = request;
    if r.output.is_dir() {
        return Err(Error::OutputIsDirectory(r.output.clone()));
    }
    let mut out = OutputPolicy::new(r.force);
    out.input(&r.measurements);
    // Before the fit, which may take a while: a refused output is found now.
    out.check(&r.output)?;
    if let Some(g) = r.options.gamma {
        if r.model != Some(ModelKind::PlccGamma) {
            return Err(Error::GammaWithoutPlccGamma);
        }
        if !(g.is_finite() && g > 0.0) {
            return Err(Error::BadGamma(g));
        }
    }
    if r.icc_version.is_some() && r.icc.is_none() {
        return Err(Error::IccVersionWithoutIcc);
    }
    // The ICC profile and the chart follow the output policy: never onto the measurements
    // or the JSON profile, never over an existing file; checked before the fit so no work
    // is lost.
    let mut extra = OutputPolicy::new(r.force);
    extra.inputs([r.measurements.as_path(), r.output.as_path()]);
    if let Some(path) = &r.icc {
        extra.check(path)?;
    }
    if let Some(path) = &r.chart {
        if r.model.is_some() {
            return Err(Error::ChartWithoutSelection);
        }
        extra.check(path)?;
    }
    let m = read_measurement_file(&r.measurements)?;
    if !m.absolute {
        events(Event::Warning(format!(
            "{} holds white-relative XYZ (no LUMINANCE_XYZ_CDM2): taken as if the white had \
             100 cd/m²",
            r.measurements.display()
        )));
    }
    if let Some(n) = r.options.noise_de00 {
        if !(n.is_finite() && n >= 0.0) {
            return Err(Error::BadNoise(n));
        }
    }
    if r.folds < 2 {
        return Err(Error::Folds(r.folds));
    }
    let kind = match r.model {
        Some(kind) => kind,
        None => {
            let selection = select_model(&m.patches, r.folds, &r.options)?;
            events(Event::Selected(&selection));
            if let Some(path) = &r.chart {
                let svg = selection_svg(&selection).map_err(|message| Error::Chart {
                    path: path.clone(),
                    message,
                })?;
                extra.write(path, svg.as_bytes())?;
                events(Event::ChartWritten(path));
            }
            selection.model
        }
    };
    let profile = fit_profile_with(kind, &m.patches, Some(&r.measurements), &r.options)?;
    events(Event::Fitted {
        patches: m.patches.len(),
        measurements: &r.measurements,
        profile: &profile,
    });
    profile.save(&r.output, &out)?;
    events(Event::ProfileWritten(&r.output));
    let icc = match &r.icc {
        Some(path) => {
            let drives: Vec<[f64; 3]> = m.patches.iter().map(|p| p.rgb).collect();
            Some(write_icc(r, path, &profile, &drives, &extra)?)
        }
        None => None,
    };
    Ok(Report { profile, icc })
}

/// Encodes `profile` as ICC into `path` and reads it back against the model.
fn write_icc(
    r: &Request,
    path: &Path,
    profile: &Profile,
    drives: &[[f64; 3]],
    out: &OutputPolicy,
) -> Result<IccReport, Error> {
    let version = r.icc_version.unwrap_or(IccVersion::V4);
    let name = r
        .measurements
        .file_name()
        .unwrap_or_default()
        .to_string_lossy();
    let icc = encode_icc(
        profile,
        version,
        &format!("metamer {} ({name})", profile.model),
    )?;
    out.write(path, &icc.bytes)?;
    let forward = agreement(&icc.bytes, profile, drives)?;
    let inverse = inverse_agreement(&icc.bytes, profile, drives).ok();
    Ok(IccReport {
        path: path.to_path_buf(),
        summary: icc.summary,
        forward,
        inverse,
    })
}
