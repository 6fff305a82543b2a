//! Number labels beside markers, none covering another or a mark: a greedy collision pass.
//! Each label tries positions on rings of growing radius around its marker, upper right
//! first, and takes the first whose box meets no placed label, no marker, no line and stays
//! inside the frame; a label set off from its marker gets a leader line, which later labels
//! also avoid. Crowded markers are labelled first, so they get the near places.

/// An axis-aligned box in SVG user units: left, top, right, bottom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelBox {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl LabelBox {
    pub fn around(cx: f64, cy: f64, half_w: f64, half_h: f64) -> LabelBox {
        LabelBox {
            x0: cx - half_w,
            y0: cy - half_h,
            x1: cx + half_w,
            y1: cy + half_h,
        }
    }

    pub fn overlaps(&self, o: &LabelBox) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    fn within(&self, frame: &LabelBox) -> bool {
        self.x0 >= frame.x0 && self.x1 <= frame.x1 && self.y0 >= frame.y0 && self.y1 <= frame.y1
    }
}

/// Em fractions of DejaVu Sans, the widest common sans-serif face (and Debian's default):
/// a digit's advance, and ascent + descent. A narrower face only leaves more room.
const DIGIT_EM: f64 = 0.64;
const HEIGHT_EM: f64 = 1.17;
const ASCENT_EM: f64 = 0.93;
/// Clear space kept around a label's box.
const PAD: f64 = 1.0;

/// A disc of radius `r` at `c` as three boxes (a cross and a square between its arms), so
/// a label may come nearer its diagonal than a square would let it.
pub fn disc_boxes(c: (f64, f64), r: f64) -> [LabelBox; 3] {
    [
        LabelBox::around(c.0, c.1, r, 0.45 * r),
        LabelBox::around(c.0, c.1, 0.45 * r, r),
        LabelBox::around(c.0, c.1, 0.7 * r, 0.7 * r),
    ]
}

/// Small boxes along the segment from `a` to `b`, `half` wide either side of it: a line as
/// obstacles.
pub fn segment_boxes(a: (f64, f64), b: (f64, f64), half: f64) -> Vec<LabelBox> {
    let len = (b.0 - a.0).hypot(b.1 - a.1);
    let n = (len / 2.0).ceil().max(1.0) as usize;
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            LabelBox::around(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1), half, half)
        })
        .collect()
}

/// A placed label: where its text goes and whether it needs a leader line.
#[derive(Clone, Debug, PartialEq)]
pub struct Placed {
    /// The text's anchor (`text-anchor="middle"`) and baseline.
    pub x: f64,
    pub baseline: f64,
    /// The box the text occupies (without the padding).
    pub rect: LabelBox,
    /// From the marker's edge to the label's box, when the label sits away from it.
    pub leader: Option<((f64, f64), (f64, f64))>,
}

/// One label to place: its text beside the marker at `at` of radius `radius`.
pub struct Label<'a> {
    pub text: &'a str,
    pub at: (f64, f64),
    pub radius: f64,
}

/// Places every label in `labels` (font size `font`) inside `frame`, clear of `obstacles`
/// and of each other. A label that finds no free place goes where it overlaps least:
/// with its leader across other labels if it must, on a mark or a label only in a frame
/// too small for them all.
pub fn place(labels: &[Label], font: f64, obstacles: &[LabelBox], frame: LabelBox) -> Vec<Placed> {
    let half_h = HEIGHT_EM * font / 2.0;
    let mut order: Vec<usize> = (0..labels.len()).collect();
    let crowd = |i: usize| {
        labels
            .iter()
            .filter(|l| (l.at.0 - labels[i].at.0).hypot(l.at.1 - labels[i].at.1) < 6.0 * font)
            .count()
    };
    order.sort_by_key(|&i| (std::cmp::Reverse(crowd(i)), i));
    // What a label's box must keep clear of: the marks, then each placed label and leader.
    let mut taken: Vec<LabelBox> = obstacles.to_vec();
    // What a leader must not cross: the placed labels (leaders may cross each other, as
    // those of one crowded cluster all start at it).
    let mut label_boxes: Vec<LabelBox> = Vec::new();
    let mut placed: Vec<Option<Placed>> = vec![None; labels.len()];
    let angles = directions();
    for i in order {
        let l = &labels[i];
        let half_w = DIGIT_EM * font * l.text.chars().count() as f64 / 2.0;
        let mut best: Option<(usize, Placed)> = None;
        'rings: for ring in 0..14 {
            // The first ring just clears the marker (its boxes reach 1.1 r at most, the
            // padding 1); each next one a little further out.
            let gap = 1.0 + PAD + 0.15 * l.radius + ring as f64 * (0.45 * font + ring as f64 * 0.5);
            for &ang in &angles {
                let (c, s) = (ang.cos(), ang.sin());
                // Distance from the marker's centre to the box's centre along the direction,
                // so the box's nearest point (its support toward the marker) is `gap` beyond
                // the marker.
                let reach = l.radius + gap + half_w * c.abs() + half_h * s.abs();
                let (cx, cy) = (l.at.0 + reach * c, l.at.1 + reach * s);
                let rect = LabelBox::around(cx, cy, half_w, half_h);
                let padded = LabelBox::around(cx, cy, half_w + PAD, half_h + PAD);
                if !padded.within(&frame) {
                    continue;
                }
                let leader = (ring > 1).then(|| {
                    let start = (l.at.0 + l.radius * c, l.at.1 + l.radius * s);
                    (start, nearest_point(&rect, start))
                });
                // A box over a mark or a label costs far more than a leader across a label,
                // so a label walled in by its cluster's others crosses them with its leader
                // rather than sit on one.
                let mut hits = 1000 * taken.iter().filter(|t| t.overlaps(&padded)).count();
                if let Some((a, b)) = leader {
                    let line = segment_boxes(a, b, 0.5);
                    hits += label_boxes
                        .iter()
                        .filter(|t| line.iter().any(|s| s.overlaps(t)))
                        .count();
                }
                let candidate = Placed {
                    x: cx,
                    baseline: cy - half_h + ASCENT_EM * font,
                    rect,
                    leader,
                };
                if hits == 0 {
                    best = Some((0, candidate));
                    break 'rings;
                }
                if best.as_ref().is_none_or(|(h, _)| hits < *h) {
                    best = Some((hits, candidate));
                }
            }
        }
        // A frame too small for any position: on the marker, as before any placing.
        let p = best.map(|(_, p)| p).unwrap_or_else(|| Placed {
            x: l.at.0,
            baseline: l.at.1 - half_h + ASCENT_EM * font,
            rect: LabelBox::around(l.at.0, l.at.1, half_w, half_h),
            leader: None,
        });
        let own = LabelBox::around(
            (p.rect.x0 + p.rect.x1) / 2.0,
            (p.rect.y0 + p.rect.y1) / 2.0,
            half_w + PAD,
            half_h + PAD,
        );
        taken.push(own);
        label_boxes.push(own);
        if let Some((a, b)) = p.leader {
            taken.extend(segment_boxes(a, b, 0.5));
        }
        placed[i] = Some(p);
    }
    placed
        .into_iter()
        .map(|p| p.expect("every label placed"))
        .collect()
}

