//! Speed against accuracy: the largest ΔE*ab over the 24 spot readings, against a long
//! reference run, as a function of render time for each sampling strategy.

use std::path::Path;
use std::time::Instant;

use plotters::prelude::*;

use super::integrator::{Strategy, Tracer, Wavelengths};
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
    #[error("{file}: {source}")]
    Io {
        file: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("chart: {0}")]
    Chart(String),
}

/// Runs every strategy with doubling sample counts until `seconds_per_strategy` is spent.
/// The reference is the default strategy refined to `reference_de`.
pub fn run(
    scene: &Scene,
    reference_de: f64,
    seconds_per_strategy: f64,
    seed: u64,
    log: &dyn Fn(&str),
) -> Result<(Vec<Point>, [f64; 3]), ConvergenceError> {
    let reference = render_spots(
        scene,
        &SpotOptions {
            target_de: reference_de,
            seed: seed ^ 0xDEAD_BEEF,
            ..SpotOptions::default()
        },
    )?;
    let white = Xyz::from_array(reference.white);
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
                    delta_e76(
                        Xyz::from_array(m).to_lab(white),
                        Xyz::from_array(r).to_lab(white),
                    )
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
    Ok((points, reference.white))
}

/// Writes `convergence.csv` and `convergence.svg` into `dir`.
pub fn write(dir: &Path, points: &[Point]) -> Result<(), ConvergenceError> {
    let io = |file: &Path| {
        let file = file.to_path_buf();
        move |source| ConvergenceError::Io { file, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let csv = dir.join("convergence.csv");
    // Strategy names contain commas: quoted (RFC 4180).
    let mut text = String::from("strategy,samples_per_patch,seconds,max_de_ab,mean_de_ab\n");
    for p in points {
        text.push_str(&format!(
            "\"{}\",{},{:.4},{:.5},{:.5}\n",
            p.strategy, p.samples_per_patch, p.seconds, p.max_de, p.mean_de
        ));
    }
    std::fs::write(&csv, text).map_err(io(&csv))?;
    let svg = dir.join("convergence.svg");
    let chart_err = |e: &dyn std::fmt::Display| ConvergenceError::Chart(e.to_string());
    let root = SVGBackend::new(&svg, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_err(&e))?;
    let (xmin, xmax) = points.iter().fold((f64::MAX, 0.0f64), |a, p| {
        (a.0.min(p.seconds), a.1.max(p.seconds))
    });
    let (ymin, ymax) = points.iter().fold((f64::MAX, 0.0f64), |a, p| {
        (a.0.min(p.max_de), a.1.max(p.max_de))
    });
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "max ΔE*ab over 24 patches vs render seconds (2 cores)",
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (xmin.max(1e-4) * 0.8..xmax * 1.2).log_scale(),
            (ymin.clamp(1e-4, 0.05) * 0.8..ymax * 1.2).log_scale(),
        )
        .map_err(|e| chart_err(&e))?;
    chart
        .configure_mesh()
        .x_desc("seconds")
        .y_desc("max ΔE*ab")
        .draw()
        .map_err(|e| chart_err(&e))?;
    let colours = [BLACK, RED, BLUE, GREEN, MAGENTA, CYAN];
    for (i, (name, _)) in strategies().iter().enumerate() {
        let c = colours[i % colours.len()];
        let series: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.strategy == *name)
            .map(|p| (p.seconds, p.max_de))
            .collect();
        chart
            .draw_series(LineSeries::new(series, c.stroke_width(2)))
            .map_err(|e| chart_err(&e))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
    }
    // The 0.1 target.
    chart
        .draw_series(LineSeries::new(
            vec![(xmin.max(1e-4) * 0.8, 0.1), (xmax * 1.2, 0.1)],
            BLACK.mix(0.4),
        ))
        .map_err(|e| chart_err(&e))?
        .label("ΔE 0.1 target");
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| chart_err(&e))?;
    root.present().map_err(|e| chart_err(&e))?;
    Ok(())
}
