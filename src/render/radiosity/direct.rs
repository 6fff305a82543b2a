//! The direct term: irradiance from the emitter tiles at a point, per unit of each
//! emitter's spectral radiance s·S(λ). A Lambertian tile is a uniform polygon, so the
//! point-to-polygon factor gives it in closed form (E = π·gain·F); a tile with a
//! directional factor f(ω) is integrated by Gauss–Legendre over the tile with the number
//! of nodes chosen from its size over the distance.

use super::super::geometry::{Rect, Vec3, VecOps};
use super::super::scene::{Distribution, Emitter};
use super::polygon::{gauss_legendre, point_to_rect};

/// The tile (row, col) of an emitter as a rectangle.
pub fn tile_rect(e: &Emitter, row: usize, col: usize) -> Rect {
    let du = e.rect.edge_u.times(1.0 / e.cols as f64);
    let dv = e.rect.edge_v.times(1.0 / e.rows as f64);
    Rect::new(
        e.rect
            .corner
            .plus(du.times(col as f64))
            .plus(dv.times(row as f64)),
        du,
        dv,
    )
}

/// Gauss–Legendre nodes per side for integrating over a patch of size `size` at distance
/// `dist`: the 1/r² kernel's error falls like (size/2·dist)^(2n), so near patches get more.
pub fn nodes_for(size: f64, dist: f64) -> usize {
    let ratio = size / dist.max(1e-12);
    ((4.0 + 8.0 * ratio).ceil() as usize).min(24)
}

/// g(x) = E(x)/(s·S(λ)) for one emitter: irradiance at `x` (unit normal `n`) per unit
/// spectral radiance, in sr (W·m⁻² per W·sr⁻¹·m⁻²).
pub fn irradiance_factor(e: &Emitter, x: Vec3, n: Vec3) -> f64 {
    let mut total = 0.0;
    for row in 0..e.rows {
        for col in 0..e.cols {
            let gain = e.gains[row * e.cols + col];
            if gain == 0.0 {
                continue;
            }
            let tile = tile_rect(e, row, col);
            total += gain
                * match e.distribution {
                    Distribution::Lambertian => std::f64::consts::PI * point_to_rect(x, n, &tile),
                    d => quadrature(&tile, d, x, n),
                };
        }
    }
    total
}

/// ∫ f(cos θ_s) cos θ_x cos θ_s / r² dA over a tile, by tensor Gauss–Legendre.
fn quadrature(tile: &Rect, d: Distribution, x: Vec3, n: Vec3) -> f64 {
    // Behind the emitting side nothing arrives.
    if x.minus(tile.corner).dot(tile.normal) <= 0.0 {
        return 0.0;
    }
    let size = tile.edge_u.length().max(tile.edge_v.length());
    let dist = tile.centre().minus(x).length();
    let q = gauss_legendre(nodes_for(size, dist));
    let mut s = 0.0;
    for &(a, wa) in &q {
        for &(b, wb) in &q {
            let y = tile.point(a, b);
            let r = y.minus(x);
            let r2 = r.dot(r);
            let rl = r2.sqrt();
            let cos_x = r.dot(n) / rl;
            if cos_x <= 0.0 {
                continue;
            }
            let cos_s = -r.dot(tile.normal) / rl;
            s += wa * wb * d.factor(cos_s) * cos_x * cos_s / r2;
        }
    }
    s * tile.area_m2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::spectral::constant_bins;

    fn emitter(distribution: Distribution) -> Emitter {
        Emitter {
            rect: Rect::new(
                Vec3::from_array([-0.5, -0.5, 1.0]),
                Vec3::from_array([0.0, 1.0, 0.0]),
                Vec3::from_array([1.0, 0.0, 0.0]),
            ),
            rows: 3,
            cols: 3,
            gains: vec![1.0; 9],
            radiance: constant_bins(1.0),
            scale: 1.0,
            distribution,
            reflectance: constant_bins(0.0),
        }
    }

    /// cos⁰ is Lambertian: the quadrature must reproduce the closed form.
    #[test]
    fn quadrature_matches_the_closed_form() {
        let lam = emitter(Distribution::Lambertian);
        let cos0 = emitter(Distribution::CosPower(0.0));
        for (x, n) in [
            (
                Vec3::from_array([0.0, 0.0, 0.0]),
                Vec3::from_array([0.0, 0.0, 1.0]),
            ),
            (
                Vec3::from_array([0.3, -0.2, 0.5]),
                Vec3::from_array([0.0, 0.0, 1.0]),
            ),
            (
                Vec3::from_array([0.6, 0.1, 0.7]),
                Vec3::from_array([-0.6, 0.0, 0.8]),
            ),
        ] {
            let a = irradiance_factor(&lam, x, n);
            let b = irradiance_factor(&cos0, x, n);
            assert!((a - b).abs() < 1e-6 * a, "{x:?}: {a} vs {b}");
        }
    }

    /// On the axis of a disc-like source far away, a cos^m emitter of area A gives
    /// E = A·f(1)/d² with cos θ ≈ 1: the far-field limit checks the kernel's factors.
    #[test]
    fn far_field_is_inverse_square() {
        let e = emitter(Distribution::CosPower(3.0));
        let d = 200.0;
        let g = irradiance_factor(
            &e,
            Vec3::from_array([0.0, 0.0, 1.0 - d]),
            Vec3::from_array([0.0, 0.0, 1.0]),
        );
        let want = 1.0 / (d * d);
        assert!((g - want).abs() < 1e-4 * want, "{g} vs {want}");
    }
}
