//! The error bound: readings on successive refinements, Richardson extrapolation, and the
//! distance to an alternative extrapolation as the bound.
//!
//! With element size h ∝ 1/level, a reading behaves like R(h) = R∞ + C·hᵖ once the mesh
//! resolves the light, p = 2 for a smooth field. Near the room's concave edges the radiosity
//! has a logarithmic slope, and the readings then converge like h²·ln h: more slowly than
//! h², so that extrapolating with p = 2 stops short of R∞, and the two extrapolations of
//! consecutive pairs (the classical bound) agree with each other better than with R∞. So
//! the order is measured from the last three levels: where they converge more slowly than
//! assumed, the estimate is extrapolated with the observed order and the bound is its
//! distance from the assumed order's extrapolation (the truth lies between them, or close
//! beyond the observed one's side, as long as the effective order keeps rising towards p);
//! where they converge as fast or faster, the classical bound stands. With a fourth level
//! the previous estimate is a further alternative: the bound is at least the step between
//! them.
//!
//! Levels that do not converge monotonically are either not yet in the asymptotic range (a
//! point closer to an edge than the elements are small) or already converged below what
//! the sums can resolve: their changes are then the Gauss–Seidel iteration's remainder and
//! rounding, whose sign means nothing. Such an estimate is marked irregular unless its
//! changes are at that floor; its bound is then at least what the slowest convergence
//! trusted (order [`MIN_ORDER`]) could still add to the last change ([`turning_gain`] times
//! it), so a turn whose changes are small against the tolerance (at most 1/gain of it, a
//! tenth at level 3, a twentieth at level 6) is converged whatever its sign, and a turn by
//! a large change is not. A sequence that converges monotonically but more slowly than
//! [`MIN_ORDER`] stays irregular: its bound cannot be trusted however small it is.

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

/// The lowest order an extrapolation is trusted with: below it, (h₁/h₂)^q − 1 is so small
/// that the extrapolation amplifies every error in the readings.
pub const MIN_ORDER: f64 = 0.5;

/// The order q at which R∞ + C·h^q passes through the three readings (coarsest first), or
/// None when they do not converge monotonically.
pub fn observed_order(v: [f64; 3], h: [f64; 3]) -> Option<f64> {
    let (d1, d2) = (v[1] - v[0], v[2] - v[1]);
    if d1 * d2 <= 0.0 || (d1 * d2).is_nan() {
        return None;
    }
    let ratio = d1 / d2;
    // (h₀^q − h₁^q)/(h₁^q − h₂^q) grows with q; bisect in [1/64, 16].
    let f = |q: f64| (h[0].powf(q) - h[1].powf(q)) / (h[1].powf(q) - h[2].powf(q));
    let (mut lo, mut hi) = (1.0 / 64.0, 16.0);
    if ratio <= f(lo) {
        return Some(lo);
    }
    if ratio >= f(hi) {
        return Some(hi);
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// The relative rounding floor of a reading: every reading is a sum over at most
/// [`MAX_ELEMENTS`](super::mesh::MAX_ELEMENTS) elements' terms (5,000 × 2.2e-16 ≈ 1.1e-12
/// of the sum), so changes between levels this small say nothing about convergence.
pub const ROUNDING_FLOOR: f64 = 1e-12;

/// One quantity's estimate from its last levels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub value: f64,
    /// The alternative extrapolation whose distance is the bound.
    pub alt: f64,
    /// The previous levels' estimate, when there were four levels.
    pub previous: Option<f64>,
    /// The last three levels converge monotonically at an order of at least [`MIN_ORDER`],
    /// or change by no more than rounding.
    pub regular: bool,
    /// The last three levels turn back (the two changes have opposite signs, or one is 0).
    pub turning: bool,
    /// The larger of the last two changes between levels (absolute).
    pub step: f64,
}

impl Estimate {
    /// The bound of a scalar: the larger distance to an alternative.
    pub fn bound(&self) -> f64 {
        let b = (self.value - self.alt).abs();
        self.previous.map_or(b, |p| b.max((self.value - p).abs()))
    }
}

/// The estimate from the last three of `v` (coarsest first, element sizes `h`), order `p`
/// assumed; with four or more, the estimate of the three before it too.
pub fn estimate(v: &[f64], h: &[f64], p: f64) -> Estimate {
    let n = v.len();
    debug_assert!(n >= 3 && h.len() == n);
    let last = |k: usize| -> Estimate {
        let (v3, h3) = (
            [v[k - 3], v[k - 2], v[k - 1]],
            [h[k - 3], h[k - 2], h[k - 1]],
        );
        let fine = richardson(v3[1], h3[1], v3[2], h3[2], p);
        let coarse = richardson(v3[0], h3[0], v3[1], h3[1], p);
        let step = (v3[2] - v3[1]).abs().max((v3[1] - v3[0]).abs());
        // Readings equal to rounding need no order.
        let settled = step <= ROUNDING_FLOOR * v3[2].abs().max(f64::MIN_POSITIVE);
        match observed_order(v3, h3) {
            Some(q) if q < p => {
                let q_used = q.max(MIN_ORDER);
                Estimate {
                    value: richardson(v3[1], h3[1], v3[2], h3[2], q_used),
                    alt: fine,
                    previous: None,
                    regular: q >= MIN_ORDER || settled,
                    turning: false,
                    step,
                }
            }
            Some(_) => Estimate {
                value: fine,
                alt: coarse,
                previous: None,
                regular: true,
                turning: false,
                step,
            },
            None => Estimate {
                value: fine,
                alt: coarse,
                previous: None,
                regular: settled,
                turning: true,
                step,
            },
        }
    };
    let mut e = last(n);
    if n >= 4 {
        e.previous = Some(last(n - 1).value);
    }
    e
}

/// The factor by which the last levels' changes may grow into the error of their estimate
/// when the convergence is no faster than order min(`p`, [`MIN_ORDER`]): an extrapolation's
/// weights sum in magnitude to (a + b)/(a − b) ≤ 1 + 2/((h₁/h₂)^q − 1), and a monotone
/// sequence of that order whose last change is d has at most d/((h₁/h₂)^q − 1) left to go.
/// `h` holds the element sizes, coarsest first (at least two).
pub fn turning_gain(h: &[f64], p: f64) -> f64 {
    let n = h.len();
    let r = (h[n - 2] / h[n - 1]).powf(MIN_ORDER.min(p));
    1.0 + 2.0 / (r - 1.0)
}

/// A scalar's estimate from its levels, with its bound (see [`extrapolated_with_bound`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scalar {
    pub value: f64,
    pub bound: f64,
    /// See [`Estimate::regular`]; also true when the last changes are within what the
    /// stopped iteration leaves.
    pub regular: bool,
    /// The last levels turn back by changes that are not at the floor (see the module's
    /// documentation): the bound is then at least [`turning_gain`] times the last change.
    pub turning: bool,
}

