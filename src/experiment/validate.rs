//! The validation stage: box, display and simulation compared patch by patch in CIELAB
//! relative to the display's measured white (the paper's choice).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::cache::write_atomic;
use super::error::ExperimentError;
use super::readings::PatchStat;
use super::report_sections::{gather, Layout};
use crate::color::Xyz;
use crate::output::OutputPolicy;
use crate::validation::{
    assess, compare, read_readings, write_delta_e_chart_shaded, write_report_files, AssessOptions,
    Assessment, ReadingSet, ReportInput,
};

/// What the validation found, as `validation/comparisons.json`: each comparison patch by
/// patch with both readings' uncertainty (the mean's covariance in X, Y, Z), ΔE*ab and
/// ΔE00 with their bias-aware 95 % intervals, the verdict on the JND at 95 % confidence
/// (`jnd`: below, above, undecided) and the count by point estimate named as such
/// (`below_jnd_point`), and the mean and max with their intervals.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ValidationResult {
    /// The file's layout ([`RESULT_VERSION`]).
    pub version: u32,
    /// CIELAB's reference white, cd/m².
    pub white: [f64; 3],
    pub out_of_gamut_patches: Vec<usize>,
    pub display_vs_box: Assessment,
    pub simulation_vs_box: Assessment,
    pub display_vs_simulation: Assessment,
}

pub const FILE: &str = "comparisons.json";

/// The layout of [`FILE`]: 2 since it holds intervals and verdicts (1 held point
/// estimates only). Part of the validation stage's inputs, so a stage written in the
/// earlier layout runs again.
pub const RESULT_VERSION: u32 = 2;

/// The readings of `a` and `b` for the patches both have, in patch order; refuses sets
/// that do not hold the same patches (a stage that lost readings must not pass as valid).
fn paired(
    what: (&str, &[PatchStat]),
    other: (&str, &[PatchStat]),
) -> Result<(Vec<Xyz>, Vec<Xyz>), ExperimentError> {
    let mut a: Vec<&PatchStat> = what.1.iter().collect();
    let mut b: Vec<&PatchStat> = other.1.iter().collect();
    a.sort_by_key(|p| p.patch);
    b.sort_by_key(|p| p.patch);
    let pa: Vec<usize> = a.iter().map(|p| p.patch).collect();
    let pb: Vec<usize> = b.iter().map(|p| p.patch).collect();
    if pa != pb {
        return Err(ExperimentError::Option {
            what: "readings",
            message: format!(
                "the {} readings are of patches {:?} but the {} readings of {:?}",
                what.0, pa, other.0, pb
            ),
        });
    }
    let xyz = |v: &[&PatchStat]| v.iter().map(|p| Xyz::from_array(p.xyz)).collect();
    Ok((xyz(&a), xyz(&b)))
}

/// The stage's readings files, for the report (which reads them with their uncertainties).
pub struct ReadingFiles<'a> {
    pub box_spots: &'a Path,
    pub simulation: &'a Path,
    pub display: &'a Path,
}

/// The report's input from the stages' files: the three comparisons with every side's
/// uncertainty (the meters' repeatability from their repeats, the render's per-patch
/// confidence on the simulation's side) and every optional section the earlier stages'
/// files allow, each missing one noted. `dir` is the validation stage's directory inside
/// the experiment's.
pub fn report_input(
    dir: &Path,
    white: [f64; 3],
    files: &ReadingFiles<'_>,
    out_of_gamut: &[usize],
) -> Result<ReportInput, ExperimentError> {
    let read = |p: &Path| {
        read_readings(p).map_err(|e| ExperimentError::BadFile {
            file: p.to_path_buf(),
            message: e.to_string(),
        })
    };
    let (b, mut s, d) = (
        read(files.box_spots)?,
        read(files.simulation)?,
        read(files.display)?,
    );
    let root = dir.parent().unwrap_or(dir);
    let layout = Layout::of(root, files.box_spots);
    let sections = gather(
        &layout,
        &[
            ("box", files.box_spots, b.patches.len()),
            ("simulation", files.simulation, s.patches.len()),
            ("display", files.display, d.patches.len()),
        ],
    );
    let mut uncertainty = Vec::new();
    if let Some(u) = &sections.render_uncertainty {
        // The stage's readings carry the render's uncertainty themselves; a simulation
        // stage written before they did has it in its summary only.
        if s.patches.values().all(|p| p.u_lab == 0.0) {
            u.apply(&mut s);
        }
        uncertainty.push(("simulation".to_string(), u.description.clone()));
    }
    for (side, set) in [("box", &b), ("display", &d)] {
        uncertainty.push((side.to_string(), repeatability(set)));
    }
    let w = Xyz::from_array(white);
    let o = AssessOptions::default();
    let mark = |mut a: crate::validation::Assessment| {
        for p in &mut a.patches {
            p.out_of_gamut |= out_of_gamut.contains(&p.patch);
        }
        a
    };
    let mut notes = sections.notes;
    for set in [&b, &s, &d] {
        for n in &set.notes {
            notes.push(format!("{}: {n}", set.file.display()));
        }
    }
    Ok(ReportInput {
        title: "metamer experiment".into(),
        white_source: "the display's measured white (the paper's choice)".into(),
        box_vs_display: Some(mark(assess("box", &b, "display", &d, w, &o)?)),
        box_vs_simulation: Some(assess("box", &b, "simulation", &s, w, &o)?),
        display_vs_simulation: Some(mark(assess("simulation", &s, "display", &d, w, &o)?)),
        display_model: sections.display_model,
        light_fit: sections.light_fit,
        render_confidence: sections.render_confidence,
        instruments: sections.instruments,
        out_of_gamut: out_of_gamut.to_vec(),
        inputs: sections.inputs,
        uncertainty,
        notes,
    })
}

