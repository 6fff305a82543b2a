//! The scene in an RGB renderer's terms: each spectrum as the linear Rec.709 (D65) RGB a
//! careful user of Blender enters, and the RGB form of the scene — what an ideal RGB
//! renderer of those numbers must produce — as a scene metamer's own solvers can render.
//!
//! The rule (stated in the Blender export's README):
//!
//! - An emitter tile's colour is the linear Rec.709 RGB of its absolute radiance,
//!   RGB = M⁻¹ · XYZ with XYZ = 683 · Σ L(λ)·cmf(λ) · 1 nm (cd/m²) and M the RGB → XYZ
//!   matrix of the BT.709 primaries and D65 white (the matrix metamer reads an OpenEXR
//!   file with); a component below 0 (a radiance outside the Rec.709 gamut, as a narrow
//!   LED's is) is entered as 0, since a colour picker takes none.
//! - A reflectance ρ is entered as its colour under the box's light S (every emitter
//!   tile's radiance times its area, summed), normalised by the light's own colour, von
//!   Kries style: ρ_c = RGB(ρ·S)_c / RGB(S)_c, clamped to [0, 1]. Lit by S alone, an RGB
//!   renderer then gives a patch the colour the spectral scene gives it; every further
//!   bounce multiplies colours where the spectral scene multiplies spectra, and that
//!   product, and the clamping, are what rendering in RGB costs.
//!
//! The RGB form replaces every spectrum by three blocks of the 1 nm grid, one per
//! channel, each holding that channel's value, and the colour-matching functions by the
//! matrix M placed on one bin inside each block ([`CHANNEL_BINS`]). Light transport is
//! independent per wavelength, so any of metamer's renderers computes, on the three
//! bins, exactly the three channels an ideal RGB renderer does, and its XYZ is M · RGB: the
//! XYZ a read-back of that renderer's image yields. The radiosity solver solves its
//! system on nodes every few nm and interpolates between them; the channel bins and the
//! blocks' ends lie on its default 5 nm nodes, so the interpolation there is exact.

use nalgebra::Matrix3;

use super::approximation::{lambertian_form, Approximation};
use crate::image::REC709_CHROMATICITIES;
use crate::render::scene::Scene;

/// The grid bin that carries each channel's colour-matching weight.
pub const CHANNEL_BINS: [usize; 3] = [65, 200, 335];
/// Each channel's block of bins (inclusive ends), on 5 nm nodes, with zero between.
const BLOCKS: [(usize, usize); 3] = [(0, 130), (135, 265), (270, 400)];

/// M: XYZ = M · RGB for linear Rec.709 with D65.
pub fn rgb_to_xyz() -> [[f64; 3]; 3] {
    REC709_CHROMATICITIES
        .rgb_to_xyz()
        .expect("BT.709's chromaticities define an RGB space")
}

/// M⁻¹.
pub fn xyz_to_rgb() -> [[f64; 3]; 3] {
    let m = rgb_to_xyz();
    let inv = Matrix3::from_fn(|r, c| m[r][c])
        .try_inverse()
        .expect("BT.709's matrix is invertible");
    std::array::from_fn(|r| std::array::from_fn(|c| inv[(r, c)]))
}

fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| (0..3).map(|c| m[r][c] * v[c]).sum())
}

/// XYZ (cd/m² for an absolute radiance) of a spectrum on the grid.
pub fn xyz(scene: &Scene, spectrum: &[f64]) -> [f64; 3] {
    std::array::from_fn(|k| {
        metamer_color::K_M
            * spectrum
                .iter()
                .zip(&scene.cmf[k])
                .map(|(s, c)| s * c)
                .sum::<f64>()
    })
}

/// Linear Rec.709 RGB of a spectrum, unclamped.
pub fn rgb(scene: &Scene, spectrum: &[f64]) -> [f64; 3] {
    mul(&xyz_to_rgb(), xyz(scene, spectrum))
}

/// An emitter radiance's colour as entered: its RGB with negative components set to 0.
pub fn emission_rgb(scene: &Scene, radiance: &[f64]) -> [f64; 3] {
    rgb(scene, radiance).map(|c| c.max(0.0))
}

/// The box's light: every emitter tile's written radiance times its area, summed.
pub fn light(scene: &Scene, approximation: &Approximation) -> Vec<f64> {
    let mut s = vec![0.0; scene.cmf[0].len()];
    for (e, gains) in scene.emitters.iter().zip(&approximation.gains) {
        let area = e.rect.area_m2 / e.gains.len() as f64;
        for (t, g) in gains.iter().enumerate() {
            for (o, v) in s.iter_mut().zip(e.tile_spectrum(t)) {
                *o += g * area * v;
            }
        }
    }
    s
}

