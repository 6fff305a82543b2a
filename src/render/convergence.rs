//! Speed against accuracy: the largest ΔE*ab over the 24 spot readings, against a long
//! reference run, as a function of render time for each sampling strategy; and for the
//! radiosity solver its error bound and its true error (against its finest solution) as
//! the mesh is refined.

use std::path::Path;
use std::time::Instant;

use crate::output::{OutputError, OutputPolicy};
use crate::plot::{log_log_svg, LogLogChart, Series};

use super::integrator::{Strategy, Tracer, Wavelengths};
use super::method::Method;
use super::radiosity::{combine, run_level, Prepared, RadiosityError, RadiosityOptions};
use super::scene::Scene;
use super::spot::{patch_aim, render_spots, sample_cone, Aim, SpotError, SpotOptions};
use crate::color::{delta_e76, Xyz};

/// A named strategy of the chart.
pub fn strategies() -> Vec<(&'static str, Strategy)> {
    let s = |wavelengths, wavelength_is, nee_mis| Strategy {
        wavelengths,
        wavelength_is,
        nee_mis,
    };
    vec![
        ("full spectrum, NEE+MIS", s(Wavelengths::Full, true, true)),
        (
            "4 hero λ, λ-IS, NEE+MIS",
            s(Wavelengths::Hero(4), true, true),
        ),
        ("1 λ, λ-IS, NEE+MIS", s(Wavelengths::Hero(1), true, true)),
        (
            "4 hero λ, uniform λ, NEE+MIS",
            s(Wavelengths::Hero(4), false, true),
        ),
        (
            "4 hero λ, λ-IS, BRDF only",
            s(Wavelengths::Hero(4), true, false),
        ),
    ]
}

