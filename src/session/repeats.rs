//! A reading that differs from the readings taken before it at the same placement by more
//! than the instrument repeats: a moved instrument, a bumped tripod, a hand in the light.
//! Found while the operator is still there to re-aim, not later in the statistics.
//!
//! The repeatability is each instrument's stated one (1σ of one reading), the one figure
//! the session's flags, the box's outlier and spread tests and a single reading's
//! covariance in the validation all use:
//! - CS-100A: ±0.2 % in Y and ±0.001 in x, y (as 2σ), plus one unit of the last digit it
//!   sends (four significant digits of Y, four decimals of x, y); see
//!   `protocols/cs100a/README.md` (general knowledge, not yet confirmed by Konica Minolta's
//!   sheet);
//! - i1Pro, emissive: 0.15 % of Y at full signal, growing as the shot noise below the
//!   luminance where the driver's 2 s cap starts, x, y 0.3 times that
//!   (`metamer_drivers::i1pro::emulator::repeatability_y`, checked against the simulated
//!   unit; `protocols/i1pro/README.md`); ambient: 0.15 % of the illuminance; reflective:
//!   0.002 absolute per band, i.e. 0.2 in Y on the scale where white is 100, x, y not
//!   stated;
//! - other models: the CS-100A's for light and the i1Pro's for surfaces.
//!
//! A reading is flagged when its Y (or x, y) lies more than [`FLAG_SIGMAS`] σ from the
//! mean of the earlier readings, σ being the noise of that difference: σ·√(1 + 1/m) for m
//! earlier readings. At 5σ honest noise trips it about once in 1.7 million tests, so a
//! flag is worth the operator's attention; a misaimed spot meter (a few per cent) always
//! trips it.

use metamer_drivers::i1pro::emulator;
use metamer_drivers::{MeasureMode, Reading};

use crate::color::Xyz;
use crate::validation::covariance::{self, Cov3};

/// How far from the earlier readings' mean, in σ of the difference, a reading is flagged.
/// The same distance as the box assembly's outlier test, so what is flagged here is what
/// would be left out there.
pub const FLAG_SIGMAS: f64 = 5.0;

/// Below this luminance (cd/m²) an emissive reading's relative noise is taken at this
/// level: near black a relative figure means nothing.
const DARK_CD_M2: f64 = 1.0;

/// How an instrument's noise in Y depends on the level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LevelNoise {
    /// A fixed relative σ (`y_relative`) and absolute σ (`y_absolute`).
    Flat,
    /// The i1Pro's emissive noise: [`emulator::repeatability_y`] of the level in cd/m².
    I1ProEmissive,
}

/// One instrument's stated repeatability in one mode, 1σ of one reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Repeatability {
    /// σ of Y relative to Y (emissive, ambient) at full signal.
    pub y_relative: f64,
    /// σ of Y, absolute (reflective, white = 100); 0 where relative.
    pub y_absolute: f64,
    /// How σ of Y grows below full signal.
    pub level: LevelNoise,
    /// Significant digits of Y the instrument sends (its last digit is one more unit of
    /// noise); None: not rounded.
    pub y_digits: Option<i32>,
    /// σ of x and of y; None: not stated, not tested.
    pub xy: Option<XyNoise>,
    /// Decimals of x, y the instrument sends.
    pub xy_decimals: Option<i32>,
}

/// σ of x and of y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum XyNoise {
    /// Absolute, at any level.
    Fixed(f64),
    /// This many times the relative σ of Y at the level.
    PerRelativeY(f64),
}

