//! The exact point-to-polygon form factor (Lambert 1760; the edge-sum form as in
//! Baum, Rushmeier & Winget 1989) and Gauss–Legendre nodes for the quadratures around it.
//!
//! For a uniform Lambertian polygon of radiance L seen from a point x with unit normal n,
//! the irradiance is E = L·½ Σᵢ γᵢ (n·Γᵢ), with rᵢ the unit vectors to the vertices, γᵢ
//! the angle between rᵢ and rᵢ₊₁ and Γᵢ the unit normal of the plane through x and the
//! edge. The formula needs the whole polygon above x's tangent plane, so the polygon is
//! clipped against that plane first; after the clip cos θ ≥ 0 over it and the sum's
//! magnitude is the factor whatever the vertex order.

use super::super::geometry::{Rect, Vec3, VecOps};

/// Most vertices a clipped quadrilateral can have (one plane adds at most one vertex).
const MAX_VERTS: usize = 5;

/// Form factor F(x → polygon) = E/(πL) for a convex polygon given by its vertices; the
/// polygon emits from the side `front` points to (x behind it gets 0).
pub fn point_to_polygon(x: Vec3, n: Vec3, verts: &[Vec3], front: Vec3) -> f64 {
    debug_assert!(verts.len() <= 4);
    // One-sided emitter: x must be in front of the polygon's plane.
    if verts[0].minus(x).dot(front) >= 0.0 {
        return 0.0;
    }
    // Vertices relative to x, clipped to the half-space n·p ≥ 0 (Sutherland–Hodgman).
    let mut rel = [Vec3::from_array([0.0; 3]); MAX_VERTS];
    let mut h = [0.0; 4];
    let mut all_above = true;
    let mut any_above = false;
    for (i, v) in verts.iter().enumerate() {
        let r = v.minus(x);
        h[i] = r.dot(n);
        rel[i] = r;
        all_above &= h[i] >= 0.0;
        any_above |= h[i] > 0.0;
    }
    if !any_above {
        return 0.0;
    }
    let m = verts.len();
    let mut clipped = [Vec3::from_array([0.0; 3]); MAX_VERTS + 1];
    let count = if all_above {
        clipped[..m].copy_from_slice(&rel[..m]);
        m
    } else {
        let mut c = 0;
        for i in 0..m {
            let j = (i + 1) % m;
            let (a, b) = (rel[i], rel[j]);
            let (ha, hb) = (h[i], h[j]);
            if ha >= 0.0 {
                clipped[c] = a;
                c += 1;
            }
            if (ha >= 0.0) != (hb >= 0.0) {
                let t = ha / (ha - hb);
                let p = a.plus(b.minus(a).times(t));
                // Exactly on the plane: remove the rounding left by the interpolation.
                clipped[c] = p.minus(n.times(p.dot(n)));
                c += 1;
            }
        }
        c
    };
    edge_sum(n, &clipped[..count]).abs() / (2.0 * std::f64::consts::PI)
}

/// Σ γᵢ (n·Γᵢ) over the edges of a polygon given relative to the receiving point.
fn edge_sum(n: Vec3, rel: &[Vec3]) -> f64 {
    let mut unit = [Vec3::from_array([0.0; 3]); MAX_VERTS + 1];
    for (u, r) in unit.iter_mut().zip(rel) {
        let l = r.length();
        if l == 0.0 {
            // x on a vertex: the factor is still finite; move on the vertex's neighbour.
            return f64::NAN;
        }
        *u = r.times(1.0 / l);
    }
    let k = rel.len();
    let mut sum = 0.0;
    for i in 0..k {
        let a = unit[i];
        let b = unit[(i + 1) % k];
        let c = a.cross(b);
        let s = c.length();
        let d = a.dot(b);
        // γ·(n·c)/|c|, with γ/|c| → 1/d as the edge shrinks to a point seen head-on.
        let g = s.atan2(d);
        let w = if s > 1e-12 {
            g / s
        } else {
            1.0 / d.max(1e-300)
        };
        sum += w * n.dot(c);
    }
    sum
}

/// The four corners of a rectangle in the order that walks its boundary.
pub fn corners(r: &Rect) -> [Vec3; 4] {
    [
        r.corner,
        r.corner.plus(r.edge_u),
        r.corner.plus(r.edge_u).plus(r.edge_v),
        r.corner.plus(r.edge_v),
    ]
}

