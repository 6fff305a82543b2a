//! The report's one-paragraph verdict: how many patches the display reproduces within the
//! JND with 95 % confidence, which are above or undecided, and for each why where the
//! input lets us tell — outside the display's gamut, a dark patch whose readings scatter
//! more than the others', an interval that straddles the JND, and whether the error is
//! already in the simulation or arises on the display.

use std::fmt::Write;

use super::assess::{Assessment, JndVerdict, PatchAssessment, JND_DE76};
use super::figures::esc;
use super::readings::UncertaintySource;
use super::report::ReportInput;

/// CIELAB lightness below which a ColorChecker patch counts as dark (the black, 24, is
/// about L* 20; the darkest chromatic patches, blue 13 and dark skin 1, about 30–38).
const DARK_L: f64 = 30.0;

/// A dark patch's interval counts as widened by the readings' noise when it is this many
/// times as wide as the median patch's.
const WIDE_FACTOR: f64 = 2.0;

/// Why a patch may be above the JND or undecided, as short clauses. `others` are the
/// box-vs-simulation and simulation-vs-display assessments, when the report has them.
pub fn reasons(
    p: &PatchAssessment,
    out_of_gamut: &[usize],
    median_width: f64,
    others: (Option<&Assessment>, Option<&Assessment>),
) -> Vec<String> {
    let mut why = Vec::new();
    if p.out_of_gamut || out_of_gamut.contains(&p.patch) {
        why.push("outside the display's gamut".to_string());
    }
    let width = p.de76_interval.hi - p.de76_interval.lo;
    let wide = width > WIDE_FACTOR * median_width && width > 0.0;
    let dark = p.reference.lab[0] < DARK_L;
    if dark && wide {
        why.push(format!(
            "dark (L* {:.0}), where the meter's noise dominates: its interval is {:.1} wide against a median {:.1}",
            p.reference.lab[0], width, median_width
        ));
    } else if wide {
        why.push(format!(
            "its readings scatter: the interval is {width:.1} wide against a median {median_width:.1}"
        ));
    }
    if p.jnd == JndVerdict::Undecided {
        why.push(format!(
            "its interval [{:.1}, {:.1}] straddles the JND",
            p.de76_interval.lo, p.de76_interval.hi
        ));
    }
    if let (Some(sim), Some(disp)) = others {
        let find = |a: &Assessment| {
            a.patches
                .iter()
                .find(|q| q.patch == p.patch)
                .map(|q| q.de76)
        };
        if let (Some(s), Some(d)) = (find(sim), find(disp)) {
            let whose = if s >= JND_DE76 && s >= d {
                "the simulation already misses the box"
            } else if d >= s {
                "the error arises on the display"
            } else {
                "simulation and display share the error"
            };
            why.push(format!(
                "{whose} (simulation vs box {s:.1}, display vs simulation {d:.1})"
            ));
        }
    }
    if p.reference.uncertainty == UncertaintySource::Unknown
        || p.test.uncertainty == UncertaintySource::Unknown
    {
        why.push("uncertainty unknown (single readings)".to_string());
    }
    why
}

/// The median width of the patches' ΔE*ab intervals.
pub fn median_width(a: &Assessment) -> f64 {
    let mut w: Vec<f64> = a
        .patches
        .iter()
        .map(|p| p.de76_interval.hi - p.de76_interval.lo)
        .collect();
    if w.is_empty() {
        return 0.0;
    }
    w.sort_by(f64::total_cmp);
    let m = w.len() / 2;
    if w.len() % 2 == 1 {
        w[m]
    } else {
        0.5 * (w[m - 1] + w[m])
    }
}

/// The verdict on box vs display (HTML-escaped text), with the simulation's comparisons
/// used to say where an error arises.
pub fn verdict_paragraph(input: &ReportInput) -> Option<String> {
    let a = input.box_vs_display.as_ref()?;
    Some(verdict_with(
        a,
        &input.out_of_gamut,
        (
            input.box_vs_simulation.as_ref(),
            input.display_vs_simulation.as_ref(),
        ),
    ))
}

/// The one-paragraph verdict on `a` alone (no simulation to attribute errors to).
pub fn verdict(a: &Assessment, out_of_gamut: &[usize]) -> String {
    verdict_with(a, out_of_gamut, (None, None))
}

fn verdict_with(
    a: &Assessment,
    out_of_gamut: &[usize],
    others: (Option<&Assessment>, Option<&Assessment>),
) -> String {
    let n = a.patches.len();
    let mut s = format!(
        "{} vs {}: {} of {n} patches are below the JND (ΔE*ab {JND_DE76}) with 95 % confidence, {} above and {} undecided; ΔE*ab mean {:.2}, max {:.2}.",
        esc(&a.test),
        esc(&a.reference),
        a.jnd.below,
        a.jnd.above,
        a.jnd.undecided,
        a.mean_de76.value,
        a.max_de76.value
    );
    let median = median_width(a);
    let mut causes = Causes::default();
    for (verdict, label) in [
        (JndVerdict::Above, "Above the JND"),
        (JndVerdict::Undecided, "Undecided"),
    ] {
        let list: Vec<String> = a
            .patches
            .iter()
            .filter(|p| p.jnd == verdict)
            .map(|p| {
                let why = reasons(p, out_of_gamut, median, others);
                causes.count(p, &why);
                format!(
                    "{} {} (ΔE*ab {:.1} [{:.1}, {:.1}]{})",
                    p.patch,
                    esc(&p.name),
                    p.de76,
                    p.de76_interval.lo,
                    p.de76_interval.hi,
                    if why.is_empty() {
                        String::new()
                    } else {
                        format!(": {}", esc(&why.join("; ")))
                    }
                )
            })
            .collect();
        if !list.is_empty() {
            let _ = write!(s, " {label}: {}.", list.join(". "));
        }
    }
    if a.jnd.above == 0 && a.jnd.undecided == 0 {
        s.push_str(" Every patch is reproduced within the JND.");
    } else if let Some(summary) = causes.sentence(a.jnd.above + a.jnd.undecided) {
        s.push(' ');
        s.push_str(&summary);
    }
    s
}

