//! Gamut mapping for reproduction: what to show when the display cannot show a target.
//!
//! The paper sets the display's peak luminance so every rendered value fits and does no
//! gamut mapping, but a saturated ColorChecker patch (cyan, 18) can still fall outside a
//! display's primaries. Clipping the inverse model's drive values is what a naive pipeline
//! does; it moves the colour along the display's RGB axes, which can be far from the target
//! in CIELAB. The nearest-Lab mapping instead minimises ΔE*ab (relative to the display
//! white) over the drive cube, which is what a validation measured in ΔE*ab rewards.

use nalgebra::{Matrix3, Vector3};

use crate::color::{Lab, Xyz};

/// How out-of-gamut targets are brought onto the display; written by the name the
/// command line takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GamutMapping {
    /// Clip each drive value of the inverse model's solution to 0–1.
    Clip,
    /// The drive values in 0–1 whose displayed colour is closest to the target in ΔE*ab.
    #[default]
    NearestLab,
}

impl std::str::FromStr for GamutMapping {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "clip" => Ok(GamutMapping::Clip),
            "nearest-lab" => Ok(GamutMapping::NearestLab),
            _ => Err(format!(
                "unknown gamut mapping '{s}' (known: nearest-lab, clip)"
            )),
        }
    }
}

impl std::fmt::Display for GamutMapping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            GamutMapping::Clip => "clip",
            GamutMapping::NearestLab => "nearest-lab",
        })
    }
}

fn lab_of(forward: &dyn Fn([f64; 3]) -> Xyz, rgb: [f64; 3], white: Xyz) -> Vector3<f64> {
    let Lab { l, a, b } = forward(rgb).to_lab(white);
    Vector3::new(l, a, b)
}

fn clamp01(v: [f64; 3]) -> [f64; 3] {
    v.map(|c| c.clamp(0.0, 1.0))
}

/// The drive values in the unit cube whose colour through `forward` is nearest `target` in
/// ΔE*ab relative to `white`, starting from `start` (typically the clipped inverse).
///
/// Projected Gauss–Newton with an active set: coordinates held at a bound by a gradient
/// pointing outwards are frozen, the rest take the least-squares Newton step, and a
/// backtracking line search keeps every step a descent. Forward models are smooth within
/// the cube (or piecewise linear), so this converges in a handful of iterations; the test
/// against an exhaustive grid search checks it finds the global optimum on real shapes.
pub fn nearest_lab(
    forward: &dyn Fn([f64; 3]) -> Xyz,
    start: [f64; 3],
    target: Xyz,
    white: Xyz,
) -> [f64; 3] {
    let t = {
        let Lab { l, a, b } = target.to_lab(white);
        Vector3::new(l, a, b)
    };
    let mut x = clamp01(start);
    if x.iter().any(|v| v.is_nan()) {
        x = [0.5; 3];
    }
    let mut r = lab_of(forward, x, white) - t;
    let mut f = r.norm_squared();
    // A NaN target or white (or a model answering NaN) has no nearest colour, and an SVD
    // of a non-finite Jacobian does not converge: answer the start instead of searching.
    if !f.is_finite() {
        return x;
    }
    const H: f64 = 1e-6;
    for _ in 0..60 {
        // Forward differences stepping into the cube, so the model is never asked about
        // drive values it cannot show.
        let mut j = Matrix3::zeros();
        for k in 0..3 {
            let mut xp = x;
            let h = if x[k] + H <= 1.0 { H } else { -H };
            xp[k] += h;
            let col = (lab_of(forward, xp, white) - t - r) / h;
            j.set_column(k, &col);
        }
        if j.iter().any(|v| !v.is_finite()) {
            break;
        }
        let grad = j.transpose() * r;
        let free: Vec<usize> = (0..3)
            .filter(|&k| {
                let at_low = x[k] <= 0.0 && grad[k] > 0.0;
                let at_high = x[k] >= 1.0 && grad[k] < 0.0;
                !(at_low || at_high)
            })
            .collect();
        if free.is_empty() {
            break;
        }
        let mut jf = nalgebra::DMatrix::zeros(3, free.len());
        for (c, &k) in free.iter().enumerate() {
            jf.set_column(c, &j.column(k));
        }
        let rhs = nalgebra::DVector::from_iterator(3, (-r).iter().copied());
        let Ok(step) = jf.svd(true, true).solve(&rhs, 1e-12) else {
            break;
        };
        let mut dir = [0.0; 3];
        for (c, &k) in free.iter().enumerate() {
            dir[k] = step[c];
        }
        let mut s = 1.0;
        let mut improved = false;
        while s > 1e-6 {
            let xn = clamp01([x[0] + s * dir[0], x[1] + s * dir[1], x[2] + s * dir[2]]);
            let rn = lab_of(forward, xn, white) - t;
            let fnew = rn.norm_squared();
            if fnew < f {
                improved = f - fnew > 1e-14 * (1.0 + f);
                x = xn;
                r = rn;
                f = fnew;
                break;
            }
            s *= 0.5;
        }
        if !improved {
            break;
        }
    }
    x
}

