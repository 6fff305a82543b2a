//! Accuracy against measuring cost: for each side a run measured (the box's spots, the
//! display's spots, the display model), the figure its readings bought against the readings
//! they took and the minutes a rig would have taken for them, so a plan that stops early
//! (adaptive) and one that reads a fixed count can be put on one chart.
//!
//! **Spots.** A side whose targets are read repeatedly (patch after patch) is followed as if
//! every target had stopped after its first m readings, for m = 1 up to the most any target
//! took: at m the readings are Σ min(m, nⱼ) and the figure is the median over the targets of
//! the 95 % half-width in CIELAB of the mean of their first min(m, nⱼ) readings
//! ([`sequential::half_width`]: the radius of the ball holding the χ²/Hotelling region). One
//! reading's noise is the instrument's stated repeatability scaled by the figure pooled
//! over all of the side's readings, with its degrees of freedom (as the validation's
//! intervals take it), evaluated at each target's mean; the half-width of m readings is then
//! that of one reading over √m. Its last point is the run as measured. The half-width is
//! the side's own share of the verdict intervals: a comparison's interval holds both sides'.
//!
//! **Minutes.** A point's time is its readings at the stage's budgeted instrument and
//! settle time per reading, plus the stage's placements at the budget's time per
//! placement, from the budget the stage's files keep (the instrument's time at its real
//! pace, from each model's protocol facts): the same for a simulated rig, whatever its time
//! scale, as for a real one.

use serde::{Deserialize, Serialize};

use super::repeatability::Repeatability;
use super::sequential::{self, pool::Pool};
use crate::color::Xyz;

/// One line of the chart: a side of one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CostCurve {
    /// "box spots", "display spots", "display model".
    pub side: String,
    /// How the side was measured ("fixed, 5 readings", "until decided", "adaptive").
    pub plan: String,
    /// Which run: "this run" or the compared run's name.
    pub run: String,
    /// What the figure is, for the caption and the table.
    pub measure: String,
    pub points: Vec<CurvePoint>,
}

/// The figure after some readings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    pub readings: usize,
    pub minutes: f64,
    /// ΔE*ab.
    pub value: f64,
}

/// One target read repeatedly: how many readings it took and the 95 % half-width
/// (ΔE*ab) of one reading at its level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RepeatedTarget {
    pub readings: usize,
    pub one_reading: f64,
}

/// A stage's time per reading and per placement, and its placements.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pace {
    pub reading_s: f64,
    pub placement_s: f64,
    pub placements: usize,
}

impl Pace {
    /// Minutes of `readings` readings with all the stage's placements.
    pub fn minutes(&self, readings: usize) -> f64 {
        (readings as f64 * self.reading_s + self.placements as f64 * self.placement_s) / 60.0
    }
}

