//! Drawing the report's optional sections as HTML: the display model, the light
//! distribution fit, the renders' confidence, the instruments with their calibrations, the
//! inputs, and what each comparison's intervals contain. They draw what a
//! [`ReportInput`] holds; nothing here reads a file.

use std::fmt::Write;

use crate::validation::assess::Assessment;
use crate::validation::figures::esc;
use crate::validation::readings::UncertaintySource;
use crate::validation::report_data::{
    DisplayModelSection, InputFile, InstrumentUsed, LightFitSection, RenderConfidenceSection,
    ReportInput,
};

fn rows(h: &mut String, rows: &[(String, String)]) {
    h.push_str("<div class=\"scroll\"><table>");
    for (k, v) in rows {
        let _ = write!(
            h,
            "<tr><th class=\"l\">{}</th><td class=\"l\">{}</td></tr>",
            esc(k),
            esc(v)
        );
    }
    h.push_str("</table></div>\n");
}

pub fn display_section(h: &mut String, d: &DisplayModelSection) {
    let _ = writeln!(
        h,
        "<h2 id=\"display-model\">Display model: {}</h2>\n<p>{}</p>",
        esc(&d.model),
        esc(&d.verdict)
    );
    if let Some([mean, p95, max]) = d.verification_de00 {
        let _ = writeln!(
            h,
            "<p id=\"display-verification\">Verification on {} held-out patches: ΔE00 mean {mean:.2}, p95 {p95:.2}, max {max:.2}.</p>",
            d.verification_patches
        );
    }
    rows(h, &d.diagnostics);
}

pub fn light_section(h: &mut String, l: &LightFitSection) {
    h.push_str("<h2 id=\"light-fit\">Light distribution fit</h2>\n");
    rows(h, &l.summary);
    if let Some(svg) = &l.chart_svg {
        let _ = writeln!(
            h,
            "<figure id=\"light-chart\"><div class=\"scroll\">{}</div></figure>",
            inline_svg(svg)
        );
    }
}

/// An SVG document made fit to inline: its XML prolog and doctype dropped, drawn to the
/// page's width. Anything that could run code or load from elsewhere (scripts, event
/// handlers, `javascript:` links, foreign objects, external references) makes the chart
/// refused whole: the page must run nothing and fetch nothing.
pub fn inline_svg(svg: &str) -> String {
    let lower = svg.to_ascii_lowercase();
    let refused = [
        "<script",
        "<foreignobject",
        "javascript:",
        "<iframe",
        "<embed",
        "<object",
    ]
    .iter()
    .any(|t| lower.contains(t))
        || has_handler(&lower)
        || has_external_reference(&lower);
    let Some(start) = lower.find("<svg") else {
        return "<p>(the chart is not an SVG image and is not shown)</p>".into();
    };
    if refused {
        return "<p>(the chart holds scripts or external references and is not shown)</p>".into();
    }
    let body = &svg[start..];
    // Fits the page like the report's own figures, but never so small that its smallest
    // text is under 10 px: below that width it scrolls in its box.
    let min_width = readable_width(body)
        .map(|w| format!(" style=\"min-width:{:.0}px\"", w.ceil()))
        .unwrap_or_default();
    format!("<svg class=\"figure\"{min_width}{}", &body[4..])
}

/// The width at which the SVG `svg` (from its `<svg` on) draws its smallest text at 10 px:
/// its width times 10 over its smallest font size, when it states both.
fn readable_width(svg: &str) -> Option<f64> {
    let tag = &svg[..svg.find('>')?];
    let width = attribute(tag, "width")
        .or_else(|| attribute(tag, "viewBox").and_then(|v| v.split_whitespace().nth(2)))
        .and_then(|w| w.trim_end_matches("px").parse::<f64>().ok())
        .filter(|w| w.is_finite() && *w > 0.0)?;
    let smallest = svg
        .match_indices("font-size")
        .filter_map(|(i, _)| {
            let rest = svg[i + "font-size".len()..].trim_start_matches(['=', ':', ' ', '"', '\'']);
            let end = rest
                .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                .unwrap_or(rest.len());
            rest[..end].parse::<f64>().ok()
        })
        .filter(|f| f.is_finite() && *f > 0.0)
        .fold(f64::INFINITY, f64::min);
    smallest
        .is_finite()
        .then(|| (width * 10.0 / smallest).min(4.0 * width))
}

/// The value of `name="…"` in a start tag.
fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    tag[i..].split('"').next()
}

