//! The named simulated monitors and what defines one: white, black, primaries with their
//! emission spectra, chromaticity drift, tone curves and crosstalk.
//!
//! Primaries of `ideal-crt` are those of ITU-R BT.709 (the sRGB primaries, IEC 61966-2-1);
//! the others are invented to be plausible, not measured. Each preset's spectra are built
//! from the physics of its type ([`super::spectral`]); the one or two free parameters of
//! each channel (named below) were fitted so that the channel's chromaticity is the
//! preset's primary (within 2·10⁻⁵ in x and y; the module's tests hold them to 0.002):
//! - `ideal-crt`: P22 phosphors. Red Y₂O₂S:Eu³⁺, lines at 626 nm (strongest), 612, 595 and
//!   705 nm, with the weak ⁵D₁ and ⁵D₂ lines at 538 and 468 nm (their weights fitted);
//!   green ZnS:Cu,Al, one broad band (centre and width fitted: 539 nm, 78 nm FWHM); blue
//!   ZnS:Ag, a 50 nm band (centre fitted: 447 nm) with its tail towards green (a band at
//!   510 nm, weight fitted).
//! - `ips-lcd`: a white-LED backlight — an InGaN blue die at 450 nm (20 nm FWHM) and the
//!   YAG:Ce phosphor's broad band at 555 nm (120 nm FWHM, peak 0.35 of the blue) — through
//!   colour filters: red a long-pass edge (edge and leakage fitted), green a 62 nm
//!   band-pass (centre and leakage fitted), blue a short-pass edge (edge and leakage
//!   fitted). The green filter's width is the one that leaves the ColorChecker's cyan and
//!   yellow inside the panel's gamut under its own white (wider, cyan falls out; narrower,
//!   with more leakage to keep the chromaticity, yellow does): with sRGB primaries both
//!   sit at the gamut's edge.
//! - `wide-gamut-ccfl`: a wide-gamut cold-cathode lamp — mercury lines at 405 and 436 nm,
//!   BaMgAl₁₀O₁₇:Eu blue (450 nm band, 50 nm), BaMgAl₁₀O₁₇:Eu,Mn green (515 nm band,
//!   30 nm) with some LaPO₄:Ce,Tb (543 nm line), Y₂O₃:Eu red (611 nm line with 587, 593
//!   and 626 nm satellites) and Mg fluorogermanate deep red (658 nm band, 15 nm) — through
//!   filters of the same three kinds (red edge and leakage, green centre and width, blue
//!   edge and width fitted).

use std::str::FromStr;

use serde::Serialize;

use super::spectral::{Band, ChannelShape, ColourFilter, PanelSpectra};

/// The named simulated monitors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Preset {
    /// Satisfies PLCC exactly: additive, constant chromaticity, power-law TRCs, small black.
    IdealCrt,
    /// A typical sRGB IPS panel: S-shaped TRCs, bluish black, moderate drift, 1–2 % crosstalk.
    IpsLcd,
    /// A wide-gamut CCFL panel: wide primaries, stronger drift, 2–3 % crosstalk.
    WideGamutCcfl,
}

impl Preset {
    pub const ALL: [Preset; 3] = [Preset::IdealCrt, Preset::IpsLcd, Preset::WideGamutCcfl];

    /// The stable name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Preset::IdealCrt => "ideal-crt",
            Preset::IpsLcd => "ips-lcd",
            Preset::WideGamutCcfl => "wide-gamut-ccfl",
        }
    }

    /// The panel's parameters.
    pub fn params(self) -> PanelParams {
        match self {
            Preset::IdealCrt => PanelParams {
                white_xy: [0.3127, 0.3290],
                white_cd_m2: 100.0,
                black_xy: [0.300, 0.315],
                black_cd_m2: 0.05,
                primaries_xy: [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
                spectra: p22_phosphors(),
                drift_xy: [[0.0; 2]; 3],
                trc: [
                    PanelTrc::power(2.25),
                    PanelTrc::power(2.2),
                    PanelTrc::power(2.15),
                ],
                crosstalk: [[0.0; 3]; 3],
            },
            Preset::IpsLcd => PanelParams {
                white_xy: [0.3100, 0.3260],
                white_cd_m2: 200.0,
                black_xy: [0.262, 0.258],
                black_cd_m2: 0.22,
                primaries_xy: [[0.641, 0.336], [0.302, 0.604], [0.151, 0.058]],
                spectra: white_led_lcd(),
                drift_xy: [[-0.030, 0.020], [0.020, -0.030], [0.015, 0.030]],
                trc: [
                    PanelTrc::blend(2.1, 0.25, 0.55, 7.0),
                    PanelTrc::blend(2.2, 0.20, 0.50, 6.0),
                    PanelTrc::blend(2.3, 0.30, 0.45, 8.0),
                ],
                crosstalk: [
                    [0.0, 0.015, 0.010],
                    [0.020, 0.0, 0.012],
                    [0.008, 0.018, 0.0],
                ],
            },
            Preset::WideGamutCcfl => PanelParams {
                white_xy: [0.3130, 0.3290],
                white_cd_m2: 160.0,
                black_xy: [0.275, 0.285],
                black_cd_m2: 0.40,
                primaries_xy: [[0.680, 0.315], [0.210, 0.705], [0.148, 0.054]],
                spectra: wide_gamut_ccfl(),
                drift_xy: [[-0.060, 0.035], [0.040, -0.060], [0.030, 0.050]],
                trc: [
                    PanelTrc::blend(2.0, 0.40, 0.55, 8.0),
                    PanelTrc::blend(2.3, 0.35, 0.50, 7.0),
                    PanelTrc::blend(2.5, 0.45, 0.40, 9.0),
                ],
                crosstalk: [
                    [0.0, 0.025, 0.020],
                    [0.030, 0.0, 0.022],
                    [0.018, 0.028, 0.0],
                ],
            },
        }
    }
}

