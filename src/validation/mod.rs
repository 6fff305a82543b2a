//! Validation: readings of the same 24 ColorChecker patches from two sources (the real box,
//! the display showing the rendering, the simulation) compared in CIELAB with the display's
//! white as reference white, as in the paper (JND ΔE*ab ≈ 2.3; CIEDE2000 reported too).
//!
//! [`compare`] is the plain comparison of two lists of XYZ (the simulated lab's);
//! [`job::validate`], the one entry of `metamer validate` and the experiment's validation
//! stage, reads measured files ([`readings`]), propagates their uncertainty
//! ([`propagate`], [`assess`]) and writes the report ([`figures`], [`report`], [`export`]).

pub mod assess;
mod chart;
pub mod comparisons;
pub mod covariance;
#[cfg(test)]
mod coverage;
mod error;
pub mod export;
pub mod figures;
pub mod inversion;
pub mod job;
pub mod montecarlo;
pub mod plausible;
pub mod propagate;
pub mod readings;
pub mod report;
mod report_input;
mod report_sections;
pub mod uncertain;
pub mod verdict;

use serde::{Deserialize, Serialize};

use crate::color::{delta_e2000, delta_e76, Lab, Xyz, COLORCHECKER_NAMES};

pub use assess::{assess, AssessOptions, Assessment, JndVerdict, PatchAssessment, JND_DE76};
pub use chart::{write_delta_e_chart, write_delta_e_chart_shaded};
pub use error::ValidationError;
pub use export::write_report_files;
pub use propagate::Propagation;
pub use readings::{read_readings, ReadingSet, ReadingsError};
pub use report::{render_html, ReportInput};

/// One patch compared.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchComparison {
    /// 1-based ColorChecker patch number.
    pub patch: usize,
    pub name: String,
    pub reference_xyz: [f64; 3],
    pub test_xyz: [f64; 3],
    pub reference_lab: [f64; 3],
    pub test_lab: [f64; 3],
    pub de76: f64,
    pub de00: f64,
}

/// A whole comparison with its summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// What the reference readings are (e.g. "box") and what is tested (e.g. "display").
    pub reference: String,
    pub test: String,
    /// Reference white of CIELAB, cd/m².
    pub white: [f64; 3],
    pub patches: Vec<PatchComparison>,
    pub mean_de76: f64,
    pub max_de76: f64,
    pub mean_de00: f64,
    pub max_de00: f64,
    /// How many patches' ΔE*ab point estimates are below [`JND_DE76`] (no uncertainty
    /// considered: [`assess`] says what holds at 95 % confidence).
    #[serde(alias = "below_jnd")]
    pub below_jnd_point: usize,
}

/// Compares `test` against `reference`, patch by patch, in CIELAB relative to `white`.
pub fn compare(
    reference_name: &str,
    reference: &[Xyz],
    test_name: &str,
    test: &[Xyz],
    white: Xyz,
) -> Result<Comparison, ValidationError> {
    if reference.len() != test.len() {
        return Err(ValidationError::LengthMismatch {
            reference: reference.len(),
            test: test.len(),
        });
    }
    if !(white.x > 0.0 && white.y > 0.0 && white.z > 0.0) {
        return Err(ValidationError::BadWhite {
            white: white.to_array(),
        });
    }
    let patches: Vec<PatchComparison> = reference
        .iter()
        .zip(test)
        .enumerate()
        .map(|(i, (r, t))| {
            let rl: Lab = r.to_lab(white);
            let tl: Lab = t.to_lab(white);
            PatchComparison {
                patch: i + 1,
                name: COLORCHECKER_NAMES
                    .get(i)
                    .map(|s| s.to_string())
                    .unwrap_or_else(|| format!("patch {}", i + 1)),
                reference_xyz: r.to_array(),
                test_xyz: t.to_array(),
                reference_lab: rl.to_array(),
                test_lab: tl.to_array(),
                de76: delta_e76(rl, tl),
                de00: delta_e2000(rl, tl),
            }
        })
        .collect();
    let n = patches.len().max(1) as f64;
    let stat = |f: fn(&PatchComparison) -> f64| {
        let mean = patches.iter().map(f).sum::<f64>() / n;
        let max = patches.iter().map(f).fold(0.0, f64::max);
        (mean, max)
    };
    let (mean_de76, max_de76) = stat(|p| p.de76);
    let (mean_de00, max_de00) = stat(|p| p.de00);
    Ok(Comparison {
        reference: reference_name.into(),
        test: test_name.into(),
        white: white.to_array(),
        below_jnd_point: patches.iter().filter(|p| p.de76 < JND_DE76).count(),
        patches,
        mean_de76,
        max_de76,
        mean_de00,
        max_de00,
    })
}

