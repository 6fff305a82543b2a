//! Reproduction (paper §5): XYZ targets or a rendered XYZ image → display drive values
//! through a profile's inverse model. No tone mapping: the paper sets the display's peak
//! luminance so every rendered value fits, so anything that does not fit is counted and
//! reported as out of gamut (and clipped, or mapped to the nearest CIELAB colour on request).
//!
//! `mirror` flips the image left–right for the paper's set-up, where the display is seen
//! through a mirror beside the box.

use std::path::Path;

use crate::output::{OutputError, OutputPolicy};

use rayon::prelude::*;

use super::gamut::{map_to_gamut, GamutMapping};
use super::model::Inverse;
use super::profile::Profile;
use crate::color::Xyz;
use crate::image::{ImageError, XyzImage};
use crate::numeric_csv::{CsvError, NumericCsv};

/// One target's drive values after gamut handling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drive {
    /// Drive values 0–1, before quantisation.
    pub rgb: [f64; 3],
    pub out_of_gamut: bool,
}

fn drive_of(profile: &Profile, xyz: Xyz, mapping: GamutMapping) -> Drive {
    let Inverse {
        rgb,
        unclipped,
        out_of_gamut,
    } = profile.inverse(xyz);
    let rgb = if out_of_gamut && mapping != GamutMapping::Clip {
        map_to_gamut(
            mapping,
            &|d| profile.forward(d),
            unclipped,
            xyz,
            profile.white_xyz,
        )
    } else {
        rgb
    };
    Drive { rgb, out_of_gamut }
}

/// Drive values for each target, in order.
pub fn reproduce_targets(profile: &Profile, targets: &[Xyz], mapping: GamutMapping) -> Vec<Drive> {
    targets
        .par_iter()
        .map(|&xyz| drive_of(profile, xyz, mapping))
        .collect()
}

/// An image of drive values 0–1 before quantisation (32-bit floats), rows top to bottom,
/// with the count of pixels whose colour was out of gamut. Quantised and written, it reads
/// back as an [`crate::image::Drive8Image`].
#[derive(Clone, Debug, PartialEq)]
pub struct DriveImage {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[f32; 3]>,
    pub out_of_gamut: usize,
}

/// Converts every pixel (rows in parallel); `mirror` flips left–right.
pub fn reproduce_image(
    profile: &Profile,
    image: &XyzImage,
    mirror: bool,
    mapping: GamutMapping,
) -> DriveImage {
    let w = image.width;
    let mut rgb = vec![[0.0f32; 3]; image.pixels.len()];
    let out_of_gamut: usize = rgb
        .par_chunks_mut(w.max(1))
        .enumerate()
        .map(|(y, row)| {
            let mut count = 0;
            for (x, out) in row.iter_mut().enumerate() {
                let sx = if mirror { w - 1 - x } else { x };
                let p = image.pixels[y * w + sx];
                let d = drive_of(profile, Xyz::from(p.map(f64::from)), mapping);
                count += usize::from(d.out_of_gamut);
                *out = d.rgb.map(|v| v as f32);
            }
            count
        })
        .sum();
    DriveImage {
        width: w,
        height: image.height,
        rgb,
        out_of_gamut,
    }
}

/// Quantises drive values to `bits` (8 or 16) by rounding to the nearest code.
pub fn quantize(v: f32, bits: u8) -> u16 {
    let max = ((1u32 << bits) - 1) as f32;
    (v.clamp(0.0, 1.0) * max).round() as u16
}

/// Writes an RGB PNG of 8 or 16 bits per channel.
pub fn write_drive_png(
    path: &Path,
    image: &DriveImage,
    bits: u8,
    out: &OutputPolicy,
) -> Result<(), ImageError> {
    let png_err = |e: png::EncodingError| ImageError::Png {
        file: path.to_path_buf(),
        message: e.to_string(),
    };
    let data: Vec<u8> = match bits {
        8 => image
            .rgb
            .iter()
            .flat_map(|p| p.map(|v| quantize(v, 8) as u8))
            .collect(),
        16 => image
            .rgb
            .iter()
            .flat_map(|p| p.map(|v| quantize(v, 16).to_be_bytes()))
            .flatten()
            .collect(),
        other => {
            return Err(ImageError::Png {
                file: path.to_path_buf(),
                message: format!("{other} bits per channel: use 8 or 16"),
            })
        }
    };
    // Encoded in memory first: an encoding error never reaches the file.
    let mut png_bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut png_bytes, image.width as u32, image.height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(if bits == 8 {
        png::BitDepth::Eight
    } else {
        png::BitDepth::Sixteen
    });
    let mut w = enc.write_header().map_err(png_err)?;
    w.write_image_data(&data).map_err(png_err)?;
    w.finish().map_err(png_err)?;
    Ok(out.write(path, &png_bytes)?)
}

/// Reads a targets CSV with the header `X,Y,Z` (cd/m²).
pub fn read_targets(path: &Path) -> Result<Vec<Xyz>, CsvError> {
    let t = NumericCsv::read(path, &["X", "Y", "Z"])?;
    Ok(t.rows
        .into_iter()
        .map(|(_, v)| Xyz::new(v[0], v[1], v[2]))
        .collect())
}

/// Writes `r,g,b,out_of_gamut` rows (drive values as floats, flag 0/1).
pub fn write_drive_csv(
    path: &Path,
    drives: &[Drive],
    out: &OutputPolicy,
) -> Result<(), OutputError> {
    let mut s = String::from("r,g,b,out_of_gamut\n");
    for d in drives {
        s.push_str(&format!(
            "{},{},{},{}\n",
            d.rgb[0],
            d.rgb[1],
            d.rgb[2],
            u8::from(d.out_of_gamut)
        ));
    }
    out.write(path, s.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_rounds_to_the_nearest_code() {
        assert_eq!(quantize(0.0, 8), 0);
        assert_eq!(quantize(1.0, 8), 255);
        assert_eq!(quantize(0.5, 8), 128); // 127.5 rounds half away from zero
        assert_eq!(quantize(0.4999, 8), 127);
        assert_eq!(quantize(1.0, 16), 65535);
        assert_eq!(quantize(-0.2, 16), 0);
        assert_eq!(quantize(1.5, 16), 65535);
    }
}
