//! Fig. 4 (and 6): ΔE*ab per patch as bars coloured by the JND verdict, the 95 % interval
//! as an error bar, ΔE00 as a dot, the JND line, colours outside the display's gamut on a
//! grey band, and each patch's two readings as swatches. Two drawings of the same data:
//! [`delta_e_bars`] with vertical bars for a wide page and print, [`delta_e_rows`] with one
//! row per patch for a phone, where 24 bars side by side would need text too small to
//! read. The page shows one or the other by its width; the wide one is also each
//! comparison's chart file beside its CSV (the experiment's `display_vs_box.svg`, …).

use std::fmt::Write;

use super::{esc, srgb_swatch, tick_step, ticks, trim, verdict_colour};
use crate::validation::assess::{Assessment, JndVerdict, PatchAssessment, JND_DE76};

/// What the figures' titles say after their head.
const WHAT: &str = "ΔE*ab and ΔE00 per patch (CIELAB units)";

const OOG_GREY: &str = "#d9d9d9";

/// The legend's colour keys.
fn keys() -> [(&'static str, &'static str); 4] {
    [
        ("below the JND", verdict_colour(JndVerdict::Below)),
        ("above", verdict_colour(JndVerdict::Above)),
        ("undecided", verdict_colour(JndVerdict::Undecided)),
        ("outside the display's gamut", OOG_GREY),
    ]
}

/// The largest value drawn: interval ends, ΔE*ab, ΔE00, and room above the JND.
fn top(a: &Assessment) -> f64 {
    a.patches
        .iter()
        .flat_map(|p| [p.de76_interval.hi, p.de76, p.de00])
        .filter(|v| v.is_finite())
        .fold(JND_DE76 * 1.5, f64::max)
        * 1.08
}

fn bar_title(p: &PatchAssessment) -> String {
    format!(
        "<title>{} {}: ΔE*ab {:.2} [{:.2}, {:.2}], ΔE00 {:.2}, {}</title>",
        p.patch,
        esc(&p.name),
        p.de76,
        p.de76_interval.lo,
        p.de76_interval.hi,
        p.de00,
        p.jnd.name()
    )
}

/// A swatch of `lab` `size` square at (x, y), with a diagonal where the colour was clipped.
fn swatch(s: &mut String, lab: [f64; 3], x: f64, y: f64, size: f64) {
    let c = srgb_swatch(lab);
    let _ = write!(
        s,
        r##"<rect class="swatch" x="{x:.1}" y="{y:.1}" width="{size:.1}" height="{size:.1}" fill="{}" stroke="#888" stroke-width="0.5"/>"##,
        c.hex
    );
    if c.clipped {
        let _ = write!(
            s,
            r##"<path class="clipped" d="M{x:.1},{y:.1}l{size:.1},{size:.1}" stroke="#000" stroke-width="1"/>"##
        );
    }
}

fn open_svg(s: &mut String, id: &str, class: &str, w: f64, h: f64, title: &str) {
    let _ = write!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" id="{id}" class="figure {class}" viewBox="0 0 {w} {h}" width="{w}" height="{h}" role="img" aria-label="{t}"><title>{t}</title><rect x="0" y="0" width="{w}" height="{h}" fill="#ffffff"/>"##,
        t = esc(title)
    );
}

