//! Log–log line charts of error against cost, the one shape every "speed against accuracy"
//! figure here shares (render convergence, display patch budget). SVG only: text stays SVG
//! `<text>`, so no font files are needed at build or run time.

use plotters::coord::ranged1d::{BoldPoints, LightPoints};
use plotters::prelude::*;

/// One named curve.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    /// (x, y) points, both > 0; drawn in the order given.
    pub points: Vec<(f64, f64)>,
}

/// A chart to draw.
#[derive(Clone, Debug)]
pub struct LogLogChart<'a> {
    pub title: &'a str,
    pub x_desc: &'a str,
    pub y_desc: &'a str,
    pub series: &'a [Series],
    /// A horizontal reference line (value, label), e.g. a target ΔE.
    pub target: Option<(f64, &'a str)>,
    pub size: (u32, u32),
}

/// Draws `chart` as SVG text; the error is plotters' message. Callers write it through
/// their output policy.
pub fn log_log_svg(chart: &LogLogChart) -> Result<String, String> {
    let mut svg = String::new();
    draw_log_log(chart, &mut svg, &SeriesLook::of, false)?;
    Ok(svg)
}

/// Draws `chart` as [`log_log_svg`] does, series `i` in the colour and marker of
/// `looks[i].0` and dashed where `looks[i].1`: for a chart whose series come in pairs to
/// be told apart by one feature each (a side by its colour, a plan by its dash). The legend
/// stands to the right of the plot, where it hides no line.
pub fn log_log_svg_paired(chart: &LogLogChart, looks: &[(usize, bool)]) -> Result<String, String> {
    let mut svg = String::new();
    let look = |i: usize| {
        let (k, dashed) = looks.get(i).copied().unwrap_or((i, false));
        SeriesLook {
            dashed,
            ..SeriesLook::of(k)
        }
    };
    draw_log_log(chart, &mut svg, &look, true)?;
    Ok(svg)
}

