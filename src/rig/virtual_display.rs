//! A simulated monitor for characterizing without hardware: it shows 8-bit
//! drive values and the simulated instruments measure what it emits through the drivers'
//! [`World`](metamer_drivers::World) trait (`open_instrument("sim:cs100a", Some(display.stimulus()))`).
//!
//! The light model is built to break the PLCC model of the paper (Eq. 9) the way real
//! panels do, one fault at a time:
//! - the emitted XYZ is black plus one term per channel, `K + Σ_c XYZ_c(v'_c)`;
//! - black `K` has its own chromaticity (LCD backlight leakage is bluish, not white);
//! - each channel's tone response (TRC) is a blend of a power law and a normalised
//!   logistic, so no single exponent fits it ([`Trc`]);
//! - a channel's chromaticity drifts with its level, `xy_c(L) = xy_c + d_c (1 − L)`, where
//!   `L` is the channel's normalised luminance (at full drive it is exactly the primary);
//! - crosstalk: the effective drive of channel `c` is `v'_c = v_c + Σ_{d≠c} k_cd v_d (1 − v_c)`
//!   (1–3 % on the LCD presets): a driven channel leaks into its neighbours, so a
//!   "primary" carries a little of the others and mixtures are not additive, while full
//!   white is unaffected;
//! - drive values are quantised to 8 bits like a real 8-bit display.
//!
//! The channel maxima are solved so that full white has the preset's chromaticity and
//! luminance exactly (white = K + Σ_c P_c, with P_c the channels' terms at full drive).
//!
//! `ideal-crt` satisfies PLCC exactly (additive, constant chromaticity, power-law TRC,
//! small black); `ips-lcd` has moderate faults; `wide-gamut-ccfl` has wide primaries and
//! stronger drift and crosstalk. Primaries of `ideal-crt` are those of ITU-R BT.709 (the
//! sRGB primaries, IEC 61966-2-1); the others are invented to be plausible, not measured.

use std::str::FromStr;
use std::sync::{Arc, RwLock};
use std::time::Duration;

use metamer_drivers::{View, World};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

use super::screen::{Screen, ScreenError};

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
                drift_xy: [[0.0; 2]; 3],
                trc: [Trc::power(2.25), Trc::power(2.2), Trc::power(2.15)],
                crosstalk: [[0.0; 3]; 3],
            },
            Preset::IpsLcd => PanelParams {
                white_xy: [0.3100, 0.3260],
                white_cd_m2: 200.0,
                black_xy: [0.262, 0.258],
                black_cd_m2: 0.22,
                primaries_xy: [[0.641, 0.336], [0.302, 0.604], [0.151, 0.058]],
                drift_xy: [[-0.030, 0.020], [0.020, -0.030], [0.015, 0.030]],
                trc: [
                    Trc::blend(2.1, 0.25, 0.55, 7.0),
                    Trc::blend(2.2, 0.20, 0.50, 6.0),
                    Trc::blend(2.3, 0.30, 0.45, 8.0),
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
                drift_xy: [[-0.060, 0.035], [0.040, -0.060], [0.030, 0.050]],
                trc: [
                    Trc::blend(2.0, 0.40, 0.55, 8.0),
                    Trc::blend(2.3, 0.35, 0.50, 7.0),
                    Trc::blend(2.5, 0.45, 0.40, 9.0),
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

impl FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Preset, String> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown virtual display preset '{s}'"))
    }
}

/// Tone response of one channel: normalised luminance 0–1 of drive 0–1,
/// `(1 − w) vᵞ + w S(v)` with `S` the logistic `1/(1 + e^(−slope (v − mid)))` rescaled to
/// run from 0 at v = 0 to 1 at v = 1. Both terms rise monotonically, so the blend does.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Trc {
    pub gamma: f64,
    /// Weight `w` of the logistic term; 0 is a pure power law.
    pub s_weight: f64,
    pub s_mid: f64,
    pub s_slope: f64,
}

impl Trc {
    /// A pure power law `vᵞ`.
    pub const fn power(gamma: f64) -> Trc {
        Trc {
            gamma,
            s_weight: 0.0,
            s_mid: 0.5,
            s_slope: 1.0,
        }
    }

