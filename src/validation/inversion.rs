//! Confidence intervals of a colour difference that know it is biased.
//!
//! ΔE is a length: noise in either reading lengthens it on average (by about σ²/ΔE per
//! perpendicular axis, far more near 0), so percentiles of ΔE over noise draws about the
//! observed readings are shifted upward twice — once in the estimate, once in the draws —
//! and can exclude the estimate itself. Here the interval is found by inverting a test,
//! the way an interval of a noncentral χ's parameter is: each candidate truth along the
//! family "the observed difference scaled by c ≥ 0" (every patch by the same c for a
//! summary over patches) keeps the readings' noise draws; a truth stays in the 95 %
//! interval while the observed statistic is inside the middle 95 % of the statistic's
//! draws at that truth. For an isotropic CIELAB noise this is exactly the noncentral-χ
//! interval of the length; for another it plugs in the observed direction, which is what
//! the coverage tests below check.
//!
//! Where even a zero true difference makes the observed one implausibly small (noise
//! overstated), no truth passes: the interval is then [0, estimate]. Every interval holds
//! its estimate.

use super::uncertain::Interval;

/// 1 − the confidence level.
const ALPHA: f64 = 0.05;

/// How finely a patch's bounds are found, relative to their scale: ΔE to 1e-4 of itself
/// (a verdict turns on the third decimal near 2.3).
pub const PATCH_TOLERANCE: f64 = 1e-4;

/// The largest c ≥ 0 for which `holds` (true at 0) stays true, to `tolerance` of itself,
/// found by doubling from 1 until it fails and then bisecting; at most 2⁶⁰ when it never
/// fails.
fn boundary(holds: impl Fn(f64) -> bool, tolerance: f64) -> f64 {
    let (mut a, mut b) = (0.0, 1.0);
    let mut doublings = 0;
    while holds(b) {
        a = b;
        b *= 2.0;
        doublings += 1;
        if doublings == 60 {
            return b;
        }
    }
    while b - a > tolerance * b {
        let m = 0.5 * (a + b);
        if holds(m) {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// The 95 % interval of a difference observed as `obs`, from `draws` noise draws:
/// `stat(c, i)` is draw i's statistic when the truth is the observed configuration's
/// family member c, `truth(c)` the noiseless statistic there (so `truth(1)` is `obs`);
/// bounds to `tolerance` of themselves.
pub fn invert(
    obs: f64,
    draws: usize,
    stat: impl Fn(f64, usize) -> f64,
    truth: impl Fn(f64) -> f64,
    tolerance: f64,
) -> Interval {
    if draws == 0 {
        return Interval { lo: obs, hi: obs };
    }
    // Whether at least `k` draws at truth c come out no larger than what was observed;
    // counting stops as soon as the answer is known.
    let at_least = |c: f64, k: usize| {
        let mut below = 0;
        for i in 0..draws {
            if stat(c, i) <= obs {
                below += 1;
                if below >= k {
                    return true;
                }
            } else if below + (draws - i - 1) < k {
                return false;
            }
        }
        below >= k
    };
    // A truth stays while at least 2.5 % of its draws fall at or below the observation
    // (for the upper end) and no more than 97.5 % do (for the lower end).
    let low_tail = ((ALPHA / 2.0) * draws as f64).ceil() as usize;
    let high_tail = ((1.0 - ALPHA / 2.0) * draws as f64).floor() as usize + 1;
    let hi = if at_least(0.0, low_tail) {
        truth(boundary(|c| at_least(c, low_tail), tolerance))
    } else {
        obs
    };
    let lo = if at_least(0.0, high_tail) {
        truth(boundary(|c| at_least(c, high_tail), tolerance))
    } else {
        truth(0.0)
    };
    Interval {
        lo: lo.min(obs),
        hi: hi.max(obs),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metamer_drivers::noise::SplitMix64;

    fn isotropic(n: usize, sigma: f64, seed: u64) -> Vec<[f64; 3]> {
        let mut rng = SplitMix64::new(seed);
        (0..n)
            .map(|_| [0; 3].map(|_| sigma * rng.normal()))
            .collect()
    }

    fn length(v: [f64; 3]) -> f64 {
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    }

    fn interval(d: [f64; 3], noise: &[[f64; 3]]) -> Interval {
        let obs = length(d);
        invert(
            obs,
            noise.len(),
            |c, i| length([0, 1, 2].map(|k| c * d[k] + noise[i][k])),
            |c| c * obs,
            PATCH_TOLERANCE,
        )
    }

    /// Far from 0 the interval of |d| under isotropic noise σ is, to first order, the
    /// normal one about the bias-corrected length: |d| − σ²/|d| ± 1.96σ (each of the two
    /// perpendicular axes lengthens |d| by σ²/(2|d|) on average). At |d| = 10, σ = 0.5:
    /// centre 9.975, half-width 0.98; the noncentral χ₃ gives [8.9937, 10.9561] (SciPy:
    /// ncx2.cdf(20², 3, (2λ)²) = 0.975 and 0.025).
    #[test]
    fn far_from_zero_the_interval_is_the_bias_corrected_normal_one() {
        let noise = isotropic(20_000, 0.5, 3);
        let i = interval([6.0, 8.0, 0.0], &noise);
        assert!((i.lo - 8.9937).abs() < 0.03, "{i:?}");
        assert!((i.hi - 10.9561).abs() < 0.03, "{i:?}");
    }

    /// Against the noncentral χ with 3 degrees of freedom, by hand: with |d| = 0 observed
    /// as exactly σ·√χ²₃(0.5) = 1.5382σ (the median of |noise| at zero truth), the lower
    /// end is 0; the upper end is the noncentrality λ with P(χ₃(λ) ≤ 1.5382) = 0.025,
    /// λ = 3.0225 (solved with SciPy: ncx2.cdf(1.5382², 3, λ²) = 0.025).
    #[test]
    fn matches_the_noncentral_chi_at_small_differences() {
        let noise = isotropic(40_000, 1.0, 5);
        let i = interval([1.5382, 0.0, 0.0], &noise);
        assert_eq!(i.lo, 0.0);
        assert!((i.hi - 3.0225).abs() < 0.04, "{i:?}");
    }

    /// An observation smaller than the noise allows even at zero truth: [0, estimate].
    #[test]
    fn an_implausibly_small_difference_gives_zero_to_the_estimate() {
        let noise = isotropic(4000, 1.0, 9);
        let i = interval([0.01, 0.0, 0.0], &noise);
        assert_eq!((i.lo, i.hi), (0.0, 0.01));
        // No noise: the point.
        let i = invert(2.0, 0, |_, _| 0.0, |c| 2.0 * c, PATCH_TOLERANCE);
        assert_eq!((i.lo, i.hi), (2.0, 2.0));
    }
}