/// The median of `values` (the mean of the middle two for an even count); None for none.
pub fn median(values: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

/// The curve of targets read repeatedly: at m = 1 ..= the most readings of a target, the
/// readings Σ min(m, nⱼ) and the median half-width of min(m, nⱼ) readings.
pub fn repeats_curve(targets: &[RepeatedTarget], pace: Pace) -> Vec<CurvePoint> {
    let most = targets.iter().map(|t| t.readings).max().unwrap_or(0);
    (1..=most)
        .filter_map(|m| {
            let taken: Vec<usize> = targets.iter().map(|t| t.readings.min(m)).collect();
            let widths: Vec<f64> = targets
                .iter()
                .zip(&taken)
                .filter(|(_, &k)| k > 0)
                .map(|(t, &k)| t.one_reading / (k as f64).sqrt())
                .collect();
            let readings = taken.iter().sum();
            Some(CurvePoint {
                readings,
                minutes: pace.minutes(readings),
                value: median(&widths)?,
            })
        })
        .collect()
}

/// Each target's readings (in the order taken) as a [`RepeatedTarget`]: one reading's noise
/// the `stated` repeatability scaled by the figure pooled over every target's readings,
/// its half-width evaluated at the target's mean relative to `white`. A target without a
/// chromaticity (no stated covariance at its level) is left out.
pub fn repeated_targets(
    targets: &[Vec<Xyz>],
    stated: &Repeatability,
    white: Xyz,
) -> Vec<RepeatedTarget> {
    let mut pool = Pool::default();
    for readings in targets {
        pool.add(readings, stated);
    }
    let noise = pool.noise(*stated);
    targets
        .iter()
        .filter(|r| !r.is_empty())
        .filter_map(|readings| {
            let n = readings.len() as f64;
            let mean = readings.iter().fold(Xyz::new(0.0, 0.0, 0.0), |s, x| {
                Xyz::new(s[0] + x[0], s[1] + x[1], s[2] + x[2])
            });
            let mean = Xyz::new(mean[0] / n, mean[1] / n, mean[2] / n);
            Some(RepeatedTarget {
                readings: readings.len(),
                one_reading: sequential::half_width(mean, &noise, white, 1)?,
            })
        })
        .collect()
}

/// The sides in the order the chart colours them.
const SIDES: [&str; 3] = [BOX_SPOTS, DISPLAY_SPOTS, DISPLAY_MODEL];
pub const BOX_SPOTS: &str = "box spots";
pub const DISPLAY_SPOTS: &str = "display spots";
pub const DISPLAY_MODEL: &str = "display model";
/// The run a report is of, as its curves name it.
pub const THIS_RUN: &str = "this run";

/// The chart's two drawings as SVG: the figure against readings, then against minutes;
/// one line per curve, a side's colour and marker the same in every run, another run's
/// lines dashed; the JND (ΔE*ab 2.3) drawn across. The error is plotters' message.
pub fn charts(curves: &[CostCurve]) -> Result<[String; 2], String> {
    let drawn: Vec<&CostCurve> = curves.iter().filter(|c| !c.points.is_empty()).collect();
    let looks: Vec<(usize, bool)> = drawn
        .iter()
        .map(|c| {
            let side = SIDES
                .iter()
                .position(|s| *s == c.side)
                .unwrap_or(SIDES.len());
            // Colour 0 is black, kept for the JND line's black dots to stand apart.
            (side + 1, c.run != THIS_RUN)
        })
        .collect();
    let series = |x: &dyn Fn(&CurvePoint) -> f64| -> Vec<crate::plot::Series> {
        drawn
            .iter()
            .map(|c| crate::plot::Series {
                name: format!("{}, {} ({})", c.side, c.plan, c.run),
                points: c.points.iter().map(|p| (x(p), p.value)).collect(),
            })
            .collect()
    };
    let by_readings = series(&|p| p.readings as f64);
    let by_minutes = series(&|p| p.minutes);
    let jnd = format!("JND, ΔE*ab {}", super::assess::JND_DE76);
    let chart = |title, x_desc, series: &[crate::plot::Series]| {
        crate::plot::log_log_svg_paired(
            &crate::plot::LogLogChart {
                title,
                x_desc,
                y_desc: "ΔE*ab",
                series,
                target: Some((super::assess::JND_DE76, &jnd)),
                size: (1000, 440),
            },
            &looks,
        )
    };
    Ok([
        chart("Accuracy against readings", "readings", &by_readings)?,
        chart(
            "Accuracy against the rig's minutes",
            "minutes at the rig (estimated)",
            &by_minutes,
        )?,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_takes_the_middle_or_the_mean_of_the_middle_two() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&[]), None);
    }

    /// Three targets read 4, 1 and 2 times with one-reading half-widths 2, 0.5 and 1, at
    /// 2 s a reading and 2 placements of 30 s. By hand:
    /// m = 1: 3 readings, widths 2, 0.5, 1 → median 1; (6 + 60) s = 1.1 min.
    /// m = 2: 5 readings, widths 2/√2 = 1.41421, 0.5, 1/√2 = 0.70711 → 0.70711; 70 s.
    /// m = 3: 6 readings, widths 2/√3 = 1.15470, 0.5, 0.70711 → 0.70711; 72 s.
    /// m = 4: 7 readings, widths 2/√4 = 1, 0.5, 0.70711 → 0.70711; 74 s.
    #[test]
    fn a_repeats_curve_is_the_median_half_width_at_each_count() {
        let t = |readings, one_reading| RepeatedTarget {
            readings,
            one_reading,
        };
        let pace = Pace {
            reading_s: 2.0,
            placement_s: 30.0,
            placements: 2,
        };
        let c = repeats_curve(&[t(4, 2.0), t(1, 0.5), t(2, 1.0)], pace);
        let readings: Vec<usize> = c.iter().map(|p| p.readings).collect();
        assert_eq!(readings, [3, 5, 6, 7]);
        let r = std::f64::consts::FRAC_1_SQRT_2;
        let expect = [1.0, r, r, r];
        for (p, e) in c.iter().zip(expect) {
            assert!((p.value - e).abs() < 1e-12, "{c:?}");
        }
        let minutes = [66.0 / 60.0, 70.0 / 60.0, 72.0 / 60.0, 74.0 / 60.0];
        for (p, e) in c.iter().zip(minutes) {
            assert!((p.minutes - e).abs() < 1e-12, "{c:?}");
        }
        assert!(repeats_curve(&[], pace).is_empty());
    }
}
