//! `LIGHT.svg`: the measured fall-off of both planes at their signed angles with every
//! model's fitted curve, and each model's held-out (leave-one-out) error beside the tie
//! limit by which `auto` chooses, so the choice can be seen. SVG with `<text>` labels, so
//! no font files are needed.
//!
//! Every curve stays visible where models agree: each has its own colour (the Okabe–Ito
//! palette, told apart with colour vision deficiencies) and dash pattern, the chosen model
//! is a wide translucent band drawn first, the others are drawn over it, the readings last.

use plotters::coord::ranged1d::SegmentValue;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::fit::cv::tie_limit;
use super::fit::{Candidate, HalfPlane, LdcError, LdcFit, LdcModel, Plane};

/// The chart of `fit` as SVG text (the caller writes it where the user asked).
pub fn ldc_chart_svg(fit: &LdcFit) -> Result<String, LdcError> {
    let mut svg = String::new();
    draw(fit, &mut svg)?;
    Ok(svg)
}

/// Colour and dash (length, gap in px; 0 = solid) of each model.
fn style_of(model: LdcModel) -> (RGBColor, u32, u32) {
    match model {
        LdcModel::Lambertian => (RGBColor(90, 90, 90), 10, 5),
        LdcModel::CosPower => (RGBColor(213, 94, 0), 3, 3),
        LdcModel::CosPoly => (RGBColor(86, 180, 233), 8, 3),
        LdcModel::Lobes => (RGBColor(204, 121, 167), 14, 4),
        LdcModel::Series => (RGBColor(0, 114, 178), 6, 2),
        LdcModel::Spline => (RGBColor(0, 158, 115), 2, 4),
    }
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

fn chart_err(e: &dyn std::fmt::Display) -> LdcError {
    LdcError::Chart {
        message: e.to_string(),
    }
}

fn draw(fit: &LdcFit, svg: &mut String) -> Result<(), LdcError> {
    let root = SVGBackend::with_string(svg, (1100, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_err(&e))?;
    let luminance = if fit.normal_luminance == 1.0 {
        "readings relative to the normal (1 at 0°)".to_string()
    } else {
        format!("normal luminance {} cd/m²", sig(fit.normal_luminance, 5))
    };
    let root = root
        .titled(
            &format!(
                "light distribution curve: {} chosen by leave-one-out cross-validation; {luminance}",
                fit.model
            ),
            ("sans-serif", 20),
        )
        .map_err(|e| chart_err(&e))?;
    let (top, bottom) = root.split_vertically(470);
    let fitted: Vec<&Candidate> = fit
        .candidates
        .iter()
        .filter(|c| c.halves.len() == 4)
        .collect();
    // Room above the highest reading and curve (a Lambertian f = 1 must not sit on the
    // frame), but not for a curve that runs away between the readings.
    let measured_top = fit
        .residuals
        .iter()
        .map(|r| r.measured)
        .fold(1.0f64, f64::max);
    let mut y_top = measured_top;
    for cand in &fitted {
        for (neg, pos) in [
            (HalfPlane::C180, HalfPlane::C0),
            (HalfPlane::C270, HalfPlane::C90),
        ] {
            for (_, v) in curve(cand, neg, pos) {
                y_top = y_top.max(v.min(1.5 * measured_top));
            }
        }
    }
    let y_top = y_top * 1.08;
    for (area, plane) in top
        .split_evenly((1, 2))
        .iter()
        .zip([Plane::Horizontal, Plane::Vertical])
    {
        draw_plane(fit, &fitted, plane, y_top, area)?;
    }
    let (legend, bars) = bottom.split_horizontally(420);
    draw_legend(fit, &legend)?;
    draw_scores(fit, &bars)?;
    root.present().map_err(|e| chart_err(&e))?;
    Ok(())
}

/// A fitted model's curve across a plane, `neg` the half at negative angles.
fn curve(cand: &Candidate, neg: HalfPlane, pos: HalfPlane) -> Vec<(f64, f64)> {
    (-89..=89)
        .map(|a| {
            let a = f64::from(a);
            let half = if a < 0.0 { neg } else { pos };
            (a, cand.halves[half.index()].params.eval(a.abs()).max(0.0))
        })
        .collect()
}

/// One plane's readings with every fitted model's curve, the chosen one a band under the
/// rest.
fn draw_plane(
    fit: &LdcFit,
    fitted: &[&Candidate],
    plane: Plane,
    y_top: f64,
    area: &Area,
) -> Result<(), LdcError> {
    let (neg, pos) = match plane {
        Plane::Horizontal => (HalfPlane::C180, HalfPlane::C0),
        Plane::Vertical => (HalfPlane::C270, HalfPlane::C90),
    };
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{plane} plane (C{} ← 0° → C{})", neg.c_deg(), pos.c_deg()),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(52)
        .build_cartesian_2d(-90.0f64..90.0, 0.0f64..y_top)
        .map_err(|e| chart_err(&e))?;
    chart
        .configure_mesh()
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 15))
        .x_label_formatter(&|v| format!("{v:.0}"))
        .x_desc("angle off the normal (°)")
        .y_desc("relative luminance (reading / normal luminance)")
        .draw()
        .map_err(|e| chart_err(&e))?;
    let chosen = fitted.iter().find(|c| c.model == fit.model);
    if let Some(c) = chosen {
        let (colour, _, _) = style_of(c.model);
        let points = curve(c, neg, pos);
        chart
            .draw_series(LineSeries::new(
                points.clone(),
                colour.mix(0.3).stroke_width(7),
            ))
            .map_err(|e| chart_err(&e))?;
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))
            .map_err(|e| chart_err(&e))?;
    }
    for c in fitted.iter().filter(|c| c.model != fit.model) {
        let (colour, dash, gap) = style_of(c.model);
        chart
            .draw_series(DashedLineSeries::new(
                curve(c, neg, pos),
                dash,
                gap,
                colour.stroke_width(2),
            ))
            .map_err(|e| chart_err(&e))?;
    }
    let points: Vec<(f64, f64)> = fit
        .residuals
        .iter()
        .filter(|r| r.plane == plane)
        .map(|r| (r.angle_deg, r.measured))
        .collect();
    chart
        .draw_series(points.iter().map(|&p| {
            EmptyElement::at(p)
                + Circle::new((0, 0), 5, WHITE.filled())
                + Circle::new((0, 0), 4, BLACK.filled())
        }))
        .map_err(|e| chart_err(&e))?;
    Ok(())
}