impl Scalar {
    /// Whether the estimate is converged to an absolute tolerance `tol`: its bound is within
    /// it, and it converges regularly or turns back by changes so small against `tol` that
    /// their sign does not matter (the bound of a turning estimate covers them). A slow
    /// monotone sequence is not converged, however small its bound.
    pub fn converged(&self, tol: f64) -> bool {
        self.bound <= tol && (self.regular || self.turning)
    }
}

/// A scalar's estimate and bound from its levels (see [`estimate`]); `abs_err` is an
/// absolute error each level's reading may carry besides the discretization (the stopped
/// iteration), which the extrapolation can amplify. Levels whose changes are within twice
/// `abs_err` (each of two levels may carry it) and rounding are regular whatever their
/// signs; levels that turn back by more get a bound of at least [`turning_gain`] times their
/// larger change.
pub fn extrapolated_with_bound(v: &[f64], h: &[f64], p: f64, abs_err: f64) -> Scalar {
    let e = estimate(v, h, p);
    let gain = turning_gain(h, p);
    let floor = 2.0 * abs_err + ROUNDING_FLOOR * e.value.abs();
    let at_floor = e.step <= floor;
    let mut bound = e.bound();
    let turning = e.turning && !at_floor;
    if turning {
        bound = bound.max(gain * e.step);
    }
    Scalar {
        value: e.value,
        bound: bound + gain * abs_err,
        regular: e.regular || at_floor,
        turning,
    }
}

/// One patch's estimate from its levels (coarsest first) of the patch and the white.
#[derive(Clone, Copy, Debug)]
pub struct Extrapolated {
    pub xyz: Xyz,
    pub white: Xyz,
    /// ΔE*ab between the estimate and its furthest alternative, each against its own white.
    pub de_bound: f64,
    /// Every component converged regularly (see [`estimate`]).
    pub regular: bool,
}

