//! The validation report: one self-contained HTML page (inline CSS and SVG, no scripts, no
//! network) drawn from one [`ReportInput`]: the paper's figures, the per-patch table and a
//! verdict, plus the optional sections the experiment fills (display model, light
//! distribution fit, render confidence, instruments, gamut flags; drawn by [`sections`]).
//! Each optional section is drawn when present. What the experiment's stages produced is
//! gathered elsewhere (`experiment::report_input`), into [`Sections`], the one type that
//! crosses from the gathering to the validation.

mod cost;
mod sections;

use std::fmt::Write;

use super::assess::{Assessment, JND_DE76};
use super::figures::{
    decisive, delta_e_bars, delta_e_rows, esc, interval_text, lab_planes, srgb_swatch, MAX_OWN,
    OWN_COLOUR,
};
use super::readings::UncertaintySource;
use super::verdict::verdict_paragraph;
use cost::cost_section;
use sections::{
    display_section, inputs_section, instruments_section, light_section, render_section,
    uncertainty_section,
};

pub use super::report_data::{
    ComparedCost, CostCurve, CostFigures, DisplayModelSection, InputFile, InstrumentUsed,
    LightFitSection, RenderConfidenceSection, RenderUncertainty, ReportInput, Sections, StageCost,
};

/// The page's style: readable from a 390 px phone to print. Text runs at most 1000 px wide,
/// figures and tables to 1148 (an inlined 1100-unit chart with 9.7-unit text fits whole
/// at 10 px on a 1280 px screen). Tables scroll inside their own
/// box, so the page itself never scrolls sideways; each bar chart comes in a wide and a
/// narrow drawing and the page shows the one that keeps its text at 10 px or more (the wide
/// one's smallest text is 12 units in 960, so from 840 px up); in print every figure stays
/// on one page and colours print as shown.
const STYLE: &str = "*{box-sizing:border-box}\
body{font-family:sans-serif;max-width:1180px;margin:1em auto;padding:0 1em;color:#111;background:#fff;line-height:1.35}\
p,ul,h1,h2,figcaption{max-width:1000px}\
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.6em;border-bottom:1px solid #ccc}\
p,li,figcaption{overflow-wrap:anywhere}\
.scroll{overflow-x:auto;max-width:100%}\
table{border-collapse:collapse;font-size:0.85em}table.patches td{white-space:nowrap}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
th{background:#f0f0f0}th.g{text-align:center}td.l,th.l{text-align:left}.sw{display:inline-block;width:18px;height:18px;border:1px solid #888;vertical-align:middle}\
.clip{outline:2px dashed #000}.below{color:#2d7a2d}.above{color:#b03020;font-weight:bold}.undecided{color:#b06a00}\
figure{margin:1.2em 0}figcaption{font-size:0.9em;color:#333;margin-top:0.3em}svg.figure{max-width:100%;height:auto;display:block}\
svg.narrow{display:none;width:100%;max-width:540px;margin:0 auto}\
.planes{display:flex;flex-wrap:wrap;gap:8px;align-items:flex-start}.planes svg.figure{flex:1 1 340px;max-width:480px}\
.key{vertical-align:-2px}\
.verdict{background:#f7f7f0;padding:0.6em 1em;border-left:4px solid #999}\
.sw,svg,.verdict,th{-webkit-print-color-adjust:exact;print-color-adjust:exact}\
@media screen and (max-width:840px){svg.wide{display:none}svg.narrow{display:block}}\
@media screen and (max-width:500px){body{padding:0 8px}h1{font-size:1.3em}}\
@page{margin:12mm}\
@media print{body{max-width:none;margin:0;padding:0;font-size:10pt}figure,.verdict,tr{break-inside:avoid;page-break-inside:avoid}\
h2{break-after:avoid;page-break-after:avoid}.scroll{overflow:visible}.scroll>svg{min-width:0!important}table{font-size:0.8em}td code{word-break:break-all}}";

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
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>",
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
            .display_vs_box
            .as_ref()
            .or(input.simulation_vs_box.as_ref())
            .map(|a| {
                a.white
                    .iter()
                    .map(|v| format!("{v:.4}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            })
            .unwrap_or_default(),
        esc(&input.white_source),
        input
            .display_vs_box
            .as_ref()
            .or(input.simulation_vs_box.as_ref())
            .map(|a| esc(&a.propagation))
            .unwrap_or_default()
    );
    if let Some(a) = &input.display_vs_box {
        bars(
            &mut h,
            a,
            "fig4",
            &format!("Fig. 4 — {} vs {}", a.test, a.reference),
        );
        planes(&mut h, a, "fig5");
    }
    if let Some(a) = &input.simulation_vs_box {
        bars(
            &mut h,
            a,
            "fig6",
            &format!("Fig. 6 — {} vs {}", a.test, a.reference),
        );
    }
    if let Some(a) = &input.display_vs_simulation {
        bars(&mut h, a, "fig7", &format!("{} vs {}", a.test, a.reference));
    }
    for a in [
        &input.display_vs_box,
        &input.simulation_vs_box,
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
    if !input.measuring_cost.is_empty() {
        cost_section(&mut h, input);
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

/// A bar chart in its wide and narrow drawing; the caption opens with the figure's number
/// ("Fig. 4."), or its head where it has none.
fn bars(h: &mut String, a: &Assessment, id: &str, head: &str) {
    // "Fig. 4" of "Fig. 4 — display vs box"; a figure without a number is led by its head.
    let lead = head.split(" — ").next().unwrap_or(head);
    let _ = writeln!(
        h,
        "<figure id=\"{id}-figure\">{}{}<figcaption><b>{}.</b> {}</figcaption></figure>",
        delta_e_bars(a, id, head),
        delta_e_rows(a, &format!("{id}-rows"), head),
        esc(lead),
        esc(&summary_line(a))
    );
}

/// Fig. 5 with a caption that names every mark.
fn planes(h: &mut String, a: &Assessment, id: &str) {
    let f = lab_planes(a, id);
    let m = super::figures::trim(f.magnification);
    let disc = "<svg class=\"key\" width=\"12\" height=\"12\" viewBox=\"0 0 12 12\" aria-hidden=\"true\"><circle cx=\"6\" cy=\"6\" r=\"5\" fill=\"#c8a060\" stroke=\"#666\"/></svg>";
    let ring = "<svg class=\"key\" width=\"12\" height=\"12\" viewBox=\"0 0 12 12\" aria-hidden=\"true\"><circle cx=\"6\" cy=\"6\" r=\"3.4\" fill=\"none\" stroke=\"#000\" stroke-width=\"1.4\"/></svg>";
    let mut caption = format!(
        "<b>Fig. 5.</b> {test} vs {reference} in CIELAB: the a*b* plane and the L*a* plane, on one scale. {disc} {reference}'s reading of each patch, in its colour (for an sRGB screen with the display's white as white; a dashed outline marks a colour clipped to fit sRGB). {ring} {test}'s reading, at the end of the line from the disc: the displacement from {reference} to {test} is drawn ×{m}, the same in both planes; the bar in the corner is the JND (ΔE*ab {JND_DE76}) at ×{m}. Numbers are the ColorChecker patches, set off with a grey line where their disc is crowded.",
        test = esc(&a.test),
        reference = esc(&a.reference),
    );
    let own: Vec<String> = f
        .own
        .iter()
        .filter(|(_, v)| !v.is_empty())
        .map(|(plane, v)| {
            format!(
                "{plane} plane {}",
                v.iter()
                    .map(|(p, k)| format!("{p} ×{}", super::figures::trim(*k)))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    if !own.is_empty() {
        let blue = format!("<svg class=\"key\" width=\"12\" height=\"12\" viewBox=\"0 0 12 12\" aria-hidden=\"true\"><circle cx=\"6\" cy=\"6\" r=\"3.4\" fill=\"none\" stroke=\"{OWN_COLOUR}\" stroke-width=\"1.4\"/></svg>");
        let _ = write!(
            caption,
            " {blue} In blue, a displacement under {:.2} in the plane, too short to see at ×{m}, drawn at a magnification of its own (the least of 1, 2, 5, 10, … that shows it): {}.",
            f.floor,
            own.join("; ")
        );
    }
    let short: Vec<String> = f
        .unresolved
        .iter()
        .filter(|(_, v)| !v.is_empty())
        .map(|(plane, v)| {
            format!(
                "{} in the {plane} plane",
                v.iter()
                    .map(|p| p.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    if !short.is_empty() {
        let named: Vec<usize> = {
            let mut v: Vec<usize> = f.unresolved.iter().flat_map(|(_, v)| v.clone()).collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let de: Vec<String> = named
            .iter()
            .filter_map(|k| a.patches.iter().find(|p| p.patch == *k))
            .map(|p| format!("{:.2} ({})", p.de76, p.patch))
            .collect();
        let _ = write!(
            caption,
            " A displacement too short to draw even at ×{MAX_OWN} is drawn shorter than the ring's radius, so the ring sits on its disc: {}; their ΔE*ab are {}.",
            short.join("; "),
            de.join(", ")
        );
    }
    let _ = writeln!(
        h,
        "<figure id=\"{id}-figure\">{}<figcaption>{caption}</figcaption></figure>",
        f.html
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
    let (r, t) = (esc(&a.reference), esc(&a.test));
    let _ = writeln!(
        h,
        "<h2>{t} vs {r}: per patch</h2>\n<div class=\"scroll\"><table class=\"patches\"><thead><tr><th rowspan=\"2\">#</th><th rowspan=\"2\" class=\"l\">patch</th><th colspan=\"2\" class=\"g\">colour</th><th colspan=\"3\" class=\"g\">{r}</th><th colspan=\"3\" class=\"g\">{t}</th><th colspan=\"2\" class=\"g\">ΔE*ab</th><th colspan=\"2\" class=\"g\">ΔE00</th><th rowspan=\"2\">JND</th><th rowspan=\"2\" class=\"l\">uncertainty from<br>{r} / {t}</th></tr>\n<tr><th>{r}</th><th>{t}</th><th>L*</th><th>a*</th><th>b*</th><th>L*</th><th>a*</th><th>b*</th><th>value</th><th>95 %</th><th>value</th><th>95 %</th></tr></thead><tbody>"
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
            "<tr><td>{}</td><td class=\"l\">{}{}</td><td>{}</td><td>{}</td>{}{}<td>{}</td><td>{}</td><td>{:.2}</td><td>[{:.2}, {:.2}]</td><td class=\"{}\">{}</td><td class=\"l\">{} / {}</td></tr>",
            p.patch,
            esc(&p.name),
            if p.out_of_gamut { " (out of gamut)" } else { "" },
            sw(p.reference.lab),
            sw(p.test.lab),
            lab(p.reference.lab),
            lab(p.test.lab),
            decisive(p.de76, JND_DE76),
            interval_text(p.de76_interval.lo, p.de76_interval.hi, JND_DE76),
            p.de00,
            p.de00_interval.lo,
            p.de00_interval.hi,
            p.jnd.name(),
            p.jnd.name(),
            source_name(p.reference.uncertainty),
            source_name(p.test.uncertainty)
        );
    }
    h.push_str("</tbody></table></div>\n");
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
            display_vs_box: Some(a.clone()),
            ..ReportInput::default()
        };
        let bare = render_html(&input);
        assert!(bare.contains("<h1>T &lt;1&gt;</h1>"));
        assert!(bare.contains("id=\"fig4\"") && bare.contains("id=\"fig5\""));
        assert!(!bare.contains("id=\"fig6\"") && !bare.contains("display-model"));
        assert!(!bare.contains("<script"));
        assert!(bare.contains("outside the display's gamut (2 light skin)"));
        input.simulation_vs_box = Some(a);
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
