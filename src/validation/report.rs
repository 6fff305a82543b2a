//! The validation report: one self-contained HTML page (inline CSS and SVG, no scripts, no
//! network) with the paper's figures, the per-patch table and a verdict, plus the optional
//! sections the experiment pipeline fills (display model, light distribution fit, render
//! confidence, instruments, gamut flags; [`super::report_sections`]). Each optional section
//! is drawn when present.

use std::fmt::Write;

use super::assess::{Assessment, JND_DE76};
use super::figures::{delta_e_bars, esc, lab_planes, srgb_swatch};
use super::readings::UncertaintySource;
use super::report_sections::{
    display_section, inputs_section, instruments_section, light_section, render_section,
    uncertainty_section,
};
use super::verdict::verdict_paragraph;

pub use super::report_input::{
    DisplayModelSection, InputFile, InstrumentUsed, LightFitSection, RenderConfidenceSection,
    ReportInput,
};

const STYLE: &str = "body{font-family:sans-serif;max-width:1000px;margin:1em auto;padding:0 1em;color:#111;background:#fff}\
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}\
table{border-collapse:collapse;font-size:0.85em}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
th{background:#f0f0f0}td.l{text-align:left}.sw{display:inline-block;width:18px;height:18px;border:1px solid #888;vertical-align:middle}\
.clip{outline:2px dashed #000}.below{color:#2d7a2d}.above{color:#b03020;font-weight:bold}.undecided{color:#b06a00}\
figure{margin:1em 0}figcaption{font-size:0.9em;color:#333}svg.figure{max-width:100%;height:auto}.verdict{background:#f7f7f0;padding:0.6em 1em;border-left:4px solid #999}";

/// The HTML page of `input`.
pub fn render_html(input: &ReportInput) -> String {
    let mut h = String::new();
    let title = if input.title.is_empty() {
        "Validation report"
    } else {
        &input.title
    };
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>",
        esc(title),
        esc(title)
    );
    if let Some(v) = verdict_paragraph(input) {
        let _ = writeln!(h, "<p class=\"verdict\" id=\"verdict\">{v}</p>");
    }
    let _ = writeln!(
        h,
        "<p>CIELAB relative to the white X, Y, Z = {}; {}. ΔE*ab is CIE 1976, ΔE00 CIEDE2000; the JND is ΔE*ab {JND_DE76}. Intervals are 95 %: {}. A patch is <span class=\"below\">below</span> the JND only where its interval's upper end is below {JND_DE76}, <span class=\"above\">above</span> only where the lower end is above; otherwise <span class=\"undecided\">undecided</span>.</p>",
        input
            .box_vs_display
            .as_ref()
            .or(input.box_vs_simulation.as_ref())
            .map(|a| a.white.map(|v| format!("{v:.4}")).join(", "))
            .unwrap_or_default(),
        esc(&input.white_source),
        input
            .box_vs_display
            .as_ref()
            .or(input.box_vs_simulation.as_ref())
            .map(|a| esc(&a.propagation))
            .unwrap_or_default()
    );
    if let Some(a) = &input.box_vs_display {
        figure(
            &mut h,
            &delta_e_bars(
                a,
                "fig4",
                &format!("Fig. 4 — {} vs {}: ΔE*ab per patch", a.test, a.reference),
            ),
            &summary_line(a),
        );
        figure(
            &mut h,
            &lab_planes(a, "fig5", &format!("Fig. 5 — from {} (disc) to {} (arrow head)", a.reference, a.test)),
            "a*b* plane (left) and L*a* plane (right); each disc is the reference reading in its colour.",
        );
    }
    if let Some(a) = &input.box_vs_simulation {
        figure(
            &mut h,
            &delta_e_bars(
                a,
                "fig6",
                &format!("Fig. 6 — {} vs {}: ΔE*ab per patch", a.test, a.reference),
            ),
            &summary_line(a),
        );
    }
    if let Some(a) = &input.display_vs_simulation {
        figure(
            &mut h,
            &delta_e_bars(
                a,
                "fig7",
                &format!("{} vs {}: ΔE*ab per patch", a.test, a.reference),
            ),
            &summary_line(a),
        );
    }
    for a in [
        &input.box_vs_display,
        &input.box_vs_simulation,
        &input.display_vs_simulation,
    ]
    .into_iter()
    .flatten()
    {
        table(&mut h, a);
    }
    uncertainty_section(&mut h, input);
    if let Some(d) = &input.display_model {
        display_section(&mut h, d);
    }
    if let Some(l) = &input.light_fit {
        light_section(&mut h, l);
    }
    if let Some(r) = &input.render_confidence {
        render_section(&mut h, r);
    }
    if !input.instruments.is_empty() {
        instruments_section(&mut h, &input.instruments);
    }
    if !input.inputs.is_empty() {
        inputs_section(&mut h, &input.inputs);
    }
    if !input.notes.is_empty() {
        h.push_str("<h2>Notes</h2>\n<ul>");
        for n in &input.notes {
            let _ = write!(h, "<li>{}</li>", esc(n));
        }
        h.push_str("</ul>\n");
    }
    h.push_str("</body></html>\n");
    h
}

fn figure(h: &mut String, svg: &str, caption: &str) {
    let _ = writeln!(
        h,
        "<figure>{svg}<figcaption>{}</figcaption></figure>",
        esc(caption)
    );
}

fn summary_line(a: &Assessment) -> String {
    let i = |s: &super::assess::Stat| {
        s.interval
            .map(|i| format!(" [{:.2}, {:.2}]", i.lo, i.hi))
            .unwrap_or_default()
    };
    format!(
        "{} of {} patches below the JND at 95 % confidence, {} above, {} undecided; ΔE*ab mean {:.2}{} max {:.2}{}; ΔE00 mean {:.2}{} max {:.2}{}.",
        a.jnd.below,
        a.patches.len(),
        a.jnd.above,
        a.jnd.undecided,
        a.mean_de76.value,
        i(&a.mean_de76),
        a.max_de76.value,
        i(&a.max_de76),
        a.mean_de00.value,
        i(&a.mean_de00),
        a.max_de00.value,
        i(&a.max_de00)
    )
}

fn table(h: &mut String, a: &Assessment) {
    let _ = writeln!(
        h,
        "<h2>{} vs {}: per patch</h2>\n<table class=\"patches\"><tr><th>#</th><th>patch</th><th>{}</th><th>{}</th><th>L*</th><th>a*</th><th>b*</th><th>L*</th><th>a*</th><th>b*</th><th>ΔE*ab</th><th>95 %</th><th>ΔE00</th><th>95 %</th><th>JND</th><th>uncertainty from</th></tr>",
        esc(&a.test),
        esc(&a.reference),
        esc(&a.reference),
        esc(&a.test)
    );
    for p in &a.patches {
        let sw = |lab: [f64; 3]| {
            let c = srgb_swatch(lab);
            format!(
                "<span class=\"sw{}\" style=\"background:{}\" title=\"{}\"></span>",
                if c.clipped { " clip" } else { "" },
                c.hex,
                if c.clipped { "clipped to sRGB" } else { "sRGB" }
            )
        };
        let lab = |l: [f64; 3]| {
            l.iter()
                .map(|v| format!("<td>{v:.2}</td>"))
                .collect::<String>()
        };
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td class=\"l\">{}{}</td><td>{}</td><td>{}</td>{}{}<td>{:.2}</td><td>[{:.2}, {:.2}]</td><td>{:.2}</td><td>[{:.2}, {:.2}]</td><td class=\"{}\">{}</td><td class=\"l\">{} / {}</td></tr>",
            p.patch,
            esc(&p.name),
            if p.out_of_gamut { " (out of gamut)" } else { "" },
            sw(p.reference.lab),
            sw(p.test.lab),
            lab(p.reference.lab),
            lab(p.test.lab),
            p.de76,
            p.de76_interval.lo,
            p.de76_interval.hi,
            p.de00,
            p.de00_interval.lo,
            p.de00_interval.hi,
            p.jnd.name(),
            p.jnd.name(),
            source_name(p.reference.uncertainty),
            source_name(p.test.uncertainty)
        );
    }
    h.push_str("</table>\n");
}

fn source_name(s: UncertaintySource) -> &'static str {
    match s {
        UncertaintySource::Repeats => "repeats",
        UncertaintySource::Given => "given sd",
        UncertaintySource::Instrument => "stated repeatability",
        UncertaintySource::Render => "render",
        UncertaintySource::Unknown => "unknown",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Xyz;
    use crate::validation::assess::{assess, AssessOptions};
    use crate::validation::readings::parse_readings;
    use std::path::Path;

    fn assessment() -> Assessment {
        let r =
            parse_readings("patch,X,Y,Z\n1,10,10,10\n2,40,30,10\n", Path::new("r.csv")).unwrap();
        let t = parse_readings(
            "patch,X,Y,Z,out_of_gamut\n1,10,10,10,0\n2,30,30,20,1\n",
            Path::new("t.csv"),
        )
        .unwrap();
        assess(
            "box",
            &r,
            "display",
            &t,
            Xyz::new(95.0, 100.0, 108.0),
            &AssessOptions::default(),
        )
        .unwrap()
    }

    #[test]
    fn sections_appear_only_when_given() {
        let a = assessment();
        let mut input = ReportInput {
            title: "T <1>".into(),
            box_vs_display: Some(a.clone()),
            ..ReportInput::default()
        };
        let bare = render_html(&input);
        assert!(bare.contains("<h1>T &lt;1&gt;</h1>"));
        assert!(bare.contains("id=\"fig4\"") && bare.contains("id=\"fig5\""));
        assert!(!bare.contains("id=\"fig6\"") && !bare.contains("display-model"));
        assert!(!bare.contains("<script"));
        assert!(bare.contains("outside the display's gamut (2 light skin)"));
        input.box_vs_simulation = Some(a);
        input.display_model = Some(DisplayModelSection {
            model: "lut".into(),
            ..Default::default()
        });
        input.light_fit = Some(LightFitSection {
            summary: vec![("m".into(), "1.3".into())],
            chart_svg: Some("<?xml version=\"1.0\"?><svg><script>x()</script></svg>".into()),
        });
        let full = render_html(&input);
        assert!(full.contains("id=\"fig6\"") && full.contains("Display model: lut"));
        assert!(full.contains("holds scripts") && !full.contains("<script"));
    }
}