/// An attribute `on…=` (an event handler) anywhere in the markup.
fn has_handler(lower: &str) -> bool {
    let b = lower.as_bytes();
    (1..b.len().saturating_sub(2)).any(|i| {
        b[i - 1].is_ascii_whitespace() && b[i] == b'o' && b[i + 1] == b'n' && {
            let name_end = b[i + 2..]
                .iter()
                .position(|c| !c.is_ascii_alphabetic())
                .map(|p| i + 2 + p);
            name_end.is_some_and(|e| {
                e > i + 2 && b[e..].iter().find(|c| !c.is_ascii_whitespace()) == Some(&b'=')
            })
        }
    })
}

/// An `href` or `src` that points outside the document (anything but `#fragment`).
fn has_external_reference(lower: &str) -> bool {
    ["href=\"", "href='", "src=\"", "src='"].iter().any(|attr| {
        lower
            .match_indices(attr)
            .any(|(i, _)| !lower[i + attr.len()..].starts_with('#'))
    })
}

pub fn render_section(h: &mut String, r: &RenderConfidenceSection) {
    let mut facts = Vec::new();
    if let Some(t) = r.target_de {
        facts.push(format!("target ΔE*ab {t}"));
    }
    match r.converged {
        Some(true) => facts.push("every patch reached it".into()),
        Some(false) => facts.push("not every patch reached it (time limit)".into()),
        None => {}
    }
    if let Some(s) = r.seconds {
        facts.push(format!("{s:.1} s"));
    }
    let measure = if r.measure.is_empty() {
        "95 % ΔE*ab"
    } else {
        &r.measure
    };
    let _ = writeln!(
        h,
        "<h2 id=\"render-confidence\">Render confidence</h2>\n<p>{}{}</p>",
        esc(&r.method),
        if facts.is_empty() {
            String::new()
        } else {
            format!("; {}", esc(&facts.join(", ")))
        }
    );
    if !r.per_patch.is_empty() {
        let worst = r.per_patch.iter().map(|p| p.1).fold(0.0, f64::max);
        let _ = write!(
            h,
            "<p>Per patch, the render's {} (largest {worst:.3}):</p><div class=\"scroll\"><table>",
            esc(measure)
        );
        // Rows of 12 patches, one ColorChecker row pair each, to fit the page.
        for chunk in r.per_patch.chunks(12) {
            h.push_str("<tr><th>patch</th>");
            for (p, _) in chunk {
                let _ = write!(h, "<th>{p}</th>");
            }
            h.push_str("</tr><tr><td>ΔE*ab</td>");
            for (_, d) in chunk {
                let _ = write!(h, "<td>{d:.3}</td>");
            }
            h.push_str("</tr>");
        }
        h.push_str("</table></div>\n");
    }
}

pub fn instruments_section(h: &mut String, list: &[InstrumentUsed]) {
    h.push_str("<h2 id=\"instruments\">Instruments and calibrations</h2>\n<div class=\"scroll\"><table><tr><th>role</th><th>model</th><th>serial</th><th>firmware</th><th>connection</th><th>calibrations</th></tr>");
    let or_dash = |v: &Option<String>| esc(v.as_deref().unwrap_or("—"));
    for i in list {
        let cal = if i.calibrations.is_empty() {
            "none recorded".to_string()
        } else {
            i.calibrations
                .iter()
                .map(|c| esc(c))
                .collect::<Vec<_>>()
                .join("<br>")
        };
        let _ = write!(
            h,
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{cal}</td></tr>",
            esc(&i.role),
            esc(&i.model),
            or_dash(&i.serial),
            or_dash(&i.firmware),
            or_dash(&i.connection),
        );
    }
    h.push_str("</table></div>\n");
}

pub fn inputs_section(h: &mut String, files: &[InputFile]) {
    h.push_str("<h2 id=\"inputs\">Inputs</h2>\n<div class=\"scroll\"><table><tr><th>role</th><th>file</th><th>format</th><th>patches</th><th>SHA-256</th></tr>");
    for f in files {
        let _ = write!(
            h,
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td class=\"l\"><code>{}</code></td></tr>",
            esc(&f.role),
            esc(&f.path),
            esc(&f.format),
            if f.patches > 0 {
                f.patches.to_string()
            } else {
                "—".into()
            },
            esc(f.sha256.as_deref().unwrap_or("—"))
        );
    }
    h.push_str("</table></div>\n");
}

