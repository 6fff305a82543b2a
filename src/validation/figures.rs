//! The report's figures as inline SVG text: the paper's Fig. 4/6 (ΔE*ab per patch with
//! error bars and the JND line) and Fig. 5 (a*b* and L*a* planes with an arrow from each
//! reference reading to its test reading), and the patch swatches in sRGB.
//!
//! Hand-written SVG rather than a plotting library: the figures go inline into one HTML
//! file, need ids unique within it, and must not depend on fonts or scripts.

use std::fmt::Write;

use crate::color::{Lab, Xyz};

use super::assess::JND_DE76;
use super::assess::{Assessment, JndVerdict};

/// Escapes text for HTML and SVG.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A colour for an sRGB screen, and whether it had to be clipped to fit.
#[derive(Clone, Debug, PartialEq)]
pub struct Swatch {
    /// `#rrggbb`.
    pub hex: String,
    pub clipped: bool,
}

/// A channel may leave [0, 1] by this much before the colour counts as clipped: the
/// matrix's rounding makes the white itself 1.0002 or so.
const CLIP_TOLERANCE: f64 = 2e-3;

/// The sRGB colour of `lab` (CIELAB relative to the display's white), shown with that white
/// as the screen's white: Lab → XYZ relative to D65 → sRGB (IEC 61966-2-1). The swap of
/// whites is how CIELAB itself adapts (a von Kries scaling in XYZ), so the display's white
/// is drawn as white.
pub fn srgb_swatch(lab: [f64; 3]) -> Swatch {
    const D65: Xyz = Xyz::new(0.950_47, 1.0, 1.088_83);
    const M: [[f64; 3]; 3] = [
        [3.2406, -1.5372, -0.4986],
        [-0.9689, 1.8758, 0.0415],
        [0.0557, -0.2040, 1.0570],
    ];
    let xyz = Lab::new(lab[0], lab[1], lab[2]).to_xyz(D65).to_array();
    let linear = M.map(|row| row.iter().zip(xyz).map(|(m, v)| m * v).sum::<f64>());
    let clipped = linear
        .iter()
        .any(|v| !(-CLIP_TOLERANCE..=1.0 + CLIP_TOLERANCE).contains(v));
    let enc = |v: f64| {
        let v = v.clamp(0.0, 1.0);
        let s = if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round() as u8
    };
    let [r, g, b] = linear.map(enc);
    Swatch {
        hex: format!("#{r:02x}{g:02x}{b:02x}"),
        clipped,
    }
}

fn verdict_colour(v: JndVerdict) -> &'static str {
    match v {
        JndVerdict::Below => "#3a8f3a",
        JndVerdict::Above => "#c0392b",
        JndVerdict::Undecided => "#d68910",
    }
}

/// A "nice" tick step for a range of `span` with about `n` ticks.
fn tick_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-9);
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    mag * if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// Most ticks on an axis; a readable axis has a dozen.
const MAX_TICKS: usize = 100;

/// Tick values from `start` by `step` up to `end`: none when the range is not finite, and
/// at most [`MAX_TICKS`], so an infinite bound or a step lost to rounding beside a huge one
/// cannot loop (and write SVG) without end.
fn ticks(start: f64, end: f64, step: f64) -> Vec<f64> {
    let mut out = Vec::new();
    if !(start.is_finite() && end.is_finite() && step.is_finite() && step > 0.0) {
        return out;
    }
    let mut v = start;
    while v <= end && out.len() < MAX_TICKS {
        out.push(v);
        v += step;
    }
    out
}

