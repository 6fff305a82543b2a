//! The report's figures as inline SVG text: the paper's Fig. 4/6 (ΔE*ab per patch with
//! error bars and the JND line, [`bars`]) and Fig. 5 (a*b* and L*a* planes with each
//! reference reading and its test reading, [`planes`]), and the patch swatches in sRGB.
//!
//! Hand-written SVG rather than a plotting library: the figures go inline into one HTML
//! file, need ids unique within it, must not depend on fonts or scripts, and need text of
//! a size chosen for the width they are shown at.

mod bars;
mod labels;
mod planes;

pub use bars::{delta_e_bars, delta_e_rows};
pub use planes::{lab_planes, Planes, MAX_OWN, MIN_DRAWN, OWN_COLOUR};

use crate::color::{srgb_encode, xyz_to_linear_srgb, Lab, Xyz};

use super::assess::JndVerdict;

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
    let xyz = Lab::new(lab[0], lab[1], lab[2]).to_xyz(D65).to_array();
    let linear = xyz_to_linear_srgb(xyz);
    let clipped = linear
        .iter()
        .any(|v| !(-CLIP_TOLERANCE..=1.0 + CLIP_TOLERANCE).contains(v));
    let [r, g, b] = linear.map(|v| (srgb_encode(v.clamp(0.0, 1.0)) * 255.0).round() as u8);
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

/// `v` with as many decimals (2 to 4) as it takes to show on which side of `threshold` it
/// lies: 2.2796 beside the JND 2.3 is "2.28", not "2.3"; 2.2996 is "2.2996".
pub fn decisive(v: f64, threshold: f64) -> String {
    for d in 2..=4 {
        let s = format!("{v:.d$}");
        let shown: f64 = s.parse().unwrap_or(v);
        let same_side = (shown - threshold).signum() == (v - threshold).signum();
        if v == threshold || (same_side && shown != threshold) || !v.is_finite() {
            return s;
        }
    }
    format!("{v:.4}")
}

/// A 95 % interval "[lo, hi]", each end to the decimals [`decisive`] gives it against
/// `threshold`.
pub fn interval_text(lo: f64, hi: f64, threshold: f64) -> String {
    format!("[{}, {}]", decisive(lo, threshold), decisive(hi, threshold))
}

/// `v` to 2 decimals without trailing zeros ("20", "2.5").
pub(crate) fn trim(v: f64) -> String {
    let t = format!("{v:.2}");
    t.trim_end_matches('0').trim_end_matches('.').to_string()
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
    fn an_interval_shows_the_digits_that_place_it_against_the_jnd() {
        assert_eq!(interval_text(2.2796, 2.6104, 2.3), "[2.28, 2.61]");
        // 2.2996 rounds to 2.30 and 2.300: only four decimals show it below 2.3.
        assert_eq!(decisive(2.2996, 2.3), "2.2996");
        assert_eq!(decisive(2.3004, 2.3), "2.3004");
        assert_eq!(decisive(2.3, 2.3), "2.30");
        assert_eq!(decisive(0.153, 2.3), "0.15");
        // Closer than 4 decimals resolve: shown as near as that.
        assert_eq!(decisive(2.299_999, 2.3), "2.3000");
        assert_eq!(decisive(f64::NAN, 2.3), "NaN");
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