impl Comparison {
    /// One CSV row per patch: `patch,name,X_ref,…,de76,de00`.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "patch,name,X_ref,Y_ref,Z_ref,X_test,Y_test,Z_test,L_ref,a_ref,b_ref,L_test,a_test,b_test,de76,de00\n",
        );
        for p in &self.patches {
            let nums: Vec<String> = p
                .reference_xyz
                .iter()
                .chain(&p.test_xyz)
                .chain(&p.reference_lab)
                .chain(&p.test_lab)
                .chain([&p.de76, &p.de00])
                .map(|v| format!("{v:.6}"))
                .collect();
            s += &format!("{},{},{}\n", p.patch, p.name, nums.join(","));
        }
        s
    }

    /// The one-line summary a user reads first.
    pub fn summary(&self) -> String {
        format!(
            "{} of {} patches below the JND (ΔE*ab < {JND_DE76}) by point estimate; ΔE*ab mean {:.2} max {:.2}; ΔE00 mean {:.2} max {:.2}",
            self.below_jnd_point,
            self.patches.len(),
            self.mean_de76,
            self.max_de76,
            self.mean_de00,
            self.max_de00
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_readings_differ_by_zero_and_scaled_white_by_hand_value() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let a = vec![Xyz::new(20.0, 21.0, 22.0), Xyz::new(40.0, 42.0, 44.0)];
        let c = compare("box", &a, "display", &a, white).unwrap();
        assert_eq!(c.below_jnd_point, 2);
        assert_eq!(c.max_de76, 0.0);
        // A grey at L* = 50 against one at L* = 51.5 (by hand: ((50+16)/116)^3 = 0.18418652,
        // ((51.5+16)/116)^3 = 0.19703227): neutral, so ΔE*ab = ΔL* = 1.5.
        let g = |y: f64| Xyz::new(white.x * y, white.y * y, white.z * y);
        let c = compare("r", &[g(0.18418652)], "t", &[g(0.19703227)], white).unwrap();
        assert!((c.patches[0].de76 - 1.5).abs() < 1e-4, "{:?}", c.patches[0]);
        assert_eq!(c.below_jnd_point, 1);
        assert!(c
            .summary()
            .starts_with("1 of 1 patches below the JND (ΔE*ab < 2.3) by point estimate"));
    }

    #[test]
    fn mismatched_inputs_are_errors() {
        let w = Xyz::new(95.0, 100.0, 108.0);
        let e = compare("r", &[w], "t", &[], w).unwrap_err();
        assert!(e.to_string().contains("1 reference vs 0 test"));
        let e = compare("r", &[w], "t", &[w], Xyz::default()).unwrap_err();
        assert!(e.to_string().contains("must have positive"));
    }
}

#[cfg(test)]
mod chart_tests {
    use super::*;

    #[test]
    fn a_chart_of_an_infinite_difference_is_refused_at_once() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let x = Xyz::new(10.0, 11.0, 12.0);
        let mut c = compare("box", &[x], "display", &[x], white).unwrap();
        // The experiment's box readings of X = −1e308 gave this, and plotters then
        // searched an infinite axis for ticks without end.
        c.patches[0].de76 = f64::INFINITY;
        let file = std::env::temp_dir().join(format!("metamer-inf-{}.svg", std::process::id()));
        let start = std::time::Instant::now();
        let e = write_delta_e_chart(&c, &file, &crate::output::OutputPolicy::new(true))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("a colour difference of inf cannot be drawn"),
            "{e}"
        );
        assert!(start.elapsed().as_secs() < 5);
        assert!(!file.exists());
    }

    #[test]
    fn chart_has_two_bars_per_patch_and_the_jnd_line() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let reference: Vec<Xyz> = (0..24)
            .map(|i| Xyz::new(10.0 + i as f64, 11.0 + i as f64, 12.0))
            .collect();
        let test: Vec<Xyz> = reference
            .iter()
            .enumerate()
            .map(|(i, x)| x.scaled(1.0 + 0.01 * i as f64))
            .collect();
        let c = compare("box", &reference, "display", &test, white).unwrap();
        let file = std::env::temp_dir().join(format!("metamer-chart-{}.svg", std::process::id()));
        write_delta_e_chart(&c, &file, &crate::output::OutputPolicy::new(true)).unwrap();
        let svg = std::fs::read_to_string(&file).unwrap();
        write_delta_e_chart_shaded(
            &c,
            &[7, 16],
            "out of gamut",
            &file,
            &crate::output::OutputPolicy::new(true),
        )
        .unwrap();
        let shaded = std::fs::read_to_string(&file).unwrap();
        assert!(shaded.contains("out of gamut") && !svg.contains("out of gamut"));
        assert_eq!(
            shaded.matches("<rect").count(),
            svg.matches("<rect").count() + 3,
            "two bands and their legend key"
        );
        if let Ok(dir) = std::env::var("METAMER_KEEP_CHART") {
            std::fs::copy(&file, std::path::Path::new(&dir).join("chart.svg")).unwrap();
        }
        std::fs::remove_file(&file).ok();
        assert!(svg.starts_with("<svg"));
        // 48 bars + background rectangles; the caption carries the count.
        assert!(
            svg.matches("<rect").count() >= 48,
            "{}",
            svg.matches("<rect").count()
        );
        assert!(svg.contains(&format!(
            "{} of 24 below JND by point estimate",
            c.below_jnd_point
        )));
    }
}
