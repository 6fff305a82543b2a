//! A reading that differs from the readings taken before it at the same placement by more
//! than the instrument repeats: a moved instrument, a bumped tripod, a hand in the light.
//! Found while the operator is still there to re-aim, not later in the statistics.
//!
//! The repeatability is each model's stated one (1σ of one reading), data in its driver
//! registry row ([`metamer_drivers::registry::stated_repeatability`]), the one figure the
//! session's flags, the box's outlier and spread tests and a single reading's covariance in
//! the validation all use (the figures and their sources: `metamer devices --describe
//! MODEL`).
//!
//! A reading is flagged when its Y (or x, y) lies more than [`FLAG_SIGMAS`] σ from the
//! mean of the earlier readings, σ being the noise of that difference: σ·√(1 + 1/m) for m
//! earlier readings. At 5σ honest noise trips it about once in 1.7 million tests, so a
//! flag is worth the operator's attention; a misaimed spot meter (a few per cent) always
//! trips it.

use metamer_drivers::registry::{Repeatability, XyNoise, DARK_CD_M2};
use metamer_drivers::Reading;

/// How far from the earlier readings' mean, in σ of the difference, a reading is flagged.
/// The same distance as the box assembly's outlier test, so what is flagged here is what
/// would be left out there.
pub const FLAG_SIGMAS: f64 = 5.0;

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
        let digit = r.digit_xy();
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
    if r.follows_level() {
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
    use metamer_drivers::registry::stated_repeatability as stated;
    use metamer_drivers::MeasureMode;

    fn reading(x: f64, y: f64, lum: f64) -> Reading {
        Reading::from_yxy(lum, x, y, "test")
    }

    #[test]
    fn honest_noise_is_not_flagged_and_a_moved_meter_is() {
        let cs = stated("cs100a", MeasureMode::Emissive);
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
        let cs = stated("cs100a", MeasureMode::Emissive);
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
        let i1 = stated("i1pro", MeasureMode::Reflective);
        let grey = reading(0.31, 0.33, 20.0);
        assert_eq!(deviation(&[&grey], &reading(0.35, 0.33, 21.4), i1), None);
        let d = deviation(&[&grey], &reading(0.31, 0.33, 21.5), i1).unwrap();
        assert!(d.to_string().ends_with("repeats within ±0.4 in Y"), "{d}");
        // Nothing to compare with.
        assert_eq!(deviation(&[], &grey, i1), None);
    }

    /// The i1Pro's flags follow the level: a dim reading 1.2 % off the one before it is
    /// noise at 5 cd/m² (σ 0.72 %, 5σ·√2 = 5.1 %) but not at 200 cd/m² (σ 0.15 %: 5σ·√2 =
    /// 1.06 %).
    #[test]
    fn the_i1pros_flags_follow_the_level() {
        let r = stated("i1pro", MeasureMode::Emissive);
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
