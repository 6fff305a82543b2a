//! The paper's per-patch figure: ΔE*ab and ΔE00 of each ColorChecker patch as bars, with the
//! JND line, as an SVG (text is SVG <text>, so no font files are needed).

use std::path::Path;

use plotters::prelude::*;

use super::assess::JND_DE76;
use super::error::ValidationError;
use super::Comparison;
use crate::output::OutputPolicy;

/// Writes the per-patch ΔE chart of `comparison` to `file` (SVG) under the output policy
/// `out`.
pub fn write_delta_e_chart(
    comparison: &Comparison,
    file: &Path,
    out: &OutputPolicy,
) -> Result<(), ValidationError> {
    write_delta_e_chart_shaded(comparison, &[], "", file, out)
}

/// [`write_delta_e_chart`] with the 1-based patches in `shaded` on a grey band labelled
/// `shaded_label` in the legend (the lab marks the colours the display cannot show, so a
/// reader sees at once which errors no display model could remove).
pub fn write_delta_e_chart_shaded(
    comparison: &Comparison,
    shaded: &[usize],
    shaded_label: &str,
    file: &Path,
    out: &OutputPolicy,
) -> Result<(), ValidationError> {
    let mut svg = String::new();
    draw(comparison, shaded, shaded_label, file, &mut svg)?;
    Ok(out.write(file, svg.as_bytes())?)
}

fn draw(
    comparison: &Comparison,
    shaded: &[usize],
    shaded_label: &str,
    file: &Path,
    svg: &mut String,
) -> Result<(), ValidationError> {
    let chart_err = |e: &dyn std::fmt::Display| ValidationError::Chart {
        file: file.to_path_buf(),
        message: e.to_string(),
    };
    let n = comparison.patches.len();
    let top = comparison
        .patches
        .iter()
        .map(|p| p.de76.max(p.de00))
        .fold(JND_DE76, f64::max)
        * 1.15;
    // plotters looks for axis ticks on an infinite range without end.
    if !top.is_finite() {
        return Err(chart_err(&format!(
            "a colour difference of {top} cannot be drawn: a reading is not a colour"
        )));
    }
    let root = SVGBackend::with_string(svg, (900, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_err(&e))?;
    let caption = format!(
        "{} vs {}: ΔE per patch (CIELAB units); {} of {} below JND by point estimate",
        comparison.test, comparison.reference, comparison.below_jnd_point, n
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(48)
        .build_cartesian_2d(0.5f64..n as f64 + 0.5, 0.0..top)
        .map_err(|e| chart_err(&e))?;
    chart
        .configure_mesh()
        .x_desc("ColorChecker patch")
        .y_desc("ΔE (CIELAB units)")
        .x_labels(n)
        .x_label_formatter(&|x| format!("{}", x.round() as i64))
        .disable_x_mesh()
        .draw()
        .map_err(|e| chart_err(&e))?;
    if !shaded.is_empty() {
        let band = RGBColor(200, 200, 200).mix(0.6).filled();
        chart
            .draw_series(shaded.iter().map(|&k| {
                let x = k as f64;
                Rectangle::new([(x - 0.45, 0.0), (x + 0.45, top)], band)
            }))
            .map_err(|e| chart_err(&e))?
            .label(shaded_label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], band));
    }
    let bars = |offset: f64, pick: fn(&super::PatchComparison) -> f64, style: ShapeStyle| {
        comparison.patches.iter().map(move |p| {
            let x = p.patch as f64 + offset;
            Rectangle::new([(x - 0.17, 0.0), (x + 0.17, pick(p))], style)
        })
    };
    chart
        .draw_series(bars(-0.18, |p| p.de76, BLUE.mix(0.7).filled()))
        .map_err(|e| chart_err(&e))?
        .label("ΔE*ab")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], BLUE.mix(0.7).filled()));
    chart
        .draw_series(bars(0.18, |p| p.de00, RED.mix(0.6).filled()))
        .map_err(|e| chart_err(&e))?
        .label("ΔE00")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], RED.mix(0.6).filled()));
    chart
        .draw_series(LineSeries::new(
            [(0.5, JND_DE76), (n as f64 + 0.5, JND_DE76)],
            BLACK.stroke_width(1),
        ))
        .map_err(|e| chart_err(&e))?
        .label("JND 2.3")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 12, y)], BLACK));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| chart_err(&e))?;
    root.present().map_err(|e| chart_err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Xyz;
    use crate::validation::compare;

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