fn draw_log_log(
    chart: &LogLogChart,
    svg: &mut String,
    look_of: &dyn Fn(usize) -> SeriesLook,
    legend_right: bool,
) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let (xmin, xmax, ymin, ymax) = extent(chart)?;
    let (x0, y0) = (
        axis_start(xmin, legend_right),
        axis_start(ymin, legend_right),
    );
    let labels = if legend_right { 30 } else { 10 };
    let label = |v: &f64| paired_tick(*v, legend_right);
    let root = SVGBackend::with_string(svg, chart.size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (plot, side) = if legend_right {
        let (p, s) = root.split_horizontally(chart.size.0 * 62 / 100);
        (p, Some(s))
    } else {
        (root.clone(), None)
    };
    let mut c = ChartBuilder::on(&plot)
        .caption(chart.title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            log_axis(x0..xmax * 1.25, labels),
            log_axis(y0..ymax * 1.25, labels),
        )
        .map_err(|e| err(&e))?;
    let mut mesh = c.configure_mesh();
    mesh.x_labels(labels)
        .y_labels(labels)
        .x_label_formatter(&label)
        .y_label_formatter(&label)
        .x_desc(chart.x_desc)
        .y_desc(chart.y_desc);
    if legend_right {
        // Only the labelled decades' lines: the lines between them would grey the plot.
        mesh.light_line_style(WHITE);
    }
    mesh.draw().map_err(|e| err(&e))?;
    for (i, s) in chart.series.iter().enumerate() {
        let look = look_of(i);
        let line = look.colour.stroke_width(2);
        let fill = look.colour.filled();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0)
            .collect();
        let outline = look.marker.outline();
        c.draw_series(
            pts.iter()
                .map(|&p| EmptyElement::at(p) + Polygon::new(outline.clone(), fill)),
        )
        .map_err(|e| err(&e))?;
        let drawn = if look.dashed {
            c.draw_series(DashedLineSeries::new(pts, 8, 5, line))
        } else {
            c.draw_series(LineSeries::new(pts, line))
        };
        // The legend repeats the marker on the line, and shows a dash as a gap.
        let gap = if look.dashed { 4 } else { 0 };
        let legend_mark: Vec<(i32, i32)> = outline.iter().map(|&(x, y)| (x + 12, y)).collect();
        drawn
            .map_err(|e| err(&e))?
            .label(s.name.as_str())
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (12 - gap, 0)], line)
                    + PathElement::new(vec![(12 + gap, 0), (24, 0)], line)
                    + Polygon::new(legend_mark.clone(), fill)
            });
    }
    if let Some((t, label)) = chart.target {
        draw_target(&mut c, t, label, x0..xmax * 1.25).map_err(|e| err(&e))?;
    }
    match side {
        Some(side) => legend_beside(&side, chart, look_of).map_err(|e| err(&e))?,
        None => c
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?,
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The axes of a log–log chart.
type LogLog = Cartesian2d<
    plotters::coord::combinators::WithKeyPoints<LogCoord<f64>>,
    plotters::coord::combinators::WithKeyPoints<LogCoord<f64>>,
>;

/// The target line at `t` across `x`, in dots, with its legend entry.
fn draw_target<'a, DB: DrawingBackend + 'a>(
    c: &mut ChartContext<'a, DB, LogLog>,
    t: f64,
    label: &str,
    x: std::ops::Range<f64>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (dot, gap) = TARGET_DOT;
    c.draw_series(DashedLineSeries::new(
        vec![(x.start, t), (x.end, t)],
        dot,
        gap,
        target_style(),
    ))?
    .label(label)
    .legend(|(x, y)| {
        EmptyElement::at((x, y))
            + PathElement::new(vec![(0, 0), (2, 0)], target_style())
            + PathElement::new(vec![(9, 0), (11, 0)], target_style())
            + PathElement::new(vec![(18, 0), (20, 0)], target_style())
    });
    Ok(())
}

/// The target line's dots, pixels drawn and left (as a dashed series' dash and gap).
const TARGET_DOT: (u32, u32) = (2, 5);

/// The target line: black dots, 2 px, where the grid's lines are thin, solid and light
/// grey and a series' line is coloured, solid or dashed, and carries markers.
fn target_style() -> ShapeStyle {
    BLACK.stroke_width(2)
}

/// A log axis over `range` with plotters' own grid and label points, each once. Asked
/// for about 30 labels (a paired chart), plotters puts 1…10 in each decade, so the last
/// point of one decade is the first of the next and its label is drawn twice, one text on
/// the other.
fn log_axis(
    range: std::ops::Range<f64>,
    labels: usize,
) -> plotters::coord::combinators::WithKeyPoints<LogCoord<f64>> {
    let coord: LogCoord<f64> = range.log_scale().into();
    let bold = distinct(coord.key_points(BoldPoints(labels)));
    let light = distinct(coord.key_points(LightPoints::new(labels, labels * 10)));
    coord.with_key_points(bold).with_light_points(light)
}

/// `points` without the repeats of a value (within rounding), in their order.
fn distinct(points: Vec<f64>) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(points.len());
    for p in points {
        if !out
            .iter()
            .any(|q| (p - q).abs() <= 1e-9 * p.abs().max(q.abs()))
        {
            out.push(p);
        }
    }
    out
}

/// Where an axis whose smallest value is `min` starts: a fifth below it; for a paired
/// chart at the power of ten below that, where plotters' log axis starts its labels, so a
/// range within one decade is labelled too (a hair below it: plotters rounds the log of an
/// exact power of ten up past it).
fn axis_start(min: f64, paired: bool) -> f64 {
    if paired {
        decade_below(min * 0.8) * 0.999
    } else {
        min * 0.8
    }
}

/// A tick's label; a paired chart labels only 1, 2 and 5 of each decade, so its labels
/// do not crowd a decade's top.
fn paired_tick(v: f64, paired: bool) -> String {
    if paired && !one_two_five(v) {
        String::new()
    } else {
        tick(v)
    }
}

/// The largest power of ten at or below `v` (> 0).
fn decade_below(v: f64) -> f64 {
    10f64.powf(v.log10().floor())
}

/// Whether `v` is 1, 2 or 5 times a power of ten.
fn one_two_five(v: f64) -> bool {
    let m = v / decade_below(v);
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .any(|k| (m - k).abs() < 1e-6 * k)
}

/// The smallest and largest x and y of the chart's positive points and its target.
fn extent(chart: &LogLogChart) -> Result<(f64, f64, f64, f64), String> {
    let points = chart
        .series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0 > 0.0 && p.1 > 0.0);
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (f64::MAX, 0.0f64, f64::MAX, 0.0f64);
    for &(x, y) in points {
        xmin = xmin.min(x);
        xmax = xmax.max(x);
        ymin = ymin.min(y);
        ymax = ymax.max(y);
    }
    if let Some((t, _)) = chart.target {
        ymin = ymin.min(t);
        ymax = ymax.max(t);
    }
    if xmax <= 0.0 || ymax <= 0.0 {
        return Err("no positive points to draw".into());
    }
    Ok((xmin, xmax, ymin, ymax))
}