/// One point of a curve.
#[derive(Clone, Debug)]
pub struct Point {
    pub strategy: &'static str,
    pub samples_per_patch: u64,
    pub seconds: f64,
    pub max_de: f64,
    pub mean_de: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum ConvergenceError {
    #[error(transparent)]
    Spot(#[from] SpotError),
    #[error(transparent)]
    Radiosity(#[from] RadiosityError),
    #[error("{file}: {source}")]
    Io {
        file: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("chart: {0}")]
    Chart(String),
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error(
        "the time budget per strategy must be more than 0 s and at most {MAX_SECONDS_PER_STRATEGY} \
         s (a day), got {seconds:?} s"
    )]
    Seconds { seconds: f64 },
}

/// Longest time budget per strategy: a day. Beyond it a budget is a mistake (1e308 would
/// run for ever), not a longer chart.
pub const MAX_SECONDS_PER_STRATEGY: f64 = 86_400.0;

/// Whether `seconds` can be a time budget per strategy. [`run`] checks it before its
/// reference run, which alone takes tens of seconds (with no time per strategy there would
/// be nothing to chart); callers that create outputs first can check it sooner.
pub fn check_seconds(seconds: f64) -> Result<(), ConvergenceError> {
    if seconds > 0.0 && seconds <= MAX_SECONDS_PER_STRATEGY {
        Ok(())
    } else {
        Err(ConvergenceError::Seconds { seconds })
    }
}

/// Runs every strategy with doubling sample counts until `seconds_per_strategy` is spent.
/// The reference is the default strategy refined to `reference_de`.
pub fn run(
    scene: &Scene,
    reference_de: f64,
    seconds_per_strategy: f64,
    seed: u64,
    log: &dyn Fn(&str),
) -> Result<(Vec<Point>, Xyz), ConvergenceError> {
    check_seconds(seconds_per_strategy)?;
    let reference = render_spots(
        scene,
        &SpotOptions {
            target_de: reference_de,
            seed: seed ^ 0xDEAD_BEEF,
            ..SpotOptions::default()
        },
    )?;
    let white = reference.white;
    log(&format!(
        "reference: ΔE95 < {reference_de} in {:.1} s",
        reference.seconds
    ));
    let aims: Vec<Aim> = (1..=24)
        .map(|k| patch_aim(scene, k))
        .collect::<Result<_, _>>()?;
    let mut points = Vec::new();
    for (name, strategy) in strategies() {
        let tracer = Tracer::new(scene, strategy);
        let mut n = 64u64;
        let mut spent = 0.0;
        while spent < seconds_per_strategy {
            let t = Instant::now();
            let des: Vec<f64> = aims
                .iter()
                .enumerate()
                .map(|(k, aim)| {
                    let m = sample_cone(&tracer, *aim, seed, k as u64 + 1, 0, n).mean();
                    let r = reference.patches[k].xyz;
                    delta_e76(m.to_lab(white), r.to_lab(white))
                })
                .collect();
            let seconds = t.elapsed().as_secs_f64();
            spent += seconds;
            let p = Point {
                strategy: name,
                samples_per_patch: n,
                seconds,
                max_de: des.iter().cloned().fold(0.0, f64::max),
                mean_de: des.iter().sum::<f64>() / des.len() as f64,
            };
            log(&format!(
                "{name}: {n} samples/patch, {seconds:.2} s, max ΔE {:.3}",
                p.max_de
            ));
            points.push(p);
            n *= 2;
        }
    }
    // The radiosity curves where the solver applies: what `auto` would render it with.
    if Method::Auto.resolve(scene)?.is_radiosity() {
        points.extend(radiosity_points(scene, RADIOSITY_LEVELS, log)?);
    }
    Ok((points, reference.white))
}

/// Mesh levels the radiosity curves run to; the last three give the "true" answer.
pub const RADIOSITY_LEVELS: usize = 9;

/// The two radiosity curves of the chart.
pub const RADIOSITY_BOUND: &str = "radiosity: error bound";
pub const RADIOSITY_TRUE: &str = "radiosity: true error";

/// Levels 1…`levels`: at each level from the third on, the seconds spent on all levels so
/// far (the bound needs them all), the largest bound, and the largest ΔE*ab against the
/// extrapolation of the finest levels (each against its own white), up to two levels below
/// the finest.
pub fn radiosity_points(
    scene: &Scene,
    levels: usize,
    log: &dyn Fn(&str),
) -> Result<Vec<Point>, ConvergenceError> {
    let opts = RadiosityOptions::default();
    let prepared = Prepared::new(scene).map_err(ConvergenceError::Radiosity)?;
    let mut done = Vec::new();
    let mut spent = Vec::new();
    let mut total = 0.0;
    for level in 1..=levels.max(5) {
        let l = run_level(&prepared, &opts, level, super::deadline::Deadline::never())?;
        total += l.seconds;
        log(&format!(
            "radiosity level {level}: {} elements, {:.2} s",
            l.elements, l.seconds
        ));
        spent.push(total);
        done.push(l);
    }
    let n = done.len();
    let (finest, fw) = combine(&done, &opts);
    let reference_bound = finest
        .iter()
        .map(|a| a.uncertainty.de_ab())
        .fold(0.0, f64::max);
    log(&format!(
        "radiosity reference: levels 1–{n}, its own bound ΔE*ab {reference_bound:.5}"
    ));
    let lab = |x: Xyz, w: Xyz| x.to_lab(w);
    let mut points = Vec::new();
    // A level's error is measured against a reference two or more levels finer: one level
    // finer, the reference's own error (its bound) is as large as the error it measures.
    for m in 3..n - 1 {
        let (r, w) = combine(&done[..m], &opts);
        let errors: Vec<f64> = r
            .iter()
            .zip(&finest)
            .map(|(a, b)| delta_e76(lab(a.xyz, w), lab(b.xyz, fw)))
            .collect();
        let bounds: Vec<f64> = r.iter().map(|a| a.uncertainty.de_ab()).collect();
        let elements = done[m - 1].elements as u64;
        for (name, v) in [(RADIOSITY_BOUND, &bounds), (RADIOSITY_TRUE, &errors)] {
            points.push(Point {
                strategy: name,
                samples_per_patch: elements,
                seconds: spent[m - 1],
                max_de: v.iter().cloned().fold(0.0, f64::max),
                mean_de: v.iter().sum::<f64>() / v.len() as f64,
            });
        }
    }
    Ok(points)
}

/// The chart's files in its directory.
pub const CSV_FILE: &str = "convergence.csv";
pub const SVG_FILE: &str = "convergence.svg";

/// Writes `convergence.csv` and `convergence.svg` into `dir` under the output policy `out`
/// (both checked before either is written).
pub fn write(dir: &Path, points: &[Point], out: &OutputPolicy) -> Result<(), ConvergenceError> {
    out.dir(dir)?;
    let csv = dir.join(CSV_FILE);
    let svg = dir.join(SVG_FILE);
    out.check(&csv)?;
    out.check(&svg)?;
    // Strategy names contain commas: quoted (RFC 4180).
    // For the radiosity rows the second column is the finest level's element count.
    let mut text = String::from("strategy,samples_per_patch,seconds,max_de_ab,mean_de_ab\n");
    for p in points {
        text.push_str(&format!(
            "\"{}\",{},{:.4},{:.5},{:.5}\n",
            p.strategy, p.samples_per_patch, p.seconds, p.max_de, p.mean_de
        ));
    }
    out.write(&csv, text.as_bytes())?;
    let mut names: Vec<&str> = strategies().iter().map(|(name, _)| *name).collect();
    names.extend([RADIOSITY_BOUND, RADIOSITY_TRUE]);
    let series: Vec<Series> = names
        .iter()
        .filter(|name| points.iter().any(|p| p.strategy == **name))
        .map(|name| Series {
            name: name.to_string(),
            points: points
                .iter()
                .filter(|p| p.strategy == *name)
                .map(|p| (p.seconds, p.max_de))
                .collect(),
        })
        .collect();
    let chart = LogLogChart {
        title: "max ΔE*ab over 24 patches vs render seconds (2 cores)",
        x_desc: "seconds",
        y_desc: "max ΔE*ab",
        series: &series,
        target: Some((0.1, "ΔE 0.1 target")),
        size: (900, 560),
    };
    let text = log_log_svg(&chart).map_err(ConvergenceError::Chart)?;
    Ok(out.write(&svg, text.as_bytes())?)
}
