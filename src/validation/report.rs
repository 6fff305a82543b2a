//! The validation report: one self-contained HTML page (inline CSS and SVG, no scripts, no
//! network) with the paper's figures, the per-patch table and a verdict, plus the optional
//! sections the experiment pipeline fills (display model, light distribution fit, render
//! confidence, instruments, gamut flags). Each optional section is drawn when present.

use std::fmt::Write;

use serde::{Deserialize, Serialize};

use super::assess::{Assessment, JndVerdict, PatchAssessment};
use super::figures::{delta_e_bars, esc, lab_planes, srgb_swatch};
use super::readings::UncertaintySource;
use super::JND_DE76;

/// Everything a report can show. `box_vs_display` is the paper's result and always there;
/// the rest is drawn when given.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ReportInput {
    pub title: String,
    /// How CIELAB's white was chosen (for the reader).
    pub white_source: String,
    /// Fig. 4 and 5: the box against the display showing the rendering.
    pub box_vs_display: Option<Assessment>,
    /// Fig. 6: the box against the simulation.
    pub box_vs_simulation: Option<Assessment>,
    pub display_vs_simulation: Option<Assessment>,
    pub display_model: Option<DisplayModelSection>,
    pub light_fit: Option<LightFitSection>,
    pub render_confidence: Option<RenderConfidenceSection>,
    pub instruments: Vec<InstrumentUsed>,
    /// 1-based patches whose colour the display cannot show (beyond what the readings say).
    pub out_of_gamut: Vec<usize>,
    /// The input files and what they held.
    pub inputs: Vec<InputFile>,
    pub notes: Vec<String>,
}

/// The display's characterization: the model, its diagnostics and its verification.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DisplayModelSection {
    pub model: String,
    /// The fit's verdict in words ("PLCC's assumptions hold within ΔE00 0.5 …").
    pub verdict: String,
    /// Diagnostics as (what, value) rows.
    pub diagnostics: Vec<(String, String)>,
    /// Held-out verification ΔE00 (mean, p95, max) and the patch count.
    pub verification_de00: Option<[f64; 3]>,
    pub verification_patches: usize,
}

/// The light distribution (LDC) fit.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LightFitSection {
    pub summary: Vec<(String, String)>,
    /// An SVG chart of the fit, drawn inline (scripts are removed).
    pub chart_svg: Option<String>,
}

/// The renderer's confidence.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RenderConfidenceSection {
    pub method: String,
    /// The target 95 % ΔE*ab half-width.
    pub target_de: Option<f64>,
    /// Per patch: (patch, 95 % ΔE*ab half-width or bound).
    pub per_patch: Vec<(usize, f64)>,
}

/// An instrument used, with its calibrations.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InstrumentUsed {
    pub role: String,
    pub model: String,
    pub calibrations: Vec<String>,
}

/// An input file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InputFile {
    pub role: String,
    pub path: String,
    pub format: String,
    pub patches: usize,
}

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
    if let Some(a) = &input.box_vs_display {
        let _ = writeln!(
            h,
            "<p class=\"verdict\" id=\"verdict\">{}</p>",
            verdict(a, &input.out_of_gamut)
        );
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
        h.push_str("<h2 id=\"instruments\">Instruments and calibrations</h2>\n<ul>");
        for i in &input.instruments {
            let _ = write!(h, "<li>{}: {}", esc(&i.role), esc(&i.model));
            if !i.calibrations.is_empty() {
                let list: Vec<String> = i.calibrations.iter().map(|c| esc(c)).collect();
                let _ = write!(h, " — calibrated: {}", list.join("; "));
            }
            h.push_str("</li>");
        }
        h.push_str("</ul>\n");
    }
    if !input.inputs.is_empty() {
        h.push_str("<h2 id=\"inputs\">Inputs</h2>\n<table><tr><th>role</th><th>file</th><th>format</th><th>patches</th></tr>");
        for f in &input.inputs {
            let _ = write!(
                h,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td></tr>",
                esc(&f.role),
                esc(&f.path),
                esc(&f.format),
                f.patches
            );
        }
        h.push_str("</table>\n");
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
        "{} of {} patches below the JND, {} above, {} undecided; ΔE*ab mean {:.2}{} max {:.2}{}; ΔE00 mean {:.2}{} max {:.2}{}.",
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

/// Why a patch may fail, where the input lets us know.
fn reasons(p: &PatchAssessment, out_of_gamut: &[usize]) -> Vec<&'static str> {
    let mut why = Vec::new();
    if p.out_of_gamut || out_of_gamut.contains(&p.patch) {
        why.push("out of the display's gamut");
    }
    let width = p.de76_interval.hi - p.de76_interval.lo;
    if p.reference.lab[0] < 30.0 && width > 1.0 {
        why.push("a dark patch, where the readings' uncertainty is large");
    } else if width > 2.0 {
        why.push("a wide interval: the readings scatter");
    }
    if p.reference.uncertainty == UncertaintySource::Unknown
        || p.test.uncertainty == UncertaintySource::Unknown
    {
        why.push("uncertainty unknown (single readings)");
    }
    why
}