/// The legend in its own area: each series' line, dash and marker with its name, one a
/// row, then the target line's.
fn legend_beside<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    chart: &LogLogChart,
    look_of: &dyn Fn(usize) -> SeriesLook,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = ("sans-serif", 13).into_font();
    let row = |i: usize| 60 + 22 * i as i32;
    for (i, s) in chart.series.iter().enumerate() {
        let look = look_of(i);
        let y = row(i);
        let line = look.colour.stroke_width(2);
        // A dashed line's sample in dashes on either side of the marker.
        let dashes: &[(i32, i32)] = if look.dashed {
            &[(4, 10), (14, 20), (36, 42), (46, 52)]
        } else {
            &[(4, 52)]
        };
        for &(a, b) in dashes {
            area.draw(&PathElement::new(vec![(a, y), (b, y)], line))?;
        }
        let mark: Vec<(i32, i32)> = look
            .marker
            .outline()
            .iter()
            .map(|&(x, dy)| (x + 28, y + dy))
            .collect();
        area.draw(&Polygon::new(mark, look.colour.filled()))?;
        area.draw(&Text::new(
            s.name.as_str(),
            (60, y - 7),
            font.clone().color(&BLACK),
        ))?;
    }
    if let Some((_, label)) = chart.target {
        let y = row(chart.series.len());
        let (dot, gap) = (TARGET_DOT.0 as i32, TARGET_DOT.1 as i32);
        for a in (4..52).step_by((dot + gap) as usize) {
            area.draw(&PathElement::new(
                vec![(a, y), (a + dot, y)],
                target_style(),
            ))?;
        }
        area.draw(&Text::new(label, (60, y - 7), font.color(&BLACK)))?;
    }
    Ok(())
}

/// Ten colours that stay apart for the common colour-vision deficiencies (P. Tol's "muted"
/// scheme, with black first), so a chart needs neither colour names nor good eyes.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(0, 0, 0),
    RGBColor(204, 102, 119),
    RGBColor(51, 34, 136),
    RGBColor(221, 204, 119),
    RGBColor(17, 119, 51),
    RGBColor(136, 204, 238),
    RGBColor(136, 34, 85),
    RGBColor(68, 170, 153),
    RGBColor(153, 153, 51),
    RGBColor(170, 68, 153),
];

/// Point markers, drawn as filled polygons in pixels around the point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Marker {
    Circle,
    Triangle,
    Square,
    Diamond,
}

impl Marker {
    const ALL: [Marker; 4] = [
        Marker::Circle,
        Marker::Triangle,
        Marker::Square,
        Marker::Diamond,
    ];

    fn outline(self) -> Vec<(i32, i32)> {
        match self {
            Marker::Circle => (0..12)
                .map(|k| {
                    let a = f64::from(k) * std::f64::consts::PI / 6.0;
                    (
                        (4.0 * a.cos()).round() as i32,
                        (4.0 * a.sin()).round() as i32,
                    )
                })
                .collect(),
            Marker::Triangle => vec![(0, -5), (5, 4), (-5, 4)],
            Marker::Square => vec![(-4, -4), (4, -4), (4, 4), (-4, 4)],
            Marker::Diamond => vec![(0, -5), (5, 0), (0, 5), (-5, 0)],
        }
    }
}

/// How series `i` is drawn: colour and marker cycle together (10 and 4, so 20 series get
/// distinct pairs), and the next 20 are dashed, so no two of the first 40 look alike.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SeriesLook {
    colour: RGBColor,
    marker: Marker,
    dashed: bool,
}

impl SeriesLook {
    fn of(i: usize) -> SeriesLook {
        SeriesLook {
            colour: PALETTE[i % PALETTE.len()],
            marker: Marker::ALL[i % Marker::ALL.len()],
            dashed: (i / 20) % 2 == 1,
        }
    }
}

