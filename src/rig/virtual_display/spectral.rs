//! Emission spectra of the simulated panels, from parametric shapes.
//!
//! A channel's light is a source spectrum (phosphor bands and lines, or an LCD's backlight)
//! times a colour filter's transmittance (1 for a CRT, whose phosphors are the channels).
//! Bands and lines are Gaussians given by centre and full width at half maximum; filters
//! are logistic edges or a Gaussian band over a floor (the filter's leakage outside its
//! pass band). Spectra are sampled at 1 nm over 380–780 nm, the range and step of the
//! colour core's Eq. 8 integration, so a spectrum's XYZ here is exactly what a simulated
//! meter integrating it gets.
//!
//! Emission lines (Eu³⁺, Tb³⁺, Hg) are physically 2–5 nm wide; here they get 12 nm. The
//! simulated i1Pro samples its spectrum every 10 nm, and narrower lines would fall between
//! its samples; a real 10 nm-bandwidth spectrometer likewise sees such lines broadened.

use metamer_color::{radiance_to_xyz, ObserverKind, Quantity, Spectrum};
use serde::Serialize;

/// First wavelength of the sampled spectra, nm.
pub const START_NM: f64 = 380.0;
/// Samples at 1 nm from [`START_NM`] to 780 nm.
pub const SAMPLES: usize = 401;

/// The width given to narrow emission lines, nm (see the module documentation).
pub const LINE_FWHM_NM: f64 = 12.0;

/// A Gaussian emission band.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Band {
    pub centre_nm: f64,
    pub fwhm_nm: f64,
    /// Peak height relative to the other bands of the same source.
    pub weight: f64,
}

impl Band {
    pub const fn new(centre_nm: f64, fwhm_nm: f64, weight: f64) -> Band {
        Band {
            centre_nm,
            fwhm_nm,
            weight,
        }
    }

    /// A narrow emission line of the given weight (width [`LINE_FWHM_NM`]).
    pub const fn line(centre_nm: f64, weight: f64) -> Band {
        Band::new(centre_nm, LINE_FWHM_NM, weight)
    }

    pub fn eval(&self, nm: f64) -> f64 {
        let t = (nm - self.centre_nm) / self.fwhm_nm;
        self.weight * (-4.0 * std::f64::consts::LN_2 * t * t).exp()
    }
}

/// A colour filter's transmittance: `floor + (1 − floor)·shape(λ)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum ColourFilter {
    /// No filter (a CRT's phosphor is its own channel).
    None,
    /// Passes long wavelengths: the logistic `1/(1 + e^(−(λ − edge)/width))`.
    LongPass {
        edge_nm: f64,
        width_nm: f64,
        floor: f64,
    },
    /// Passes short wavelengths: the logistic `1/(1 + e^(−(edge − λ)/width))`.
    ShortPass {
        edge_nm: f64,
        width_nm: f64,
        floor: f64,
    },
    /// A Gaussian pass band.
    BandPass {
        centre_nm: f64,
        fwhm_nm: f64,
        floor: f64,
    },
}

impl ColourFilter {
    pub fn transmittance(&self, nm: f64) -> f64 {
        let logistic = |t: f64| 1.0 / (1.0 + (-t).exp());
        match *self {
            ColourFilter::None => 1.0,
            ColourFilter::LongPass {
                edge_nm,
                width_nm,
                floor,
            } => floor + (1.0 - floor) * logistic((nm - edge_nm) / width_nm),
            ColourFilter::ShortPass {
                edge_nm,
                width_nm,
                floor,
            } => floor + (1.0 - floor) * logistic((edge_nm - nm) / width_nm),
            ColourFilter::BandPass {
                centre_nm,
                fwhm_nm,
                floor,
            } => floor + (1.0 - floor) * Band::new(centre_nm, fwhm_nm, 1.0).eval(nm),
        }
    }
}

/// One channel's emission: its source through its filter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ChannelShape {
    pub source: Vec<Band>,
    pub filter: ColourFilter,
}

