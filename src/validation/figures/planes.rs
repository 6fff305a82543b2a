//! Fig. 5: the a*b* and L*a* planes, two SVGs that sit side by side on a wide page and one
//! above the other on a narrow one. Each patch's reference reading is a disc in its colour
//! at its place; the test reading is a ring at the end of a line from it, the displacement
//! magnified by one stated factor, so differences of a few tenths of a ΔE*ab show in a
//! plane that spans ±90. Both planes share one scale (isotropic), so a line's length in
//! either is its displacement times the factor. A displacement too short to see at that
//! factor is drawn in blue at a larger one of its own, which the caption states patch by
//! patch, so every difference shows. Labels are placed by a collision pass
//! ([`super::labels`]).

use std::fmt::Write;

use super::labels::{disc_boxes, place, segment_boxes, Label, LabelBox};
use super::{esc, srgb_swatch, tick_step, ticks, trim};
use crate::validation::assess::{Assessment, JND_DE76};

/// Width of each plane's SVG (user units): at 390 px the plane is drawn ~370 px wide, and
/// [`FONT`] comes out at 10.5 px.
const W: f64 = 460.0;
const LEFT: f64 = 48.0;
const RIGHT: f64 = 12.0;
/// The plot's side: both axes at one scale.
const P: f64 = W - LEFT - RIGHT;
const TOP: f64 = 30.0;
/// Below the plot: tick labels and the axis name.
const BOTTOM: f64 = 40.0;
const FONT: f64 = 13.0;
const DISC: f64 = 5.0;
const RING: f64 = 3.4;
/// A displacement drawn shorter than the ring's radius leaves the ring on its disc.
pub const MIN_DRAWN: f64 = RING;
/// A displacement drawn shorter than this (user units) is drawn at a magnification of its
/// own: long enough that a line shows between disc and ring.
const SEEN: f64 = RING + 3.0;
/// The largest magnification a patch of its own may get; a displacement too short to see
/// even at this is drawn as short, its ring on its disc, and named as such.
pub const MAX_OWN: f64 = 1000.0;
/// The colour of a displacement drawn at a magnification of its own.
pub const OWN_COLOUR: &str = "#1f5fbf";
/// The longest displacement, magnified, is drawn at most this share of the plot's side: a
/// factor that shows small displacements, while the longest line crosses no more than
/// part of the plane.
const LONGEST_SHARE: f64 = 0.4;