/// A tick label without spurious decimals: 10, 0.5, 0.02.
fn tick(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paired_axes_label_one_two_and_five_of_each_decade() {
        assert_eq!(decade_below(0.24), 0.1);
        assert_eq!(decade_below(19.2), 10.0);
        for v in [0.1, 0.2, 0.5, 1.0, 20.0, 500.0] {
            assert!(one_two_five(v), "{v}");
        }
        for v in [0.3, 0.7, 3.0, 90.0] {
            assert!(!one_two_five(v), "{v}");
        }
    }

    #[test]
    fn ticks_drop_spurious_decimals() {
        assert_eq!(tick(1000.0), "1000");
        assert_eq!(tick(1.0), "1");
        assert_eq!(tick(0.5), "0.5");
        assert_eq!(tick(0.02), "0.02");
    }

    #[test]
    fn draws_every_series_and_the_target() {
        let series = [
            Series {
                name: "alpha".into(),
                points: vec![(1.0, 1.0), (10.0, 0.3)],
            },
            Series {
                name: "beta".into(),
                points: vec![(2.0, 2.0), (20.0, 0.1)],
            },
        ];
        let chart = LogLogChart {
            title: "t",
            x_desc: "x",
            y_desc: "y",
            series: &series,
            target: Some((0.5, "goal")),
            size: (400, 300),
        };
        let svg = log_log_svg(&chart).unwrap();
        for word in ["alpha", "beta", "goal"] {
            assert!(svg.contains(word), "{word} missing");
        }
        let empty = LogLogChart {
            series: &[],
            target: None,
            ..chart
        };
        assert!(log_log_svg(&empty).is_err());
    }

    /// A paired chart over three decades (the cost chart's shape): plotters' grid puts 1…10
    /// in each decade, so each decade's label once came twice, one text on the other.
    /// Every label is drawn once, and 1, 10 and 100 are among them; the target line is
    /// drawn in none of the grid's greys.
    #[test]
    fn paired_axes_draw_each_label_once_and_the_target_apart_from_the_grid() {
        let series = [Series {
            name: "box".into(),
            points: vec![(2.0, 3.0), (30.0, 0.9), (300.0, 0.25)],
        }];
        let chart = LogLogChart {
            title: "t",
            x_desc: "readings",
            y_desc: "ΔE*ab",
            series: &series,
            target: Some((2.3, "JND")),
            size: (1000, 440),
        };
        let svg = log_log_svg_paired(&chart, &[(1, false)]).unwrap();
        if let Ok(path) = std::env::var("METAMER_KEEP_PAIRED_SVG") {
            std::fs::write(path, &svg).unwrap();
        }
        let texts: Vec<&str> = svg
            .split("<text")
            .skip(1)
            .map(|t| t.split("</text>").next().unwrap())
            .collect();
        for (i, t) in texts.iter().enumerate() {
            assert!(!texts[..i].contains(t), "drawn twice: <text{t}</text>");
        }
        let words: Vec<&str> = texts
            .iter()
            .map(|t| t.split_once('>').map_or("", |w| w.1.trim()))
            .collect();
        for label in ["1", "10", "100", "0.2", "2", "5"] {
            assert!(words.contains(&label), "{label} is not labelled: {words:?}");
        }
        // The grid: thin lines in black at 0.2 opacity (plotters' bold mesh); the target:
        // black at full opacity, 2 px wide, in dots.
        let lines: Vec<&str> = svg
            .split('<')
            .filter(|e| e.starts_with("polyline") || e.starts_with("line"))
            .collect();
        let target: Vec<&&str> = lines
            .iter()
            .filter(|e| e.contains("stroke=\"#000000\"") && e.contains("stroke-width=\"2\""))
            .collect();
        assert!(target.len() > 50, "the target's dots: {}", target.len());
        assert!(
            target.iter().all(|e| !e.contains("opacity=\"0.")),
            "{:?}",
            target[0]
        );
    }

    /// Forty series (the budget chart has more than the seven colours there once were)
    /// must all be told apart, and the palette must have ten different colours.
    #[test]
    fn series_looks_are_all_different() {
        let looks: Vec<SeriesLook> = (0..40).map(SeriesLook::of).collect();
        for i in 0..looks.len() {
            for j in 0..i {
                assert_ne!(looks[i], looks[j], "series {i} and {j} look alike");
            }
        }
        for (i, a) in PALETTE.iter().enumerate() {
            assert!(PALETTE[..i].iter().all(|b| b != a), "colour {i} repeats");
        }
    }
}