fn p22_phosphors() -> PanelSpectra {
    let phosphor = |source: Vec<Band>| ChannelShape {
        source,
        filter: ColourFilter::None,
    };
    PanelSpectra {
        primaries: [
            phosphor(vec![
                Band::line(626.0, 1.0),
                Band::line(612.0, 0.35),
                Band::line(595.0, 0.10),
                Band::line(705.0, 0.12),
                Band::line(538.0, 0.0708),
                Band::line(468.0, 0.0396),
            ]),
            phosphor(vec![Band::new(539.13, 78.45, 1.0)]),
            phosphor(vec![
                Band::new(447.03, 50.0, 1.0),
                Band::new(510.0, 60.0, 0.08875),
            ]),
        ],
    }
}

fn white_led_lcd() -> PanelSpectra {
    let backlight = vec![Band::new(450.0, 20.0, 1.0), Band::new(555.0, 120.0, 0.35)];
    let through = |filter| ChannelShape {
        source: backlight.clone(),
        filter,
    };
    PanelSpectra {
        primaries: [
            through(ColourFilter::LongPass {
                edge_nm: 620.39,
                width_nm: 12.0,
                floor: 0.00258,
            }),
            through(ColourFilter::BandPass {
                centre_nm: 542.12,
                fwhm_nm: 62.0,
                floor: 0.04069,
            }),
            through(ColourFilter::ShortPass {
                edge_nm: 500.47,
                width_nm: 12.0,
                floor: 0.00916,
            }),
        ],
    }
}

fn wide_gamut_ccfl() -> PanelSpectra {
    let lamp = vec![
        Band::line(405.0, 0.05),
        Band::line(436.0, 0.25),
        Band::new(450.0, 50.0, 0.7),
        Band::new(515.0, 30.0, 1.0),
        Band::line(543.0, 0.3),
        Band::line(587.0, 0.1),
        Band::line(593.0, 0.1),
        Band::line(611.0, 1.0),
        Band::line(626.0, 0.1),
        Band::new(658.0, 15.0, 0.6),
    ];
    let through = |filter| ChannelShape {
        source: lamp.clone(),
        filter,
    };
    PanelSpectra {
        primaries: [
            through(ColourFilter::LongPass {
                edge_nm: 616.91,
                width_nm: 10.0,
                floor: 0.000834,
            }),
            through(ColourFilter::BandPass {
                centre_nm: 550.50,
                fwhm_nm: 46.06,
                floor: 0.01,
            }),
            through(ColourFilter::ShortPass {
                edge_nm: 489.99,
                width_nm: 11.30,
                floor: 0.002,
            }),
        ],
    }
}

impl FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Preset, String> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown virtual display preset '{s}'"))
    }
}

/// A simulated panel's true tone response of one channel (what a characterization's
/// fitted `display::model::Trc` tries to recover): normalised luminance 0–1 of drive 0–1,
/// `(1 − w) vᵞ + w S(v)` with `S` the logistic `1/(1 + e^(−slope (v − mid)))` rescaled to
/// run from 0 at v = 0 to 1 at v = 1. Both terms rise monotonically, so the blend does.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PanelTrc {
    pub gamma: f64,
    /// Weight `w` of the logistic term; 0 is a pure power law.
    pub s_weight: f64,
    pub s_mid: f64,
    pub s_slope: f64,
}

impl PanelTrc {
    /// A pure power law `vᵞ`.
    pub const fn power(gamma: f64) -> PanelTrc {
        PanelTrc {
            gamma,
            s_weight: 0.0,
            s_mid: 0.5,
            s_slope: 1.0,
        }
    }

    pub const fn blend(gamma: f64, s_weight: f64, s_mid: f64, s_slope: f64) -> PanelTrc {
        PanelTrc {
            gamma,
            s_weight,
            s_mid,
            s_slope,
        }
    }

    /// Normalised luminance at drive `v` (clamped to 0–1).
    pub fn eval(&self, v: f64) -> f64 {
        let v = v.clamp(0.0, 1.0);
        let power = v.powf(self.gamma);
        if self.s_weight == 0.0 {
            return power;
        }
        let sigmoid = |t: f64| 1.0 / (1.0 + (-self.s_slope * (t - self.s_mid)).exp());
        let s = (sigmoid(v) - sigmoid(0.0)) / (sigmoid(1.0) - sigmoid(0.0));
        (1.0 - self.s_weight) * power + self.s_weight * s
    }
}

/// Everything that defines a simulated panel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PanelParams {
    /// Chromaticity and luminance of full white.
    pub white_xy: [f64; 2],
    pub white_cd_m2: f64,
    /// Chromaticity and luminance of black (all drives 0).
    pub black_xy: [f64; 2],
    pub black_cd_m2: f64,
    /// The chromaticity each channel is designed to have at full drive (R, G, B); the
    /// emitted one is that of its spectrum in `spectra`, fitted to this.
    pub primaries_xy: [[f64; 2]; 3],
    /// The channels' emission spectra.
    pub spectra: PanelSpectra,
    /// Shift of each channel's chromaticity as its level goes to zero.
    pub drift_xy: [[f64; 2]; 3],
    pub trc: [PanelTrc; 3],
    /// `crosstalk[c][d]`: how much channel `d`'s drive raises channel `c`'s (diagonal 0).
    pub crosstalk: [[f64; 3]; 3],
}