/// Fig. 5 as HTML, and what its caption must say.
#[derive(Clone, Debug, PartialEq)]
pub struct Planes {
    /// `<div class="planes" id=…>` with the two SVGs.
    pub html: String,
    /// Every displacement is drawn this many times its length.
    pub magnification: f64,
    /// ΔE*ab (in a plane) under which a displacement would be too short to see at
    /// [`Self::magnification`]: such a one gets a magnification of its own.
    pub floor: f64,
    /// Per plane ("a*b*", "L*a*"), the patches drawn at a magnification of their own, and it.
    pub own: Vec<(&'static str, Vec<(usize, f64)>)>,
    /// Per plane ("a*b*", "L*a*"), the patches drawn shorter than [`MIN_DRAWN`] even so.
    pub unresolved: Vec<(&'static str, Vec<usize>)>,
}

/// The largest of 1, 2, 5, 10, 20, … not above `v` (1 at least, 1000 at most).
fn nice_floor(v: f64) -> f64 {
    let mut best = 1.0;
    for e in 0..4 {
        for m in [1.0, 2.0, 5.0] {
            let c = m * 10f64.powi(e);
            if c <= v && c <= 1000.0 {
                best = c;
            }
        }
    }
    best
}

/// The smallest of 1, 2, 5, 10, 20, … not below `v`, or `None` above [`MAX_OWN`].
fn nice_ceil(v: f64) -> Option<f64> {
    (0..4)
        .flat_map(|e| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(e)))
        .find(|&c| c >= v && c <= MAX_OWN)
}

/// The magnification a displacement of `d` (in the plane) is drawn at, where `m` makes one
/// CIELAB unit `scale` user units: `m` itself where that draws it at least [`SEEN`] long,
/// else the smallest 1-2-5 factor that does, if there is one up to [`MAX_OWN`].
fn own_magnification(d: f64, m: f64, scale: f64) -> f64 {
    if d.is_nan() || d <= 0.0 || d * m * scale >= SEEN {
        return m;
    }
    nice_ceil(SEEN / (d * scale)).map_or(m, |own| own.max(m))
}

/// One plane: its name, axes (horizontal, vertical) as indices into L*, a*, b*.
struct Axes {
    name: &'static str,
    x: usize,
    y: usize,
    xlabel: &'static str,
    ylabel: &'static str,
}

const AB: Axes = Axes {
    name: "a*b*",
    x: 1,
    y: 2,
    xlabel: "a*",
    ylabel: "b*",
};
const LA: Axes = Axes {
    name: "L*a*",
    x: 1,
    y: 0,
    xlabel: "a*",
    ylabel: "L*",
};

/// Fig. 5 of `a`; `id` prefixes its element ids.
pub fn lab_planes(a: &Assessment, id: &str) -> Planes {
    let pairs: Vec<([f64; 3], [f64; 3])> = a
        .patches
        .iter()
        .map(|p| (p.reference.lab, p.test.lab))
        .collect();
    let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
    // The a* and b* extent of every reading sets the scale; the magnification then is the
    // largest 1-2-5 factor that keeps the longest displacement within its share.
    let extent = |m: f64| {
        pairs
            .iter()
            .flat_map(|(r, t)| {
                (1..3).flat_map(move |k| {
                    [r[k], t[k], r[k] + m * (t[k] - r[k])].map(|v| finite(v).abs())
                })
            })
            .fold(10.0, f64::max)
    };
    let scale0 = P / (2.0 * extent(1.0) * 1.06);
    let longest = pairs
        .iter()
        .flat_map(|(r, t)| [AB, LA].map(|ax| finite((t[ax.x] - r[ax.x]).hypot(t[ax.y] - r[ax.y]))))
        .fold(0.0, f64::max);
    let magnification = if longest > 0.0 {
        nice_floor(LONGEST_SHARE * P / (scale0 * longest))
    } else {
        1.0
    };
    let half = extent(magnification) * 1.06;
    let scale = P / (2.0 * half);
    // L* from 0 to 100, wider only where a magnified end leaves it.
    let (l_lo, l_hi) = pairs.iter().fold((0.0f64, 100.0f64), |(lo, hi), (r, t)| {
        let e = finite(r[0] + magnification * (t[0] - r[0]));
        (lo.min(e - 3.0), hi.max(e + 3.0))
    });
    let l_range = ((l_lo / 10.0).floor() * 10.0, (l_hi / 10.0).ceil() * 10.0);
    let mut html = format!("<div class=\"planes\" id=\"{id}\">");
    let mut unresolved = Vec::new();
    let mut own = Vec::new();
    for (ax, range) in [(AB, (-half, half)), (LA, l_range)] {
        let (svg, short, more) = plane(
            a,
            id,
            &ax,
            &pairs,
            scale,
            (-half, half),
            range,
            magnification,
        );
        html.push_str(&svg);
        unresolved.push((ax.name, short));
        own.push((ax.name, more));
    }
    html.push_str("</div>");
    Planes {
        html,
        magnification,
        floor: SEEN / (scale * magnification),
        own,
        unresolved,
    }
}

/// Where a patch is drawn: its disc's centre, and its ring's at the magnified displacement.
type Mark = ((f64, f64), (f64, f64));

/// Where a plane's values land in its SVG: the plot's scale and ranges, and its bottom
/// right corner.
struct Frame {
    scale: f64,
    xmin: f64,
    ymax: f64,
    /// The plot's height and the SVG's.
    ph: f64,
    h: f64,
    x1: f64,
    y1: f64,
}

impl Frame {
    fn px(&self, v: f64) -> f64 {
        LEFT + (v - self.xmin) * self.scale
    }
    fn py(&self, v: f64) -> f64 {
        TOP + (self.ymax - v) * self.scale
    }
}

/// One plane's SVG, the patches whose displacement is drawn shorter than [`MIN_DRAWN`], and
/// those drawn at a magnification of their own (with it): the frame and axes, the discs,
/// the displacements, the JND's scale bar and the labels, in the order they are drawn.
#[allow(clippy::too_many_arguments)]
fn plane(
    a: &Assessment,
    id: &str,
    ax: &Axes,
    pairs: &[([f64; 3], [f64; 3])],
    scale: f64,
    (xmin, xmax): (f64, f64),
    (ymin, ymax): (f64, f64),
    m: f64,
) -> (String, Vec<usize>, Vec<(usize, f64)>) {
    let ph = (ymax - ymin) * scale;
    let f = Frame {
        scale,
        xmin,
        ymax,
        ph,
        h: TOP + ph + BOTTOM,
        x1: LEFT + P,
        y1: TOP + ph,
    };
    let mut s = String::new();
    frame_and_axes(&mut s, &f, id, ax, (xmin, xmax), (ymin, ymax), m);
    // Each patch's magnification in this plane: the figure's, or its own where that would
    // not show its displacement.
    let factors: Vec<f64> = pairs
        .iter()
        .map(|(r, t)| {
            let d = (t[ax.x] - r[ax.x]).hypot(t[ax.y] - r[ax.y]);
            own_magnification(d, m, scale)
        })
        .collect();
    // Where each patch is drawn: its disc, and its ring at the magnified displacement.
    let marks: Vec<Mark> = pairs
        .iter()
        .zip(&factors)
        .map(|((r, t), &k)| {
            let at = (f.px(r[ax.x]), f.py(r[ax.y]));
            let end = (
                f.px(r[ax.x] + k * (t[ax.x] - r[ax.x])),
                f.py(r[ax.y] + k * (t[ax.y] - r[ax.y])),
            );
            (at, end)
        })
        .collect();
    let more: Vec<(usize, f64)> = a
        .patches
        .iter()
        .zip(&factors)
        .filter(|(_, &k)| k != m)
        .map(|(p, &k)| (p.patch, k))
        .collect();
    // The JND at the same magnification, as a scale bar in the plot's lower right.
    let jnd_len = JND_DE76 * m * scale;
    let bar = (jnd_len < 0.45 * P).then(|| {
        let (bx1, by) = (f.x1 - 10.0, f.y1 - 10.0);
        (bx1 - jnd_len, bx1, by)
    });
    let obstacles = obstacles(bar, &marks);
    discs(&mut s, a, &marks);
    let short = displacements(&mut s, a, &marks, &factors, m);
    if let Some((bx0, bx1, by)) = bar {
        let _ = write!(
            s,
            r##"<path class="scale" d="M{bx0:.1},{:.1}V{by:.1}H{bx1:.1}V{:.1}" stroke="#000" stroke-width="1.4" fill="none"/><text x="{bx1:.1}" y="{:.1}" text-anchor="end" font-size="{FONT}" font-family="sans-serif">JND {JND_DE76} at ×{}</text>"##,
            by - 4.0,
            by - 4.0,
            by - 7.0,
            trim(m)
        );
    }
    labels(&mut s, a, &marks, &obstacles, &f);
    s.push_str("</svg>");
    (s, short, more)
}

/// The SVG's opening, title, plot area, grid with tick labels, and axis names.
fn frame_and_axes(
    s: &mut String,
    f: &Frame,
    id: &str,
    ax: &Axes,
    (xmin, xmax): (f64, f64),
    (ymin, ymax): (f64, f64),
    m: f64,
) {
    let (h, ph, x1, y1) = (f.h, f.ph, f.x1, f.y1);
    let title = format!(
        "{} plane (CIELAB units), displacement ×{}",
        ax.name,
        trim(m)
    );
    let pid = format!("{id}-{}", if ax.y == 2 { "ab" } else { "la" });
    let _ = write!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" id="{pid}" class="figure plane" viewBox="0 0 {W} {h:.1}" width="{W}" height="{h:.1}" role="img" aria-label="{t}"><title>{t}</title><rect x="0" y="0" width="{W}" height="{h:.1}" fill="#ffffff"/><text x="{:.1}" y="18" text-anchor="middle" font-size="14" font-family="sans-serif">{t}</text><rect x="{LEFT}" y="{TOP}" width="{P}" height="{ph:.1}" fill="#fafafa" stroke="#000"/>"##,
        W / 2.0,
        t = esc(&title)
    );
    let step = tick_step(xmax - xmin, 6.0);
    for v in ticks((xmin / step).ceil() * step, xmax, step) {
        let _ = write!(
            s,
            r##"<line x1="{x:.1}" x2="{x:.1}" y1="{TOP}" y2="{y1:.1}" stroke="{}"/><text x="{x:.1}" y="{:.1}" text-anchor="middle" font-size="{FONT}" font-family="sans-serif">{}</text>"##,
            if v == 0.0 { "#999" } else { "#e4e4e4" },
            y1 + 15.0,
            trim(v),
            x = f.px(v)
        );
    }
    let step = tick_step(ymax - ymin, 6.0);
    for v in ticks((ymin / step).ceil() * step, ymax, step) {
        let _ = write!(
            s,
            r##"<line x1="{LEFT}" x2="{x1:.1}" y1="{y:.1}" y2="{y:.1}" stroke="{}"/><text x="{:.1}" y="{:.1}" text-anchor="end" font-size="{FONT}" font-family="sans-serif">{}</text>"##,
            if v == 0.0 && ax.y != 0 {
                "#999"
            } else {
                "#e4e4e4"
            },
            LEFT - 4.0,
            f.py(v) + 4.5,
            trim(v),
            y = f.py(v)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="{FONT}" font-family="sans-serif">{}</text><text transform="translate(14,{:.1}) rotate(-90)" text-anchor="middle" font-size="{FONT}" font-family="sans-serif">{}</text>"#,
        LEFT + P / 2.0,
        h - 6.0,
        ax.xlabel,
        TOP + ph / 2.0,
        ax.ylabel
    );
}

/// What a label must not cover: the scale bar, every disc and ring, every line.
fn obstacles(bar: Option<(f64, f64, f64)>, marks: &[Mark]) -> Vec<LabelBox> {
    let mut obstacles: Vec<LabelBox> = Vec::new();
    if let Some((bx0, bx1, by)) = bar {
        obstacles.push(LabelBox {
            x0: bx0 - 2.0,
            y0: by - 20.0,
            x1: bx1 + 2.0,
            y1: by + 4.0,
        });
    }
    for &(at, end) in marks {
        obstacles.extend(disc_boxes(at, DISC));
        obstacles.extend(disc_boxes(end, RING + 0.7));
        obstacles.extend(segment_boxes(at, end, 1.0));
    }
    obstacles
}

/// Each patch's reference reading as a disc in its colour, its readings in its tooltip.
fn discs(s: &mut String, a: &Assessment, marks: &[Mark]) {
    for (p, &(at, _)) in a.patches.iter().zip(marks) {
        let c = srgb_swatch(p.reference.lab);
        let _ = write!(
            s,
            r##"<circle class="box" data-patch="{}" cx="{:.2}" cy="{:.2}" r="{DISC}" fill="{}" stroke="{}" stroke-width="{}"{}><title>{} {}: {} L* {:.2}, a* {:.2}, b* {:.2}; {} L* {:.2}, a* {:.2}, b* {:.2}; ΔE*ab {:.2}</title></circle>"##,
            p.patch,
            at.0,
            at.1,
            c.hex,
            if c.clipped { "#000" } else { "#666" },
            if c.clipped { 1.3 } else { 0.8 },
            if c.clipped {
                r#" stroke-dasharray="2 1.6""#
            } else {
                ""
            },
            p.patch,
            esc(&p.name),
            esc(&a.reference),
            p.reference.lab[0],
            p.reference.lab[1],
            p.reference.lab[2],
            esc(&a.test),
            p.test.lab[0],
            p.test.lab[1],
            p.test.lab[2],
            p.de76
        );
    }
}

/// Each displacement as a line from its disc to a ring; the patches drawn shorter than
/// [`MIN_DRAWN`].
fn displacements(
    s: &mut String,
    a: &Assessment,
    marks: &[Mark],
    factors: &[f64],
    m: f64,
) -> Vec<usize> {
    // White under every line and ring first, then the black marks over them, so a mark
    // shows on a dark disc and where it crosses another.
    let mut short = Vec::new();
    // The marks at a magnification of their own come last: they are short, and would
    // hide under the long lines of their neighbours.
    for pass in 0..3 {
        for ((p, &(at, end)), &f) in a.patches.iter().zip(marks).zip(factors) {
            if (pass == 1 && f != m) || (pass == 2 && f == m) {
                continue;
            }
            let len = (end.0 - at.0).hypot(end.1 - at.1);
            if pass == 0 && len < MIN_DRAWN {
                short.push(p.patch);
            }
            let (stroke, line_w, ring_w, class) = match pass {
                0 => ("#ffffff", 3.4, 3.6, "halo"),
                1 => ("#000000", 1.3, 1.4, "vector"),
                _ => (OWN_COLOUR, 1.3, 1.4, "vector"),
            };
            if len > RING {
                let k = (len - RING) / len;
                let _ = write!(
                    s,
                    r#"<line class="{class}" data-patch="{}" x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="{stroke}" stroke-width="{line_w}" stroke-linecap="round"/>"#,
                    p.patch,
                    at.0,
                    at.1,
                    at.0 + k * (end.0 - at.0),
                    at.1 + k * (end.1 - at.1)
                );
            }
            let _ = write!(
                s,
                r#"<circle class="{}" data-patch="{}" data-magnification="{}" cx="{:.2}" cy="{:.2}" r="{RING}" fill="none" stroke="{stroke}" stroke-width="{ring_w}"/>"#,
                if pass == 0 { "halo" } else { "display" },
                p.patch,
                trim(f),
                end.0,
                end.1
            );
        }
    }
    short
}

/// The patch numbers, placed clear of `obstacles`, with a leader line where one had to
/// move away from its disc.
fn labels(s: &mut String, a: &Assessment, marks: &[Mark], obstacles: &[LabelBox], f: &Frame) {
    let names: Vec<String> = a.patches.iter().map(|p| p.patch.to_string()).collect();
    let labels: Vec<Label> = names
        .iter()
        .zip(marks)
        .map(|(text, &(at, _))| Label {
            text,
            at,
            radius: DISC,
        })
        .collect();
    let frame = LabelBox {
        x0: LEFT,
        y0: TOP,
        x1: f.x1,
        y1: f.y1,
    };
    let placed = place(&labels, FONT, obstacles, frame);
    for l in &placed {
        if let Some((from, to)) = l.leader {
            let _ = write!(
                s,
                r##"<line class="leader" x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#888" stroke-width="0.8"/>"##,
                from.0, from.1, to.0, to.1
            );
        }
    }
    for (p, l) in a.patches.iter().zip(&placed) {
        let _ = write!(
            s,
            r##"<text class="label" data-patch="{}" x="{:.1}" y="{:.1}" text-anchor="middle" font-size="{FONT}" font-family="sans-serif" paint-order="stroke" stroke="#ffffff" stroke-width="3" stroke-linejoin="round">{}</text>"##,
            p.patch, l.x, l.baseline, p.patch
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magnifications_step_one_two_five() {
        assert_eq!(nice_floor(0.3), 1.0);
        assert_eq!(nice_floor(1.9), 1.0);
        assert_eq!(nice_floor(21.3), 20.0);
        assert_eq!(nice_floor(49.9), 20.0);
        assert_eq!(nice_floor(50.0), 50.0);
        assert_eq!(nice_floor(1e9), 1000.0);
    }

    #[test]
    fn a_short_displacement_gets_the_least_factor_that_shows_it() {
        // One CIELAB unit is 2 user units at ×1: 0.02 at ×20 would be 0.8 long.
        assert_eq!(own_magnification(1.0, 20.0, 2.0), 20.0);
        // SEEN = 6.4: 0.02 needs ×160, so ×200 (8 units long).
        assert_eq!(own_magnification(0.02, 20.0, 2.0), 200.0);
        // Exactly long enough at the figure's factor keeps it.
        assert_eq!(own_magnification(SEEN / 40.0, 20.0, 2.0), 20.0);
        // Too short even at ×1000, or none at all: the figure's factor.
        assert_eq!(own_magnification(0.001, 20.0, 2.0), 20.0);
        assert_eq!(own_magnification(0.0, 20.0, 2.0), 20.0);
        assert_eq!(nice_ceil(160.0), Some(200.0));
        assert_eq!(nice_ceil(1000.0), Some(1000.0));
        assert_eq!(nice_ceil(1000.1), None);
    }
}
