//! The chart of a model selection: each candidate's cross-validated mean ΔE00 as a bar,
//! the chosen one dark, those the measured white set aside pale, the white's miss as a
//! marker with the allowance line (on sets with few mixtures), and why a candidate was not
//! fitted written in its row. SVG with `<text>` labels, in the project's palette.

use plotters::prelude::*;

use super::select::Selection;
use crate::plot::PALETTE;

/// The chart of `selection` as SVG text; the error is plotters' message.
pub fn selection_svg(selection: &Selection) -> Result<String, String> {
    let mut svg = String::new();
    draw(selection, &mut svg)?;
    Ok(svg)
}

fn draw(sel: &Selection, svg: &mut String) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let rows = sel.candidates.len();
    let few = sel.mixtures.few;
    let top = sel
        .candidates
        .iter()
        .flat_map(|c| {
            c.cv_mean_de00
                .as_ref()
                .ok()
                .copied()
                .into_iter()
                .chain(c.white_de00)
        })
        .chain(few.then_some(sel.mixtures.allowance_de00))
        .fold(0.0f64, f64::max)
        .max(1e-3)
        * 1.3;
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
    let chosen_colour = PALETTE[2];
    let competing_colour = PALETTE[5];
    let aside_colour = RGBColor(215, 215, 215);
    let white_colour = PALETTE[1];
    for (k, c) in sel.candidates.iter().enumerate() {
        // Top to bottom in the order of the list the text report prints.
        let y = (rows - 1 - k) as f64;
        match &c.cv_mean_de00 {
            Ok(v) => {
                let colour = if c.model == sel.model {
                    chosen_colour
                } else if c.set_aside.is_some() {
                    aside_colour
                } else {
                    competing_colour
                };
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(0.0, y - 0.32), (*v, y + 0.32)],
                        colour.filled(),
                    )))
                    .map_err(|e| err(&e))?;
                let mut note = format!("{v:.3}");
                if c.model == sel.model {
                    note.push_str(" chosen");
                } else if c.set_aside.is_some() {
                    note.push_str(" set aside");
                }
                chart
                    .draw_series(std::iter::once(Text::new(
                        note,
                        (*v + top * 0.01, y + 0.12),
                        ("sans-serif", 13),
                    )))
                    .map_err(|e| err(&e))?;
                if let Some(w) = c.white_de00 {
                    chart
                        .draw_series(std::iter::once(
                            EmptyElement::at((w, y))
                                + Polygon::new(
                                    vec![(0, -7), (7, 0), (0, 7), (-7, 0)],
                                    white_colour.filled(),
                                ),
                        ))
                        .map_err(|e| err(&e))?;
                }
            }
            Err(why) => {
                let short: String = why.chars().take(95).collect();
                let ellipsis = if why.chars().count() > 95 { "…" } else { "" };
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("not fitted: {short}{ellipsis}"),
                        (top * 0.01, y + 0.12),
                        ("sans-serif", 12).into_font().color(&RGBColor(90, 90, 90)),
                    )))
                    .map_err(|e| err(&e))?;
            }
        }
    }
    if few {
        let a = sel.mixtures.allowance_de00;
        chart
            .draw_series(DashedLineSeries::new(
                vec![(a, -0.5), (a, rows as f64 - 0.5)],
                6,
                4,
                white_colour.stroke_width(1),
            ))
            .map_err(|e| err(&e))?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("white allowance {a:.2}"),
                (a + top * 0.01, rows as f64 - 0.62),
                ("sans-serif", 12).into_font().color(&white_colour),
            )))
            .map_err(|e| err(&e))?;
    }
    let foot = if few {
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
    };
    root.draw(&Text::new(
        foot,
        (125, height as i32 - 16),
        ("sans-serif", 13).into_font().color(&RGBColor(60, 60, 60)),
    ))
    .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
