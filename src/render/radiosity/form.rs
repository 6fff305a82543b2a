//! The form factor between two rectangles, exactly, by the contour-integral form.
//!
//! For two surfaces that see each other whole (each in front of the other's plane),
//! F₁₂ = 1/(2π A₁) ∮∮ ln r dr₁·dr₂ over their boundaries (Stokes' theorem applied twice to
//! the area integral; Sparrow 1963, "A new and simpler formulation for radiative angle
//! factors", J. Heat Transfer 85). Edges at right angles contribute nothing; for parallel
//! edges the double integral of ln r has a closed form, so rectangles whose edges are
//! pairwise parallel or perpendicular — every pair in a room of axis-aligned walls — get
//! their factor to rounding, however close they are. Edges at other angles are integrated
//! along one edge by Gauss–Legendre with the other edge in closed form.
//!
//! Why it matters: elements that meet at a corner of the room have a factor whose
//! integrand is singular along the shared edge. A fixed quadrature rule makes the same
//! relative error there at every refinement level, and as those elements are a fraction
//! ∝ h of the mesh, the solution acquires an O(h) error that the solver's h²
//! extrapolation cannot remove and its bound does not see.

use super::super::geometry::{Rect, Vec3, VecOps};
use super::polygon::{corners, gauss_legendre};

/// Two directions this close to parallel (|cos| ≥ 1 − ε) or perpendicular (|cos| ≤ ε) are
/// treated as exactly so.
const ANGLE_EPS: f64 = 1e-12;

/// Where `b` lies against the plane of `a`.
fn side(a: &Rect, b: &Rect, tol: f64) -> (bool, bool) {
    let mut front = false;
    let mut back = false;
    for c in corners(b) {
        let h = c.minus(a.corner).dot(a.normal);
        front |= h > tol;
        back |= h < -tol;
    }
    (front, back)
}

/// F(a → b) for one-sided rectangles (front = `edge_u × edge_v`) with nothing between
/// them. A rectangle that straddles the other's plane counts with its part in front, when
/// that plane cuts it across an edge; None for an oblique cut (a point rule with clipping
/// does then). Rectangles that cannot see each other's front give 0.
pub fn rect_to_rect(a: &Rect, b: &Rect) -> Option<f64> {
    let scale = a
        .edge_u
        .length()
        .max(a.edge_v.length())
        .max(b.edge_u.length())
        .max(b.edge_v.length());
    let tol = 1e-12 * scale;
    let (b_front, b_back) = side(a, b, tol);
    let (a_front, a_back) = side(b, a, tol);
    if !b_front || !a_front {
        // Behind, or in the plane of, the other: no light passes between the fronts.
        return Some(0.0);
    }
    // A part behind the other's plane neither sees nor is seen by the other's front, so
    // the factor is that of the parts in front (a decal's neighbours straddle its plane).
    let b_seen = if b_back { front_part(b, a)? } else { *b };
    let a_seen = if a_back { front_part(a, b)? } else { *a };
    Some(contour(&a_seen, &b_seen) * a_seen.area_m2 / a.area_m2)
}

/// The part of `r` in front of `plane`'s plane, when that plane cuts `r` across one of its
/// edges (then the part is a rectangle); None for an oblique cut.
fn front_part(r: &Rect, plane: &Rect) -> Option<Rect> {
    let n = plane.normal;
    let h0 = r.corner.minus(plane.corner).dot(n);
    let (hu, hv) = (r.edge_u.dot(n), r.edge_v.dot(n));
    let scale = r.edge_u.length().max(r.edge_v.length());
    let (edge, other, dh, along_u) = if hv.abs() <= ANGLE_EPS * scale {
        (r.edge_u, r.edge_v, hu, true)
    } else if hu.abs() <= ANGLE_EPS * scale {
        (r.edge_v, r.edge_u, hv, false)
    } else {
        return None;
    };
    // h(t) = h0 + t·dh along `edge`, t ∈ [0, 1]; keep h > 0.
    let t = (-h0 / dh).clamp(0.0, 1.0);
    let (t0, t1) = if dh > 0.0 { (t, 1.0) } else { (0.0, t) };
    if t1 <= t0 {
        return None;
    }
    let corner = r.corner.plus(edge.times(t0));
    let cut = edge.times(t1 - t0);
    Some(if along_u {
        Rect::new(corner, cut, other)
    } else {
        Rect::new(corner, other, cut)
    })
}

