//! The report's one-paragraph verdict: how many patches the display reproduces within the
//! JND with 95 % confidence, which are above or undecided, and for each why where the
//! input lets us tell — outside the display's gamut, a dark patch whose readings scatter
//! more than the others', an interval that straddles the JND, and whether the error is
//! already in the simulation or arises on the display.

use std::fmt::Write;

use super::assess::{Assessment, JndVerdict, PatchAssessment, JND_DE76};
use super::figures::{decisive, esc, interval_text};
use super::readings::UncertaintySource;
use super::report_data::ReportInput;

/// CIELAB lightness below which a ColorChecker patch counts as dark (the black, 24, is
/// about L* 20; the darkest chromatic patches, blue 13 and dark skin 1, about 30–38).
const DARK_L: f64 = 30.0;

/// A dark patch's interval counts as widened by the readings' noise when it is this many
/// times as wide as the median patch's.
const WIDE_FACTOR: f64 = 2.0;

/// Where a patch's error arises, told by the simulation's two comparisons.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Origin {
    /// The simulation is within the JND of the box and the display misses it by more.
    Display,
    /// The simulation itself misses the box by at least the JND.
    Simulation,
    /// Neither alone: both differ by comparable amounts.
    Shared,
}

/// Why a patch may be above the JND or undecided, as far as the input tells.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Why {
    pub out_of_gamut: bool,
    /// Dark, its interval widened by the readings' noise ("L* 20, interval 1.7 wide
    /// against a median 0.3").
    pub dark: Option<String>,
    /// Not dark, yet its readings scatter: the same detail.
    pub scatter: Option<String>,
    pub straddles: bool,
    /// (where, simulation vs box ΔE*ab, display vs simulation ΔE*ab).
    pub origin: Option<(Origin, f64, f64)>,
    pub unknown_uncertainty: bool,
}

impl Why {
    /// The clauses of a patch's own details (the group it falls in is said elsewhere).
    fn details(&self) -> Vec<String> {
        let mut v = Vec::new();
        if let Some(d) = self.dark.as_ref().or(self.scatter.as_ref()) {
            v.push(d.clone());
        }
        if self.straddles {
            v.push("straddles the JND".into());
        }
        if let Some((o, s, d)) = self.origin {
            v.push(match o {
                Origin::Display => format!("display vs simulation {d:.1}"),
                Origin::Simulation => format!("simulation vs box {s:.1}"),
                Origin::Shared => {
                    format!("simulation vs box {s:.1}, display vs simulation {d:.1}")
                }
            });
        }
        if self.unknown_uncertainty {
            v.push("uncertainty unknown: single readings".into());
        }
        v
    }
}

