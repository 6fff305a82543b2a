//! The characterization report as one SVG: the measured tone response of each channel
//! (black subtracted, normalised to full drive, paper Eq. 9's TRC) with the fitted model's
//! prediction as a line; each channel's chromaticity x and y (black subtracted) against
//! drive, which a PLCC display keeps constant; and the ΔE00 of every verification patch,
//! each bar filled with the patch's own drive values. Text is SVG `<text>` (no font files).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::color::Xyz;
use crate::output::{OutputError, OutputPolicy};

use super::verify::AveragedPatch;
use crate::display::verify::Verification;

/// The report could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("drawing the report {}: {message}", file.display())]
    Draw { file: PathBuf, message: String },
    #[error("{0}")]
    Output(#[from] OutputError),
}

/// What the report shows.
pub struct Report<'a> {
    pub title: String,
    pub patches: &'a [AveragedPatch],
    /// The fitted model, drive 0–1 → XYZ, drawn over the measured TRCs.
    pub forward: Option<&'a dyn Fn([f64; 3]) -> Xyz>,
    pub verification: Option<&'a Verification>,
}

/// The ramps: red, green, blue and grey, each with the drive mask it varies.
const RAMPS: [(&str, [u8; 3], RGBColor); 4] = [
    ("red", [1, 0, 0], RGBColor(200, 30, 30)),
    ("green", [0, 1, 0], RGBColor(30, 150, 30)),
    ("blue", [0, 0, 1], RGBColor(30, 60, 210)),
    ("grey", [1, 1, 1], RGBColor(90, 90, 90)),
];

/// (drive 0–1, XYZ) of the patches on ramp `mask`, black and full drive included, sorted.
fn ramp(patches: &[AveragedPatch], mask: [u8; 3]) -> Vec<(f64, Xyz)> {
    let mut pts: Vec<(f64, Xyz)> = patches
        .iter()
        .filter(|p| {
            let v = p.rgb8.iter().copied().max().unwrap_or(0);
            (0..3).all(|c| p.rgb8[c] == mask[c] * v)
        })
        .map(|p| {
            (
                f64::from(p.rgb8.iter().copied().max().unwrap_or(0)) / 255.0,
                p.xyz,
            )
        })
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts
}

fn sub(a: Xyz, b: Xyz) -> Xyz {
    a - b
}

/// Chromaticity of a black-subtracted term, None where it has no light.
fn chromaticity(xyz: Xyz) -> Option<(f64, f64)> {
    let s = xyz[0] + xyz[1] + xyz[2];
    (s > 1e-9 && xyz[1] > 0.0).then(|| (xyz[0] / s, xyz[1] / s))
}

/// Draws `report` to `file` (SVG, 1200×860) under the output policy `out`.
pub fn write_report(report: &Report, file: &Path, out: &OutputPolicy) -> Result<(), ReportError> {
    let mut svg = String::new();
    draw_report(report, file, &mut svg)?;
    Ok(out.write(file, svg.as_bytes())?)
}