/// F(x → rectangle) for a rectangle emitting from its front (normal) side.
pub fn point_to_rect(x: Vec3, n: Vec3, r: &Rect) -> f64 {
    let f = point_to_polygon(x, n, &corners(r), r.normal);
    if f.is_nan() {
        // x sits on a corner of the rectangle: coplanar with it, so the factor is 0.
        0.0
    } else {
        f
    }
}

/// Gauss–Legendre nodes and weights on [0, 1] (weights sum to 1), by Newton's method on
/// the Legendre recurrence (Golub–Welsch would do as well; n is small).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let n = n.max(1);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let p = if n == 1 { x } else { p1 };
            let pm1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * p - pm1) / (x * x - 1.0);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push(((1.0 - x) / 2.0, w / 2.0));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square_at(h: f64) -> Rect {
        // 1×1 square centred on the z axis at height h, facing down (−z).
        Rect::new(
            Vec3::from_array([-0.5, -0.5, h]),
            Vec3::from_array([0.0, 1.0, 0.0]),
            Vec3::from_array([1.0, 0.0, 0.0]),
        )
    }

    /// The parallel-rectangle factor from a point under a corner (Howell's catalogue C-11:
    /// F = (1/2π)[X/√(1+X²)·atan(Y/√(1+X²)) + Y/√(1+Y²)·atan(X/√(1+Y²))]).
    fn corner_factor(a: f64, b: f64, c: f64) -> f64 {
        let (x, y) = (a / c, b / c);
        let sx = (1.0 + x * x).sqrt();
        let sy = (1.0 + y * y).sqrt();
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
    }

    #[test]
    fn parallel_square_matches_the_catalogue() {
        let up = Vec3::from_array([0.0, 0.0, 1.0]);
        for h in [0.1, 0.5, 1.0, 3.0] {
            let f = point_to_rect(Vec3::from_array([0.0; 3]), up, &unit_square_at(h));
            let want = 4.0 * corner_factor(0.5, 0.5, h);
            assert!((f - want).abs() < 1e-12, "h {h}: {f} vs {want}");
        }
    }

    #[test]
    fn back_side_and_below_the_horizon_give_zero() {
        let r = unit_square_at(1.0);
        // Above the square: behind its emitting side.
        assert_eq!(
            point_to_rect(
                Vec3::from_array([0.0, 0.0, 2.0]),
                Vec3::from_array([0.0, 0.0, -1.0]),
                &r
            ),
            0.0
        );
        // Facing away.
        assert_eq!(
            point_to_rect(
                Vec3::from_array([0.0; 3]),
                Vec3::from_array([0.0, 0.0, -1.0]),
                &r
            ),
            0.0
        );
    }

    /// A receiver tilted 90° sees half of a square centred over it: the clip must give
    /// exactly the perpendicular-rectangle factor of the half it keeps (catalogue C-14
    /// in its point form: F = (1/2π)[atan(1/Y) − Y/√(X²+Y²)·atan(1/√(X²+Y²))] for a
    /// point at the corner, X, Y the rectangle's sides over the distance).
    #[test]
    fn straddling_polygon_is_clipped() {
        let r = unit_square_at(1.0);
        // Normal +x: keeps the half x ≥ 0 (a 0.5 × 1 rectangle at height 1).
        let f = point_to_rect(
            Vec3::from_array([0.0; 3]),
            Vec3::from_array([1.0, 0.0, 0.0]),
            &r,
        );
        // Point in the plane perpendicular to the half-square through its edge x = 0;
        // split the half into two 0.5 × 0.5 pieces at y = 0 sharing the corner above x.
        // Each piece: a rectangle parallel to the receiver's normal direction, at
        // distance 1 along z. Factor of a rectangle of width w (along x, normal) and
        // length l (along y) in a plane at distance c, with x at the foot of one corner:
        // (1/2π)[atan(l/c) − c/√(w²+c²)·atan(l/√(w²+c²))].
        let piece = |w: f64, l: f64, c: f64| {
            let s = (w * w + c * c).sqrt();
            ((l / c).atan() - c / s * (l / s).atan()) / (2.0 * std::f64::consts::PI)
        };
        let want = 2.0 * piece(0.5, 0.5, 1.0);
        assert!((f - want).abs() < 1e-12, "{f} vs {want}");
    }

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        for n in 1..=8 {
            let q = gauss_legendre(n);
            for k in 0..(2 * n) {
                let s: f64 = q.iter().map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!(
                    (s - 1.0 / (k as f64 + 1.0)).abs() < 1e-13,
                    "n {n} k {k}: {s}"
                );
            }
        }
    }
}