/// Fig. 4 (and 6): ΔE*ab per patch as bars coloured by the JND verdict, the 95 % interval
/// as an error bar, ΔE00 as a dot, the JND line, colours outside the display's gamut on a
/// grey band, and under each bar the two readings' swatches (reference above, test below).
/// `id` makes the figure's element ids unique in the page.
pub fn delta_e_bars(a: &Assessment, id: &str, title: &str) -> String {
    let (w, h) = (960.0, 430.0);
    let (left, right, top, bottom) = (56.0, 16.0, 40.0, 110.0);
    let n = a.patches.len().max(1) as f64;
    let ymax = a
        .patches
        .iter()
        .map(|p| p.de76_interval.hi.max(p.de76).max(p.de00))
        .fold(JND_DE76 * 1.5, f64::max)
        * 1.08;
    let pw = w - left - right;
    let ph = h - top - bottom;
    let x_of = |i: usize| left + pw * (i as f64 + 0.5) / n;
    let y_of = |v: f64| top + ph * (1.0 - v / ymax);
    let slot = pw / n;
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" id="{id}" class="figure" viewBox="0 0 {w} {h}" width="{w}" height="{h}" role="img" aria-label="{t}"><title>{t}</title>"#,
        t = esc(title)
    );
    let _ = write!(
        s,
        r##"<rect x="0" y="0" width="{w}" height="{h}" fill="#ffffff"/><text x="{}" y="22" text-anchor="middle" font-size="16" font-family="sans-serif">{}</text>"##,
        w / 2.0,
        esc(title)
    );
    for (i, p) in a.patches.iter().enumerate() {
        if p.out_of_gamut {
            let _ = write!(
                s,
                r##"<rect class="oog" x="{:.1}" y="{top}" width="{:.1}" height="{ph}" fill="#d9d9d9"/>"##,
                x_of(i) - slot / 2.0,
                slot
            );
        }
    }
    let step = tick_step(ymax, 6.0);
    for v in ticks(0.0, ymax, step) {
        let y = y_of(v);
        let _ = write!(
            s,
            r##"<line x1="{left}" x2="{}" y1="{y:.1}" y2="{y:.1}" stroke="#e4e4e4"/><text x="{}" y="{:.1}" text-anchor="end" font-size="11" font-family="sans-serif">{}</text>"##,
            w - right,
            left - 6.0,
            y + 4.0,
            trim(v)
        );
    }
    let bw = slot * 0.55;
    for (i, p) in a.patches.iter().enumerate() {
        let x = x_of(i);
        let _ = write!(
            s,
            r#"<rect class="bar" x="{:.1}" y="{:.1}" width="{bw:.1}" height="{:.1}" fill="{}"><title>{} {}: ΔE*ab {:.2} [{:.2}, {:.2}], ΔE00 {:.2}, {}</title></rect>"#,
            x - bw / 2.0,
            y_of(p.de76),
            y_of(0.0) - y_of(p.de76),
            verdict_colour(p.jnd),
            p.patch,
            esc(&p.name),
            p.de76,
            p.de76_interval.lo,
            p.de76_interval.hi,
            p.de00,
            p.jnd.name()
        );
        let (lo, hi) = (y_of(p.de76_interval.lo), y_of(p.de76_interval.hi));
        let _ = write!(
            s,
            r##"<path class="errorbar" d="M{x:.1},{lo:.1}V{hi:.1}M{:.1},{lo:.1}h{:.1}M{:.1},{hi:.1}h{:.1}" stroke="#222" stroke-width="1.2" fill="none"/>"##,
            x - 4.0,
            8.0,
            x - 4.0,
            8.0
        );
        let _ = write!(
            s,
            r##"<circle cx="{x:.1}" cy="{:.1}" r="3" fill="#1f4e9c"/>"##,
            y_of(p.de00)
        );
        let _ = write!(
            s,
            r#"<text x="{x:.1}" y="{:.1}" text-anchor="middle" font-size="11" font-family="sans-serif">{}</text>"#,
            y_of(0.0) + 14.0,
            p.patch
        );
        let sw = slot * 0.8;
        for (k, side) in [&p.reference, &p.test].into_iter().enumerate() {
            let c = srgb_swatch(side.lab);
            let y = y_of(0.0) + 20.0 + k as f64 * sw;
            let _ = write!(
                s,
                r##"<rect class="swatch" x="{:.1}" y="{y:.1}" width="{sw:.1}" height="{sw:.1}" fill="{}" stroke="#888" stroke-width="0.5"/>"##,
                x - sw / 2.0,
                c.hex
            );
            if c.clipped {
                let _ = write!(
                    s,
                    r##"<path class="clipped" d="M{:.1},{y:.1}l{sw:.1},{sw:.1}" stroke="#000" stroke-width="1"/>"##,
                    x - sw / 2.0
                );
            }
        }
    }
    let jy = y_of(JND_DE76);
    let _ = write!(
        s,
        r##"<line class="jnd" x1="{left}" x2="{}" y1="{jy:.1}" y2="{jy:.1}" stroke="#000" stroke-dasharray="6 4" stroke-width="1.3"/><text x="{}" y="{:.1}" text-anchor="end" font-size="11" font-family="sans-serif">JND {JND_DE76}</text>"##,
        w - right,
        w - right - 4.0,
        jy - 4.0
    );
    let _ = write!(
        s,
        r##"<line x1="{left}" x2="{left}" y1="{top}" y2="{:.1}" stroke="#000"/><line x1="{left}" x2="{}" y1="{:.1}" y2="{:.1}" stroke="#000"/><text transform="translate(16,{:.1}) rotate(-90)" text-anchor="middle" font-size="12" font-family="sans-serif">ΔE*ab (bar, 95 % interval) · ΔE00 (dot)</text>"##,
        y_of(0.0),
        w - right,
        y_of(0.0),
        y_of(0.0),
        top + ph / 2.0
    );
    let legend_y = h - 12.0;
    let mut lx = left;
    for (label, colour) in [
        ("below the JND", verdict_colour(JndVerdict::Below)),
        ("above", verdict_colour(JndVerdict::Above)),
        ("undecided", verdict_colour(JndVerdict::Undecided)),
        ("out of the display's gamut", "#d9d9d9"),
    ] {
        let _ = write!(
            s,
            r#"<rect x="{lx}" y="{}" width="12" height="10" fill="{colour}"/><text x="{}" y="{legend_y}" font-size="11" font-family="sans-serif">{label}</text>"#,
            legend_y - 9.0,
            lx + 16.0
        );
        lx += 22.0 + 6.5 * label.chars().count() as f64;
    }
    let _ = write!(
        s,
        r#"<text x="{lx}" y="{legend_y}" font-size="11" font-family="sans-serif">swatches: {} above, {} below; a diagonal marks a clipped colour</text>"#,
        esc(&a.reference),
        esc(&a.test)
    );
    s.push_str("</svg>");
    s
}