impl Repeatability {
    /// The stated repeatability of `model` in `mode`.
    pub fn stated(model: &str, mode: MeasureMode) -> Repeatability {
        match (model, mode) {
            (_, MeasureMode::Reflective) => Repeatability {
                y_relative: 0.0,
                y_absolute: 0.2,
                level: LevelNoise::Flat,
                y_digits: None,
                xy: None,
                xy_decimals: None,
            },
            ("i1pro", MeasureMode::Emissive) => Repeatability {
                y_relative: emulator::REPEATABILITY_Y,
                y_absolute: 0.0,
                level: LevelNoise::I1ProEmissive,
                y_digits: None,
                xy: Some(XyNoise::PerRelativeY(emulator::REPEATABILITY_XY_PER_Y)),
                xy_decimals: None,
            },
            ("i1pro", _) => Repeatability {
                y_relative: emulator::REPEATABILITY_Y,
                y_absolute: 0.0,
                level: LevelNoise::Flat,
                y_digits: None,
                xy: None,
                xy_decimals: None,
            },
            _ => Repeatability {
                y_relative: 0.001,
                y_absolute: 0.0,
                level: LevelNoise::Flat,
                y_digits: Some(4),
                xy: Some(XyNoise::Fixed(0.0005)),
                xy_decimals: Some(4),
            },
        }
    }

    /// The emissive repeatability of the instrument an instrument name or spec names
    /// (`cs100a`, `sim:i1pro?seed=2`, `CS-100A`); None for a name that is neither.
    pub fn emissive_of(name: &str) -> Option<Repeatability> {
        let n = name.trim().to_ascii_lowercase();
        let model = if n.contains("i1pro") {
            "i1pro"
        } else if n.contains("cs100a") || n.contains("cs-100a") {
            "cs100a"
        } else {
            return None;
        };
        Some(Repeatability::stated(model, MeasureMode::Emissive))
    }

    /// σ of one reading's Y at the level `y`, without the rounding of the last digit.
    pub fn sigma_y(&self, y: f64) -> f64 {
        match self.level {
            LevelNoise::Flat => self.y_absolute + self.y_relative * y.abs().max(DARK_CD_M2),
            LevelNoise::I1ProEmissive => emulator::repeatability_y(y) * y.abs(),
        }
    }

    /// σ of one reading's x and y at the level `y`; None where not stated.
    pub fn sigma_xy(&self, y: f64) -> Option<f64> {
        self.xy.map(|xy| match xy {
            XyNoise::Fixed(s) => s,
            XyNoise::PerRelativeY(k) => k * self.sigma_y(y) / y.abs().max(f64::MIN_POSITIVE),
        })
    }

    /// One unit of the last digit sent at the level `y`.
    fn digit_y(&self, y: f64) -> f64 {
        match self.y_digits {
            Some(d) if y != 0.0 && y.is_finite() => {
                10f64.powi(y.abs().log10().floor() as i32 - d + 1)
            }
            _ => 0.0,
        }
    }

    /// The covariance of X, Y, Z of one reading of `xyz`: with X = xY/y and
    /// Z = (1 − x − y)Y/y, J·diag(σx², σy², σY²)·Jᵀ with J the derivatives of (X, Y, Z) by
    /// (x, y, Y), the last digit's rounding counted as a uniform error (variance d²/12).
    /// None without a chromaticity (X + Y + Z ≤ 0, Y ≤ 0) or without a stated x, y figure.
    pub fn covariance(&self, xyz: Xyz) -> Option<Cov3> {
        let s = xyz[0] + xyz[1] + xyz[2];
        if !(s > 0.0 && xyz[1] > 0.0) {
            return None;
        }
        let (x, y, big_y) = (xyz[0] / s, xyz[1] / s, xyz[1]);
        let xy = self.sigma_xy(big_y)?;
        let digit = self.digit_y(big_y);
        // Columns: ∂/∂x, ∂/∂y, ∂/∂Y.
        let j = [
            [big_y / y, -x * big_y / (y * y), x / y],
            [0.0, 0.0, 1.0],
            [-big_y / y, -(1.0 - x) * big_y / (y * y), (1.0 - x - y) / y],
        ];
        let var = [
            xy * xy,
            xy * xy,
            self.sigma_y(big_y).powi(2) + digit * digit / 12.0,
        ];
        let mut c = covariance::ZERO;
        for (a, row) in c.iter_mut().enumerate() {
            for (b, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|k| j[a][k] * var[k] * j[b][k]).sum();
            }
        }
        Some(c)
    }

    /// The figure as a data sheet states it (2σ) at the level `y`: `±0.2 %`, `±0.4`,
    /// `±0.68 %` (at this level).
    fn stated_y(&self, y: f64) -> String {
        match self.level {
            LevelNoise::I1ProEmissive => format!(
                "±{:.2} %",
                200.0 * self.sigma_y(y) / y.abs().max(f64::MIN_POSITIVE)
            ),
            LevelNoise::Flat if self.y_relative > 0.0 => format!("±{} %", 200.0 * self.y_relative),
            LevelNoise::Flat => format!("±{}", 2.0 * self.y_absolute),
        }
    }
}