/// The directions a label is tried in: 32, upper right first, then those nearest it.
fn directions() -> Vec<f64> {
    let mut a: Vec<f64> = (0..32)
        .map(|k| k as f64 * std::f64::consts::TAU / 32.0)
        .collect();
    let pref = -std::f64::consts::FRAC_PI_4;
    let dist = |x: f64| {
        let d = (x - pref).rem_euclid(std::f64::consts::TAU);
        d.min(std::f64::consts::TAU - d)
    };
    a.sort_by(|x, y| dist(*x).total_cmp(&dist(*y)));
    a
}

/// The point of `r` nearest to `p`.
fn nearest_point(r: &LabelBox, p: (f64, f64)) -> (f64, f64) {
    (p.0.clamp(r.x0, r.x1), p.1.clamp(r.y0, r.y1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crowded_labels_never_overlap_each_other_or_the_markers() {
        // Six markers within 16 units, as the ColorChecker's neutrals sit in a*b*.
        let at = [
            (100.0, 100.0),
            (104.0, 96.0),
            (96.0, 98.0),
            (101.0, 104.0),
            (98.0, 92.0),
            (103.0, 101.0),
        ];
        let texts = ["19", "20", "21", "22", "23", "24"];
        let labels: Vec<Label> = at
            .iter()
            .zip(texts)
            .map(|(&at, text)| Label {
                text,
                at,
                radius: 5.0,
            })
            .collect();
        let markers: Vec<LabelBox> = at.iter().flat_map(|&c| disc_boxes(c, 5.0)).collect();
        let frame = LabelBox {
            x0: 0.0,
            y0: 0.0,
            x1: 200.0,
            y1: 200.0,
        };
        let placed = place(&labels, 13.0, &markers, frame);
        for (i, p) in placed.iter().enumerate() {
            for q in &placed[i + 1..] {
                assert!(!p.rect.overlaps(&q.rect), "{p:?} {q:?}");
            }
            assert!(markers.iter().all(|m| !m.overlaps(&p.rect)), "{p:?}");
            // A label's box is 0.64 em per digit wide and 1.17 em tall.
            assert!((p.rect.x1 - p.rect.x0 - 2.0 * 0.64 * 13.0).abs() < 1e-9);
            assert!((p.rect.y1 - p.rect.y0 - 1.17 * 13.0).abs() < 1e-9);
        }
        // Twenty markers on one spot (readings that coincide): every label still finds a
        // place of its own, each with a leader.
        let texts: Vec<String> = (1..=20).map(|k| k.to_string()).collect();
        let same: Vec<Label> = texts
            .iter()
            .map(|text| Label {
                text,
                at: (100.0, 100.0),
                radius: 5.0,
            })
            .collect();
        let fan = place(&same, 13.0, &markers[..3], frame);
        for (i, p) in fan.iter().enumerate() {
            for q in &fan[i + 1..] {
                assert!(!p.rect.overlaps(&q.rect), "{p:?} {q:?}");
            }
        }
        // The first, alone on its ring, sits just off its marker without a leader.
        let lone = place(&labels[..1], 13.0, &markers[..3], frame);
        assert!(lone[0].leader.is_none());
        assert!(
            lone[0].rect.x0 > 100.0 && lone[0].rect.y1 < 100.0,
            "{lone:?}"
        );
    }
}
