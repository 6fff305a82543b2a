//! The searches the fits share: a bounded one-dimensional minimum (grid, then golden
//! section) and Nelder–Mead on two variables, over exponents up to [`MAX_EXPONENT`].

/// The largest exponent searched: cos¹⁰⁰ is already below 1 % at 12°, far narrower than
/// any panel light.
pub const MAX_EXPONENT: f64 = 100.0;

/// Minimum of `f` on [lo, hi]: the best of `steps` + 1 grid points, then golden-section
/// search in the two grid cells around it (the sums of squares here are smooth but not
/// always unimodal over the whole range).
pub fn minimise_1d(f: impl Fn(f64) -> f64, lo: f64, hi: f64, steps: usize) -> f64 {
    let h = (hi - lo) / steps as f64;
    let (mut best_x, mut best_v) = (lo, f64::INFINITY);
    for k in 0..=steps {
        let x = lo + h * k as f64;
        let v = f(x);
        if v < best_v {
            (best_x, best_v) = (x, v);
        }
    }
    let (mut a, mut b) = ((best_x - h).max(lo), (best_x + h).min(hi));
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (b - r * (b - a), a + r * (b - a));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..100 {
        if f1 < f2 {
            b = x2;
            (x2, f2) = (x1, f1);
            x1 = b - r * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            (x1, f1) = (x2, f2);
            x2 = a + r * (b - a);
            f2 = f(x2);
        }
    }
    let x = (a + b) / 2.0;
    if f(x) <= best_v {
        x
    } else {
        best_x
    }
}

/// Nelder–Mead on two variables with the standard coefficients (reflection 1, expansion 2,
/// contraction ½, shrink ½), from `start` with an initial simplex of edge `step`.
pub fn nelder_mead(
    f: impl Fn([f64; 2]) -> f64,
    start: [f64; 2],
    step: f64,
    iterations: usize,
) -> [f64; 2] {
    let mut s = [
        start,
        [start[0] + step, start[1]],
        [start[0], start[1] + step],
    ];
    let mut v = s.map(&f);
    let lerp =
        |a: [f64; 2], b: [f64; 2], t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    for _ in 0..iterations {
        let mut idx = [0, 1, 2];
        idx.sort_by(|&i, &j| v[i].total_cmp(&v[j]));
        s = idx.map(|i| s[i]);
        v = idx.map(|i| v[i]);
        let spread = (v[2] - v[0]).abs();
        let size = (s[2][0] - s[0][0]).abs().max((s[2][1] - s[0][1]).abs());
        if spread <= 1e-30 + 1e-15 * v[0].abs() && size < 1e-12 {
            break;
        }
        let centroid = lerp(s[0], s[1], 0.5);
        let reflected = lerp(s[2], centroid, 2.0);
        let fr = f(reflected);
        if fr < v[0] {
            let expanded = lerp(s[2], centroid, 3.0);
            let fe = f(expanded);
            (s[2], v[2]) = if fe < fr {
                (expanded, fe)
            } else {
                (reflected, fr)
            };
        } else if fr < v[1] {
            (s[2], v[2]) = (reflected, fr);
        } else {
            let contracted = lerp(s[2], centroid, 0.5);
            let fc = f(contracted);
            if fc < v[2] {
                (s[2], v[2]) = (contracted, fc);
            } else {
                for k in 1..3 {
                    s[k] = lerp(s[0], s[k], 0.5);
                    v[k] = f(s[k]);
                }
            }
        }
    }
    let best = (0..3).min_by(|&i, &j| v[i].total_cmp(&v[j])).unwrap_or(0);
    s[best]
}
