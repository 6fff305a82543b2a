//! The error bound: readings on three successive refinements, Richardson extrapolation
//! from each consecutive pair, and their disagreement as ΔE*ab.
//!
//! With element size h ∝ 1/level, a reading behaves like R(h) = R∞ + C·hᵖ once the mesh
//! resolves the light. Extrapolating the pairs (m−2, m−1) and (m−1, m) gives two estimates
//! of R∞; if the model holds they agree to a higher order, and their difference is a
//! bound for the error left in the finer one.

use crate::color::{delta_e76, Xyz};

/// R∞ from readings `coarse` at size `h_coarse` and `fine` at `h_fine`, order `p`.
pub fn richardson(coarse: f64, h_coarse: f64, fine: f64, h_fine: f64, p: f64) -> f64 {
    let a = h_coarse.powf(p);
    let b = h_fine.powf(p);
    (fine * a - coarse * b) / (a - b)
}

/// The same for XYZ triples.
pub fn richardson3(
    coarse: [f64; 3],
    h_coarse: f64,
    fine: [f64; 3],
    h_fine: f64,
    p: f64,
) -> [f64; 3] {
    std::array::from_fn(|k| richardson(coarse[k], h_coarse, fine[k], h_fine, p))
}

/// One patch's estimate from three levels (coarsest first) of the patch and the white.
#[derive(Clone, Copy, Debug)]
pub struct Extrapolated {
    pub xyz: [f64; 3],
    pub white: [f64; 3],
    /// ΔE*ab between the two extrapolations, each against its own white.
    pub de_bound: f64,
}

/// Extrapolates levels `h[0] > h[1] > h[2]`; with `fixed_white` the white is not refined.
pub fn extrapolate(
    patch: [[f64; 3]; 3],
    white: [[f64; 3]; 3],
    h: [f64; 3],
    p: f64,
    fixed_white: Option<[f64; 3]>,
) -> Extrapolated {
    let fine = richardson3(patch[1], h[1], patch[2], h[2], p);
    let coarse = richardson3(patch[0], h[0], patch[1], h[1], p);
    let (wf, wc) = match fixed_white {
        Some(w) => (w, w),
        None => (
            richardson3(white[1], h[1], white[2], h[2], p),
            richardson3(white[0], h[0], white[1], h[1], p),
        ),
    };
    let lab = |x: [f64; 3], w: [f64; 3]| Xyz::from_array(x).to_lab(Xyz::from_array(w));
    Extrapolated {
        xyz: fine,
        white: wf,
        de_bound: delta_e76(lab(fine, wf), lab(coarse, wc)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reading that follows R∞ + C·h² exactly is recovered from any two levels.
    #[test]
    fn exact_model_is_recovered() {
        let f = |h: f64| 3.0 + 0.7 * h * h;
        let r = richardson(f(0.5), 0.5, f(1.0 / 3.0), 1.0 / 3.0, 2.0);
        assert!((r - 3.0).abs() < 1e-14, "{r}");
    }

    /// With R = R∞ + C·h² + D·h³ the two extrapolations differ by O(h³), and the finer
    /// one is closer to R∞ than that difference: the bound holds.
    #[test]
    fn bound_covers_a_higher_order_term() {
        let f = |h: f64| [10.0 + 2.0 * h * h + 3.0 * h.powi(3), 10.0, 10.0];
        let h = [1.0, 0.5, 1.0 / 3.0];
        let w = [[100.0; 3]; 3];
        let e = extrapolate([f(h[0]), f(h[1]), f(h[2])], w, h, 2.0, None);
        let truth = Xyz::from_array([10.0, 10.0, 10.0]).to_lab(Xyz::from_array([100.0; 3]));
        let got = Xyz::from_array(e.xyz).to_lab(Xyz::from_array(e.white));
        let err = delta_e76(truth, got);
        assert!(err < e.de_bound, "error {err} vs bound {}", e.de_bound);
    }
}