/// The contour integral for two rectangles wholly in front of each other: F(a → b).
fn contour(a: &Rect, b: &Rect) -> f64 {
    let ca = corners(a);
    let cb = corners(b);
    let mut sum = 0.0;
    for i in 0..4 {
        let (p0, p1) = (ca[i], ca[(i + 1) % 4]);
        for k in 0..4 {
            let (q0, q1) = (cb[k], cb[(k + 1) % 4]);
            sum += edge_pair(p0, p1, q0, q1);
        }
    }
    // Both boundaries are walked counter-clockwise about their own fronts, the orientation
    // in which the double contour integral is +2π A₁ F₁₂ (rounding can leave −1e-17).
    (sum / (2.0 * std::f64::consts::PI * a.area_m2)).max(0.0)
}

/// F(a → b) for the mesh: in closed form when every edge of one is parallel or
/// perpendicular to every edge of the other (rooms of axis-aligned walls), by the contour
/// form with one quadrature when the pair is `near` and oblique, else None (a point rule
/// does well enough for an oblique pair far apart).
pub fn form_factor(a: &Rect, b: &Rect, near: bool) -> Option<f64> {
    if near || aligned(a, b) {
        rect_to_rect(a, b)
    } else {
        None
    }
}

/// Every edge direction of `a` parallel or perpendicular to every edge direction of `b`.
fn aligned(a: &Rect, b: &Rect) -> bool {
    [a.edge_u, a.edge_v].iter().all(|x| {
        [b.edge_u, b.edge_v].iter().all(|y| {
            let c = x.dot(*y) / (x.length() * y.length());
            c.abs() <= ANGLE_EPS || c.abs() >= 1.0 - ANGLE_EPS
        })
    })
}

/// ∫∫ ln|p − q| (dp·dq) over the segments p0→p1 and q0→q1.
fn edge_pair(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3) -> f64 {
    let da = p1.minus(p0);
    let db = q1.minus(q0);
    let la = da.length();
    let lb = db.length();
    let (ua, ub) = (da.times(1.0 / la), db.times(1.0 / lb));
    let cos = ua.dot(ub);
    if cos.abs() <= ANGLE_EPS {
        return 0.0;
    }
    if cos.abs() >= 1.0 - ANGLE_EPS {
        // Walk b along a's direction; a reversed b flips the sign of dp·dq.
        let (start, sign) = if cos > 0.0 { (q0, 1.0) } else { (q1, -1.0) };
        let w = p0.minus(start);
        let c = w.dot(ua);
        let d2 = (w.dot(w) - c * c).max(0.0);
        return sign * parallel(c, la, lb, d2.sqrt());
    }
    skew(p0, ua, la, q0, ub, lb) * cos
}

/// ∫₀^La ∫₀^Lb ½ ln((c + s − t)² + D²) dt ds: with G'' = ½ ln(u² + D²), the integral is
/// G(c + La) − G(c) − G(c + La − Lb) + G(c − Lb).
fn parallel(c: f64, la: f64, lb: f64, d: f64) -> f64 {
    g2(c + la, d) - g2(c, d) - g2(c + la - lb, d) + g2(c - lb, d)
}

/// G(u) = ¼(u² − D²) ln(u² + D²) − ¾u² + D·u·atan(u/D), the second antiderivative of
/// ½ ln(u² + D²) (at D = 0: ½u² ln|u| − ¾u², 0 at u = 0).
fn g2(u: f64, d: f64) -> f64 {
    let r2 = u * u + d * d;
    if r2 == 0.0 {
        return 0.0;
    }
    let at = if d == 0.0 {
        0.0
    } else {
        d * u * (u / d).atan()
    };
    0.25 * (u * u - d * d) * r2.ln() - 0.75 * u * u + at
}

