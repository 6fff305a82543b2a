//! A model's stated repeatability in one mode (1σ of one reading) as data in its registry
//! row, and what the figure says at a level: σ of Y, σ of x and y, the last digit the
//! instrument sends, and the figure in a data sheet's words. The session's re-aim flags,
//! the box's outlier and spread tests and a single reading's covariance in the validation
//! all read these figures; the covariance itself is the library's
//! (`metamer::validation::repeatability`).

use serde::Serialize;

/// Below this luminance (cd/m²) an emissive reading's relative noise is taken at this
/// level: near black a relative figure means nothing.
pub const DARK_CD_M2: f64 = 1.0;

/// How an instrument's noise in Y depends on the level.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LevelNoise {
    /// A fixed relative σ (`y_relative`) and absolute σ (`y_absolute`).
    Flat,
    /// A spectrometer whose integration time is capped: `y_relative` down to
    /// `full_signal_cd_m2`, below it growing as the shot noise does (√(full / Y)), with the
    /// sensor's own noise `dark_cd_m2` (1σ, cd/m²) in quadrature.
    Shot {
        full_signal_cd_m2: f64,
        dark_cd_m2: f64,
    },
}

/// σ of x and of y.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum XyNoise {
    /// Absolute, at any level.
    Fixed(f64),
    /// This many times the relative σ of Y at the level.
    PerRelativeY(f64),
}

/// One model's stated repeatability in one mode, 1σ of one reading.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
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
    /// Where the figure comes from, for `metamer devices --describe`.
    #[serde(skip)]
    pub source: &'static str,
}

impl Repeatability {
    /// The relative σ of Y at the level `y` (cd/m²) where it depends on the level.
    fn relative_y(&self, y: f64) -> f64 {
        match self.level {
            LevelNoise::Flat => self.y_relative,
            LevelNoise::Shot {
                full_signal_cd_m2,
                dark_cd_m2,
            } => {
                let y = y.abs().max(f64::MIN_POSITIVE);
                let shot = self.y_relative * self.y_relative * (full_signal_cd_m2 / y).max(1.0);
                (shot + (dark_cd_m2 / y).powi(2)).sqrt()
            }
        }
    }

    /// σ of one reading's Y at the level `y`, without the rounding of the last digit.
    pub fn sigma_y(&self, y: f64) -> f64 {
        match self.level {
            LevelNoise::Flat => self.y_absolute + self.y_relative * y.abs().max(DARK_CD_M2),
            LevelNoise::Shot { .. } => self.relative_y(y) * y.abs(),
        }
    }

    /// σ of one reading's x and y at the level `y`; None where not stated.
    pub fn sigma_xy(&self, y: f64) -> Option<f64> {
        self.xy.map(|xy| match xy {
            XyNoise::Fixed(s) => s,
            XyNoise::PerRelativeY(k) => k * self.sigma_y(y) / y.abs().max(f64::MIN_POSITIVE),
        })
    }

    /// One unit of the last digit of Y sent at the level `y`.
    pub fn digit_y(&self, y: f64) -> f64 {
        match self.y_digits {
            Some(d) if y != 0.0 && y.is_finite() => {
                10f64.powi(y.abs().log10().floor() as i32 - d + 1)
            }
            _ => 0.0,
        }
    }

    /// One unit of the last decimal of x, y sent; 0 where not rounded.
    pub fn digit_xy(&self) -> f64 {
        self.xy_decimals.map_or(0.0, |d| 10f64.powi(-d))
    }

    /// Whether the figure depends on the level.
    pub fn follows_level(&self) -> bool {
        self.level != LevelNoise::Flat
    }

    /// The Y figure as a data sheet states it (2σ) at the level `y`: `±0.2 %`, `±0.4`,
    /// `±0.68 %` (at this level).
    pub fn stated_y(&self, y: f64) -> String {
        match self.level {
            LevelNoise::Shot { .. } => format!(
                "±{:.2} %",
                200.0 * self.sigma_y(y) / y.abs().max(f64::MIN_POSITIVE)
            ),
            LevelNoise::Flat if self.y_relative > 0.0 => format!("±{} %", 200.0 * self.y_relative),
            LevelNoise::Flat => format!("±{}", 2.0 * self.y_absolute),
        }
    }

    /// The whole figure in words (2σ), for a model's description: `±0.2 % in Y and ±0.001
    /// in x, y`, or for a level-dependent one its full-signal figure and how it grows.
    pub fn describe(&self) -> String {
        let mut s = match self.level {
            LevelNoise::Flat => format!("{} in Y", self.stated_y(1.0)),
            LevelNoise::Shot {
                full_signal_cd_m2,
                dark_cd_m2,
            } => format!(
                "±{} % in Y from {full_signal_cd_m2} cd/m² up, growing as √({full_signal_cd_m2} \
                 cd/m² / Y) below, with ±{} cd/m² of sensor noise",
                200.0 * self.y_relative,
                2.0 * dark_cd_m2
            ),
        };
        match self.xy {
            Some(XyNoise::Fixed(sigma)) => s.push_str(&format!(" and ±{} in x, y", 2.0 * sigma)),
            Some(XyNoise::PerRelativeY(k)) => {
                s.push_str(&format!("; x, y {k} times Y's relative figure"))
            }
            None => s.push_str("; x, y not stated"),
        }
        if let Some(d) = self.y_digits {
            s.push_str(&format!(
                ", plus the last of the {d} significant digits of Y it sends"
            ));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use crate::i1pro::emulator;
    use crate::registry::by_name;
    use crate::MeasureMode;

    /// The i1Pro row's figure is the emulator's own curve, bit for bit, at every level from
    /// near black to far above full signal.
    #[test]
    fn the_i1pro_rows_curve_is_the_emulators() {
        let r = by_name("i1pro")
            .unwrap()
            .stated_repeatability(MeasureMode::Emissive)
            .unwrap();
        for k in -40..40 {
            let y = 10f64.powf(k as f64 / 10.0);
            assert_eq!(r.sigma_y(y), emulator::repeatability_y(y) * y, "{y} cd/m²");
        }
    }

    #[test]
    fn figures_in_words() {
        let cs = by_name("cs100a")
            .unwrap()
            .stated_repeatability(MeasureMode::Emissive)
            .unwrap();
        assert_eq!(
            cs.describe(),
            "±0.2 % in Y and ±0.001 in x, y, plus the last of the 4 significant digits of Y \
             it sends"
        );
        // 100 cd/m² has four digits 100.0: one unit is 0.1.
        assert_eq!(cs.digit_y(100.0), 0.1);
        assert_eq!(cs.digit_xy(), 1e-4);
        let i1 = by_name("i1pro").unwrap();
        assert_eq!(
            i1.stated_repeatability(MeasureMode::Reflective)
                .unwrap()
                .describe(),
            "±0.4 in Y; x, y not stated"
        );
        assert_eq!(
            i1.stated_repeatability(MeasureMode::Emissive)
                .unwrap()
                .describe(),
            "±0.3 % in Y from 100 cd/m² up, growing as √(100 cd/m² / Y) below, with ±0.026 \
             cd/m² of sensor noise; x, y 0.3 times Y's relative figure"
        );
    }
}