/// The wide drawing (960 user units; text 12 or more, so 10 px from 800 px wide);
/// `head` starts its title ("Fig. 4 — display vs box").
pub fn delta_e_bars(a: &Assessment, id: &str, head: &str) -> String {
    let (w, h) = (960.0, 456.0);
    // The right margin holds the JND line's label, clear of the bars.
    let (left, right, top_y, ph) = (62.0, 56.0, 44.0, 280.0);
    let n = a.patches.len().max(1) as f64;
    let ymax = top(a);
    let pw = w - left - right;
    let x_of = |i: usize| left + pw * (i as f64 + 0.5) / n;
    let y_of = |v: f64| top_y + ph * (1.0 - v / ymax);
    let slot = pw / n;
    let title = format!("{head}: {WHAT}");
    let mut s = String::new();
    open_svg(&mut s, id, "wide", w, h, &title);
    let _ = write!(
        s,
        r#"<text x="{}" y="24" text-anchor="middle" font-size="17" font-family="sans-serif">{}</text>"#,
        w / 2.0,
        esc(&title)
    );
    for (i, p) in a.patches.iter().enumerate() {
        if p.out_of_gamut {
            let _ = write!(
                s,
                r#"<rect class="oog" x="{:.1}" y="{top_y}" width="{:.1}" height="{ph}" fill="{OOG_GREY}"/>"#,
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
            r##"<line x1="{left}" x2="{}" y1="{y:.1}" y2="{y:.1}" stroke="#e4e4e4"/><text x="{}" y="{:.1}" text-anchor="end" font-size="12" font-family="sans-serif">{}</text>"##,
            w - right,
            left - 6.0,
            y + 4.0,
            trim(v)
        );
    }
    let bw = slot * 0.55;
    let base = y_of(0.0);
    for (i, p) in a.patches.iter().enumerate() {
        let x = x_of(i);
        let _ = write!(
            s,
            r#"<rect class="bar" data-patch="{}" x="{:.1}" y="{:.1}" width="{bw:.1}" height="{:.1}" fill="{}">{}</rect>"#,
            p.patch,
            x - bw / 2.0,
            y_of(p.de76),
            base - y_of(p.de76),
            verdict_colour(p.jnd),
            bar_title(p)
        );
        let (lo, hi) = (y_of(p.de76_interval.lo), y_of(p.de76_interval.hi));
        let _ = write!(
            s,
            r##"<path class="errorbar" d="M{x:.1},{lo:.1}V{hi:.1}M{:.1},{lo:.1}h8M{:.1},{hi:.1}h8" stroke="#222" stroke-width="1.2" fill="none"/><circle cx="{x:.1}" cy="{:.1}" r="3" fill="#1f4e9c"/><text x="{x:.1}" y="{:.1}" text-anchor="middle" font-size="12" font-family="sans-serif">{}</text>"##,
            x - 4.0,
            x - 4.0,
            y_of(p.de00),
            base + 15.0,
            p.patch
        );
        let sw = slot * 0.8;
        swatch(&mut s, p.reference.lab, x - sw / 2.0, base + 21.0, sw);
        swatch(&mut s, p.test.lab, x - sw / 2.0, base + 21.0 + sw, sw);
    }
    let jy = y_of(JND_DE76);
    let _ = write!(
        s,
        r##"<line class="jnd" x1="{left}" x2="{}" y1="{jy:.1}" y2="{jy:.1}" stroke="#000" stroke-dasharray="6 4" stroke-width="1.3"/><text x="{}" y="{:.1}" font-size="12" font-family="sans-serif">JND {JND_DE76}</text>"##,
        w - right,
        w - right + 4.0,
        jy + 4.0
    );
    let _ = write!(
        s,
        r##"<line x1="{left}" x2="{left}" y1="{top_y}" y2="{base:.1}" stroke="#000"/><line x1="{left}" x2="{}" y1="{base:.1}" y2="{base:.1}" stroke="#000"/><text transform="translate(18,{:.1}) rotate(-90)" text-anchor="middle" font-size="13" font-family="sans-serif">ΔE (CIELAB units)</text>"##,
        w - right,
        top_y + ph / 2.0
    );
    wide_legend(&mut s, a, left, h - 30.0);
    s.push_str("</svg>");
    s
}

/// The wide drawing's legend in one row at `legend_y` from `left`, and what its marks say
/// below it.
fn wide_legend(s: &mut String, a: &Assessment, left: f64, legend_y: f64) {
    let mut lx = left;
    for (label, colour) in keys() {
        let _ = write!(
            s,
            r#"<rect x="{lx}" y="{}" width="12" height="11" fill="{colour}"/><text x="{}" y="{legend_y}" font-size="12" font-family="sans-serif">{label}</text>"#,
            legend_y - 10.0,
            lx + 16.0
        );
        lx += 30.0 + 7.5 * label.chars().count() as f64;
    }
    let _ = write!(
        s,
        r#"<text x="{left}" y="{}" font-size="12" font-family="sans-serif">bar: ΔE*ab with its 95 % interval · dot: ΔE00 · swatches: {} above, {} below; a diagonal marks a colour clipped to sRGB</text>"#,
        legend_y + 18.0,
        esc(&a.reference),
        esc(&a.test)
    );
}

/// The narrow drawing: one row per patch (360 user units wide, text 11 or more, so 10 px
/// from 330 px wide).
pub fn delta_e_rows(a: &Assessment, id: &str, head: &str) -> String {
    let w = 360.0;
    let (x0, x1) = (58.0, 346.0);
    let (axis_y, rows_y, row) = (60.0, 66.0, 17.0);
    let n = a.patches.len() as f64;
    let rows_end = rows_y + row * n;
    let legend_y = rows_end + 36.0;
    let h = (legend_y + 4.0 * 15.0 - 4.0).round();
    let xmax = top(a);
    let x_of = |v: f64| x0 + (x1 - x0) * v / xmax;
    let title = format!("{head}: {WHAT}");
    let mut s = String::new();
    open_svg(&mut s, id, "narrow", w, h, &title);
    let _ = write!(
        s,
        r#"<text x="{}" y="17" text-anchor="middle" font-size="14" font-family="sans-serif">{}</text><text x="{}" y="35" text-anchor="middle" font-size="12" font-family="sans-serif">{WHAT}</text>"#,
        w / 2.0,
        esc(head),
        w / 2.0
    );
    for (i, p) in a.patches.iter().enumerate() {
        if p.out_of_gamut {
            let _ = write!(
                s,
                r#"<rect class="oog" x="2" y="{:.1}" width="{}" height="{row}" fill="{OOG_GREY}"/>"#,
                rows_y + row * i as f64,
                w - 4.0
            );
        }
    }
    let step = tick_step(xmax, 5.0);
    for v in ticks(0.0, xmax, step) {
        let x = x_of(v);
        let _ = write!(
            s,
            r##"<line x1="{x:.1}" x2="{x:.1}" y1="{rows_y}" y2="{rows_end:.1}" stroke="#e4e4e4"/><text x="{x:.1}" y="{axis_y}" text-anchor="middle" font-size="11" font-family="sans-serif">{}</text>"##,
            trim(v)
        );
    }
    for (i, p) in a.patches.iter().enumerate() {
        let y = rows_y + row * i as f64;
        let c = y + row / 2.0;
        let _ = write!(
            s,
            r#"<text x="20" y="{:.1}" text-anchor="end" font-size="11" font-family="sans-serif">{}</text>"#,
            c + 4.0,
            p.patch
        );
        swatch(&mut s, p.reference.lab, 24.0, c - 6.0, 12.0);
        swatch(&mut s, p.test.lab, 38.0, c - 6.0, 12.0);
        let _ = write!(
            s,
            r#"<rect class="bar" data-patch="{}" x="{x0}" y="{:.1}" width="{:.1}" height="10" fill="{}">{}</rect>"#,
            p.patch,
            c - 5.0,
            x_of(p.de76) - x0,
            verdict_colour(p.jnd),
            bar_title(p)
        );
        let (lo, hi) = (x_of(p.de76_interval.lo), x_of(p.de76_interval.hi));
        let _ = write!(
            s,
            r##"<path class="errorbar" d="M{lo:.1},{c:.1}H{hi:.1}M{lo:.1},{:.1}v8M{hi:.1},{:.1}v8" stroke="#222" stroke-width="1.2" fill="none"/><circle cx="{:.1}" cy="{c:.1}" r="2.5" fill="#1f4e9c"/>"##,
            c - 4.0,
            c - 4.0,
            x_of(p.de00)
        );
    }
    let jx = x_of(JND_DE76);
    let _ = write!(
        s,
        r##"<line class="jnd" x1="{jx:.1}" x2="{jx:.1}" y1="{rows_y}" y2="{:.1}" stroke="#000" stroke-dasharray="6 4" stroke-width="1.3"/><text x="{jx:.1}" y="{:.1}" text-anchor="middle" font-size="11" font-family="sans-serif">JND {JND_DE76}</text><line x1="{x0}" x2="{x0}" y1="{rows_y}" y2="{rows_end:.1}" stroke="#000"/>"##,
        rows_end + 4.0,
        rows_end + 17.0
    );
    narrow_legend(&mut s, a, legend_y);
    s.push_str("</svg>");
    s
}

/// The narrow drawing's legend from `legend_y`, three keys to a row, and what its marks say
/// below it.
fn narrow_legend(s: &mut String, a: &Assessment, legend_y: f64) {
    let mut lx = 4.0;
    let mut ly = legend_y;
    for (k, (label, colour)) in keys().into_iter().enumerate() {
        if k == 3 {
            lx = 4.0;
            ly += 15.0;
        }
        let _ = write!(
            s,
            r#"<rect x="{lx}" y="{:.1}" width="11" height="10" fill="{colour}"/><text x="{}" y="{ly:.1}" font-size="11" font-family="sans-serif">{label}</text>"#,
            ly - 9.0,
            lx + 14.0
        );
        lx += 26.0 + 6.9 * label.chars().count() as f64;
    }
    for (k, line) in [
        "bar: ΔE*ab, whisker: its 95 % interval, dot: ΔE00".to_string(),
        format!(
            "swatches: {} left, {} right; diagonal: clipped",
            esc(&a.reference),
            esc(&a.test)
        ),
    ]
    .iter()
    .enumerate()
    {
        let _ = write!(
            s,
            r#"<text x="4" y="{:.1}" font-size="11" font-family="sans-serif">{line}</text>"#,
            ly + 15.0 * (k + 1) as f64
        );
    }
}