impl ChannelShape {
    /// Relative spectral radiance at `nm`.
    pub fn eval(&self, nm: f64) -> f64 {
        let source: f64 = self.source.iter().map(|b| b.eval(nm)).sum();
        source * self.filter.transmittance(nm)
    }

    /// The shape sampled at 1 nm and scaled to 1 cd/m² (W·sr⁻¹·m⁻²·nm⁻¹).
    pub fn unit_radiance(&self) -> Spectrum {
        let values = (0..SAMPLES)
            .map(|i| self.eval(START_NM + i as f64))
            .collect();
        let s = radiance(values);
        let lum = radiance_to_xyz(&s, ObserverKind::Cie1931).y;
        assert!(lum > 0.0, "a channel shape emits nothing visible: {self:?}");
        s.scaled(1.0 / lum)
    }
}

/// A radiance on the 1 nm grid of this module.
pub fn radiance(values: Vec<f64>) -> Spectrum {
    Spectrum::from_grid(START_NM, 1.0, values)
        .expect("a 1 nm grid of finite values")
        .with_quantity(Quantity::Radiance)
}

/// A spectrum as the project's spectral CSV: `#` lines of `comment`, the header
/// `nm,<column>` and one row per sample, values with 7 significant digits.
pub fn to_csv(spectrum: &Spectrum, comment: &str, column: &str) -> String {
    let mut out = String::new();
    for line in comment.lines() {
        out.push_str(&format!("# {line}\n"));
    }
    out.push_str(&format!("nm,{column}\n"));
    for (nm, v) in spectrum.wavelengths_nm().iter().zip(spectrum.values()) {
        out.push_str(&format!("{nm},{v:.6e}\n"));
    }
    out
}

/// The emission shapes of a panel's three channels (R, G, B). Black and the chromaticity
/// drift of dim channels are mixtures of these (see [`super::panel`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PanelSpectra {
    pub primaries: [ChannelShape; 3],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_and_filters_have_their_stated_widths_and_edges() {
        let b = Band::new(550.0, 40.0, 2.0);
        assert_eq!(b.eval(550.0), 2.0);
        // Half maximum at centre ± FWHM/2.
        assert!((b.eval(570.0) - 1.0).abs() < 1e-12 && (b.eval(530.0) - 1.0).abs() < 1e-12);
        let long = ColourFilter::LongPass {
            edge_nm: 600.0,
            width_nm: 10.0,
            floor: 0.02,
        };
        // At the edge the logistic is ½: floor + (1 − floor)/2.
        assert!((long.transmittance(600.0) - 0.51).abs() < 1e-12);
        assert!(long.transmittance(400.0) < 0.0201 && long.transmittance(780.0) > 0.9999);
        let short = ColourFilter::ShortPass {
            edge_nm: 500.0,
            width_nm: 10.0,
            floor: 0.0,
        };
        assert!((short.transmittance(500.0) - 0.5).abs() < 1e-12);
        assert!((short.transmittance(490.0) - 1.0 / (1.0 + (-1.0f64).exp())).abs() < 1e-12);
        let band = ColourFilter::BandPass {
            centre_nm: 530.0,
            fwhm_nm: 60.0,
            floor: 0.1,
        };
        assert!((band.transmittance(560.0) - 0.55).abs() < 1e-12);
    }

    #[test]
    fn a_unit_radiance_has_a_luminance_of_one() {
        // A single 1 nm-wide spike at 555 nm (ȳ = 1): 1/683 W·sr⁻¹·m⁻²·nm⁻¹ gives 1 cd/m².
        let spike = ChannelShape {
            source: vec![Band::new(555.0, 0.01, 1.0)],
            filter: ColourFilter::None,
        };
        let s = spike.unit_radiance();
        assert!((s.value_at(555.0) - 1.0 / 683.0).abs() < 1e-12);
        let xyz = radiance_to_xyz(&s, ObserverKind::Cie1931);
        assert!((xyz.y - 1.0).abs() < 1e-12);
    }
}
