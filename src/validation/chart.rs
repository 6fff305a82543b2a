//! A comparison's ΔE chart as a file of its own (`STEM.svg` beside its CSV): the report's bar
//! figure ([`delta_e_bars`]: ΔE*ab per patch coloured by its JND verdict, its 95 %
//! interval, ΔE00, the JND line, colours outside the display's gamut on a grey band), so the
//! file and the report draw one figure.

use std::path::Path;

use super::assess::Assessment;
use super::error::ValidationError;
use super::figures::delta_e_bars;
use crate::output::OutputPolicy;

/// Writes the ΔE chart of `assessment` to `file` (SVG) under the output policy `out`. Its
/// title names the comparison and how many patches are below the JND by point estimate.
pub fn write_delta_e_chart(
    assessment: &Assessment,
    file: &Path,
    out: &OutputPolicy,
) -> Result<(), ValidationError> {
    // A reading that is not a colour (the experiment's box readings of X = −1e308 once
    // gave ΔE = inf) has no place on an axis; say so rather than draw nonsense.
    if let Some(v) = assessment
        .patches
        .iter()
        .flat_map(|p| [p.de76, p.de00, p.de76_interval.lo, p.de76_interval.hi])
        .find(|v| !v.is_finite())
    {
        return Err(ValidationError::Chart {
            file: file.to_path_buf(),
            message: format!(
                "a colour difference of {v} cannot be drawn: a reading is not a colour"
            ),
        });
    }
    let head = format!(
        "{} vs {} ({} of {} below the JND by point estimate)",
        assessment.test,
        assessment.reference,
        assessment.below_jnd_point,
        assessment.patches.len()
    );
    let svg = delta_e_bars(assessment, "chart", &head);
    Ok(out.write(file, svg.as_bytes())?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Xyz;
    use crate::validation::assess::compare_pairs;
    use crate::validation::compare::exact_pairs;
    use crate::validation::propagate::Propagation;

    /// `test` against `reference`, both taken as exact, the patches in `oog` marked as
    /// outside the display's gamut.
    fn exact(reference: &[Xyz], test: &[Xyz], oog: &[usize]) -> Assessment {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let pairs = exact_pairs(reference, test, white, oog);
        compare_pairs("box", "display", pairs, white, Propagation::Linear)
    }

    #[test]
    fn a_chart_of_an_infinite_difference_is_refused_at_once() {
        let x = Xyz::new(10.0, 11.0, 12.0);
        let mut a = exact(&[x], &[x], &[]);
        a.patches[0].de76 = f64::INFINITY;
        let file = std::env::temp_dir().join(format!("metamer-inf-{}.svg", std::process::id()));
        let start = std::time::Instant::now();
        let e = write_delta_e_chart(&a, &file, &OutputPolicy::new(true))
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
    fn chart_has_a_bar_per_patch_its_interval_and_the_jnd_line() {
        let reference: Vec<Xyz> = (0..24)
            .map(|i| Xyz::new(10.0 + i as f64, 11.0 + i as f64, 12.0))
            .collect();
        let test: Vec<Xyz> = reference
            .iter()
            .enumerate()
            .map(|(i, x)| x.scaled(1.0 + 0.01 * i as f64))
            .collect();
        let file = std::env::temp_dir().join(format!("metamer-chart-{}.svg", std::process::id()));
        let policy = OutputPolicy::new(true);
        let a = exact(&reference, &test, &[]);
        write_delta_e_chart(&a, &file, &policy).unwrap();
        let svg = std::fs::read_to_string(&file).unwrap();
        write_delta_e_chart(&exact(&reference, &test, &[7, 16]), &file, &policy).unwrap();
        let shaded = std::fs::read_to_string(&file).unwrap();
        if let Ok(dir) = std::env::var("METAMER_KEEP_CHART") {
            std::fs::copy(&file, Path::new(&dir).join("chart.svg")).unwrap();
        }
        std::fs::remove_file(&file).ok();
        assert!(svg.starts_with("<svg"));
        assert_eq!(svg.matches(r#"class="bar""#).count(), 24);
        assert_eq!(svg.matches(r#"class="errorbar""#).count(), 24);
        assert_eq!(svg.matches(r#"class="jnd""#).count(), 1);
        assert!(svg.contains("JND 2.3") && svg.contains("outside the display's gamut"));
        assert_eq!(svg.matches(r#"class="oog""#).count(), 0);
        assert_eq!(shaded.matches(r#"class="oog""#).count(), 2, "two bands");
        assert!(svg.contains(&format!(
            "display vs box ({} of 24 below the JND by point estimate)",
            a.below_jnd_point
        )));
    }
}
