//! Emitters hidden by a surface in their own plane.
//!
//! A panel drawn in the plane of an unbroken ceiling is a common slip when a room is
//! written by hand. The two renderers would then disagree without a word: a ray from the
//! room meets the ceiling and the panel at the same distance and the path tracer takes the
//! ceiling, so it reads no light, while the radiosity solver, which needs no visibility
//! tests in a convex room, lights the room as if the ceiling had a hole. So the scene is
//! refused, saying how to mend it.

use super::model::{Emitter, Surface};
use super::reader::PathError;
use crate::render::geometry::{Rect, Vec3, VecOps};

/// Planes closer than this fraction of the larger rectangle's size count as one plane.
const COPLANAR: f64 = 1e-6;

/// The first emitter that a coplanar, same-facing surface overlaps, as an error on that
/// emitter's JSON path.
pub fn check(surfaces: &[Surface], emitters: &[Emitter]) -> Result<(), PathError> {
    for (i, e) in emitters.iter().enumerate() {
        for s in surfaces {
            let area = coplanar_overlap(&e.rect, &s.rect);
            if area > 1e-9 * e.rect.area_m2 {
                return Err(PathError {
                    path: format!("emitters[{i}]"),
                    // Short: a scene error quotes at most 120 characters.
                    message: format!(
                        "hidden by surface '{}' in its plane ({:.0} % of it): cut that surface \
                         around it, or move it off",
                        s.name,
                        100.0 * area / e.rect.area_m2
                    ),
                });
            }
        }
    }
    Ok(())
}

/// The area (m²) of `a` that `b` covers when both lie in one plane and face the same way;
/// 0 otherwise.
pub fn coplanar_overlap(a: &Rect, b: &Rect) -> f64 {
    if a.normal.dot(b.normal) < 1.0 - 1e-9 {
        return 0.0;
    }
    let size = [a.edge_u, a.edge_v, b.edge_u, b.edge_v]
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max);
    if b.corner.minus(a.corner).dot(a.normal).abs() > COPLANAR * size {
        return 0.0;
    }
    // In a's plane, with a's edges as axes: a is the unit square scaled to its edge lengths.
    let (eu, ev) = (a.edge_u.normalized(), a.normal.cross(a.edge_u).normalized());
    let to2 = |p: Vec3| {
        let d = p.minus(a.corner);
        [d.dot(eu), d.dot(ev)]
    };
    let poly_a = [
        a.corner,
        a.point(1.0, 0.0),
        a.point(1.0, 1.0),
        a.point(0.0, 1.0),
    ]
    .map(to2);
    let poly_b = [
        b.corner,
        b.point(1.0, 0.0),
        b.point(1.0, 1.0),
        b.point(0.0, 1.0),
    ]
    .map(to2);
    area(&clip(&poly_a, &poly_b))
}

/// Signed-area orientation of a convex polygon made counter-clockwise.
fn ccw(p: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut v = p.to_vec();
    if signed_area(&v) < 0.0 {
        v.reverse();
    }
    v
}

fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        / 2.0
}

fn area(p: &[[f64; 2]]) -> f64 {
    if p.len() < 3 {
        0.0
    } else {
        signed_area(p).abs()
    }
}

/// The part of convex polygon `subject` inside convex polygon `window` (Sutherland–Hodgman).
fn clip(subject: &[[f64; 2]], window: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let window = ccw(window);
    let mut out = ccw(subject);
    let n = window.len();
    for i in 0..n {
        let (a, b) = (window[i], window[(i + 1) % n]);
        // Left of a→b is inside.
        let inside = |p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let input = std::mem::take(&mut out);
        let m = input.len();
        for k in 0..m {
            let (p, q) = (input[k], input[(k + 1) % m]);
            let (sp, sq) = (inside(p), inside(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        if out.is_empty() {
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::from_array([x, y, z])
    }

    fn ceiling() -> Rect {
        // 2 × 2 m at y = 2, facing down.
        Rect::new(v(0.0, 2.0, 0.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, 2.0))
    }

    #[test]
    fn a_panel_in_the_ceiling_is_covered_whole() {
        let panel = Rect::new(v(0.9, 2.0, 0.9), v(0.2, 0.0, 0.0), v(0.0, 0.0, 0.2));
        assert!(panel.normal.y < 0.0);
        assert!((coplanar_overlap(&panel, &ceiling()) - 0.04).abs() < 1e-12);
    }

    #[test]
    fn half_over_the_edge_and_rotated() {
        // Straddles the edge x = 2: 0.1 × 0.2 of it is under the ceiling.
        let panel = Rect::new(v(1.9, 2.0, 0.9), v(0.2, 0.0, 0.0), v(0.0, 0.0, 0.2));
        assert!((coplanar_overlap(&panel, &ceiling()) - 0.02).abs() < 1e-12);
        // A square turned 45° about its centre (1, 2, 1), wholly inside.
        let s = 0.1 * std::f64::consts::SQRT_2;
        let turned = Rect::new(v(1.0 - s, 2.0, 1.0), v(s, 0.0, -s), v(s, 0.0, s));
        assert!(turned.normal.y < 0.0);
        assert!((coplanar_overlap(&turned, &ceiling()) - 0.04).abs() < 1e-12);
    }

    #[test]
    fn below_beside_or_facing_away_is_not_hidden() {
        let below = Rect::new(v(0.9, 1.999, 0.9), v(0.2, 0.0, 0.0), v(0.0, 0.0, 0.2));
        assert_eq!(coplanar_overlap(&below, &ceiling()), 0.0);
        let beside = Rect::new(v(2.0, 2.0, 0.9), v(0.2, 0.0, 0.0), v(0.0, 0.0, 0.2));
        assert_eq!(coplanar_overlap(&beside, &ceiling()), 0.0);
        let up = Rect::new(v(0.9, 2.0, 0.9), v(0.0, 0.0, 0.2), v(0.2, 0.0, 0.0));
        assert!(up.normal.y > 0.0);
        assert_eq!(coplanar_overlap(&up, &ceiling()), 0.0);
    }
}