fn draw_report(report: &Report, file: &Path, svg: &mut String) -> Result<(), ReportError> {
    let fail = |e: &dyn std::fmt::Display| ReportError::Draw {
        file: file.to_path_buf(),
        message: e.to_string(),
    };
    let root = SVGBackend::with_string(svg, (1200, 860)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let root = root
        .titled(&report.title, ("sans-serif", 20))
        .map_err(|e| fail(&e))?;
    let (top, bottom) = root.split_vertically(430);
    let panels = top.split_evenly((1, 3));
    let black = report
        .patches
        .iter()
        .find(|p| p.rgb8 == [0, 0, 0])
        .map_or(Xyz::default(), |p| p.xyz);
    draw_trc(&panels[0], report, black).map_err(|e| fail(&e))?;
    for (k, name) in ["x", "y"].into_iter().enumerate() {
        draw_chromaticity(&panels[1 + k], report.patches, black, k, name).map_err(|e| fail(&e))?;
    }
    if let Some(v) = report.verification {
        draw_delta_e(&bottom, v).map_err(|e| fail(&e))?;
    }
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

type DrawResult = Result<(), DrawingAreaErrorKind<std::io::Error>>;

fn draw_trc(area: &DrawingArea<SVGBackend, Shift>, report: &Report, black: Xyz) -> DrawResult {
    let mut chart = ChartBuilder::on(area)
        .caption("tone response (black subtracted)", ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(44)
        .build_cartesian_2d(0.0..1.0, 0.0..1.05)?;
    chart
        .configure_mesh()
        .x_desc("drive")
        .y_desc("relative luminance")
        .draw()?;
    for (name, mask, colour) in RAMPS {
        let pts = ramp(report.patches, mask);
        let Some(&(1.0, full)) = pts.last() else {
            continue;
        };
        let span = full[1] - black[1];
        if span <= 0.0 {
            continue;
        }
        let rel = |xyz: Xyz| (xyz[1] - black[1]) / span;
        chart
            .draw_series(
                pts.iter()
                    .map(|&(v, xyz)| Circle::new((v, rel(xyz)), 3, colour.filled())),
            )?
            .label(name)
            .legend(move |(x, y)| Circle::new((x + 6, y), 3, colour.filled()));
        if let Some(forward) = report.forward {
            let line = (0..=64).map(|i| {
                let v = f64::from(i) / 64.0;
                let drive = mask.map(|m| f64::from(m) * v);
                (v, rel(forward(drive)))
            });
            chart.draw_series(LineSeries::new(line, colour.stroke_width(1)))?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

fn draw_chromaticity(
    area: &DrawingArea<SVGBackend, Shift>,
    patches: &[AveragedPatch],
    black: Xyz,
    which: usize,
    name: &str,
) -> DrawResult {
    let series: Vec<(RGBColor, Vec<(f64, f64)>)> = RAMPS
        .iter()
        .map(|&(_, mask, colour)| {
            let pts = ramp(patches, mask)
                .into_iter()
                .filter_map(|(v, xyz)| {
                    chromaticity(sub(xyz, black))
                        .map(|xy| (v, if which == 0 { xy.0 } else { xy.1 }))
                })
                .collect();
            (colour, pts)
        })
        .collect();
    let values = series.iter().flat_map(|(_, p)| p.iter().map(|q| q.1));
    let (lo, hi) = values.fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (lo, hi) = if lo <= hi {
        (lo - 0.02, hi + 0.02)
    } else {
        (0.0, 1.0)
    };
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("chromaticity {name} of each channel against drive"),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    chart.configure_mesh().x_desc("drive").y_desc(name).draw()?;
    for (colour, pts) in series {
        chart.draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(1)))?;
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
    }
    Ok(())
}

fn draw_delta_e(area: &DrawingArea<SVGBackend, Shift>, v: &Verification) -> DrawResult {
    let n = v.patches.len();
    let top = v.patches.iter().map(|p| p.de00).fold(1.0, f64::max) * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!(
                "ΔE00 of the {n} verification patches: mean {:.2}, p95 {:.2}, max {:.2} (bars in the patch's drive colour)",
                v.de00.mean, v.de00.p95, v.de00.max
            ),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(44)
        .build_cartesian_2d(0.5..n as f64 + 0.5, 0.0..top)?;
    chart
        .configure_mesh()
        .x_desc("verification patch (random 1–24, then ColorChecker 1–24)")
        .y_desc("ΔE00")
        .x_labels(n.min(48))
        .x_label_formatter(&|x| format!("{}", x.round() as i64))
        .disable_x_mesh()
        .draw()?;
    chart.draw_series(v.patches.iter().enumerate().map(|(i, p)| {
        let x = i as f64 + 1.0;
        let [r, g, b] = p.rgb8();
        Rectangle::new(
            [(x - 0.35, 0.0), (x + 0.35, p.de00)],
            RGBColor(r, g, b).filled(),
        )
    }))?;
    chart.draw_series(v.patches.iter().enumerate().map(|(i, p)| {
        let x = i as f64 + 1.0;
        Rectangle::new([(x - 0.35, 0.0), (x + 0.35, p.de00)], BLACK.stroke_width(1))
    }))?;
    for (value, label, colour) in [(v.de00.mean, "mean", BLUE), (v.de00.p95, "p95", RED)] {
        chart
            .draw_series(LineSeries::new(
                [(0.5, value), (n as f64 + 0.5, value)],
                colour.stroke_width(1),
            ))?
            .label(format!("{label} {value:.2}"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 14, y)], colour));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::characterize::plan::Purpose;

    #[test]
    fn ramps_are_picked_by_their_drive_mask() {
        let p = |rgb8: [u8; 3], y: f64| AveragedPatch {
            patch: 0,
            label: String::new(),
            rgb8,
            purpose: Purpose::Fit,
            xyz: Xyz::new(y, y, y),
            readings: 1,
        };
        let patches = [
            p([0, 0, 0], 0.1),
            p([255, 0, 0], 9.0),
            p([64, 0, 0], 1.0),
            p([64, 64, 64], 2.0),
            p([64, 1, 0], 5.0),
        ];
        let red = ramp(&patches, [1, 0, 0]);
        assert_eq!(
            red.iter().map(|q| q.0).collect::<Vec<_>>(),
            vec![0.0, 64.0 / 255.0, 1.0]
        );
        let grey = ramp(&patches, [1, 1, 1]);
        assert_eq!(
            grey.iter().map(|q| q.1[1]).collect::<Vec<_>>(),
            vec![0.1, 2.0]
        );
        assert_eq!(chromaticity(Xyz::default()), None);
        assert_eq!(chromaticity(Xyz::new(1.0, 2.0, 1.0)), Some((0.25, 0.5)));
    }

    #[test]
    fn a_report_of_a_simulated_panel_draws_every_panel() {
        use crate::display::characterize::plan::{Plan, PlanOptions};
        use crate::display::characterize::verify::verify_held_out;
        use crate::rig::virtual_display::{Preset, VirtualPanel};
        let panel = VirtualPanel::preset(Preset::IpsLcd);
        let plan = Plan::new(PlanOptions::default()).unwrap();
        let patches: Vec<AveragedPatch> = plan
            .distinct
            .iter()
            .map(|p| AveragedPatch {
                patch: p.patch,
                label: p.label.clone(),
                rgb8: p.rgb,
                purpose: p.purpose,
                xyz: panel.xyz(p.rgb),
                readings: 1,
            })
            .collect();
        // The panel predicting itself: every ΔE00 is 0.
        let forward = |rgb: [f64; 3]| panel.xyz_of_drive(rgb);
        let v = verify_held_out(&patches, panel.xyz([255; 3]), &forward)
            .unwrap()
            .unwrap();
        assert_eq!((v.patches.len(), v.de00.max), (48, 0.0));
        let file = std::env::temp_dir().join(format!("metamer-report-{}.svg", std::process::id()));
        write_report(
            &Report {
                title: "virtual:ips-lcd".into(),
                patches: &patches,
                forward: Some(&forward),
                verification: Some(&v),
            },
            &file,
            &crate::output::OutputPolicy::new(true),
        )
        .unwrap();
        let svg = std::fs::read_to_string(&file).unwrap();
        std::fs::remove_file(&file).unwrap();
        for text in [
            "<svg",
            "tone response (black subtracted)",
            "chromaticity x of each channel against drive",
            "chromaticity y of each channel against drive",
            "ΔE00 of the 48 verification patches: mean 0.00, p95 0.00, max 0.00",
        ] {
            assert!(svg.contains(text), "{text}");
        }
        // One filled bar per verification patch in its own drive colour, e.g. ColorChecker
        // white 9.5 (245, 245, 240).
        assert!(
            svg.contains("#F5F5F0") || svg.contains("rgb(245,245,240)"),
            "white bar"
        );
    }
}