/// Each model's line style, size and score in words; the readings' marker.
fn draw_legend(fit: &LdcFit, area: &Area) -> Result<(), LdcError> {
    let font = ("sans-serif", 16).into_font();
    let (x0, mut y) = (20i32, 44i32);
    area.draw(&Text::new(
        "curves (every model fitted to the readings)",
        (x0, y - 22),
        font.clone(),
    ))
    .map_err(|e| chart_err(&e))?;
    for c in &fit.candidates {
        let (colour, dash, gap) = style_of(c.model);
        let line = vec![(x0, y), (x0 + 46, y)];
        if c.model == fit.model {
            area.draw(&PathElement::new(
                line.clone(),
                colour.mix(0.3).stroke_width(7),
            ))
            .map_err(|e| chart_err(&e))?;
            area.draw(&PathElement::new(line, colour.stroke_width(2)))
                .map_err(|e| chart_err(&e))?;
        } else if c.halves.len() == 4 {
            area.draw(&DashedPathElement::new(
                line,
                dash,
                gap,
                colour.stroke_width(2),
            ))
            .map_err(|e| chart_err(&e))?;
        }
        let text = match (c.halves.len() == 4, c.model == fit.model) {
            (false, _) => format!("{}: not fitted", c.model),
            (true, true) => format!("{} (chosen), {} parameters", c.model, c.parameters),
            (true, false) => format!("{}, {} parameters", c.model, c.parameters),
        };
        area.draw(&Text::new(
            text,
            (x0 + 56, y),
            TextStyle::from(font.clone()).pos(Pos::new(HPos::Left, VPos::Center)),
        ))
        .map_err(|e| chart_err(&e))?;
        y += 26;
    }
    area.draw(
        &(EmptyElement::at((x0 + 23, y))
            + Circle::new((0, 0), 5, WHITE.filled())
            + Circle::new((0, 0), 4, BLACK.filled())),
    )
    .map_err(|e| chart_err(&e))?;
    area.draw(&Text::new(
        "readings",
        (x0 + 56, y),
        TextStyle::from(font.clone()).pos(Pos::new(HPos::Left, VPos::Center)),
    ))
    .map_err(|e| chart_err(&e))?;
    y += 24;
    area.draw(&DashedPathElement::new(
        vec![(x0, y), (x0 + 46, y)],
        8,
        4,
        BLACK.stroke_width(1),
    ))
    .map_err(|e| chart_err(&e))?;
    for (k, line) in [
        "tie limit: lowest leave-one-out RMS × 1.1 + 0.0005;",
        "the model under it with the fewest parameters is chosen",
    ]
    .iter()
    .enumerate()
    {
        area.draw(&Text::new(
            *line,
            (x0 + 56, y + 18 * k as i32),
            TextStyle::from(font.clone()).pos(Pos::new(HPos::Left, VPos::Center)),
        ))
        .map_err(|e| chart_err(&e))?;
    }
    Ok(())
}