/// What a side's interval holds when the input does not say: from its readings' sources.
fn described(a: &Assessment, reference: bool) -> String {
    let sides: Vec<(UncertaintySource, usize)> = a
        .patches
        .iter()
        .map(|p| {
            let s = if reference { &p.reference } else { &p.test };
            (s.uncertainty, s.n)
        })
        .collect();
    let mut parts = Vec::new();
    for (source, what) in [
        (
            UncertaintySource::Repeats,
            "the scatter of repeated readings",
        ),
        (
            UncertaintySource::Given,
            "the standard deviations given with the readings",
        ),
        (
            UncertaintySource::Instrument,
            "the instrument's stated repeatability (single readings)",
        ),
        (UncertaintySource::Render, "the renderer's confidence"),
        (
            UncertaintySource::Unknown,
            "nothing (single readings, uncertainty unknown)",
        ),
    ] {
        let n: Vec<usize> = sides
            .iter()
            .filter(|s| s.0 == source)
            .map(|s| s.1)
            .collect();
        if n.is_empty() {
            continue;
        }
        let (lo, hi) = (
            n.iter().copied().min().unwrap_or(0),
            n.iter().copied().max().unwrap_or(0),
        );
        let count = if lo == hi {
            format!("{lo}")
        } else {
            format!("{lo}–{hi}")
        };
        parts.push(format!(
            "{what} ({} patches, {count} readings each)",
            n.len()
        ));
    }
    parts.join("; ")
}

/// One line per comparison: what its intervals contain, side by side.
pub fn uncertainty_section(h: &mut String, input: &ReportInput) {
    let list: Vec<&Assessment> = [
        &input.display_vs_box,
        &input.simulation_vs_box,
        &input.display_vs_simulation,
    ]
    .into_iter()
    .flatten()
    .collect();
    if list.is_empty() {
        return;
    }
    let side = |name: &str, a: &Assessment, reference: bool| {
        input
            .uncertainty
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, d)| d.clone())
            .unwrap_or_else(|| described(a, reference))
    };
    h.push_str("<h2 id=\"uncertainty\">What the intervals contain</h2>\n<ul>");
    for a in list {
        let _ = write!(
            h,
            "<li>{} vs {}: {} — {}; {} — {}.</li>",
            esc(&a.test),
            esc(&a.reference),
            esc(&a.reference),
            esc(&side(&a.reference, a, true)),
            esc(&a.test),
            esc(&side(&a.test, a, false))
        );
    }
    h.push_str("</ul>\n<p>The white is taken as exact (an error in it moves both sides' CIELAB alike). The display's readings are measurements of what it showed: the display model's verification error explains a display-side ΔE, it is not uncertainty of those readings, and is reported with the model.</p>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plain_chart_is_inlined_and_a_dangerous_one_refused() {
        let plain = "<?xml version=\"1.0\"?>\n<svg width=\"10\" height=\"5\"><line x1=\"0\"/><text>on = off</text></svg>";
        let out = inline_svg(plain);
        assert_eq!(
            out,
            "<svg class=\"figure\" width=\"10\" height=\"5\"><line x1=\"0\"/><text>on = off</text></svg>"
        );
        // 1100 wide with 9.677-unit text: 10 px text needs 1100 · 10 / 9.677 = 1136.7 px.
        let small = "<svg width=\"1100\" height=\"480\"><text font-size=\"14.5\">t</text><text font-size=\"9.677\">u</text></svg>";
        assert!(inline_svg(small)
            .starts_with("<svg class=\"figure\" style=\"min-width:1137px\" width="));
        // From the viewBox and a style property when there is no width attribute.
        let styled = "<svg viewBox=\"0 0 400 100\"><text style=\"font-size:8px\">t</text></svg>";
        assert!(inline_svg(styled).contains("min-width:500px"));
        for bad in [
            "<svg><script>x()</script></svg>",
            "<svg><rect onload=\"x()\"/></svg>",
            "<svg><rect ONCLICK = 'x()'/></svg>",
            "<svg><a href=\"javascript:x()\"><text>t</text></a></svg>",
            "<svg><image href=\"http://example.org/a.png\"/></svg>",
            "<svg><foreignObject><div/></foreignObject></svg>",
        ] {
            assert!(inline_svg(bad).contains("is not shown"), "{bad}");
        }
        assert!(inline_svg("<svg><use href=\"#a\"/></svg>").starts_with("<svg class"));
        assert!(inline_svg("not an image").contains("not an SVG"));
    }
}