fn trim(v: f64) -> String {
    let t = format!("{v:.2}");
    t.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Fig. 5: the a*b* plane and the L*a* plane side by side, each reference reading a disc in
/// its colour with an arrow to the test reading.
pub fn lab_planes(a: &Assessment, id: &str, title: &str) -> String {
    let (w, h) = (960.0, 500.0);
    let mut s = String::new();
    let _ = write!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" id="{id}" class="figure" viewBox="0 0 {w} {h}" width="{w}" height="{h}" role="img" aria-label="{t}"><title>{t}</title><defs><marker id="{id}-arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" orient="auto-start-reverse"><path d="M0,0L10,5L0,10z" fill="#222"/></marker></defs><rect x="0" y="0" width="{w}" height="{h}" fill="#ffffff"/><text x="{}" y="22" text-anchor="middle" font-size="16" font-family="sans-serif">{t}</text>"##,
        w / 2.0,
        t = esc(title)
    );
    let pts = |f: fn([f64; 3]) -> (f64, f64)| -> Vec<Arrow> {
        a.patches
            .iter()
            .map(|p| (f(p.reference.lab), f(p.test.lab)))
            .collect()
    };
    let ab = pts(|l| (l[1], l[2]));
    let la = pts(|l| (l[1], l[0]));
    plane(
        &mut s,
        a,
        id,
        &ab,
        (40.0, 40.0, 420.0, 420.0),
        "a*",
        "b*",
        None,
    );
    plane(
        &mut s,
        a,
        id,
        &la,
        (520.0, 40.0, 420.0, 420.0),
        "a*",
        "L*",
        Some((0.0, 100.0)),
    );
    s.push_str("</svg>");
    s
}

/// From a reference point to a test point in one plane.
type Arrow = ((f64, f64), (f64, f64));

