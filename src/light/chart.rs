//! `LIGHT.svg`: the measured fall-off of both planes at their signed angles, every model's
//! fitted curve, the chosen one drawn heavy. SVG with `<text>` labels, so no font files
//! are needed.

use plotters::prelude::*;

use super::fit::{HalfPlane, LdcError, LdcFit, Plane};

/// The chart of `fit` as SVG text (the caller writes it where the user asked).
pub fn ldc_chart_svg(fit: &LdcFit) -> Result<String, LdcError> {
    let mut svg = String::new();
    draw(fit, &mut svg)?;
    Ok(svg)
}

fn draw(fit: &LdcFit, svg: &mut String) -> Result<(), LdcError> {
    let chart_err = |e: &dyn std::fmt::Display| LdcError::Chart {
        message: e.to_string(),
    };
    let top = fit
        .residuals
        .iter()
        .map(|r| r.measured)
        .fold(1.0f64, f64::max)
        * 1.1;
    let root = SVGBackend::with_string(svg, (1100, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_err(&e))?;
    let root = root
        .titled(
            &format!(
                "light distribution curve: {} chosen, normal luminance {:.4}",
                fit.model, fit.normal_luminance
            ),
            ("sans-serif", 18),
        )
        .map_err(|e| chart_err(&e))?;
    let colours = [
        RGBColor(120, 120, 120),
        RGBColor(200, 30, 30),
        RGBColor(30, 90, 200),
        RGBColor(20, 150, 60),
    ];
    let panels = root.split_evenly((1, 2));
    for (area, plane) in panels.iter().zip([Plane::Horizontal, Plane::Vertical]) {
        let (neg, pos) = match plane {
            Plane::Horizontal => (HalfPlane::C180, HalfPlane::C0),
            Plane::Vertical => (HalfPlane::C270, HalfPlane::C90),
        };
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("{plane} plane ({} ← 0 → {})", short(neg), short(pos)),
                ("sans-serif", 16),
            )
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(48)
            .build_cartesian_2d(-90.0f64..90.0, 0.0f64..top)
            .map_err(|e| chart_err(&e))?;
        chart
            .configure_mesh()
            .x_desc("angle off the normal (°)")
            .y_desc("luminance / normal luminance")
            .draw()
            .map_err(|e| chart_err(&e))?;
        for (k, cand) in fit.candidates.iter().enumerate() {
            if cand.halves.len() != 4 {
                continue;
            }
            let chosen = cand.model == fit.model;
            let colour = colours[k % colours.len()];
            let style = if chosen {
                colour.stroke_width(3)
            } else {
                colour.mix(0.55).stroke_width(1)
            };
            let curve: Vec<(f64, f64)> = (-89..=89)
                .map(|a| {
                    let a = a as f64;
                    let half = if a < 0.0 { neg } else { pos };
                    (a, cand.halves[half.index()].params.eval(a.abs()).max(0.0))
                })
                .collect();
            let label = if chosen {
                format!("{} (chosen)", cand.model)
            } else {
                cand.model.to_string()
            };
            chart
                .draw_series(LineSeries::new(curve, style))
                .map_err(|e| chart_err(&e))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
        let points: Vec<(f64, f64)> = fit
            .residuals
            .iter()
            .filter(|r| r.plane == plane)
            .map(|r| (r.angle_deg, r.measured))
            .collect();
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 4, BLACK.filled())))
            .map_err(|e| chart_err(&e))?
            .label("measured")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, BLACK.filled()));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerMiddle)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| chart_err(&e))?;
    }
    root.present().map_err(|e| chart_err(&e))?;
    Ok(())
}

fn short(h: HalfPlane) -> String {
    format!("C{}", h.c_deg())
}
