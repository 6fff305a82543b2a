//! The light model of a simulated panel: drive values to an emitted spectrum and its XYZ.
//!
//! Everything the panel emits is a non-negative mixture of its three channel spectra
//! ([`super::spectral`]), each scaled to 1 cd/m², so the model keeps three luminances (the
//! mixture's weights) and both the spectrum and its XYZ follow from them:
//! - black is the mixture with the preset's black chromaticity and luminance: light leaking
//!   through all three subpixels (or a CRT's three phosphors glowing);
//! - a channel at normalised luminance `L` has chromaticity `xy_c + d_c (1 − L)`, `xy_c`
//!   its spectrum's own: its light is its spectrum mixed with a fixed mixture of all three
//!   whose chromaticity is `xy_c + d_c`, in the proportion that puts the blend at that
//!   point (neighbouring subpixels leaking light that matters more as the channel dims);
//! - crosstalk, tone curves and 8-bit quantisation act on the drive values as before the
//!   spectra existed, so the XYZ is what the XYZ-only model gave for the same primaries.

use metamer_color::{radiance_to_xyz, ObserverKind, Spectrum, Xyz};
use nalgebra::{Matrix3, Vector3};

use super::presets::{PanelParams, Preset};
use super::spectral::{radiance, SAMPLES};

/// A simulated panel: drive values to emitted spectrum and XYZ (cd/m²).
#[derive(Clone, Debug, PartialEq)]
pub struct VirtualPanel {
    name: String,
    params: PanelParams,
    /// Each channel's spectrum at 1 cd/m².
    basis: [Spectrum; 3],
    /// Columns: XYZ of each basis spectrum (Y = 1).
    basis_xyz: Matrix3<f64>,
    /// Black as luminances of the three bases, cd/m².
    black: [f64; 3],
    /// For each channel, the mixture (weights summing to 1 cd/m²) it drifts towards.
    drift_mix: [[f64; 3]; 3],
    /// Full-on luminance of each channel's own term, cd/m².
    channel_max_cd_m2: [f64; 3],
}

/// The 8-bit code a display shows for drive `v` (0–1, clamped; halves round up).
pub fn quantize(v: f64) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// XYZ of chromaticity (x, y) at luminance `lum`.
fn xyy_to_xyz(x: f64, y: f64, lum: f64) -> Vector3<f64> {
    Vector3::from(
        crate::color::XyY {
            x,
            y,
            luminance: lum,
        }
        .to_xyz()
        .to_array(),
    )
}

fn xy_of(v: Vector3<f64>) -> [f64; 2] {
    let s = v.sum();
    [v[0] / s, v[1] / s]
}

impl VirtualPanel {
    /// A panel from its parameters; `name` is how it is shown (`ips-lcd`).
    ///
    /// Panics if black, white or a drifted channel lies outside the triangle of the
    /// channels' spectra (a preset bug).
    pub fn new(name: &str, params: PanelParams) -> VirtualPanel {
        let basis = params.spectra.primaries.clone().map(|s| s.unit_radiance());
        let basis_xyz = Matrix3::from_columns(
            &basis
                .clone()
                .map(|s| Vector3::from(radiance_to_xyz(&s, ObserverKind::Cie1931).to_array())),
        );
        let inv = basis_xyz
            .try_inverse()
            .expect("the primaries of a preset are independent");
        let inside = |what: &str, w: Vector3<f64>| {
            assert!(
                w.iter().all(|&l| l >= 0.0),
                "{what} of {name} is outside its primaries: {w:?}"
            );
            [w[0], w[1], w[2]]
        };
        let black_xyz = xyy_to_xyz(params.black_xy[0], params.black_xy[1], params.black_cd_m2);
        let black = inside("black", inv * black_xyz);
        let white = xyy_to_xyz(params.white_xy[0], params.white_xy[1], params.white_cd_m2);
        let max = inside("white", inv * (white - black_xyz));
        let drift_mix = std::array::from_fn(|c| {
            let d = params.drift_xy[c];
            if d == [0.0; 2] {
                let mut unit = [0.0; 3];
                unit[c] = 1.0;
                return unit;
            }
            let [x, y] = xy_of(basis_xyz.column(c).into());
            inside(
                "a drifted channel",
                inv * xyy_to_xyz(x + d[0], y + d[1], 1.0),
            )
        });
        VirtualPanel {
            name: name.to_string(),
            params,
            basis,
            basis_xyz,
            black,
            drift_mix,
            channel_max_cd_m2: max,
        }
    }

    pub fn preset(preset: Preset) -> VirtualPanel {
        VirtualPanel::new(preset.name(), preset.params())
    }