/// Extrapolates the patch and the white over levels of sizes `h` (decreasing, at least
/// three); with `fixed_white` the white is not refined.
pub fn extrapolate(
    patch: &[Xyz],
    white: &[Xyz],
    h: &[f64],
    p: f64,
    fixed_white: Option<Xyz>,
) -> Extrapolated {
    let comps = |levels: &[Xyz]| -> [Estimate; 3] {
        std::array::from_fn(|k| {
            let v: Vec<f64> = levels.iter().map(|x| x[k]).collect();
            estimate(&v, h, p)
        })
    };
    let pe = comps(patch);
    let we = match fixed_white {
        Some(w) => [w.x, w.y, w.z].map(|x| Estimate {
            value: x,
            alt: x,
            previous: Some(x),
            regular: true,
            turning: false,
            step: 0.0,
        }),
        None => comps(white),
    };
    let pick = |e: &[Estimate; 3], f: &dyn Fn(&Estimate) -> f64| -> Xyz {
        Xyz::new(f(&e[0]), f(&e[1]), f(&e[2]))
    };
    let lab = |x: Xyz, w: Xyz| x.to_lab(w);
    let value = lab(pick(&pe, &|e| e.value), pick(&we, &|e| e.value));
    let alt = lab(pick(&pe, &|e| e.alt), pick(&we, &|e| e.alt));
    let mut de_bound = delta_e76(value, alt);
    if pe.iter().chain(&we).all(|e| e.previous.is_some()) {
        let prev = lab(
            pick(&pe, &|e| e.previous.unwrap_or(e.value)),
            pick(&we, &|e| e.previous.unwrap_or(e.value)),
        );
        de_bound = de_bound.max(delta_e76(value, prev));
    }
    Extrapolated {
        xyz: pick(&pe, &|e| e.value),
        white: pick(&we, &|e| e.value),
        de_bound,
        regular: pe.iter().chain(&we).all(|e| e.regular),
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

    /// The order of R∞ + C·h^q is found for q on either side of the assumed 2.
    #[test]
    fn observed_order_is_the_model_order() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        for q in [0.7, 1.0, 1.5, 2.0, 3.0] {
            let v = h.map(|x: f64| 5.0 - 2.0 * x.powf(q));
            let got = observed_order(v, h).unwrap();
            assert!((got - q).abs() < 1e-9, "{q}: {got}");
        }
        assert_eq!(observed_order([1.0, 2.0, 1.5], h), None);
    }

    /// With R = R∞ + C·h² + D·h³ the two extrapolations differ by O(h³), and the finer
    /// one is closer to R∞ than that difference: the bound holds.
    #[test]
    fn bound_covers_a_higher_order_term() {
        let f = |h: f64| Xyz::new(10.0 + 2.0 * h * h + 3.0 * h.powi(3), 10.0, 10.0);
        let h = [1.0, 0.5, 1.0 / 3.0];
        let w = [Xyz::new(100.0, 100.0, 100.0); 3];
        let e = extrapolate(&[f(h[0]), f(h[1]), f(h[2])], &w, &h, 2.0, None);
        let truth = Xyz::from_array([10.0, 10.0, 10.0]).to_lab(Xyz::from_array([100.0; 3]));
        let got = e.xyz.to_lab(e.white);
        let err = delta_e76(truth, got);
        assert!(err < e.de_bound, "error {err} vs bound {}", e.de_bound);
        assert!(e.regular);
    }

    /// Readings converging like h²·ln h — what a room's concave edges give — on levels 1
    /// to 14: the assumed-order extrapolation's classical bound fails from level 4 on, the
    /// observed-order estimate's bound holds at every level.
    #[test]
    fn bound_holds_for_a_logarithmic_term() {
        let r = |h: f64| 1.0 + 0.3 * h * h * (1.0 - 2.0 * h.ln()) - 0.1 * h.powi(3);
        let levels: Vec<f64> = (1..=14).map(|k| 0.5 / k as f64).collect();
        let v: Vec<f64> = levels.iter().map(|&h| r(h)).collect();
        for m in 3..=levels.len() {
            let (vs, hs) = (&v[..m], &levels[..m]);
            let classical = (richardson(vs[m - 2], hs[m - 2], vs[m - 1], hs[m - 1], 2.0)
                - richardson(vs[m - 3], hs[m - 3], vs[m - 2], hs[m - 2], 2.0))
            .abs();
            let classical_err =
                (richardson(vs[m - 2], hs[m - 2], vs[m - 1], hs[m - 1], 2.0) - 1.0).abs();
            if m >= 4 {
                assert!(
                    classical_err > classical,
                    "level {m}: the classical bound held"
                );
            }
            let s = extrapolated_with_bound(vs, hs, 2.0, 0.0);
            assert!(s.regular && !s.turning);
            assert!(
                (s.value - 1.0).abs() <= s.bound,
                "level {m}: error {} vs bound {}",
                (s.value - 1.0).abs(),
                s.bound
            );
        }
    }

    /// Readings that turn back are irregular.
    #[test]
    fn a_turning_sequence_is_irregular() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        let e = estimate(&[1.0, 1.2, 1.1], &h, 2.0);
        assert!(!e.regular && e.turning);
        let e = estimate(&[1.0, 1.0, 1.0], &h, 2.0);
        assert!(e.regular && e.bound() == 0.0);
    }

    /// Levels 1–3 (h ratio 3/2 last): at order 1/2 the gain is 1 + 2/(√1.5 − 1) = 9.899.
    #[test]
    fn the_turning_gain_is_that_of_order_one_half() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        assert!((turning_gain(&h, 2.0) - (1.0 + 2.0 / (1.5f64.sqrt() - 1.0))).abs() < 1e-12);
        assert!((turning_gain(&h, 2.0) - 9.899).abs() < 1e-3);
    }

    /// Changes within what the stopped iteration leaves (here 1e-9 per level) are converged
    /// whatever their signs: regular, and bounded by the iteration's own term.
    #[test]
    fn a_turn_at_the_iteration_floor_is_converged() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        let v = [600.0 + 1e-9, 600.0 - 1e-9, 600.0 + 0.5e-9];
        let s = extrapolated_with_bound(&v, &h, 2.0, 1e-9);
        assert!(s.regular && !s.turning, "{s:?}");
        assert!(s.bound < 1e-7 && s.converged(1e-6), "{s:?}");
        // Without the iteration's error the same turn is not at the floor: it turns, and
        // its bound is the gain times its larger change (2e-9, to the rounding of 600).
        let s = extrapolated_with_bound(&v, &h, 2.0, 0.0);
        assert!(!s.regular && s.turning, "{s:?}");
        assert!(s.bound >= turning_gain(&h, 2.0) * 1.999e-9, "{s:?}");
    }

    /// A turn by 0.002 in 100: converged to 0.1 (the bound, 9.899 × 0.002 ≈ 0.0198, is
    /// within it), not to 0.01, and a turn by 0.2 is never taken for convergence at a
    /// tolerance below 1.979.
    #[test]
    fn a_turn_is_converged_only_when_small_against_the_tolerance() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        let s = extrapolated_with_bound(&[100.001, 99.999, 100.0005], &h, 2.0, 0.0);
        assert!(s.turning && !s.regular);
        assert!((s.bound - 9.899 * 0.002).abs() < 1e-4, "{s:?}");
        assert!(s.converged(0.1));
        assert!(!s.converged(0.01));
        let s = extrapolated_with_bound(&[1.0, 1.2, 1.1], &h, 2.0, 0.0);
        assert!(s.bound >= 1.979 && !s.converged(1.97), "{s:?}");
    }

    /// A sequence that converges monotonically at order 0.3, slower than trusted, is not
    /// converged however small its bound against the tolerance.
    #[test]
    fn a_slow_monotone_sequence_is_not_converged() {
        let h = [1.0, 0.5, 1.0 / 3.0];
        let v = h.map(|x: f64| 5.0 - 1e-6 * x.powf(0.3));
        let s = extrapolated_with_bound(&v, &h, 2.0, 0.0);
        assert!(!s.regular && !s.turning && s.bound < 1.0, "{s:?}");
        assert!(!s.converged(1.0));
    }

    /// A converged reading R∞ = 1 with a small h² term under an iteration error of ±1e-9
    /// alternating from level to level, on levels 1–12: the estimate is within its bound at
    /// every level, turning or not.
    #[test]
    fn a_noisy_converged_sequence_is_within_its_bound() {
        let eta = 1e-9;
        for c in [0.0, 1e-9, 1e-8, 1e-6] {
            let hs: Vec<f64> = (1..=12).map(|k| 0.5 / k as f64).collect();
            let v: Vec<f64> = hs
                .iter()
                .enumerate()
                .map(|(k, h)| 1.0 + c * h * h + if k % 2 == 0 { eta } else { -eta })
                .collect();
            for m in 3..=hs.len() {
                let first = m.saturating_sub(4);
                let s = extrapolated_with_bound(&v[first..m], &hs[first..m], 2.0, eta);
                assert!(
                    (s.value - 1.0).abs() <= s.bound,
                    "c {c}, level {m}: error {:e}, {s:?}",
                    (s.value - 1.0).abs()
                );
            }
        }
    }
}