/// How a reading differs from the earlier readings of its placement, when by more than
/// the instrument repeats.
#[derive(Clone, Debug, PartialEq)]
pub struct Deviation {
    /// Earlier readings compared with.
    pub earlier: usize,
    /// This reading's Y minus their mean, relative to their mean.
    pub y_relative: f64,
    /// This reading's Y minus their mean.
    pub y: f64,
    /// The larger of |Δx| and |Δy| from their mean x, y.
    pub xy: f64,
    /// Which of the two is beyond the instrument's repeatability.
    pub y_beyond: bool,
    pub xy_beyond: bool,
    /// The repeatability as stated (`±0.2 %` in Y, and `±0.001` in x, y when tested).
    pub stated: String,
}

impl std::fmt::Display for Deviation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let before = match self.earlier {
            1 => "the reading before it".to_string(),
            n => format!("the mean of the {n} readings before it"),
        };
        let mut parts = Vec::new();
        if self.y_beyond {
            let side = if self.y >= 0.0 { "above" } else { "below" };
            parts.push(format!(
                "Y {:.2} % {side} {before}",
                100.0 * self.y_relative.abs()
            ));
        }
        if self.xy_beyond {
            let of = if self.y_beyond { "it" } else { before.as_str() };
            parts.push(format!("x, y {:.4} off {of}", self.xy));
        }
        write!(
            f,
            "{}; the instrument repeats within {}",
            parts.join(", "),
            self.stated
        )
    }
}

