//! The validation stage: box, display and simulation compared patch by patch in CIELAB
//! relative to the display's measured white (the paper's choice), through the one
//! validation entry [`crate::validation::job::validate`] that `metamer validate` calls too.

use std::path::Path;

use super::error::ExperimentError;
use super::report_input::{compare_with, gather, Layout};
use crate::color::Xyz;
use crate::validation::job::{self, Context, Coverage, ReadingFiles, Request, White};
use crate::validation::{AssessOptions, ReportInput, ValidationError};

pub use crate::validation::comparisons::{ValidationResult, FILE, RESULT_VERSION};

/// The stage's request: all three sides on the same patches, the display's measured white,
/// the default propagation, no display model term, and the report's sections from the
/// earlier stages' files. `dir` is the validation stage's directory inside the
/// experiment's.
fn request<'a>(
    dir: &'a Path,
    white: Xyz,
    files: &ReadingFiles<'a>,
    out_of_gamut: &[usize],
    compare: Option<&Path>,
) -> Request<'a> {
    let root = dir.parent().unwrap_or(dir);
    let layout = Layout::of(root, files.box_readings);
    // The readings' patch counts are filled in by the validation once it has read them.
    let mut sides = vec![("box", files.box_readings, 0)];
    if let Some(simulation) = files.simulation {
        sides.push(("simulation", simulation, 0));
    }
    sides.push(("display", files.display, 0));
    let mut sections = gather(&layout, &sides);
    if let Some(other) = compare {
        compare_with(&mut sections, other);
    }
    Request {
        readings: *files,
        white: White::Measured {
            xyz: white,
            source: "the display's measured white (the paper's choice)".into(),
        },
        options: AssessOptions::default(),
        out_of_gamut: out_of_gamut.to_vec(),
        coverage: Coverage::Same,
        check_readings: false,
        context: Context::Stages(Box::new(sections)),
        point_files: true,
        title: "metamer experiment".into(),
        out: dir,
        force: true,
    }
}

/// The stage's errors as it has always worded them.
fn stage_error(e: ValidationError) -> ExperimentError {
    match e {
        ValidationError::Readings(e) => ExperimentError::BadFile {
            file: e.file().to_path_buf(),
            message: e.to_string(),
        },
        ValidationError::DifferentPatches {
            first,
            first_patches,
            second,
            second_patches,
        } => ExperimentError::Option {
            what: "readings",
            message: format!(
                "the {first} readings are of patches {first_patches:?} but the {second} readings of {second_patches:?}"
            ),
        },
        e => ExperimentError::Validation(e),
    }
}

/// The report's input from the stages' files: the three comparisons with every side's
/// uncertainty (the meters' repeatability from their repeats, the render's per-patch
/// confidence on the simulation's side) and every optional section the earlier stages'
/// files allow, each missing one noted, and the measuring cost of the run saved in
/// `compare` beside this one's. `dir` is the validation stage's directory inside the
/// experiment's.
pub fn report_input(
    dir: &Path,
    white: Xyz,
    files: &ReadingFiles<'_>,
    out_of_gamut: &[usize],
    compare: Option<&Path>,
) -> Result<ReportInput, ExperimentError> {
    job::report(&request(dir, white, files, out_of_gamut, compare)).map_err(stage_error)
}

/// Compares box, display and simulation: the point comparisons' CSV and ΔE chart each,
/// then the assessments with uncertainty into `comparisons.json` and the report. The
/// readings are read from `inputs`, once, by the validation's reader; the report's cost
/// section sets the run saved in `compare` beside this one.
pub fn validate(
    dir: &Path,
    white: Xyz,
    inputs: &ReadingFiles<'_>,
    out_of_gamut: &[usize],
    compare: Option<&Path>,
) -> Result<(ValidationResult, Vec<String>), ExperimentError> {
    let outcome =
        job::validate(&request(dir, white, inputs, out_of_gamut, compare)).map_err(stage_error)?;
    let files = outcome
        .files
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    let result = outcome
        .result
        .expect("the stage's request has the simulation and asks for comparisons.json");
    Ok((result, files))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::report_input::RenderUncertainty;
    use crate::render::spot::Uncertainty;
    use crate::validation::assess;
    use crate::validation::propagate::{render_lab_sigma, Propagation};
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
            sigma_lab: [(
                7,
                render_lab_sigma(Uncertainty::HalfWidth95 {
                    de: 0.5,
                    sampling: None,
                }),
            )]
            .into(),
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

    /// The report names each readings file's format as it was read: a box's readings given
    /// as `metamer spot --json` lines are not called a CSV.
    #[test]
    fn the_report_names_the_format_each_readings_file_was_read_in() {
        let exp = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/report/experiment");
        let csv = std::fs::read_to_string(exp.join("box/spots.csv")).unwrap();
        let lines: String = csv
            .lines()
            .skip(1)
            .map(|row| {
                let f: Vec<&str> = row.split(',').collect();
                format!(
                    "{{\"patch\":{},\"XYZ\":[{},{},{}]}}\n",
                    f[0], f[1], f[2], f[3]
                )
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("metamer-formats-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let spot_json = dir.join("box.jsonl");
        std::fs::write(&spot_json, lines).unwrap();
        let files = ReadingFiles {
            box_readings: &spot_json,
            display: &exp.join("display-spots/spots.csv"),
            simulation: Some(&exp.join("simulation/spots.csv")),
        };
        let white = Xyz::new(29.424_122_518_279_695, 31.015, 34.538_708_337_905_01);
        let input = report_input(&exp.join("validation"), white, &files, &[], None).unwrap();
        let formats: Vec<(&str, &str, usize)> = input.inputs[..3]
            .iter()
            .map(|i| (i.role.as_str(), i.format.as_str(), i.patches))
            .collect();
        assert_eq!(
            formats,
            [
                ("box", "readings (metamer spot --json)", 24),
                ("simulation", "readings (CSV)", 24),
                ("display", "readings (CSV)", 24),
            ]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
