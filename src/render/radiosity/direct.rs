//! The direct term: irradiance from the emitter tiles at a point, per unit of one
//! component's spectral radiance (the tiles that radiate that spectrum, each with its gain
//! as weight). A Lambertian tile is a uniform polygon, so the point-to-polygon factor gives
//! it in closed form (E = π·gain·F); a tile with a directional factor f(ω) — cosᵐ or a
//! C-γ table, evaluated in the emitter's frame — is integrated by Gauss–Legendre over the
//! tile with the number of nodes chosen from its size over the distance.

use super::super::geometry::{Rect, Vec3, VecOps};
use super::super::scene::{Distribution, Emitter};

use super::form::form_factor;
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

/// g(x) = E(x)/S(λ) for the tiles of emitter `e` weighted by `weights` (one per tile, 0 to
/// leave a tile out): irradiance at `x` (unit normal `n`) per unit spectral radiance, in sr
/// (W·m⁻² per W·sr⁻¹·m⁻²).
pub fn irradiance_factor(e: &Emitter, weights: &[f64], x: Vec3, n: Vec3) -> f64 {
    let mut total = 0.0;
    for row in 0..e.rows {
        for col in 0..e.cols {
            let gain = weights[row * e.cols + col];
            if gain == 0.0 {
                continue;
            }
            let tile = tile_rect(e, row, col);
            total += gain
                * match e.distribution {
                    Distribution::Lambertian => std::f64::consts::PI * point_to_rect(x, n, &tile),
                    _ => quadrature(e, &tile, x, n),
                };
        }
    }
    total
}

/// ∫ f(ω) cos θ_x cos θ_s / r² dA over a tile, by tensor Gauss–Legendre.
fn quadrature(e: &Emitter, tile: &Rect, x: Vec3, n: Vec3) -> f64 {
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
            s += wa * wb * e.directional(r.times(-1.0 / rl)) * cos_x * cos_s / r2;
        }
    }
    s * tile.area_m2
}