/// The colour a reflectance is entered as under `light` (von Kries, clamped to [0, 1]),
/// and whether the clamp changed it. A channel the light lacks entirely takes the
/// reflectance's colour under an equal-energy light instead.
pub fn reflectance_rgb(scene: &Scene, reflectance: &[f64], light: &[f64]) -> ([f64; 3], bool) {
    let white = rgb(scene, light);
    let lit: Vec<f64> = reflectance.iter().zip(light).map(|(r, s)| r * s).collect();
    let under = rgb(scene, &lit);
    let flat = rgb(scene, &vec![1.0; reflectance.len()]);
    let flat_lit = rgb(scene, reflectance);
    let raw: [f64; 3] = std::array::from_fn(|c| {
        if white[c] > 0.0 {
            under[c] / white[c]
        } else {
            flat_lit[c] / flat[c]
        }
    });
    let clamped = raw.map(|c| c.clamp(0.0, 1.0));
    (clamped, clamped != raw)
}

/// A spectrum holding each channel's value on its block.
fn blocks(rgb: [f64; 3], bins: usize) -> Vec<f64> {
    let mut s = vec![0.0; bins];
    for (c, (a, b)) in BLOCKS.iter().enumerate() {
        s[*a..=*b].iter_mut().for_each(|v| *v = rgb[c]);
    }
    s
}

/// The scene an ideal RGB renderer of the export renders: the export's (Lambertian) form
/// with every spectrum replaced by its entered colour on three blocks and the
/// colour-matching functions by M on [`CHANNEL_BINS`], scaled so that 683 · Σ L · cmf gives
/// M · RGB. Its readings are XYZ in cd/m², comparable with the read-back of an RGB
/// renderer's image and, by difference, with the spectral scene's readings.
pub fn rgb_form(scene: &Scene, approximation: &Approximation) -> Scene {
    let s = light(scene, approximation);
    let mut out = lambertian_form(scene, approximation);
    let n = out.cmf[0].len();
    for surface in &mut out.surfaces {
        surface.reflectance = blocks(reflectance_rgb(scene, &surface.reflectance, &s).0, n);
    }
    for e in &mut out.emitters {
        e.reflectance = blocks(reflectance_rgb(scene, &e.reflectance, &s).0, n);
        for spectrum in &mut e.spectra {
            *spectrum = blocks(emission_rgb(scene, spectrum), n);
        }
    }
    let m = rgb_to_xyz();
    for (k, cmf) in out.cmf.iter_mut().enumerate() {
        cmf.iter_mut().for_each(|v| *v = 0.0);
        for (c, bin) in CHANNEL_BINS.iter().enumerate() {
            cmf[*bin] = m[k][c] / metamer_color::K_M;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::approximation::choose;

    #[test]
    fn the_matrices_take_d65_white_to_rgb_one() {
        // D65 at Y = 1 (x 0.3127, y 0.3290, BT.709's white) is RGB (1, 1, 1).
        let (x, y) = (0.3127, 0.3290);
        let rgb = mul(&xyz_to_rgb(), [x / y, 1.0, (1.0 - x - y) / y]);
        for c in rgb {
            assert!((c - 1.0).abs() < 1e-12, "{rgb:?}");
        }
        // BT.709's luminance coefficients, ITU-R BT.709-6 item 3.2: 0.2126, 0.7152, 0.0722.
        let m = rgb_to_xyz();
        for (c, want) in [0.2126, 0.7152, 0.0722].iter().enumerate() {
            assert!((m[1][c] - want).abs() < 5e-5, "{:?}", m[1]);
        }
    }

    #[test]
    fn a_grey_is_its_reflectance_under_any_light_and_the_form_reads_m_times_rgb() {
        let scene = Scene::builtin("validation-box-led-rgb1").unwrap();
        let a = choose(&scene, "led", false).unwrap();
        let s = light(&scene, &a);
        let (g, clamped) = reflectance_rgb(&scene, &vec![0.4; s.len()], &s);
        assert!(!clamped);
        for c in g {
            assert!((c - 0.4).abs() < 1e-12, "{g:?}");
        }
        // The RGB form's emitter reads as M · (its entered colour), by construction.
        let form = rgb_form(&scene, &a);
        let e = &scene.emitters[0];
        let want = mul(&rgb_to_xyz(), emission_rgb(&scene, e.tile_spectrum(0)));
        let got = xyz(&form, form.emitters[0].tile_spectrum(0));
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() <= 1e-9 * want[1],
                "{got:?} {want:?}"
            );
        }
    }
}
