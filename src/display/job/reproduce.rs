//! `metamer reproduce` as one call: XYZ targets (CSV) or an absolute XYZ image through a
//! display profile's inverse model to drive values, written as CSV or PNG, with the
//! out-of-gamut values counted. The image is read as [`crate::image`] interprets every
//! reader's header: an OpenEXR `whiteLuminance` scales its values to cd/m², as it does for
//! the read-back, so both see the same XYZ in one file.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::display::gamut::GamutMapping;
use crate::display::reproduce::{
    read_targets, reproduce_image, reproduce_targets, write_drive_csv, write_drive_png,
};
use crate::display::{Profile, ProfileError};
use crate::image::{read_xyz_image, ImageError};
use crate::numeric_csv::CsvError;
use crate::output::{OutputError, OutputPolicy};

/// What to reproduce: exactly one of `xyz` and `image`.
#[derive(Clone, Debug)]
pub struct Request {
    /// A profile written by `fit` or `characterize`.
    pub profile: PathBuf,
    /// Targets: CSV with the header `X,Y,Z` (cd/m²); writes `r,g,b,out_of_gamut`.
    pub xyz: Option<PathBuf>,
    /// An absolute XYZ image (`.exr` or `.pfm`); writes a PNG of drive values.
    pub image: Option<PathBuf>,
    pub output: PathBuf,
    /// Replace the output if it exists (never one of the inputs).
    pub force: bool,
    /// The PNG's bits per channel (8 or 16; default 8), images only.
    pub bits: Option<u8>,
    /// Flip the image left–right (the paper's display is seen in a mirror), images only.
    pub mirror: bool,
    pub gamut: GamutMapping,
}

/// What was reproduced.
#[derive(Clone, Debug)]
pub enum Report {
    Targets {
        count: usize,
        out_of_gamut: usize,
    },
    Image {
        width: usize,
        height: usize,
        /// The conversion alone, without reading and writing.
        elapsed: Duration,
        out_of_gamut: usize,
        bits: u8,
    },
}

/// A reproduction was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("the PNG depth must be 8 or 16 bits, got {0}")]
    Bits(u8),
    #[error("a PNG depth applies to an image only; targets are written as CSV numbers")]
    BitsForTargets,
    #[error("{}: is a directory; give the file to write", .0.display())]
    OutputIsDirectory(PathBuf),
    #[error("mirroring applies to an image only")]
    MirrorForTargets,
    #[error("give exactly one of the targets and the image")]
    NoInput,
    /// Not transparent: the caller finds the output error in the chain (to offer --force).
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error(transparent)]
    Profile(#[from] ProfileError),
    #[error(transparent)]
    Targets(#[from] CsvError),
    #[error(transparent)]
    Image(#[from] ImageError),
}

/// Reproduces the request's targets or image through its profile and writes the drive
/// values.
///
/// # Examples
///
/// Two targets through a profile fitted to a `.ti3` of the test data:
///
/// ```
/// use metamer::display::gamut::GamutMapping;
/// use metamer::display::job::reproduce::{run, Report, Request};
/// use metamer::display::{fit_profile, read_measurements, ModelKind};
/// use metamer::output::OutputPolicy;
///
/// let dir = std::env::temp_dir().join(format!("metamer-doc-reproduce-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let ti3 = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/dispread_analytic.ti3");
/// let profile = fit_profile(ModelKind::Plcc, &read_measurements(ti3.as_ref())?, None)?;
/// profile.save(&dir.join("profile.json"), &OutputPolicy::new(true))?;
/// std::fs::write(dir.join("targets.csv"), "X,Y,Z\n20,20,20\n5000,9000,100\n")?;
/// let request = Request {
///     profile: dir.join("profile.json"),
///     xyz: Some(dir.join("targets.csv")),
///     image: None,
///     output: dir.join("rgb.csv"),
///     force: true,
///     bits: None,
///     mirror: false,
///     gamut: GamutMapping::Clip,
/// };
/// let report = run(&request)?;
/// assert!(matches!(report, Report::Targets { count: 2, out_of_gamut: 1 }));
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run(request: &Request) -> Result<Report, Error> {
    let r = request;
    let bits = r.bits.unwrap_or(8);
    if bits != 8 && bits != 16 {
        return Err(Error::Bits(bits));
    }
    if r.bits.is_some() && r.xyz.is_some() {
        return Err(Error::BitsForTargets);
    }
    if r.output.is_dir() {
        return Err(Error::OutputIsDirectory(r.output.clone()));
    }
    let mut out = OutputPolicy::new(r.force);
    out.input(&r.profile);
    out.inputs(r.xyz.iter().chain(&r.image).map(PathBuf::as_path));
    out.check(&r.output)?;
    let profile = Profile::load(&r.profile)?;
    match (&r.xyz, &r.image) {
        (Some(targets), None) => {
            if r.mirror {
                return Err(Error::MirrorForTargets);
            }
            let xyz = read_targets(targets)?;
            let drives = reproduce_targets(&profile, &xyz, r.gamut);
            write_drive_csv(&r.output, &drives, &out)?;
            Ok(Report::Targets {
                count: drives.len(),
                out_of_gamut: drives.iter().filter(|d| d.out_of_gamut).count(),
            })
        }
        (None, Some(image)) => {
            let img = read_xyz_image(image)?;
            let start = Instant::now();
            let drive = reproduce_image(&profile, &img, r.mirror, r.gamut);
            let elapsed = start.elapsed();
            write_drive_png(&r.output, &drive, bits, &out)?;
            Ok(Report::Image {
                width: img.width,
                height: img.height,
                elapsed,
                out_of_gamut: drive.out_of_gamut,
                bits,
            })
        }
        _ => Err(Error::NoInput),
    }
}