/// The mean of g/π over a receiving rectangle, exactly, for a Lambertian emitter: the
/// element-to-tile form factors weighted by the tiles' gains. None for a directional
/// emitter, or when a tile straddles the element's plane (a point rule with clipping does).
pub fn mean_factor_over(e: &Emitter, weights: &[f64], el: &Rect) -> Option<f64> {
    if e.distribution != Distribution::Lambertian {
        return None;
    }
    let mut total = 0.0;
    for row in 0..e.rows {
        for col in 0..e.cols {
            let gain = weights[row * e.cols + col];
            if gain != 0.0 {
                total += gain * form_factor(el, &tile_rect(e, row, col), true)?;
            }
        }
    }
    Some(total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::CGammaTable;
    use crate::render::spectral::constant_bins;
    use std::sync::Arc;

    fn panel(corner: [f64; 3], side: f64, n: usize, distribution: Distribution) -> Emitter {
        // edge_u along +y, edge_v along +x: the normal y × x = −z.
        let rect = Rect::new(
            Vec3::from_array(corner),
            Vec3::from_array([0.0, side, 0.0]),
            Vec3::from_array([side, 0.0, 0.0]),
        );
        Emitter {
            axis_u: rect.edge_u.normalized(),
            axis_v: rect.edge_v.normalized(),
            rect,
            rows: n,
            cols: n,
            gains: vec![1.0; n * n],
            tile_spectrum: vec![0; n * n],
            spectra: vec![constant_bins(1.0)],
            scale: 1.0,
            distribution,
            reflectance: constant_bins(0.0),
        }
    }

    fn emitter(distribution: Distribution) -> Emitter {
        panel([-0.5, -0.5, 1.0], 1.0, 3, distribution)
    }

    fn g(e: &Emitter, x: Vec3, n: Vec3) -> f64 {
        irradiance_factor(e, &e.gains, x, n)
    }

    /// cos⁰ is Lambertian: the quadrature must reproduce the closed form.
    #[test]
    fn quadrature_matches_the_closed_form() {
        let lam = emitter(Distribution::Lambertian);
        let cos0 = emitter(Distribution::CosPower(0.0));
        let flat = emitter(Distribution::Table(Arc::new(
            CGammaTable::symmetric(vec![0.0, 90.0], vec![1.0, 1.0]).unwrap(),
        )));
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
            let a = g(&lam, x, n);
            for other in [&cos0, &flat] {
                let b = g(other, x, n);
                assert!((a - b).abs() < 1e-6 * a, "{x:?}: {a} vs {b}");
            }
        }
    }

    /// On the axis of a disc-like source far away, a cos^m emitter of area A gives
    /// E = A·f(1)/d² with cos θ ≈ 1: the far-field limit checks the kernel's factors.
    #[test]
    fn far_field_is_inverse_square() {
        let e = emitter(Distribution::CosPower(3.0));
        let d = 200.0;
        let g = g(
            &e,
            Vec3::from_array([0.0, 0.0, 1.0 - d]),
            Vec3::from_array([0.0, 0.0, 1.0]),
        );
        let want = 1.0 / (d * d);
        assert!((g - want).abs() < 1e-4 * want, "{g} vs {want}");
    }

    /// f = 1 − a·γ/90 in the four half-planes C = 0, 90, 180, 270 with a = 0.2, 0.4, 0.6,
    /// 0.8: asymmetric left/right and front/back.
    fn table() -> Arc<CGammaTable> {
        let rows = [0.2, 0.4, 0.6, 0.8]
            .iter()
            .map(|a| vec![1.0, 1.0 - a / 2.0, 1.0 - a])
            .collect();
        Arc::new(
            CGammaTable::new(vec![0.0, 90.0, 180.0, 270.0], vec![0.0, 45.0, 90.0], rows).unwrap(),
        )
    }

    /// A 10 µm tile seen from r = 0.5 m at (C, γ), the receiver facing it (the tile spans
    /// 0.001° there, so the table's kinks across C-planes stay below 1e-6 relative):
    /// E = L₀·A·f(C, γ)·cos γ / r² (cos θ_x = 1), per unit L₀. By hand for the table above:
    /// C = 0, γ = 45°: f = 0.9; C = 180°: f = 0.7; C = 90°, γ = 22.5°: f = 1 − 0.4/4 = 0.9;
    /// C = 45°, γ = 45°: halfway between planes 0 and 90, f = 1 − 0.3/2 = 0.85.
    #[test]
    fn a_small_c_gamma_emitter_follows_its_table() {
        let side = 1e-5;
        let e = panel(
            [-side / 2.0, -side / 2.0, 1.0],
            side,
            1,
            Distribution::Table(table()),
        );
        let centre = e.rect.centre();
        let (u, v, n) = (e.axis_u, e.axis_v, e.rect.normal);
        let r = 0.5;
        let area = side * side;
        for (c, gamma, f) in [
            (0.0f64, 45.0f64, 0.9),
            (180.0, 45.0, 0.7),
            (90.0, 22.5, 0.9),
            (45.0, 45.0, 0.85),
            (0.0, 0.0, 1.0),
        ] {
            let (c, gm) = (c.to_radians(), gamma.to_radians());
            let dir = u
                .times(gm.sin() * c.cos())
                .plus(v.times(gm.sin() * c.sin()))
                .plus(n.times(gm.cos()));
            let x = centre.plus(dir.times(r));
            let got = g(&e, x, dir.times(-1.0));
            let want = area * f * gm.cos() / (r * r);
            assert!(
                (got - want).abs() < 1e-5 * want,
                "C {c} γ {gamma}: {got} vs {want}"
            );
        }
        // Left and right of the axis at the same distance: the ratio is f(0, 45)/f(180, 45).
        let at = |c: f64| {
            let dir = u
                .times(c.to_radians().cos() * 0.5f64.sqrt())
                .plus(n.times(0.5f64.sqrt()));
            g(&e, centre.plus(dir.times(r)), n.times(-1.0))
        };
        let ratio = at(0.0) / at(180.0);
        assert!((ratio - 0.9 / 0.7).abs() < 1e-5, "{ratio}");
    }
}