    pub const fn blend(gamma: f64, s_weight: f64, s_mid: f64, s_slope: f64) -> Trc {
        Trc {
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
    /// Chromaticity of each channel at full drive (R, G, B).
    pub primaries_xy: [[f64; 2]; 3],
    /// Shift of each channel's chromaticity as its level goes to zero.
    pub drift_xy: [[f64; 2]; 3],
    pub trc: [Trc; 3],
    /// `crosstalk[c][d]`: how much channel `d`'s drive raises channel `c`'s (diagonal 0).
    pub crosstalk: [[f64; 3]; 3],
}

/// A simulated panel: drive values to emitted XYZ (cd/m²).
#[derive(Clone, Debug, PartialEq)]
pub struct VirtualPanel {
    name: String,
    params: PanelParams,
    black: [f64; 3],
    /// Full-on luminance of each channel's own term, cd/m².
    channel_max_cd_m2: [f64; 3],
}

/// XYZ of chromaticity (x, y) at luminance `lum`.
fn xyy_to_xyz(x: f64, y: f64, lum: f64) -> [f64; 3] {
    crate::color::XyY {
        x,
        y,
        luminance: lum,
    }
    .to_xyz()
    .to_array()
}

impl VirtualPanel {
    /// A panel from its parameters; `name` is how it is shown (`ips-lcd`).
    ///
    /// Panics if the white point is outside the primaries' triangle (a preset bug).
    pub fn new(name: &str, params: PanelParams) -> VirtualPanel {
        let black = xyy_to_xyz(params.black_xy[0], params.black_xy[1], params.black_cd_m2);
        let white = xyy_to_xyz(params.white_xy[0], params.white_xy[1], params.white_cd_m2);
        // Columns: XYZ per cd/m² of each primary; solve for the luminances that add up to
        // white minus black.
        let m = Matrix3::from_fn(|row, c| {
            xyy_to_xyz(params.primaries_xy[c][0], params.primaries_xy[c][1], 1.0)[row]
        });
        let target = Vector3::new(
            white[0] - black[0],
            white[1] - black[1],
            white[2] - black[2],
        );
        let lum = m
            .try_inverse()
            .expect("the primaries of a preset are independent")
            * target;
        assert!(
            lum.iter().all(|&l| l > 0.0),
            "white of {name} is outside its primaries: {lum:?}"
        );
        VirtualPanel {
            name: name.to_string(),
            params,
            black,
            channel_max_cd_m2: [lum[0], lum[1], lum[2]],
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

    /// Emitted XYZ (cd/m²) for 8-bit drive values.
    pub fn xyz(&self, rgb: [u8; 3]) -> [f64; 3] {
        let v = rgb.map(|c| f64::from(c) / 255.0);
        let p = &self.params;
        let mut out = self.black;
        for c in 0..3 {
            let pushed: f64 = (0..3)
                .filter(|&d| d != c)
                .map(|d| p.crosstalk[c][d] * v[d])
                .sum();
            let effective = v[c] + pushed * (1.0 - v[c]);
            let level = p.trc[c].eval(effective);
            let x = p.primaries_xy[c][0] + p.drift_xy[c][0] * (1.0 - level);
            let y = p.primaries_xy[c][1] + p.drift_xy[c][1] * (1.0 - level);
            let term = xyy_to_xyz(x, y, level * self.channel_max_cd_m2[c]);
            for (o, t) in out.iter_mut().zip(term) {
                *o += t;
            }
        }
        out
    }

    /// Emitted XYZ for drive values 0–1, quantised to 8 bits first as the display does.
    pub fn xyz_of_drive(&self, rgb: [f64; 3]) -> [f64; 3] {
        self.xyz(rgb.map(quantize))
    }
}

/// The 8-bit code a display shows for drive `v` (0–1, clamped; halves round up).
pub fn quantize(v: f64) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The panel plus what it shows now; this is what a simulated meter looks at.
struct LitPanel {
    panel: VirtualPanel,
    shown: RwLock<[u8; 3]>,
}

impl World for LitPanel {
    fn view(&self) -> View {
        let shown = *self.shown.read().unwrap_or_else(|e| e.into_inner());
        View::xyz(self.panel.xyz(shown))
    }
}

/// A simulated monitor as a [`Screen`]; it starts black.
pub struct VirtualDisplay {
    lit: Arc<LitPanel>,
}

impl VirtualDisplay {
    pub fn new(panel: VirtualPanel) -> VirtualDisplay {
        VirtualDisplay {
            lit: Arc::new(LitPanel {
                panel,
                shown: RwLock::new([0; 3]),
            }),
        }
    }

    pub fn preset(preset: Preset) -> VirtualDisplay {
        VirtualDisplay::new(VirtualPanel::preset(preset))
    }

    /// The same display with full white at `cd_m2` (see [`VirtualPanel::with_white_luminance`]).
    pub fn with_white_luminance(self, cd_m2: f64) -> VirtualDisplay {
        VirtualDisplay::new(self.lit.panel.with_white_luminance(cd_m2))
    }

    pub fn panel(&self) -> &VirtualPanel {
        &self.lit.panel
    }

    /// The drive values shown now.
    pub fn shown(&self) -> [u8; 3] {
        *self.lit.shown.read().unwrap_or_else(|e| e.into_inner())
    }
}

impl Screen for VirtualDisplay {
    fn spec(&self) -> String {
        format!("virtual:{}", self.lit.panel.name)
    }

    fn describe(&self) -> String {
        let p = &self.lit.panel.params;
        format!(
            "simulated monitor '{}': white {:.1} cd/m² at x {:.4} y {:.4}, black {:.3} cd/m²",
            self.lit.panel.name, p.white_cd_m2, p.white_xy[0], p.white_xy[1], p.black_cd_m2
        )
    }

    fn show(&mut self, rgb: [u8; 3]) -> Result<(), ScreenError> {
        *self.lit.shown.write().unwrap_or_else(|e| e.into_inner()) = rgb;
        Ok(())
    }

    /// The simulated panel changes instantly.
    fn default_settle(&self) -> Duration {
        Duration::ZERO
    }

    fn stimulus(&self) -> Option<Arc<dyn World>> {
        Some(self.lit.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }

    fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= tol * y.abs().max(1.0))
    }

    fn xy(v: [f64; 3]) -> [f64; 2] {
        let s = v[0] + v[1] + v[2];
        [v[0] / s, v[1] / s]
    }

    #[test]
    fn full_white_is_the_preset_white_exactly() {
        // D65 at 100 cd/m²: X = 0.3127/0.3290·100 = 95.04559…, Z = 0.3583/0.3290·100.
        let crt = VirtualPanel::preset(Preset::IdealCrt);
        let w = crt.xyz([255; 3]);
        assert!(
            close(
                w,
                [95.045_592_705_167_17, 100.0, 108.905_775_075_987_84],
                1e-12
            ),
            "{w:?}"
        );
        for p in Preset::ALL {
            let panel = VirtualPanel::preset(p);
            let w = panel.xyz([255; 3]);
            let q = p.params();
            assert!((w[1] - q.white_cd_m2).abs() < 1e-9, "{}", p.name());
            let c = xy(w);
            assert!((c[0] - q.white_xy[0]).abs() < 1e-12 && (c[1] - q.white_xy[1]).abs() < 1e-12);
        }
        // Without crosstalk, white = black + the three primaries' own terms; with it, each
        // primary also lights its neighbours a little, so their sum exceeds white.
        for p in Preset::ALL {
            let panel = VirtualPanel::preset(p);
            let w = panel.xyz([255; 3]);
            let k = panel.xyz([0; 3]);
            let sum = (0..3).fold(k, |acc, c| {
                let mut rgb = [0u8; 3];
                rgb[c] = 255;
                let t = sub(panel.xyz(rgb), k);
                [acc[0] + t[0], acc[1] + t[1], acc[2] + t[2]]
            });
            if p == Preset::IdealCrt {
                assert!(close(w, sum, 1e-12), "{w:?} vs {sum:?}");
            } else {
                let excess = sum[1] / w[1] - 1.0;
                assert!((0.001..0.03).contains(&excess), "{}: {excess}", p.name());
            }
        }
    }

    #[test]
    fn ideal_crt_is_plcc_exactly() {
        let crt = VirtualPanel::preset(Preset::IdealCrt);
        let k = crt.xyz([0; 3]);
        // Black: 0.05 cd/m² at (0.300, 0.315).
        assert!(close(
            k,
            [0.05 * 0.300 / 0.315, 0.05, 0.05 * 0.385 / 0.315],
            1e-12
        ));
        let full: Vec<[f64; 3]> = (0..3)
            .map(|c| {
                let mut rgb = [0u8; 3];
                rgb[c] = 255;
                sub(crt.xyz(rgb), k)
            })
            .collect();
        // Primaries keep the BT.709 chromaticities at every level; TRC = v^γ.
        let gammas = [2.25, 2.2, 2.15];
        let primaries = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];
        for c in 0..3 {
            for code in [1u8, 17, 128, 200] {
                let mut rgb = [0u8; 3];
                rgb[c] = code;
                let term = sub(crt.xyz(rgb), k);
                let expect = (f64::from(code) / 255.0).powf(gammas[c]);
                assert!(
                    close(term, full[c].map(|t| t * expect), 1e-9),
                    "c {c} code {code}"
                );
                let [x, y] = xy(term);
                assert!((x - primaries[c][0]).abs() < 1e-9 && (y - primaries[c][1]).abs() < 1e-9);
            }
        }
        // Additive: any mixture is black plus the sum of its channels alone.
        for rgb in [[10u8, 200, 33], [128, 128, 128], [255, 1, 77]] {
            let mut sum = k;
            for c in 0..3 {
                let mut alone = [0u8; 3];
                alone[c] = rgb[c];
                let t = sub(crt.xyz(alone), k);
                sum = [sum[0] + t[0], sum[1] + t[1], sum[2] + t[2]];
            }
            assert!(close(crt.xyz(rgb), sum, 1e-12), "{rgb:?}");
        }
    }

    #[test]
    fn lcd_black_has_its_own_chromaticity_and_channels_drift() {
        let lcd = VirtualPanel::preset(Preset::IpsLcd);
        let k = lcd.xyz([0; 3]);
        assert!((k[1] - 0.22).abs() < 1e-12);
        let [x, y] = xy(k);
        assert!((x - 0.262).abs() < 1e-12 && (y - 0.258).abs() < 1e-12);
        // Red alone at code 64 (crosstalk off, so red is all there is): chromaticity =
        // primary + drift·(1 − L), L its level.
        let mut params = Preset::IpsLcd.params();
        params.crosstalk = [[0.0; 3]; 3];
        let lcd = VirtualPanel::new("no crosstalk", params);
        let full = sub(lcd.xyz([255, 0, 0]), k);
        let term = sub(lcd.xyz([64, 0, 0]), k);
        let level = term[1] / full[1];
        let [x, y] = xy(term);
        assert!((x - (0.641 - 0.030 * (1.0 - level))).abs() < 1e-12);
        assert!((y - (0.336 + 0.020 * (1.0 - level))).abs() < 1e-12);
        assert!(0.030 * (1.0 - level) > 0.02, "drift visible at a low level");
    }

    #[test]
    fn lcd_mixtures_are_not_additive_by_the_crosstalk() {
        // Only red ↔ green crosstalk, no drift: luminances follow by hand.
        let mut params = Preset::IpsLcd.params();
        params.crosstalk = [[0.0, 0.015, 0.0], [0.020, 0.0, 0.0], [0.0; 3]];
        params.drift_xy = [[0.0; 2]; 3];
        let lcd = VirtualPanel::new("red-green crosstalk", params.clone());
        let k = lcd.xyz([0; 3]);
        let max = lcd.channel_max_cd_m2;
        let v = 128.0 / 255.0;
        // Red alone at v: red driven at v, green leaks at 0.020·v·(1 − 0).
        let red = sub(lcd.xyz([128, 0, 0]), k);
        let expect = max[0] * params.trc[0].eval(v) + max[1] * params.trc[1].eval(0.020 * v);
        assert!(
            (red[1] - expect).abs() < 1e-9 * expect,
            "{} vs {expect}",
            red[1]
        );
        // Both at v: red driven at v + 0.015·v(1 − v), green at v + 0.020·v(1 − v).
        let mixed = sub(lcd.xyz([128, 128, 0]), k);
        let expect = max[0] * params.trc[0].eval(v + 0.015 * v * (1.0 - v))
            + max[1] * params.trc[1].eval(v + 0.020 * v * (1.0 - v));
        assert!(
            (mixed[1] - expect).abs() < 1e-9 * expect,
            "{} vs {expect}",
            mixed[1]
        );
        // On the preset itself the additivity failure of a mixture is of the order of 1 %.
        let lcd = VirtualPanel::preset(Preset::IpsLcd);
        let k = lcd.xyz([0; 3]);
        let alone: f64 = (0..3)
            .map(|c| {
                let mut rgb = [0u8; 3];
                rgb[c] = 128;
                lcd.xyz(rgb)[1] - k[1]
            })
            .sum();
        let failure = ((lcd.xyz([128; 3])[1] - k[1]) / alone - 1.0).abs();
        assert!(
            (0.003..0.05).contains(&failure),
            "additivity failure {failure}"
        );
    }

    #[test]
    fn lcd_trcs_are_not_power_laws() {
        // Local exponent d ln L / d ln v: constant γ for a power law.
        let exponent = |t: &Trc, v: f64| {
            let h = 1e-4;
            ((t.eval(v + h)).ln() - (t.eval(v - h)).ln()) / ((v + h).ln() - (v - h).ln())
        };
        for preset in [Preset::IpsLcd, Preset::WideGamutCcfl] {
            for t in preset.params().trc {
                assert_eq!(t.eval(0.0), 0.0);
                assert!((t.eval(1.0) - 1.0).abs() < 1e-15);
                let (lo, hi) = (exponent(&t, 0.25), exponent(&t, 0.75));
                assert!((lo - hi).abs() > 0.1, "{}: {lo} vs {hi}", preset.name());
                let mut last = 0.0;
                for i in 1..=255 {
                    let l = t.eval(f64::from(i) / 255.0);
                    assert!(l > last);
                    last = l;
                }
            }
        }
        let t = Trc::power(2.2);
        assert!((exponent(&t, 0.25) - 2.2).abs() < 1e-6 && (exponent(&t, 0.75) - 2.2).abs() < 1e-6);
    }

    #[test]
    fn drive_values_are_quantised_to_8_bits() {
        let lcd = VirtualPanel::preset(Preset::IpsLcd);
        assert_eq!(quantize(0.5), 128); // 127.5 rounds up
        assert_eq!(quantize(0.499), 127);
        assert_eq!(quantize(-0.2), 0);
        assert_eq!(quantize(1.7), 255);
        assert_eq!(lcd.xyz_of_drive([0.5, 0.2, 1.0]), lcd.xyz([128, 51, 255]));
        assert_eq!(
            lcd.xyz_of_drive([0.5011, 0.2, 1.0]),
            lcd.xyz([128, 51, 255])
        );
    }

    #[test]
    fn white_luminance_scales_everything_alike() {
        let crt = VirtualPanel::preset(Preset::IdealCrt);
        let dim = crt.with_white_luminance(80.0);
        for rgb in [[0u8, 0, 0], [255, 255, 255], [12, 200, 99]] {
            assert!(
                close(dim.xyz(rgb), crt.xyz(rgb).map(|v| v * 0.8), 1e-12),
                "{rgb:?}"
            );
        }
        assert!((dim.xyz([0; 3])[1] - 0.04).abs() < 1e-15);
    }

    #[test]
    fn the_simulated_meter_measures_what_is_shown() {
        let mut display = VirtualDisplay::preset(Preset::IdealCrt);
        let mut meter = metamer_drivers::open_instrument(
            "sim:cs100a?time_scale=0&noise=off",
            display.stimulus(),
        )
        .unwrap();
        let request = metamer_drivers::Request::default();
        display.show([255, 255, 255]).unwrap();
        let r = meter.measure(&request).unwrap();
        // The CS-100A sends x, y with 4 decimals and Y with 3 significant digits or more.
        assert_eq!(r.xyy, [0.3127, 0.3290, 100.0]);
        display.show([0, 0, 255]).unwrap();
        assert_eq!(display.shown(), [0, 0, 255]);
        let r = meter.measure(&request).unwrap();
        let expect = display.panel().xyz([0, 0, 255]);
        assert!(
            (r.xyy[2] - expect[1]).abs() < 0.01,
            "{:?} vs {expect:?}",
            r.xyy
        );
        assert_eq!(display.spec(), "virtual:ideal-crt");
    }
}