/// What a meter's readings' intervals contain: the covariance of the mean of each patch's
/// repeats, or for a patch read once the instrument's stated repeatability, or nothing.
fn repeatability(set: &ReadingSet) -> String {
    let ns: Vec<usize> = set.patches.values().map(|p| p.n).collect();
    let (lo, hi) = (
        ns.iter().copied().min().unwrap_or(0),
        ns.iter().copied().max().unwrap_or(0),
    );
    let k = if lo == hi {
        format!("{lo}")
    } else {
        format!("{lo}–{hi}")
    };
    let known = set.patches.values().all(|p| !p.u_factors.is_empty());
    if hi <= 1 && known {
        "single readings: the meter's stated repeatability (CS-100A: 0.1 % in Y, 0.0005 in x and y, 1σ) carried to X, Y, Z".into()
    } else if hi <= 1 {
        "single readings: the meter's repeatability is unknown and not in the interval".into()
    } else {
        format!(
            "the meter's repeatability: the full covariance in X, Y, Z of the mean of {k} repeats per patch, widened for the few repeats it is estimated from (Student's t with k − 1 degrees of freedom)"
        )
    }
}

/// Compares box, display and simulation: the point comparisons' CSV and ΔE chart each,
/// then the assessments with uncertainty into `comparisons.json` and the report.
pub fn validate(
    dir: &Path,
    white: [f64; 3],
    inputs: &ReadingFiles<'_>,
    box_spots: &[PatchStat],
    simulation: &[PatchStat],
    display: &[PatchStat],
    out_of_gamut: &[usize],
) -> Result<(ValidationResult, Vec<String>), ExperimentError> {
    let w = Xyz::from_array(white);
    let (b, d) = paired(("box", box_spots), ("display", display))?;
    let display_vs_box = compare("box", &b, "display", &d, w)?;
    let (b, s) = paired(("box", box_spots), ("simulation", simulation))?;
    let simulation_vs_box = compare("box", &b, "simulation", &s, w)?;
    let (s, d) = paired(("simulation", simulation), ("display", display))?;
    let display_vs_simulation = compare("simulation", &s, "display", &d, w)?;
    std::fs::create_dir_all(dir).map_err(|source| ExperimentError::Io {
        file: dir.to_path_buf(),
        source,
    })?;
    let mut files = Vec::new();
    for (stem, c) in [
        ("display_vs_box", &display_vs_box),
        ("simulation_vs_box", &simulation_vs_box),
        ("display_vs_simulation", &display_vs_simulation),
    ] {
        let csv = format!("{stem}.csv");
        write_atomic(&dir.join(&csv), c.to_csv().as_bytes())?;
        let svg = format!("{stem}.svg");
        let shaded: &[usize] = if stem == "simulation_vs_box" {
            &[]
        } else {
            out_of_gamut
        };
        // The stage directory is the stage's own: a re-run replaces its files.
        write_delta_e_chart_shaded(
            c,
            shaded,
            "outside the display's gamut",
            &dir.join(&svg),
            &OutputPolicy::new(true),
        )?;
        files.extend([csv, svg]);
    }
    let input = report_input(dir, white, inputs, out_of_gamut)?;
    let take = |a: &Option<Assessment>| a.clone().expect("the experiment's report has all three");
    let result = ValidationResult {
        version: RESULT_VERSION,
        white,
        out_of_gamut_patches: out_of_gamut.to_vec(),
        display_vs_box: take(&input.box_vs_display),
        simulation_vs_box: take(&input.box_vs_simulation),
        display_vs_simulation: take(&input.display_vs_simulation),
    };
    let text = serde_json::to_string_pretty(&result).map_err(ExperimentError::Json)?;
    write_atomic(&dir.join(FILE), text.as_bytes())?;
    files.push(FILE.to_string());
    let written = write_report_files(dir, &input, &OutputPolicy::new(true))?;
    files.extend(
        written
            .iter()
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned())),
    );
    Ok((result, files))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::report_sections::RenderUncertainty;
    use crate::validation::propagate::{render_lab_sigma, Propagation, RenderStatement};
    use crate::validation::readings::{parse_readings, UncertaintySource};

    /// One grey patch: the box at L* 50 read 4 times, the meter's repeats scaling X, Y and
    /// Z together by 1 ± ε (ε = 0.2·√3/Y, so the mean's standard error in Y is
    /// √(4·(εY)²/12) = 0.2 and a*, b* stay 0); the simulation at L* 60 with the path
    /// tracer's half-width 0.5. By hand: dL*/dY = (116/3)·(116/66)²/100 = 1.194441 at
    /// Y = 18.418652, so the box's σ(L*) = 0.238888; the render's σ per axis is
    /// 0.5/(1.96·√3) = 0.147286. ΔE of greys that differ in L* only moves, to first order,
    /// with ΔL* alone: σ(ΔE) = √(0.238888² + 0.147286²) = 0.280643, the interval
    /// 10 ± 1.96·0.280643 = [9.44995, 10.55005].
    #[test]
    fn render_and_meter_uncertainty_add_as_by_hand() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let grey = |y: f64| format!("{},{y},{}", 0.950_47 * y, 1.088_83 * y);
        let y = 18.418_652;
        let eps = 0.2 * 3f64.sqrt() / y;
        let b = parse_readings(
            &format!(
                "patch,X,Y,Z\n7,{}\n7,{}\n7,{}\n7,{}\n",
                grey(y * (1.0 + eps)),
                grey(y * (1.0 - eps)),
                grey(y * (1.0 + eps)),
                grey(y * (1.0 - eps))
            ),
            Path::new("box.csv"),
        )
        .unwrap();
        assert_eq!(b.patches[&7].source, UncertaintySource::Repeats);
        assert!((b.patches[&7].u_xyz[1] - 0.2).abs() < 1e-9);
        let sim = || {
            parse_readings(
                &format!(
                    "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n\n7,{},0,0,0,1\n",
                    grey(28.123_334)
                ),
                Path::new("sim.csv"),
            )
            .unwrap()
        };
        let mut s = sim();
        let u = RenderUncertainty {
            sigma_lab: [(7, render_lab_sigma(0.5, RenderStatement::HalfWidth95))].into(),
            description: String::new(),
        };
        u.apply(&mut s);
        assert_eq!(s.patches[&7].source, UncertaintySource::Render);
        let linear = AssessOptions {
            propagation: Propagation::Linear,
            ..AssessOptions::default()
        };
        let a = assess("box", &b, "simulation", &s, white, &linear).unwrap();
        let i = a.patches[0].de76_interval;
        assert!((a.patches[0].de76 - 10.0).abs() < 1e-5);
        assert!((i.lo - 9.449_95).abs() < 1e-4, "{i:?}");
        assert!((i.hi - 10.550_05).abs() < 1e-4, "{i:?}");
        // Without the render's term the interval is the meter's alone: 10 ± 1.96·0.238888.
        let a = assess("box", &b, "simulation", &sim(), white, &linear).unwrap();
        let i = a.patches[0].de76_interval;
        assert!((i.hi - 10.468_21).abs() < 1e-4, "{i:?}");
        // Monte Carlo knows the box's covariance comes from 4 repeats (3 degrees of
        // freedom) and the render's is stated: Welch–Satterthwaite gives
        // ν = (0.238888² + 0.147286²)² / (0.238888⁴/3) = 5.7143, t(0.975, 5.7143) =
        // 2.47688 (SciPy), a half-width 2.47688·0.280643 = 0.69512; the render's a*, b*
        // terms lengthen ΔE by 2·σ²/(2ΔE) ≈ 0.002: [9.3027, 10.6929]. A 2.5 % quantile of
        // 20 000 draws is good to about 0.01.
        let many = AssessOptions {
            propagation: Propagation::MonteCarlo {
                draws: 20_000,
                seed: 1,
            },
            ..AssessOptions::default()
        };
        let mc = assess("box", &b, "simulation", &s, white, &many).unwrap();
        let m = mc.patches[0].de76_interval;
        assert!(
            (m.lo - 9.3027).abs() < 0.025 && (m.hi - 10.6929).abs() < 0.025,
            "{m:?}"
        );
        // The same scatter given as a known covariance (one row, n = 1: a stated
        // repeatability), all along the grey axis: Monte Carlo agrees with linearisation.
        let u = [0.950_47, 1.0, 1.088_83].map(|v| 0.2 * v);
        let known = parse_readings(
            &format!(
                "patch,X,Y,Z,sd_X,sd_Y,sd_Z,cov_XY,cov_XZ,cov_YZ,n\n7,{},{},{},{},{},{},{},1\n",
                grey(y),
                u[0],
                u[1],
                u[2],
                u[0] * u[1],
                u[0] * u[2],
                u[1] * u[2]
            ),
            Path::new("box.csv"),
        )
        .unwrap();
        assert_eq!(known.patches[&7].dof, None);
        let m = assess(
            "box",
            &known,
            "simulation",
            &s,
            white,
            &AssessOptions::default(),
        )
        .unwrap()
        .patches[0]
            .de76_interval;
        assert!(
            (m.lo - 9.448).abs() < 0.03 && (m.hi - 10.548).abs() < 0.03,
            "{m:?}"
        );
    }
}