/// Patches above or undecided, grouped by the first reason that explains them.
#[derive(Default)]
struct Causes {
    gamut: Vec<usize>,
    dark: Vec<usize>,
    straddle: Vec<usize>,
    other: Vec<usize>,
}

impl Causes {
    fn count(&mut self, p: &PatchAssessment, why: &[String]) {
        let has = |w: &str| why.iter().any(|c| c.starts_with(w));
        if has("outside the display's gamut") {
            self.gamut.push(p.patch);
        } else if has("dark") {
            self.dark.push(p.patch);
        } else if p.jnd == JndVerdict::Undecided {
            self.straddle.push(p.patch);
        } else {
            self.other.push(p.patch);
        }
    }

    fn sentence(&self, total: usize) -> Option<String> {
        let list = |v: &[usize]| {
            v.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        };
        let parts: Vec<String> = [
            (&self.gamut, "outside the display's gamut"),
            (&self.dark, "dark, where the meter's noise dominates"),
            (&self.straddle, "within noise of the JND"),
            (
                &self.other,
                "in gamut and clear of noise: the display model's error",
            ),
        ]
        .into_iter()
        .filter(|(v, _)| !v.is_empty())
        .map(|(v, what)| format!("{} {what} ({})", v.len(), list(v)))
        .collect();
        (!parts.is_empty()).then(|| {
            format!(
                "Of the {total} not shown to be below the JND: {}.",
                parts.join("; ")
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Xyz;
    use crate::validation::assess::{assess, AssessOptions};
    use crate::validation::readings::parse_readings;
    use std::path::Path;

    const WHITE: Xyz = Xyz::new(95.047, 100.0, 108.883);

    /// A neutral grey of lightness `l`, with X and Z in the white's proportions.
    fn grey(patch: usize, l: f64, scale: f64) -> String {
        let y = 100.0 * ((l + 16.0) / 116.0f64).powi(3) * scale;
        format!("{patch},{},{y},{}\n", 0.950_47 * y, 1.088_83 * y)
    }

    /// Patch 1 (L* 50) is 4 ΔE off, known exactly on the box side and from two close
    /// repeats on the display: above. Patch 2 is out of gamut. Patch 24 (L* 20) has two
    /// far-apart display repeats: dark, wide and undecided. Patch 3 passes.
    #[test]
    fn names_each_failing_patch_with_its_cause() {
        let reference = parse_readings(
            &format!(
                "patch,X,Y,Z\n{}{}{}{}",
                grey(1, 50.0, 1.0),
                grey(2, 60.0, 1.0),
                grey(3, 70.0, 1.0),
                grey(24, 20.0, 1.0)
            ),
            Path::new("box.csv"),
        )
        .unwrap();
        let test = parse_readings(
            &format!(
                "patch,X,Y,Z\n{}{}{}{}{}{}{}{}",
                grey(1, 54.0, 1.0),
                grey(1, 54.0, 1.001),
                grey(2, 66.0, 1.0),
                grey(2, 66.0, 1.001),
                grey(3, 70.0, 1.0),
                grey(3, 70.0, 1.001),
                grey(24, 19.0, 1.0),
                grey(24, 23.0, 1.0),
            ),
            Path::new("display.csv"),
        )
        .unwrap();
        let a = assess(
            "box",
            &reference,
            "display",
            &test,
            WHITE,
            &AssessOptions::default(),
        )
        .unwrap();
        let v = verdict(&a, &[2]);
        assert!(
            v.starts_with("display vs box: 1 of 4 patches are below the JND"),
            "{v}"
        );
        assert!(v.contains("2 light skin (ΔE*ab 6.0"), "{v}");
        assert!(v.contains("outside the display's gamut"), "{v}");
        assert!(v.contains("24 black") && v.contains("dark (L* 20)"), "{v}");
        assert!(v.contains("straddles the JND"), "{v}");
        assert!(
            v.contains("Of the 3 not shown to be below the JND: 1 outside the display's gamut (2); 1 dark, where the meter's noise dominates (24); 1 in gamut and clear of noise: the display model's error (1)."),
            "{v}"
        );
    }

    #[test]
    fn the_simulation_says_where_an_error_arises() {
        let set = |rows: &str, name: &str| {
            parse_readings(&format!("patch,X,Y,Z\n{rows}"), Path::new(name)).unwrap()
        };
        let b = set(&grey(5, 50.0, 1.0), "b.csv");
        let s = set(&grey(5, 50.5, 1.0), "s.csv");
        let d = set(&grey(5, 55.0, 1.0), "d.csv");
        let o = AssessOptions::default();
        let bd = assess("box", &b, "display", &d, WHITE, &o).unwrap();
        let bs = assess("box", &b, "simulation", &s, WHITE, &o).unwrap();
        let sd = assess("simulation", &s, "display", &d, WHITE, &o).unwrap();
        let why = reasons(&bd.patches[0], &[], 0.0, (Some(&bs), Some(&sd)));
        assert!(
            why.iter().any(|w| w
                == "the error arises on the display (simulation vs box 0.5, display vs simulation 4.5)"),
            "{why:?}"
        );
    }
}