/// The one-paragraph verdict: how many patches pass, which fail or cannot be decided, and
/// why where the input says.
pub fn verdict(a: &Assessment, out_of_gamut: &[usize]) -> String {
    let n = a.patches.len();
    let mut s = format!(
        "{} vs {}: {} of {n} patches are below the JND (ΔE*ab {JND_DE76}) with 95 % confidence, {} above and {} undecided; ΔE*ab mean {:.2}, max {:.2}.",
        esc(&a.test),
        esc(&a.reference),
        a.jnd.below,
        a.jnd.above,
        a.jnd.undecided,
        a.mean_de76.value,
        a.max_de76.value
    );
    for (verdict, label) in [
        (JndVerdict::Above, "Above the JND"),
        (JndVerdict::Undecided, "Undecided"),
    ] {
        let list: Vec<String> = a
            .patches
            .iter()
            .filter(|p| p.jnd == verdict)
            .map(|p| {
                let why = reasons(p, out_of_gamut);
                format!(
                    "{} {} ({:.1} [{:.1}, {:.1}]{})",
                    p.patch,
                    esc(&p.name),
                    p.de76,
                    p.de76_interval.lo,
                    p.de76_interval.hi,
                    if why.is_empty() {
                        String::new()
                    } else {
                        format!("; {}", why.join(", "))
                    }
                )
            })
            .collect();
        if !list.is_empty() {
            let _ = write!(s, " {label}: {}.", list.join("; "));
        }
    }
    if a.jnd.above == 0 && a.jnd.undecided == 0 {
        s.push_str(" Every patch is reproduced within the JND.");
    }
    s
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
        UncertaintySource::Render => "render",
        UncertaintySource::Unknown => "unknown",
    }
}

fn rows(h: &mut String, rows: &[(String, String)]) {
    h.push_str("<table>");
    for (k, v) in rows {
        let _ = write!(
            h,
            "<tr><th class=\"l\">{}</th><td class=\"l\">{}</td></tr>",
            esc(k),
            esc(v)
        );
    }
    h.push_str("</table>\n");
}

fn display_section(h: &mut String, d: &DisplayModelSection) {
    let _ = writeln!(
        h,
        "<h2 id=\"display-model\">Display model: {}</h2>\n<p>{}</p>",
        esc(&d.model),
        esc(&d.verdict)
    );
    if let Some([mean, p95, max]) = d.verification_de00 {
        let _ = writeln!(
            h,
            "<p>Verification on {} held-out patches: ΔE00 mean {mean:.2}, p95 {p95:.2}, max {max:.2}.</p>",
            d.verification_patches
        );
    }
    rows(h, &d.diagnostics);
}

fn light_section(h: &mut String, l: &LightFitSection) {
    h.push_str("<h2 id=\"light-fit\">Light distribution fit</h2>\n");
    rows(h, &l.summary);
    if let Some(svg) = &l.chart_svg {
        let _ = writeln!(h, "<figure>{}</figure>", inline_svg(svg));
    }
}

/// An SVG document made fit to inline: its XML prolog removed; anything scripted is refused
/// (the page must run no code).
fn inline_svg(svg: &str) -> String {
    let lower = svg.to_ascii_lowercase();
    if lower.contains("<script") || has_handler(&lower) {
        return "<p>(the chart holds scripts and is not shown)</p>".into();
    }
    let start = svg.find("<svg").unwrap_or(0);
    svg[start..].to_string()
}

fn has_handler(lower: &str) -> bool {
    ["onload=", "onclick=", "onerror=", "onmouseover="]
        .iter()
        .any(|h| lower.contains(h))
}

fn render_section(h: &mut String, r: &RenderConfidenceSection) {
    let _ = writeln!(
        h,
        "<h2 id=\"render-confidence\">Render confidence</h2>\n<p>{}{}</p>",
        esc(&r.method),
        r.target_de
            .map(|t| format!("; target 95 % ΔE*ab half-width {t}"))
            .unwrap_or_default()
    );
    if !r.per_patch.is_empty() {
        h.push_str("<table><tr><th>patch</th><th>95 % ΔE*ab</th></tr>");
        for (p, d) in &r.per_patch {
            let _ = write!(h, "<tr><td>{p}</td><td>{d:.3}</td></tr>");
        }
        h.push_str("</table>\n");
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
        assert!(bare.contains("2 light skin (") && bare.contains("out of the display's gamut"));
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
