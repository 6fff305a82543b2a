//! The reproduction stage: the rendered spot readings (and image) through the display
//! profile's inverse to drive values, with no tone mapping; what the display cannot show is
//! counted and marked, and mapped as the user chose. The image is mirrored as in the
//! paper's set-up, where the display is seen in a mirror beside the box; each patch's spot
//! is located on the image as shown (mirrored) for aiming the meter at the display, with
//! the pixels under it that the display cannot show.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::cache::write_atomic;
use super::error::ExperimentError;
use super::simulation::ImagePatch;
use crate::color::Xyz;
use crate::display::gamut::GamutMapping;
use crate::display::reproduce::{reproduce_image, reproduce_targets, write_drive_png};
use crate::display::Profile;
use crate::image::{read_xyz_image, XyzImage};
use crate::output::OutputPolicy;
use crate::rig::virtual_display::quantize;

/// How targets are reproduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReproductionOptions {
    /// Written as `clip` or `nearest-lab`.
    pub gamut: GamutMapping,
    pub mirror: bool,
}

/// One patch's drive values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchDrive {
    pub patch: usize,
    #[serde(rename = "target_XYZ")]
    pub target_xyz: Xyz,
    /// The inverse model's drive values before gamut handling (outside 0–1 when out of gamut).
    pub unclipped_rgb: [f64; 3],
    pub out_of_gamut: bool,
    /// The 8-bit values shown.
    pub rgb8: [u8; 3],
}

/// A patch's spot on the image as shown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchRegion {
    pub patch: usize,
    /// The patch's row (1–4) and column (1–6) on the ColorChecker.
    pub row: usize,
    pub column: usize,
    /// The meter's aim as fractions of the shown image's width and height from its
    /// top-left corner (mirrored when the image is), and the spot's radius as a fraction of
    /// its height.
    pub x: f64,
    pub y: f64,
    pub radius: f64,
    /// Pixels under the spot, and how many of them lie outside the display's gamut.
    pub pixels: usize,
    pub out_of_gamut_pixels: usize,
}

impl PatchRegion {
    /// The patch's spot on the screen, for the image placed at `placement`.
    pub fn on_screen(&self, placement: &crate::rig::Placement) -> crate::image::ScreenSpot {
        placement.on_screen(crate::image::ScreenSpot {
            x: self.x,
            y: self.y,
            radius: self.radius,
        })
    }
}

/// What `reproduction/reproduction.json` holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Reproduction {
    pub patches: Vec<PatchDrive>,
    pub out_of_gamut_patches: Vec<usize>,
    /// Pixels of the image outside the gamut, when an image was reproduced.
    pub image_out_of_gamut_pixels: Option<usize>,
    /// Each patch's spot on the shown image, when an image was reproduced.
    #[serde(default)]
    pub image_patches: Vec<PatchRegion>,
}

pub const FILE: &str = "reproduction.json";
pub const IMAGE_FILE: &str = "display.png";

pub fn reproduce(
    dir: &Path,
    profile: &Profile,
    spots: &[crate::render::spot::RenderedReading],
    image: Option<(&Path, &[ImagePatch])>,
    opts: &ReproductionOptions,
) -> Result<(Reproduction, Vec<&'static str>), ExperimentError> {
    let mapping = opts.gamut;
    let targets: Vec<Xyz> = spots.iter().map(|s| s.xyz).collect();
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
    let mut image_patches = Vec::new();
    let image_out_of_gamut_pixels = match image {
        Some((path, located)) => {
            let img = read_xyz_image(path)?;
            let drive = reproduce_image(profile, &img, opts.mirror, mapping);
            // The stage directory is the stage's own: a re-run replaces its files.
            write_drive_png(&dir.join(IMAGE_FILE), &drive, 8, &OutputPolicy::new(true))?;
            files.push(IMAGE_FILE);
            image_patches = located
                .iter()
                .map(|p| region(profile, &img, p, opts.mirror))
                .collect();
            Some(drive.out_of_gamut)
        }
        None => {
            // An image of an earlier run with other options is not this run's.
            remove_stale(&dir.join(IMAGE_FILE))?;
            None
        }
    };
    let r = Reproduction {
        out_of_gamut_patches: patches
            .iter()
            .filter(|p| p.out_of_gamut)
            .map(|p| p.patch)
            .collect(),
        patches,
        image_out_of_gamut_pixels,
        image_patches,
    };
    let text = serde_json::to_string_pretty(&r).map_err(ExperimentError::Json)?;
    write_atomic(&dir.join(FILE), text.as_bytes())?;
    Ok((r, files))
}

/// Patch `p`'s spot on the shown image: pixel centres inside the spot's disc on the
/// rendered image, checked against the display's gamut; the aim mirrored with the image.
fn region(profile: &Profile, img: &XyzImage, p: &ImagePatch, mirror: bool) -> PatchRegion {
    let (cx, cy) = (p.x * img.width as f64, p.y * img.height as f64);
    let r = p.radius * img.height as f64;
    let (mut pixels, mut out) = (0, 0);
    let span =
        |c: f64, n: usize| (c - r).floor().max(0.0) as usize..((c + r).ceil() as usize).min(n);
    for y in span(cy, img.height) {
        for x in span(cx, img.width) {
            let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
            if dx * dx + dy * dy > r * r {
                continue;
            }
            pixels += 1;
            if profile
                .inverse(Xyz::from(img.at(x, y).map(f64::from)))
                .out_of_gamut
            {
                out += 1;
            }
        }
    }
    PatchRegion {
        patch: p.patch,
        row: (p.patch - 1) / 6 + 1,
        column: (p.patch - 1) % 6 + 1,
        x: if mirror { 1.0 - p.x } else { p.x },
        y: p.y,
        radius: p.radius,
        pixels,
        out_of_gamut_pixels: out,
    }
}

fn remove_stale(path: &Path) -> Result<(), ExperimentError> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(ExperimentError::Io {
            file: path.to_path_buf(),
            source: e,
        }),
        _ => Ok(()),
    }
}
