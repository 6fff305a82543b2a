//! The chart of a model selection: each candidate's cross-validated mean ΔE00 as a bar,
//! the chosen one dark, those the measured white set aside pale, the white's miss as a
//! marker with the allowance line (on sets with few mixtures), and why a candidate was not
//! fitted written in its row. SVG with `<text>` labels, in the project's palette.

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::select::{Candidate, Selection};
use crate::plot::PALETTE;

/// The white's miss and allowance.
const WHITE_COLOUR: RGBColor = PALETTE[1];

/// The chart of `selection` as SVG text; the error is plotters' message.
pub fn selection_svg(selection: &Selection) -> Result<String, String> {
    let mut svg = String::new();
    draw(selection, &mut svg)?;
    Ok(svg)
}

type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The chart: its frame and axes, a row per candidate, the white's allowance on sets with
/// few mixtures, and the footnote.
fn draw(sel: &Selection, svg: &mut String) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let rows = sel.candidates.len();
    let few = sel.mixtures.few;
    let top = x_range(sel);
    let height = 150 + 44 * rows as u32;
    let root = SVGBackend::with_string(svg, (900, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let title = format!(
        "model selection: {}-fold cross-validation, {} patches held out; chose {}",
        sel.folds, sel.held_out, sel.model
    );
    let names: Vec<&str> = sel.candidates.iter().map(|c| c.model.name()).collect();
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(15)
        .x_label_area_size(42)
        .y_label_area_size(110)
        .build_cartesian_2d(0.0..top, -0.5f64..rows as f64 - 0.5)
        .map_err(|e| err(&e))?;
    let label_names = names.clone();
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(rows)
        .y_label_formatter(&move |y| {
            let i = y.round();
            if (y - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < label_names.len() {
                label_names[rows - 1 - i as usize].to_string()
            } else {
                String::new()
            }
        })
        .x_desc(if few {
            "ΔE00: held-out mean (bars), fit's miss of the measured white (diamonds)"
        } else {
            "held-out mean ΔE00"
        })
        .draw()
        .map_err(|e| err(&e))?;
    for (k, c) in sel.candidates.iter().enumerate() {
        // Top to bottom in the order of the list the text report prints.
        let y = (rows - 1 - k) as f64;
        candidate_row(&mut chart, sel, c, y, top).map_err(|e| err(&e))?;
    }
    if few {
        allowance(&mut chart, sel.mixtures.allowance_de00, rows, top).map_err(|e| err(&e))?;
    }
    root.draw(&Text::new(
        footnote(sel),
        (125, height as i32 - 16),
        ("sans-serif", 13).into_font().color(&RGBColor(60, 60, 60)),
    ))
    .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The x axis's end: 1.3 times the largest value drawn (a mean, the white's miss, the
/// allowance), at least a little above 0.
fn x_range(sel: &Selection) -> f64 {
    sel.candidates
        .iter()
        .flat_map(|c| {
            c.cv_mean_de00
                .as_ref()
                .ok()
                .copied()
                .into_iter()
                .chain(c.white_de00)
        })
        .chain(sel.mixtures.few.then_some(sel.mixtures.allowance_de00))
        .fold(0.0f64, f64::max)
        .max(1e-3)
        * 1.3
}

/// One candidate's row at `y`: its bar (dark if chosen, pale if the white set it aside),
/// its value and the white's miss, or why it was not fitted.
fn candidate_row(
    chart: &mut Chart,
    sel: &Selection,
    c: &Candidate,
    y: f64,
    top: f64,
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    match &c.cv_mean_de00 {
        Ok(v) => {
            let colour = if c.model == sel.model {
                PALETTE[2]
            } else if c.set_aside.is_some() {
                RGBColor(215, 215, 215)
            } else {
                PALETTE[5]
            };
            chart.draw_series(std::iter::once(Rectangle::new(
                [(0.0, y - 0.32), (*v, y + 0.32)],
                colour.filled(),
            )))?;
            let mut note = format!("{v:.3}");
            if c.model == sel.model {
                note.push_str(" chosen");
            } else if c.set_aside.is_some() {
                note.push_str(" set aside");
            }
            chart.draw_series(std::iter::once(Text::new(
                note,
                (*v + top * 0.01, y + 0.12),
                ("sans-serif", 13),
            )))?;
            if let Some(w) = c.white_de00 {
                chart.draw_series(std::iter::once(
                    EmptyElement::at((w, y))
                        + Polygon::new(
                            vec![(0, -7), (7, 0), (0, 7), (-7, 0)],
                            WHITE_COLOUR.filled(),
                        ),
                ))?;
            }
        }
        Err(why) => {
            let short: String = why.chars().take(95).collect();
            let ellipsis = if why.chars().count() > 95 { "…" } else { "" };
            chart.draw_series(std::iter::once(Text::new(
                format!("not fitted: {short}{ellipsis}"),
                (top * 0.01, y + 0.12),
                ("sans-serif", 12).into_font().color(&RGBColor(90, 90, 90)),
            )))?;
        }
    }
    Ok(())
}

/// The white's allowance `a` as a dashed line across the rows, with its value.
fn allowance(
    chart: &mut Chart,
    a: f64,
    rows: usize,
    top: f64,
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    chart.draw_series(DashedLineSeries::new(
        vec![(a, -0.5), (a, rows as f64 - 0.5)],
        6,
        4,
        WHITE_COLOUR.stroke_width(1),
    ))?;
    chart.draw_series(std::iter::once(Text::new(
        format!("white allowance {a:.2}"),
        (a + top * 0.01, rows as f64 - 0.62),
        ("sans-serif", 12).into_font().color(&WHITE_COLOUR),
    )))?;
    Ok(())
}

/// What the bars judge, by how many mixed patches the set has.
fn footnote(sel: &Selection) -> String {
    if sel.mixtures.few {
        format!(
            "{} mixed patches besides the white: too few to judge mixtures; bars judge the \
             channels' curves, the white decides who competes",
            sel.mixtures.mixed
        )
    } else {
        format!(
            "{} mixed patches; cube corners always fitted",
            sel.mixtures.mixed
        )
    }
}