/// Each model's leave-one-out RMS as a bar (log scale), the tie limit as a line: the
/// model with the fewest parameters under the line is the one `auto` chooses.
fn draw_scores(fit: &LdcFit, area: &Area) -> Result<(), LdcError> {
    let n = fit.candidates.len();
    let (lo, hi, limit) = score_range(fit);
    let mut chart = ChartBuilder::on(area)
        .caption(
            "held-out error: leave-one-out RMS (relative luminance, log scale)",
            ("sans-serif", 17),
        )
        .margin(12)
        .margin_right(24)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d((0..n - 1).into_segmented(), (lo..hi).log_scale())
        .map_err(|e| chart_err(&e))?;
    let names: Vec<&'static str> = fit.candidates.iter().map(|c| c.model.name()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 15))
        .x_labels(n)
        .x_label_formatter(&|v| match v {
            SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
                names.get(*i).copied().unwrap_or("").to_string()
            }
            SegmentValue::Last => String::new(),
        })
        .y_label_formatter(&|v| sig(*v, 2))
        .y_desc("LOO RMS")
        .draw()
        .map_err(|e| chart_err(&e))?;
    for (i, c) in fit.candidates.iter().enumerate() {
        let (colour, _, _) = style_of(c.model);
        let label_style = TextStyle::from(("sans-serif", 15).into_font())
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        let Some(v) = c.cv_rms else {
            chart
                .draw_series(std::iter::once(Text::new(
                    "not cross-validated",
                    (SegmentValue::CenterOf(i), lo * 1.5),
                    label_style,
                )))
                .map_err(|e| chart_err(&e))?;
            continue;
        };
        let top = v.max(lo);
        let mut bar = Rectangle::new(
            [
                (SegmentValue::Exact(i), lo),
                (SegmentValue::Exact(i + 1), top),
            ],
            colour.mix(0.85).filled(),
        );
        bar.set_margin(0, 0, 12, 12);
        let chosen = c.model == fit.model;
        let mut outline = Rectangle::new(
            [
                (SegmentValue::Exact(i), lo),
                (SegmentValue::Exact(i + 1), top),
            ],
            BLACK.stroke_width(if chosen { 3 } else { 1 }),
        );
        outline.set_margin(0, 0, 12, 12);
        let text = if v > 0.0 { sig(v, 3) } else { "0".into() };
        chart
            .draw_series([bar, outline])
            .map_err(|e| chart_err(&e))?;
        chart
            .draw_series(std::iter::once(Text::new(
                text,
                (SegmentValue::CenterOf(i), top * 1.08),
                label_style,
            )))
            .map_err(|e| chart_err(&e))?;
    }
    if let Some(limit) = limit {
        chart
            .draw_series(DashedLineSeries::new(
                [(SegmentValue::Exact(0), limit), (SegmentValue::Last, limit)],
                8,
                4,
                BLACK.stroke_width(1),
            ))
            .map_err(|e| chart_err(&e))?;
    }
    Ok(())
}

/// The scores' axis, bottom and top, and the tie limit (None without a score).
fn score_range(fit: &LdcFit) -> (f64, f64, Option<f64>) {
    let scores: Vec<Option<f64>> = fit.candidates.iter().map(|c| c.cv_rms).collect();
    let positive = scores.iter().flatten().filter(|v| **v > 0.0);
    let lo_data = positive.clone().fold(f64::INFINITY, |m, v| m.min(*v));
    let hi = positive.fold(0.0f64, |m, v| m.max(*v)).max(1e-3) * 3.0;
    let best = scores
        .iter()
        .flatten()
        .fold(f64::INFINITY, |m, v| m.min(*v));
    let limit = best.is_finite().then(|| tie_limit(best));
    // A perfect score (0) has no place on a log scale: it is drawn at the floor.
    let lo = lo_data
        .min(limit.unwrap_or(f64::INFINITY))
        .min(hi / 10.0)
        .max(1e-7)
        / 3.0;
    (lo, hi, limit)
}

/// `v` to `digits` significant digits, in exponent form below 0.001.
fn sig(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if v.abs() < 1e-3 || v.abs() >= 1e6 {
        return format!("{:.*e}", (digits - 1).max(0) as usize, v);
    }
    let decimals = (digits - 1 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}
