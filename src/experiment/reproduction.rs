//! The reproduction stage: the rendered spot readings (and image) through the display
//! profile's inverse to drive values, with no tone mapping; what the display cannot show is
//! counted and marked, and mapped as the user chose. The image is mirrored as in the
//! paper's set-up, where the display is seen in a mirror beside the box.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::cache::write_atomic;
use super::error::ExperimentError;
use super::simulation::SimSpot;
use crate::display::gamut::GamutMapping;
use crate::display::reproduce::{reproduce_image, reproduce_targets, write_drive_png};
use crate::display::Profile;
use crate::output::OutputPolicy;
use crate::render::image_io::read_xyz_image;
use crate::rig::virtual_display::quantize;

/// How targets are reproduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReproductionOptions {
    /// `clip` or `nearest-lab`.
    pub gamut: String,
    pub mirror: bool,
}

/// One patch's drive values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchDrive {
    pub patch: usize,
    #[serde(rename = "target_XYZ")]
    pub target_xyz: [f64; 3],
    /// The inverse model's drive values before gamut handling (outside 0–1 when out of gamut).
    pub unclipped_rgb: [f64; 3],
    pub out_of_gamut: bool,
    /// The 8-bit values shown.
    pub rgb8: [u8; 3],
}

/// What `reproduction/reproduction.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Reproduction {
    pub patches: Vec<PatchDrive>,
    pub out_of_gamut_patches: Vec<usize>,
    /// Pixels of the image outside the gamut, when an image was reproduced.
    pub image_out_of_gamut_pixels: Option<usize>,
}

pub const FILE: &str = "reproduction.json";
pub const IMAGE_FILE: &str = "display.png";

pub fn reproduce(
    dir: &Path,
    profile: &Profile,
    spots: &[SimSpot],
    image: Option<&Path>,
    opts: &ReproductionOptions,
) -> Result<(Reproduction, Vec<&'static str>), ExperimentError> {
    let mapping: GamutMapping =
        opts.gamut
            .parse()
            .map_err(|e: String| ExperimentError::Option {
                what: "gamut mapping",
                message: e,
            })?;
    let targets: Vec<[f64; 3]> = spots.iter().map(|s| s.xyz).collect();
    let drives = reproduce_targets(profile, &targets, mapping);
    let patches: Vec<PatchDrive> = spots
        .iter()
        .zip(&drives)
        .map(|(s, d)| PatchDrive {
            patch: s.patch,
            target_xyz: s.xyz,
            unclipped_rgb: profile.inverse(s.xyz).unclipped,
            out_of_gamut: d.out_of_gamut,
            rgb8: d.rgb.map(quantize),
        })
        .collect();
    std::fs::create_dir_all(dir).map_err(|source| ExperimentError::Io {
        file: dir.to_path_buf(),
        source,
    })?;
    let mut files = vec![FILE];
    let image_out_of_gamut_pixels = match image {
        Some(path) => {
            let img = read_xyz_image(path)?;
            let drive = reproduce_image(profile, &img, opts.mirror, mapping);
            // The stage directory is the stage's own: a re-run replaces its files.
            write_drive_png(&dir.join(IMAGE_FILE), &drive, 8, &OutputPolicy::new(true))?;
            files.push(IMAGE_FILE);
            Some(drive.out_of_gamut)
        }
        None => None,
    };
    let r = Reproduction {
        out_of_gamut_patches: patches
            .iter()
            .filter(|p| p.out_of_gamut)
            .map(|p| p.patch)
            .collect(),
        patches,
        image_out_of_gamut_pixels,
    };
    let text = serde_json::to_string_pretty(&r).map_err(ExperimentError::Json)?;
    write_atomic(&dir.join(FILE), text.as_bytes())?;
    Ok((r, files))
}