/// Why `p` may be above the JND or undecided. `others` are the box-vs-simulation and
/// simulation-vs-display assessments, when the report has them.
pub fn reasons(
    p: &PatchAssessment,
    out_of_gamut: &[usize],
    median_width: f64,
    others: (Option<&Assessment>, Option<&Assessment>),
) -> Why {
    let width = p.de76_interval.hi - p.de76_interval.lo;
    let wide = width > WIDE_FACTOR * median_width && width > 0.0;
    let detail = |l: Option<f64>| {
        format!(
            "{}interval {width:.1} wide against a median {median_width:.1}",
            l.map(|l| format!("L* {l:.0}, ")).unwrap_or_default()
        )
    };
    let dark = p.reference.lab[0] < DARK_L;
    let origin = match others {
        (Some(sim), Some(disp)) => {
            let find = |a: &Assessment| {
                a.patches
                    .iter()
                    .find(|q| q.patch == p.patch)
                    .map(|q| q.de76)
            };
            match (find(sim), find(disp)) {
                (Some(s), Some(d)) => {
                    let o = if s >= JND_DE76 && s >= d {
                        Origin::Simulation
                    } else if d > s && s < JND_DE76 {
                        Origin::Display
                    } else {
                        Origin::Shared
                    };
                    Some((o, s, d))
                }
                _ => None,
            }
        }
        _ => None,
    };
    Why {
        out_of_gamut: p.out_of_gamut || out_of_gamut.contains(&p.patch),
        dark: (dark && wide).then(|| detail(Some(p.reference.lab[0]))),
        scatter: (!dark && wide).then(|| detail(None)),
        straddles: p.jnd == JndVerdict::Undecided,
        origin,
        unknown_uncertainty: p.reference.uncertainty == UncertaintySource::Unknown
            || p.test.uncertainty == UncertaintySource::Unknown,
    }
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
    let a = input.display_vs_box.as_ref()?;
    Some(verdict_with(
        a,
        &input.out_of_gamut,
        (
            input.simulation_vs_box.as_ref(),
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
        "{} vs {}: {} of {n} patches are below the JND (ΔE*ab {JND_DE76}) with 95 % confidence, {} above and {} undecided ({} below by point estimate); ΔE*ab mean {}, max {}.",
        esc(&a.test),
        esc(&a.reference),
        a.jnd.below,
        a.jnd.above,
        a.jnd.undecided,
        a.below_jnd_point,
        a.mean_de76.show(),
        a.max_de76.show()
    );
    let median = median_width(a);
    let failing: Vec<(&PatchAssessment, Why)> = a
        .patches
        .iter()
        .filter(|p| p.jnd != JndVerdict::Below)
        .map(|p| (p, reasons(p, out_of_gamut, median, others)))
        .collect();
    if failing.is_empty() {
        s.push_str(" Every patch is reproduced within the JND.");
        return s;
    }
    s.push_str(&causes(&failing));
    s.push_str(&origins(&failing));
    s.push_str(&intervals(&failing));
    s
}

/// Patch numbers and names, comma-separated.
fn named(v: &[&PatchAssessment]) -> String {
    v.iter()
        .map(|p| format!("{} {}", p.patch, esc(&p.name)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The patches not shown below the JND by cause, each in the group of the first cause that
/// explains it.
fn causes(failing: &[(&PatchAssessment, Why)]) -> String {
    let mut groups: [(Vec<&PatchAssessment>, &str); 4] = [
        (Vec::new(), "outside the display's gamut"),
        (Vec::new(), "dark, where the meter's noise dominates"),
        (Vec::new(), "within noise of the JND"),
        (
            Vec::new(),
            "in gamut and clear of noise: the display model's error",
        ),
    ];
    for (p, why) in failing {
        let g = if why.out_of_gamut {
            0
        } else if why.dark.is_some() {
            1
        } else if why.straddles {
            2
        } else {
            3
        };
        groups[g].0.push(p);
    }
    let parts: Vec<String> = groups
        .iter()
        .filter(|(v, _)| !v.is_empty())
        .map(|(v, what)| format!("{} {what} ({})", v.len(), named(v)))
        .collect();
    format!(
        " Of the {} not shown to be below the JND: {}.",
        failing.len(),
        parts.join("; ")
    )
}

/// Where the errors arise, when the simulation tells.
fn origins(failing: &[(&PatchAssessment, Why)]) -> String {
    let mut s = String::new();
    let by = |o: Origin| -> Vec<&PatchAssessment> {
        failing
            .iter()
            .filter(|(_, w)| w.origin.is_some_and(|x| x.0 == o))
            .map(|(p, _)| *p)
            .collect()
    };
    let on_display = by(Origin::Display);
    if on_display.len() == failing.len() {
        let worst = failing
            .iter()
            .filter_map(|(_, w)| w.origin.map(|o| o.1))
            .fold(0.0, f64::max);
        let which = match failing.len() {
            1 => "it".to_string(),
            2 => "both".to_string(),
            n => format!("all {n}"),
        };
        let _ = write!(
            s,
            " In {which} the simulation is within {worst:.1} of the box: the error arises on the display."
        );
    } else {
        for (v, what) in [
            (on_display, "the error arises on the display"),
            (
                by(Origin::Simulation),
                "the simulation already misses the box",
            ),
            (by(Origin::Shared), "simulation and display share the error"),
        ] {
            if !v.is_empty() {
                let _ = write!(s, " In {}: {what}.", named(&v));
            }
        }
    }
    s
}

/// Each failing patch's ΔE*ab with its 95 % interval and what explains it.
fn intervals(failing: &[(&PatchAssessment, Why)]) -> String {
    let list: Vec<String> = failing
        .iter()
        .map(|(p, why)| {
            let d = why.details();
            format!(
                "{} {} {}{}",
                p.patch,
                decisive(p.de76, JND_DE76),
                interval_text(p.de76_interval.lo, p.de76_interval.hi, JND_DE76),
                if d.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", esc(&d.join("; ")))
                }
            )
        })
        .collect();
    format!(" ΔE*ab with 95 % interval: {}.", list.join("; "))
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
        assert!(
            v.contains("Of the 3 not shown to be below the JND: 1 outside the display's gamut (2 light skin); 1 dark, where the meter's noise dominates (24 black 2); 1 in gamut and clear of noise: the display model's error (1 dark skin)."),
            "{v}"
        );
        // Intervals to the precision that decides them; two readings give one degree of
        // freedom, so patch 24's two far-apart repeats (L* 19 and 23) reach 0.
        assert!(v.contains("; 2 6.01 [5."), "{v}");
        assert!(v.contains("(uncertainty unknown: single readings)"), "{v}");
        assert!(v.contains("24 1.11 [0.00, "), "{v}");
        assert!(
            v.contains("(L* 20, interval ") && v.contains("straddles the JND;"),
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
        let (origin, s, d) = why.origin.unwrap();
        assert_eq!(origin, Origin::Display);
        assert!((s - 0.5).abs() < 1e-9 && (d - 4.5).abs() < 1e-9, "{s} {d}");
        let input = ReportInput {
            display_vs_box: Some(bd),
            simulation_vs_box: Some(bs),
            display_vs_simulation: Some(sd),
            ..ReportInput::default()
        };
        let v = verdict_paragraph(&input).unwrap();
        assert!(
            v.contains(
                "In it the simulation is within 0.5 of the box: the error arises on the display."
            ),
            "{v}"
        );
    }
}