/// How `this` differs from the `earlier` readings of the same placement, if by more than
/// `r` allows; None with no earlier reading or within the noise.
pub fn deviation(earlier: &[&Reading], this: &Reading, r: Repeatability) -> Option<Deviation> {
    let m = earlier.len();
    if m == 0 {
        return None;
    }
    let spread = (1.0 + 1.0 / m as f64).sqrt();
    let mean_y = earlier.iter().map(|e| e.xyz[1]).sum::<f64>() / m as f64;
    let dy = this.xyz[1] - mean_y;
    let y_limit = FLAG_SIGMAS * r.sigma_y(mean_y) * spread + r.digit_y(mean_y);
    let y_beyond = dy.abs() > y_limit;
    // Chromaticity means nothing near black, and is not tested where not stated.
    let xys: Vec<[f64; 2]> = earlier
        .iter()
        .map(|e| [e.xyy[0], e.xyy[1]])
        .filter(|p| p.iter().all(|v| v.is_finite()))
        .collect();
    let mut xy = 0.0;
    let mut xy_beyond = false;
    if let Some(sigma) = r.sigma_xy(mean_y).filter(|_| {
        mean_y.abs() >= DARK_CD_M2 && xys.len() == m && this.xyy[..2].iter().all(|v| v.is_finite())
    }) {
        let mean = |k: usize| xys.iter().map(|p| p[k]).sum::<f64>() / m as f64;
        xy = (this.xyy[0] - mean(0))
            .abs()
            .max((this.xyy[1] - mean(1)).abs());
        let digit = r.xy_decimals.map_or(0.0, |d| 10f64.powi(-d));
        xy_beyond = xy > FLAG_SIGMAS * sigma * spread + digit;
    }
    if !(y_beyond || xy_beyond) {
        return None;
    }
    let mut stated = format!("{} in Y", r.stated_y(mean_y));
    match r.xy {
        Some(XyNoise::Fixed(sigma)) => stated.push_str(&format!(" and ±{} in x, y", 2.0 * sigma)),
        Some(XyNoise::PerRelativeY(_)) => {
            if let Some(sigma) = r.sigma_xy(mean_y) {
                stated.push_str(&format!(" and ±{:.4} in x, y", 2.0 * sigma));
            }
        }
        None => {}
    }
    if r.level != LevelNoise::Flat {
        stated.push_str(" at this level");
    }
    Some(Deviation {
        earlier: m,
        y_relative: dy / mean_y.abs().max(f64::MIN_POSITIVE),
        y: dy,
        xy,
        y_beyond,
        xy_beyond,
        stated,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(x: f64, y: f64, lum: f64) -> Reading {
        Reading::from_yxy(lum, x, y, "test")
    }

    #[test]
    fn honest_noise_is_not_flagged_and_a_moved_meter_is() {
        let cs = Repeatability::stated("cs100a", MeasureMode::Emissive);
        let earlier = [
            reading(0.3127, 0.3290, 100.0),
            reading(0.3128, 0.3289, 100.2),
        ];
        let refs: Vec<&Reading> = earlier.iter().collect();
        // Mean 100.1; σ of the difference 0.1 % · 100.1 · √1.5 = 0.1226; 5σ = 0.613, plus
        // the last digit 0.1 (four significant digits of 100): flagged beyond 0.713.
        assert_eq!(deviation(&refs, &reading(0.3127, 0.3290, 100.8), cs), None);
        let d = deviation(&refs, &reading(0.3127, 0.3290, 100.9), cs).unwrap();
        assert!(d.y_beyond && !d.xy_beyond);
        assert!((d.y_relative - 0.8 / 100.1).abs() < 1e-12);
        assert_eq!(
            d.to_string(),
            "Y 0.80 % above the mean of the 2 readings before it; the instrument repeats \
             within ±0.2 % in Y and ±0.001 in x, y"
        );
        // x, y: σ 0.0005 · √1.5 · 5 = 0.00306, plus 0.0001: flagged beyond 0.00316 off
        // the mean (0.31275, 0.32895).
        assert_eq!(deviation(&refs, &reading(0.3158, 0.3290, 100.1), cs), None);
        let d = deviation(&refs, &reading(0.3160, 0.3290, 100.1), cs).unwrap();
        assert!(!d.y_beyond && d.xy_beyond);
        assert!((d.xy - 0.00325).abs() < 1e-12);
        assert!(d.to_string().starts_with("x, y 0.0033 off the mean"), "{d}");
    }

    #[test]
    fn one_earlier_reading_and_the_dark_and_surfaces() {
        let cs = Repeatability::stated("cs100a", MeasureMode::Emissive);
        let first = reading(0.3127, 0.3290, 10.0);
        // One earlier reading: σ·√2. At 10 cd/m², 5 · 0.01 · √2 = 0.0707, plus the last
        // digit 0.01.
        assert_eq!(
            deviation(&[&first], &reading(0.3127, 0.3290, 10.08), cs),
            None
        );
        let d = deviation(&[&first], &reading(0.3127, 0.3290, 9.91), cs).unwrap();
        assert_eq!(
            d.to_string(),
            "Y 0.90 % below the reading before it; the instrument repeats within ±0.2 % in Y \
             and ±0.001 in x, y"
        );
        // Near black Y's noise is that of 1 cd/m² and x, y are not tested.
        let dark = reading(0.30, 0.30, 0.05);
        assert_eq!(deviation(&[&dark], &reading(0.40, 0.20, 0.055), cs), None);
        assert!(deviation(&[&dark], &reading(0.30, 0.30, 0.065), cs).is_some());
        // A surface on the i1Pro: 0.2 absolute in Y (white = 100), x, y untested.
        let i1 = Repeatability::stated("i1pro", MeasureMode::Reflective);
        let grey = reading(0.31, 0.33, 20.0);
        assert_eq!(deviation(&[&grey], &reading(0.35, 0.33, 21.4), i1), None);
        let d = deviation(&[&grey], &reading(0.31, 0.33, 21.5), i1).unwrap();
        assert!(d.to_string().ends_with("repeats within ±0.4 in Y"), "{d}");
        // Nothing to compare with.
        assert_eq!(deviation(&[], &grey, i1), None);
    }

    /// The stated repeatability carried to X, Y, Z matches the scatter of readings drawn
    /// as the CS-100A's noise is (Y and x, y independent normals, Y's last digit as its
    /// variance d²/12), to within the sampling error of 200 000 draws.
    #[test]
    fn stated_repeatability_carries_to_xyz_as_sampled() {
        let r = Repeatability::emissive_of("sim:cs100a?seed=2").unwrap();
        assert_eq!(r, Repeatability::stated("cs100a", MeasureMode::Emissive));
        assert_eq!(Repeatability::emissive_of("spectralon"), None);
        // A saturated yellow (ColorChecker 16 under a white display): x 0.45, y 0.50,
        // where Z = (1 − x − y)Y/y is small and chromaticity noise moves it by a lot.
        let (x, y, big_y) = (0.45, 0.50, 10.0);
        let xyz = Xyz::new(x * big_y / y, big_y, (1.0 - x - y) * big_y / y);
        let c = r.covariance(xyz).unwrap();
        // By hand: σY² = (0.1 % of 10)² + 0.01²/12 (four digits of 10.00) = 1.08333e-4;
        // σZ from x and y: ∂Z/∂x = −Y/y = −20, ∂Z/∂y = −(1−x)Y/y² = −22, ∂Z/∂Y = 0.1:
        // σZ² = 0.0005²·(400 + 484) + 1.08333e-4·0.01 = 2.22083e-4.
        assert!((c[1][1] - 1.083_333e-4).abs() < 1e-10, "{}", c[1][1]);
        assert!((c[2][2] - 2.220_833e-4).abs() < 1e-9, "{}", c[2][2]);
        let (sxy, sy) = (0.0005, c[1][1].sqrt());
        let mut rng = metamer_drivers::noise::SplitMix64::new(7);
        let draws: Vec<Xyz> = (0..200_000)
            .map(|_| {
                let (xx, yy, ly) = (
                    x + sxy * rng.normal(),
                    y + sxy * rng.normal(),
                    big_y + sy * rng.normal(),
                );
                Xyz::new(xx * ly / yy, ly, (1.0 - xx - yy) * ly / yy)
            })
            .collect();
        let (_, s) = covariance::sample(&draws);
        for i in 0..3 {
            for j in 0..3 {
                let scale = (c[i][i] * c[j][j]).sqrt();
                assert!(
                    (s[i][j] - c[i][j]).abs() < 0.02 * scale,
                    "{i}{j}: sampled {} vs {}",
                    s[i][j],
                    c[i][j]
                );
            }
        }
        assert_eq!(r.covariance(Xyz::default()), None);
    }

    /// The i1Pro's figure depends on the level: at 25 cd/m² σY/Y is 0.30447 % (0.15 % ·
    /// √(100/25) with 0.013/25 in quadrature), x, y 0.3 times that; its flags and its
    /// covariance use the same figure.
    #[test]
    fn the_i1pros_figure_follows_the_level() {
        let r = Repeatability::emissive_of("sim:i1pro?time_scale=0").unwrap();
        assert_eq!(r, Repeatability::stated("i1pro", MeasureMode::Emissive));
        assert!((r.sigma_y(25.0) - 25.0 * 0.003_044_7).abs() < 1e-5);
        assert!((r.sigma_y(400.0) / 400.0 - 0.0015).abs() < 1e-6);
        assert!((r.sigma_xy(25.0).unwrap() - 0.3 * 0.003_044_7).abs() < 1e-7);
        let c = r.covariance(Xyz::new(20.0, 25.0, 30.0)).unwrap();
        assert!((c[1][1] - r.sigma_y(25.0).powi(2)).abs() < 1e-12);
        // A dim reading 1.2 % off the one before it is noise at 5 cd/m² (σ 0.72 %, 5σ·√2
        // = 5.1 %) but not at 200 cd/m² (σ 0.15 %: 5σ·√2 = 1.06 %).
        let at = |lum: f64| reading(0.31, 0.33, lum);
        assert_eq!(deviation(&[&at(5.0)], &at(5.06), r), None);
        let d = deviation(&[&at(200.0)], &at(202.4), r).unwrap();
        assert!(
            d.to_string()
                == "Y 1.20 % above the reading before it; the instrument repeats within ±0.30 % in Y and ±0.0009 in x, y at this level",
            "{d}"
        );
    }
}