    /// The same panel with full white at `cd_m2` (black scaled alike, so the contrast ratio
    /// and all chromaticities stay).
    pub fn with_white_luminance(&self, cd_m2: f64) -> VirtualPanel {
        let k = cd_m2 / self.params.white_cd_m2;
        let mut params = self.params.clone();
        params.white_cd_m2 = cd_m2;
        params.black_cd_m2 *= k;
        VirtualPanel::new(&self.name, params)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn params(&self) -> &PanelParams {
        &self.params
    }

    /// The chromaticity of channel `c`'s spectrum (its primary at full drive).
    pub fn primary_xy(&self, c: usize) -> [f64; 2] {
        xy_of(self.basis_xyz.column(c).into())
    }

    /// Channel `c`'s spectrum at 1 cd/m², W·sr⁻¹·m⁻²·nm⁻¹.
    pub fn channel_spectrum(&self, c: usize) -> &Spectrum {
        &self.basis[c]
    }

    /// Full-on luminance of each channel's own term, cd/m².
    pub fn channel_max_cd_m2(&self) -> [f64; 3] {
        self.channel_max_cd_m2
    }

    /// The luminances of the three channel spectra in the light of drive values `v`
    /// (0–1, continuous): black, then each channel after crosstalk, tone curve and drift.
    fn weights(&self, v: [f64; 3]) -> [f64; 3] {
        let p = &self.params;
        let mut out = self.black;
        for c in 0..3 {
            let pushed: f64 = (0..3)
                .filter(|&d| d != c)
                .map(|d| p.crosstalk[c][d] * v[d])
                .sum();
            let effective = v[c] + pushed * (1.0 - v[c]);
            let level = p.trc[c].eval(effective);
            let lum = level * self.channel_max_cd_m2[c];
            // The share of the drift mixture that puts the blend's chromaticity a
            // fraction τ = 1 − level of the way from the primary to the mixture's (shares
            // of luminance weigh chromaticity by X + Y + Z).
            let tau = 1.0 - level;
            let s_p = self.basis_xyz.column(c).sum();
            let s_d = (self.basis_xyz * Vector3::from(self.drift_mix[c])).sum();
            let beta = tau * s_p / ((1.0 - tau) * s_d + tau * s_p);
            for (k, o) in out.iter_mut().enumerate() {
                let own = if k == c { 1.0 } else { 0.0 };
                *o += lum * ((1.0 - beta) * own + beta * self.drift_mix[c][k]);
            }
        }
        out
    }

    /// Emitted XYZ (cd/m²) for drive values 0–1 taken as they are (no quantisation).
    pub fn xyz_at(&self, v: [f64; 3]) -> Xyz {
        let xyz = self.basis_xyz * Vector3::from(self.weights(v));
        Xyz::new(xyz[0], xyz[1], xyz[2])
    }

    /// Emitted XYZ (cd/m²) for 8-bit drive values.
    pub fn xyz(&self, rgb: [u8; 3]) -> Xyz {
        self.xyz_at(rgb.map(|c| f64::from(c) / 255.0))
    }

    /// Emitted XYZ for drive values 0–1, quantised to 8 bits first as the display does.
    pub fn xyz_of_drive(&self, rgb: [f64; 3]) -> Xyz {
        self.xyz(rgb.map(quantize))
    }

    /// Emitted spectral radiance (W·sr⁻¹·m⁻²·nm⁻¹, 380–780 nm at 1 nm) for 8-bit drive
    /// values; its XYZ is [`VirtualPanel::xyz`].
    pub fn spectrum(&self, rgb: [u8; 3]) -> Spectrum {
        let w = self.weights(rgb.map(|c| f64::from(c) / 255.0));
        let values = (0..SAMPLES)
            .map(|i| (0..3).map(|k| w[k] * self.basis[k].values()[i]).sum())
            .collect();
        radiance(values)
    }

    /// The mean emission of pixels showing each colour `count` times (what a meter whose
    /// spot covers them sees).
    pub fn mean_spectrum(&self, counts: &[([u8; 3], usize)]) -> Spectrum {
        let total: usize = counts.iter().map(|(_, n)| n).sum();
        let mut values = vec![0.0; SAMPLES];
        for (rgb, n) in counts {
            let s = self.spectrum(*rgb);
            for (v, x) in values.iter_mut().zip(s.values()) {
                *v += *n as f64 * x;
            }
        }
        radiance(
            values
                .into_iter()
                .map(|v| v / total.max(1) as f64)
                .collect(),
        )
    }

    /// The drive values 0–1 (continuous, before quantisation) at which the panel emits
    /// `xyz`, or None when no drive values in 0–1 do: the colour is outside its gamut.
    pub fn drive_for(&self, xyz: Xyz) -> Option<[f64; 3]> {
        let vector = |v: Xyz| Vector3::new(v.x, v.y, v.z);
        let target = vector(xyz);
        let inv = self.basis_xyz.try_inverse()?;
        // Start from the linear model without crosstalk and drift, a 2.2 power law.
        let lin = inv * (target - vector(self.xyz_at([0.0; 3])));
        let mut v: [f64; 3] =
            std::array::from_fn(|c| (lin[c] / self.channel_max_cd_m2[c]).clamp(1e-3, 1.0));
        v = v.map(|l| l.powf(1.0 / 2.2));
        let scale = self.params.white_cd_m2;
        for _ in 0..100 {
            let f = vector(self.xyz_at(v));
            let r = target - f;
            if r.norm() < 1e-10 * scale {
                return Some(v);
            }
            let h = 1e-7;
            let jac = Matrix3::from_fn(|row, c| {
                let mut w = v;
                let step = if w[c] + h > 1.0 { -h } else { h };
                w[c] += step;
                (self.xyz_at(w)[row] - f[row]) / step
            });
            let step = jac.try_inverse().map(|j| j * r)?;
            let next = std::array::from_fn(|c| (v[c] + step[c]).clamp(0.0, 1.0));
            if next == v {
                // Pinned at the cube's faces with the colour still not reached.
                return None;
            }
            v = next;
        }
        None
    }
}