/// G'(u) = ½[u ln(u² + D²) − 2u + 2D·atan(u/D)], the antiderivative of ½ ln(u² + D²).
fn g1(u: f64, d: f64) -> f64 {
    let r2 = u * u + d * d;
    let lg = if r2 == 0.0 { 0.0 } else { u * r2.ln() };
    let at = if d == 0.0 {
        0.0
    } else {
        2.0 * d * (u / d).atan()
    };
    0.5 * (lg - 2.0 * u + at)
}

/// ∫₀^La ∫₀^Lb ln|p0 + s·ua − q0 − t·ub| dt ds for segments at an angle: the inner integral
/// in closed form, the outer by composite Gauss–Legendre (the integrand is smooth unless the
/// segments touch, where it is continuous with a logarithmic slope: the panels are graded
/// towards both ends).
fn skew(p0: Vec3, ua: Vec3, la: f64, q0: Vec3, ub: Vec3, lb: f64) -> f64 {
    let inner = |s: f64| {
        let w = p0.plus(ua.times(s)).minus(q0);
        let m = w.dot(ub);
        let d = (w.dot(w) - m * m).max(0.0).sqrt();
        g1(lb - m, d) - g1(-m, d)
    };
    // Panels [0, 1/64], [1/64, 1/16], … graded geometrically towards each end.
    let cuts = [
        0.0,
        1.0 / 64.0,
        1.0 / 16.0,
        0.25,
        0.5,
        0.75,
        15.0 / 16.0,
        63.0 / 64.0,
        1.0,
    ];
    let q = gauss_legendre(12);
    let mut total = 0.0;
    for w in cuts.windows(2) {
        let (s0, s1) = (w[0] * la, w[1] * la);
        for &(x, wt) in &q {
            total += wt * (s1 - s0) * inner(s0 + x * (s1 - s0));
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::radiosity::mesh::average_over;
    use crate::render::radiosity::polygon::point_to_rect;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::from_array([x, y, z])
    }

    /// Unit squares facing each other at distance 1: F = 0.19982 (Howell's catalogue C-11,
    /// X = Y = 1: (2/πXY){ln[(1+X²)(1+Y²)/(1+X²+Y²)]^½ + X√(1+Y²)atan(X/√(1+Y²)) + …}).
    #[test]
    fn facing_squares_match_the_catalogue() {
        let below = Rect::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let above = Rect::new(v(0.0, 0.0, 1.0), v(0.0, 1.0, 0.0), v(1.0, 0.0, 0.0));
        let (x, y) = (1.0f64, 1.0f64);
        let want = 2.0 / (std::f64::consts::PI * x * y)
            * (((1.0 + x * x) * (1.0 + y * y) / (1.0 + x * x + y * y))
                .sqrt()
                .ln()
                + x * (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan()
                + y * (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
                - x * x.atan()
                - y * y.atan());
        let f = rect_to_rect(&below, &above).unwrap();
        assert!((f - want).abs() < 1e-13, "{f} vs {want}");
        assert!((want - 0.19982).abs() < 1e-5);
    }

    /// Perpendicular squares sharing an edge: F = 0.20004 (Howell C-14, H = W = 1:
    /// (1/πW)[W atan(1/W) + H atan(1/H) − √(H²+W²) atan(1/√(H²+W²)) + ¼ ln(…)]).
    #[test]
    fn squares_at_a_corner_match_the_catalogue() {
        let floor = Rect::new(v(0.0, 0.0, 0.0), v(0.0, 0.0, 1.0), v(1.0, 0.0, 0.0));
        let wall = Rect::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        assert!(floor.normal.y > 0.5 && wall.normal.z > 0.5);
        let (h, w) = (1.0f64, 1.0f64);
        let s = (h * h + w * w).sqrt();
        let a = (1.0 + w * w) * (1.0 + h * h) / (1.0 + w * w + h * h);
        let b = (w * w * (1.0 + w * w + h * h) / ((1.0 + w * w) * (w * w + h * h))).powf(w * w);
        let c = (h * h * (1.0 + h * h + w * w) / ((1.0 + h * h) * (h * h + w * w))).powf(h * h);
        let want = (w * (1.0 / w).atan() + h * (1.0 / h).atan() - s * (1.0 / s).atan()
            + 0.25 * (a * b * c).ln())
            / (std::f64::consts::PI * w);
        let f = rect_to_rect(&floor, &wall).unwrap();
        assert!((f - want).abs() < 1e-13, "{f} vs {want}");
        assert!((want - 0.20004).abs() < 1e-5);
        // Reciprocity with unequal areas: a 2 × 1 wall.
        let tall = Rect::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 2.0, 0.0));
        let f12 = rect_to_rect(&floor, &tall).unwrap();
        let f21 = rect_to_rect(&tall, &floor).unwrap();
        assert!((f12 * 1.0 - f21 * 2.0).abs() < 1e-14, "{f12} {f21}");
    }

    /// Rectangles far apart and at an odd angle: the contour form (skew edges by
    /// quadrature) against a fine area quadrature of the exact point-to-rectangle factor.
    #[test]
    fn skew_rectangles_match_an_area_quadrature() {
        let a = Rect::new(v(0.0, 0.0, 0.0), v(0.3, 0.0, 0.0), v(0.0, 0.2, 0.05));
        let b = Rect::new(v(-0.2, 0.1, 1.0), v(0.2, 0.25, 0.0), v(0.3, -0.1, -0.1));
        let b = if b.normal.z > 0.0 {
            Rect::new(b.corner, b.edge_v, b.edge_u)
        } else {
            b
        };
        let f = rect_to_rect(&a, &b).unwrap();
        let want = average_over(&a, 24, |x| point_to_rect(x, a.normal, &b));
        assert!(f > 0.0);
        assert!((f - want).abs() < 1e-9 * want.max(1e-3), "{f} vs {want}");
    }

    /// Behind the other's plane, or coplanar: nothing; one straddling the other's plane:
    /// its part in front when the cut runs across an edge, no closed form when oblique.
    #[test]
    fn invisible_and_straddling_pairs() {
        let floor = Rect::new(v(0.0, 0.0, 0.0), v(0.0, 0.0, 1.0), v(1.0, 0.0, 0.0));
        let beside = Rect::new(v(1.0, 0.0, 0.0), v(0.0, 0.0, 1.0), v(1.0, 0.0, 0.0));
        assert_eq!(rect_to_rect(&floor, &beside), Some(0.0));
        let under = Rect::new(v(0.0, -1.0, 0.0), v(0.0, 0.0, 1.0), v(1.0, 0.0, 0.0));
        assert_eq!(rect_to_rect(&floor, &under), Some(0.0));
        let through = Rect::new(v(0.0, -0.5, 2.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let through = if through.normal.z > 0.0 {
            Rect::new(through.corner, through.edge_v, through.edge_u)
        } else {
            through
        };
        // Cut across an edge: the part above the floor, against the area quadrature.
        let f = rect_to_rect(&floor, &through).unwrap();
        let want = average_over(&floor, 24, |x| point_to_rect(x, floor.normal, &through));
        assert!((f - want).abs() < 1e-9 * want, "{f} vs {want}");
        let back = rect_to_rect(&through, &floor).unwrap();
        assert!((back * through.area_m2 - f * floor.area_m2).abs() < 1e-14);
        // Cut obliquely: no closed form.
        let tilted = Rect::new(v(0.0, -0.5, 2.0), v(1.0, 0.3, 0.0), v(0.0, 1.0, 0.0));
        let tilted = if tilted.normal.z > 0.0 {
            Rect::new(tilted.corner, tilted.edge_v, tilted.edge_u)
        } else {
            tilted
        };
        assert_eq!(rect_to_rect(&floor, &tilted), None);
    }
}
