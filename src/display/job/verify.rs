//! `metamer verify` as one call: a display profile's predictions against measured patches
//! (for instance ones it was not fitted to).

use std::path::PathBuf;

use crate::display::verify::{Verification, VerifyError};
use crate::display::{
    read_measurement_file, verify_profile, MeasurementsError, Profile, ProfileError,
};

/// The profile and the patches to check it against.
#[derive(Clone, Debug)]
pub struct Request {
    /// A profile written by `fit` or `characterize`.
    pub profile: PathBuf,
    /// `.ti3` or CSV `r,g,b,X,Y,Z`.
    pub measurements: PathBuf,
}

/// The profile checked and how well it predicts.
#[derive(Clone, Debug)]
pub struct Report {
    pub profile: Profile,
    pub verification: Verification,
}

/// A check failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Profile(#[from] ProfileError),
    #[error(transparent)]
    Measurements(#[from] MeasurementsError),
    #[error(transparent)]
    Verify(#[from] VerifyError),
}

/// Predicts every measured patch with the profile and compares; `warning` hears about
/// measurements that are relative to their white (taken as if it had 100 cd/m²).
///
/// # Examples
///
/// A profile fitted to one `.ti3` of the test data, checked against another:
///
/// ```
/// use metamer::display::job::verify::{run, Request};
/// use metamer::display::{fit_profile, read_measurements, ModelKind};
/// use metamer::output::OutputPolicy;
///
/// let data = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data");
/// let fitted = read_measurements(format!("{data}/dispread_analytic.ti3").as_ref())?;
/// let profile = std::env::temp_dir().join(format!("metamer-doc-verify-{}.json", std::process::id()));
/// fit_profile(ModelKind::Plcc, &fitted, None)?.save(&profile, &OutputPolicy::new(true))?;
/// let request = Request {
///     profile: profile.clone(),
///     measurements: format!("{data}/dispread_analytic.ti3").into(),
/// };
/// let report = run(&request, &mut |_| {})?;
/// assert!(report.verification.de00.mean < 1.0);
/// # std::fs::remove_file(&profile)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run(request: &Request, warning: &mut dyn FnMut(String)) -> Result<Report, Error> {
    let profile = Profile::load(&request.profile)?;
    let m = read_measurement_file(&request.measurements)?;
    if !m.absolute {
        warning(format!(
            "{} holds white-relative XYZ (no LUMINANCE_XYZ_CDM2): taken as if the white had \
             100 cd/m²",
            request.measurements.display()
        ));
    }
    let verification = verify_profile(&profile, &m.patches)?;
    Ok(Report {
        profile,
        verification,
    })
}
