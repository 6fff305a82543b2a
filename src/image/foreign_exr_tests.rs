//! OpenEXR files as other renderers write them, read back as the XYZ they hold: R, G, B in
//! ACES2065-1 named by their `chromaticities` (pbrt-v4's film), and channels named X, Y, Z
//! (Mitsuba 3's XYZ films). The files are written here with the `exr` crate, the pixels
//! from known XYZ by the published inverse matrix, so the reader's own derivation is
//! checked against the standard's numbers.

use exr::math::Vec2;
use exr::meta::attribute::Chromaticities as ExrChromaticities;
use exr::prelude::*;

use super::{read_xyz_image, ImageError};

/// XYZ of the test pixels (cd/m²): a white, a saturated red, a dark blue.
const XYZ: [[f32; 3]; 3] = [[95.04, 100.0, 108.9], [41.2, 21.3, 1.9], [0.5, 0.2, 3.0]];

fn dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("metamer-foreign-exr-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn aces_rgb_named_by_its_chromaticities_is_read_as_its_xyz() {
    // SMPTE ST 2065-1:2012 §4.1.2: the XYZ → ACES2065-1 matrix (NPM⁻¹) as published.
    let inverse = [
        [1.0498110175, 0.0, -0.0000974845],
        [-0.4959030231, 1.3733130458, 0.0982400361],
        [0.0, 0.0, 0.9912520182],
    ];
    let rgb: Vec<[f32; 3]> = XYZ
        .iter()
        .map(|x| {
            std::array::from_fn(|r| {
                (0..3).map(|c| inverse[r][c] * f64::from(x[c])).sum::<f64>() as f32
            })
        })
        .collect();
    let pixels = rgb.clone();
    let mut image = Image::from_channels(
        (3, 1),
        SpecificChannels::rgb(move |p: Vec2<usize>| {
            let v = pixels[p.x()];
            (v[0], v[1], v[2])
        }),
    );
    image.attributes.chromaticities = Some(ExrChromaticities {
        red: Vec2(0.7347, 0.2653),
        green: Vec2(0.0, 1.0),
        blue: Vec2(0.0001, -0.077),
        white: Vec2(0.32168, 0.33767),
    });
    let d = dir("aces");
    let path = d.join("pbrt.exr");
    image.write().to_file(&path).unwrap();
    let back = read_xyz_image(&path).unwrap();
    std::fs::remove_dir_all(&d).ok();
    for (got, want) in back.pixels.iter().zip(XYZ) {
        for c in 0..3 {
            // f32 pixels and attribute: a few parts in 10⁶.
            assert!(
                (got[c] - want[c]).abs() <= 1e-5 * want[c].abs().max(1.0),
                "{got:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn channels_named_x_y_z_are_read_as_xyz_in_any_order() {
    let image = Image::from_channels(
        (3, 1),
        SpecificChannels::build()
            .with_channel("Z")
            .with_channel("X")
            .with_channel("Y")
            .with_pixel_fn(|p: Vec2<usize>| {
                let v = XYZ[p.x()];
                (v[2], v[0], v[1])
            }),
    );
    let d = dir("xyz");
    let path = d.join("mitsuba.exr");
    image.write().to_file(&path).unwrap();
    let back = read_xyz_image(&path).unwrap();
    std::fs::remove_dir_all(&d).ok();
    assert_eq!(back.pixels, XYZ.to_vec());
}

#[test]
fn an_exr_without_xyz_or_rgb_channels_is_refused_naming_them() {
    let image = Image::from_channels(
        (2, 1),
        SpecificChannels::build()
            .with_channel("L")
            .with_pixel_fn(|_p: Vec2<usize>| (1.0f32,)),
    );
    let d = dir("luma");
    let path = d.join("luma.exr");
    image.write().to_file(&path).unwrap();
    let e = read_xyz_image(&path).unwrap_err();
    std::fs::remove_dir_all(&d).ok();
    assert!(matches!(e, ImageError::Exr { .. }), "{e}");
    let message = e.to_string();
    assert!(
        message.contains("luma.exr") && message.contains("channels L"),
        "{message}"
    );
}