/// One plane of [`lab_planes`] in the box `(x, y, w, h)`; `y_range` fixes the vertical axis
/// (L* is 0–100), otherwise both axes share one symmetric range so hues keep their angles.
#[allow(clippy::too_many_arguments)]
fn plane(
    s: &mut String,
    a: &Assessment,
    id: &str,
    pts: &[Arrow],
    (bx, by, bw, bh): (f64, f64, f64, f64),
    xlabel: &str,
    ylabel: &str,
    y_range: Option<(f64, f64)>,
) {
    let extent = pts
        .iter()
        .flat_map(|&((x0, y0), (x1, y1))| {
            let mut v = vec![x0.abs(), x1.abs()];
            if y_range.is_none() {
                v.extend([y0.abs(), y1.abs()]);
            }
            v
        })
        .fold(10.0, f64::max)
        * 1.1;
    let (xmin, xmax) = (-extent, extent);
    let (ymin, ymax) = y_range.unwrap_or((-extent, extent));
    let (pl, pb) = (36.0, 30.0);
    let (pw, ph) = (bw - pl, bh - pb);
    let px = |v: f64| bx + pl + pw * (v - xmin) / (xmax - xmin);
    let py = |v: f64| by + ph * (1.0 - (v - ymin) / (ymax - ymin));
    let _ = write!(
        s,
        r##"<rect x="{:.1}" y="{by}" width="{pw}" height="{ph}" fill="#fafafa" stroke="#000"/>"##,
        bx + pl
    );
    let step = tick_step(xmax - xmin, 6.0);
    for v in ticks((xmin / step).ceil() * step, xmax, step) {
        let _ = write!(
            s,
            r##"<line x1="{x:.1}" x2="{x:.1}" y1="{by}" y2="{:.1}" stroke="{}"/><text x="{x:.1}" y="{:.1}" text-anchor="middle" font-size="10" font-family="sans-serif">{}</text>"##,
            by + ph,
            if v == 0.0 { "#999" } else { "#e4e4e4" },
            by + ph + 13.0,
            trim(v),
            x = px(v)
        );
    }
    let step = tick_step(ymax - ymin, 6.0);
    for v in ticks((ymin / step).ceil() * step, ymax, step) {
        let _ = write!(
            s,
            r##"<line x1="{:.1}" x2="{:.1}" y1="{y:.1}" y2="{y:.1}" stroke="{}"/><text x="{:.1}" y="{:.1}" text-anchor="end" font-size="10" font-family="sans-serif">{}</text>"##,
            bx + pl,
            bx + pl + pw,
            if v == 0.0 && y_range.is_none() {
                "#999"
            } else {
                "#e4e4e4"
            },
            bx + pl - 4.0,
            py(v) + 3.0,
            trim(v),
            y = py(v)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="12" font-family="sans-serif">{xlabel}</text><text transform="translate({:.1},{:.1}) rotate(-90)" text-anchor="middle" font-size="12" font-family="sans-serif">{ylabel}</text>"#,
        bx + pl + pw / 2.0,
        by + bh - 2.0,
        bx + 8.0,
        by + ph / 2.0
    );
    for (p, &((x0, y0), (x1, y1))) in a.patches.iter().zip(pts) {
        let c = srgb_swatch(p.reference.lab);
        let _ = write!(
            s,
            r##"<g class="patch"><title>{} {}: {} ({:.1}, {:.1}) → {} ({:.1}, {:.1})</title><line class="arrow" x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#222" stroke-width="1.2" marker-end="url(#{id}-arrow)"/><circle cx="{:.1}" cy="{:.1}" r="6" fill="{}" stroke="{}" stroke-width="{}"/><text x="{:.1}" y="{:.1}" font-size="9" font-family="sans-serif">{}</text></g>"##,
            p.patch,
            esc(&p.name),
            esc(&a.reference),
            x0,
            y0,
            esc(&a.test),
            x1,
            y1,
            px(x0),
            py(y0),
            px(x1),
            py(y1),
            px(x0),
            py(y0),
            c.hex,
            if c.clipped { "#000" } else { "#666" },
            if c.clipped { 2 } else { 1 },
            px(x0) + 7.0,
            py(y0) - 5.0,
            p.patch
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_axis_of_unbounded_or_huge_range_has_few_ticks_and_ends() {
        assert_eq!(ticks(0.0, 1.0, 0.25), [0.0, 0.25, 0.5, 0.75, 1.0]);
        // An infinite maximum once made `v += step` stay at inf, writing SVG forever.
        assert!(ticks(0.0, f64::INFINITY, tick_step(f64::INFINITY, 6.0)).is_empty());
        assert!(ticks(f64::NAN, 1.0, 0.1).is_empty());
        // A step lost to rounding beside a huge start never moves v.
        assert_eq!(ticks(1e300, 2e300, 1.0).len(), MAX_TICKS);
    }

    #[test]
    fn swatches_of_white_black_and_an_impossible_colour() {
        assert_eq!(
            srgb_swatch([100.0, 0.0, 0.0]),
            Swatch {
                hex: "#ffffff".into(),
                clipped: false
            }
        );
        assert_eq!(srgb_swatch([0.0, 0.0, 0.0]).hex, "#000000");
        // L* 50 neutral: Y = 0.18418652, sRGB-encoded 1.055·Y^(1/2.4) − 0.055 = 0.46635
        // → 119 (0x77).
        assert_eq!(srgb_swatch([50.0, 0.0, 0.0]).hex, "#777777");
        // A green far beyond sRGB's primaries.
        assert!(srgb_swatch([60.0, -120.0, 60.0]).clipped);
        assert_eq!(esc("<a&\"b\">"), "&lt;a&amp;&quot;b&quot;&gt;");
    }
}