/// Maps `target` to drive values with `mapping`, given the inverse model's unclipped
/// solution.
pub fn map_to_gamut(
    mapping: GamutMapping,
    forward: &dyn Fn([f64; 3]) -> Xyz,
    unclipped: [f64; 3],
    target: Xyz,
    white: Xyz,
) -> [f64; 3] {
    match mapping {
        GamutMapping::Clip => clamp01(unclipped),
        GamutMapping::NearestLab => nearest_lab(forward, clamp01(unclipped), target, white),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::delta_e76;

    /// An additive display with sRGB primaries (IEC 61966-2-1 matrix), a 2.2 power law
    /// and 100 cd/m² white.
    fn display(rgb: [f64; 3]) -> Xyz {
        let m = [
            [0.4124, 0.3576, 0.1805],
            [0.2126, 0.7152, 0.0722],
            [0.0193, 0.1192, 0.9505],
        ];
        let lin = rgb.map(|c| c.max(0.0).powf(2.2));
        let mut out = [0.0; 3];
        for i in 0..3 {
            out[i] = 100.0 * (m[i][0] * lin[0] + m[i][1] * lin[1] + m[i][2] * lin[2]);
        }
        out.into()
    }

    fn white() -> Xyz {
        display([1.0; 3])
    }

    fn de(rgb: [f64; 3], target: Xyz) -> f64 {
        delta_e76(display(rgb).to_lab(white()), target.to_lab(white()))
    }

    #[test]
    fn an_in_gamut_target_is_reached_exactly() {
        let rgb = [0.3, 0.7, 0.2];
        let target = display(rgb);
        let got = nearest_lab(&display, [0.5; 3], target, white());
        assert!(de(got, target) < 1e-6, "ΔE {}", de(got, target));
        for k in 0..3 {
            assert!((got[k] - rgb[k]).abs() < 1e-6);
        }
    }

    /// Out-of-gamut targets: the mapping must find the minimum an exhaustive search of the
    /// cube finds (a 41³ grid refined by a 21³ grid around its best point), and never be
    /// worse than clipping.
    #[test]
    fn out_of_gamut_targets_match_an_exhaustive_search() {
        let targets = [
            // A cyan more saturated than sRGB's (ColorChecker 18 under a wide-gamut light).
            [12.0, 19.0, 42.0],
            // A red beyond the red primary.
            [30.0, 15.0, 0.5],
            // Brighter than the white.
            [110.0, 115.0, 120.0],
            // A saturated green.
            [20.0, 45.0, 5.0],
        ];
        for t in targets {
            let target = Xyz::from_array(t);
            let got = nearest_lab(&display, [0.5; 3], target, white());
            let mut best = ([0.0; 3], f64::INFINITY);
            let n = 40;
            for i in 0..=n {
                for j in 0..=n {
                    for k in 0..=n {
                        let p = [i, j, k].map(|v| v as f64 / n as f64);
                        let d = de(p, target);
                        if d < best.1 {
                            best = (p, d);
                        }
                    }
                }
            }
            let (c, m) = (best.0, 20);
            for i in 0..=m {
                for j in 0..=m {
                    for k in 0..=m {
                        let off = [i, j, k].map(|v| (v as f64 / m as f64 - 0.5) / 20.0);
                        let p = clamp01([c[0] + off[0], c[1] + off[1], c[2] + off[2]]);
                        let d = de(p, target);
                        if d < best.1 {
                            best = (p, d);
                        }
                    }
                }
            }
            let d = de(got, target);
            assert!(
                d <= best.1 + 1e-3,
                "target {t:?}: mapping ΔE {d} vs grid search {}",
                best.1
            );
            assert!(got.iter().all(|&c| (0.0..=1.0).contains(&c)));
        }
    }

    #[test]
    fn nearest_lab_is_never_worse_than_clipping() {
        let target = Xyz::new(12.0, 19.0, 42.0);
        let clipped = [0.0, 0.55, 1.0];
        let got = map_to_gamut(
            GamutMapping::NearestLab,
            &display,
            [-0.3, 0.55, 1.2],
            target,
            white(),
        );
        assert!(de(got, target) <= de(clipped, target));
        let clip = map_to_gamut(
            GamutMapping::Clip,
            &display,
            [-0.3, 0.55, 1.2],
            target,
            white(),
        );
        assert_eq!(clip, clipped);
    }

    #[test]
    fn mapping_names_parse_and_print() {
        for m in [GamutMapping::Clip, GamutMapping::NearestLab] {
            assert_eq!(m.to_string().parse::<GamutMapping>().unwrap(), m);
        }
        assert!("hue-preserving".parse::<GamutMapping>().is_err());
    }
}
