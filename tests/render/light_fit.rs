//! The light distribution fit against analytic distributions, asymmetric between the four
//! half-planes, and every class of bad data.

use std::path::Path;

use metamer::light::fit::{HalfPlane, LdcError, Params, Plane};
use metamer::light::{fit, Falloff, LdcModel, ModelChoice, PlaneData};

fn cos(g: f64) -> f64 {
    g.to_radians().cos()
}

/// Readings of `l0 · truth[half](γ)` at ±10°, ±20°, … ±70° and 0° in both planes.
fn falloff(l0: f64, truth: &[Params; 4]) -> Falloff {
    let plane = |pos: &Params, neg: &Params| {
        let angles: Vec<f64> = (-7..=7).map(|k| 10.0 * k as f64).collect();
        let luminance = angles
            .iter()
            .map(|&a| l0 * if a >= 0.0 { pos } else { neg }.eval(a.abs()))
            .collect();
        PlaneData {
            angles_deg: angles,
            luminance,
        }
    };
    // truth in C0, C90, C180, C270 order.
    Falloff {
        horizontal: plane(&truth[0], &truth[2]),
        vertical: plane(&truth[1], &truth[3]),
    }
}

fn family(model: LdcModel) -> [Params; 4] {
    match model {
        LdcModel::Lambertian => std::array::from_fn(|_| Params::Lambertian),
        LdcModel::CosPower => [1.7, 2.5, 0.8, 1.2].map(|n| Params::CosPower { n }),
        LdcModel::CosPoly => [
            [0.2, 0.5, 0.3],
            [0.0, 0.4, 0.6],
            [0.4, 0.4, 0.2],
            [-0.1, 0.6, 0.5],
        ]
        .map(|coeffs| Params::CosPoly { coeffs }),
        // C0 is cos^1.7 itself (a = 1), the others are mixes of a broad and a narrow lobe.
        LdcModel::Lobes => [
            (1.0, 1.7, 1.7),
            (0.3, 0.5, 4.0),
            (0.6, 1.0, 8.0),
            (0.8, 2.0, 20.0),
        ]
        .map(|(a, n, m)| Params::Lobes { a, n, m }),
        // One series per plane: each half's odd coefficients are the other's negated.
        LdcModel::Series => [
            Params::Series {
                n: 0.8,
                b: [0.1, 0.05, 0.0, 0.0],
            },
            Params::Series {
                n: 1.5,
                b: [-0.05, -0.3, 0.02, 0.1],
            },
            Params::Series {
                n: 0.8,
                b: [-0.1, 0.05, 0.0, 0.0],
            },
            Params::Series {
                n: 1.5,
                b: [0.05, -0.3, -0.02, 0.1],
            },
        ],
        // The spline follows any smooth curve; its truth here is a lobes mix with a slope
        // at the normal that no half-plane model has (fitted by the spline itself).
        LdcModel::Spline => {
            let f = fit(&skewed_lobes(), ModelChoice::Named(LdcModel::Spline)).unwrap();
            std::array::from_fn(|k| f.halves[k].params.clone())
        }
    }
}

/// Readings every 10° of lobes mixes tilted by (1 + 0.1 sin γ).
fn skewed_lobes() -> Falloff {
    let f = |x: f64, a: f64, n: f64, m: f64| {
        let c = cos(x);
        (a * c.powf(n) + (1.0 - a) * c.powf(m)) * (1.0 + 0.1 * x.to_radians().sin())
    };
    let plane = |a, n, m| {
        let angles: Vec<f64> = (-7..=7).map(|k| 10.0 * k as f64).collect();
        PlaneData {
            luminance: angles.iter().map(|&x| f(x, a, n, m)).collect(),
            angles_deg: angles,
        }
    };
    Falloff {
        horizontal: plane(0.6, 1.0, 8.0),
        vertical: plane(0.8, 0.5, 3.0),
    }
}

/// Largest relative error of the fit (and of its table) at angles between the readings.
fn held_out_error(fit: &metamer::light::LdcFit, truth: &[Params; 4]) -> f64 {
    let mut worst = 0.0f64;
    for (h, t) in HalfPlane::ALL.iter().zip(truth) {
        for g in [5.0, 15.0, 25.0, 35.0, 45.0, 55.0, 65.0, 75.0] {
            let want = t.eval(g);
            let got = fit.relative(h.c_deg(), g);
            let table = fit.table.at(h.c_deg(), g);
            worst = worst
                .max((got - want).abs() / want)
                .max((table - want).abs() / want);
        }
    }
    worst
}

#[test]
fn each_model_recovers_its_own_asymmetric_distribution() {
    for model in LdcModel::ALL {
        let truth = family(model);
        let f = fit(&falloff(250.0, &truth), ModelChoice::Named(model)).unwrap();
        assert_eq!(f.model, model);
        assert!((f.normal_luminance - 250.0).abs() < 1e-12);
        let e = held_out_error(&f, &truth);
        assert!(e < 0.005, "{model}: {:.4} % at held-out angles", e * 100.0);
        assert!(
            f.residuals.iter().all(|r| r.residual.abs() < 1e-4),
            "{model}"
        );
    }
}

#[test]
fn auto_picks_the_generating_family_or_one_as_good() {
    // The spline's own curves are not a family to recover: past the last reading it holds
    // its correction by convention. What it is for is tested with the skewed distributions.
    for model in LdcModel::ALL.into_iter().filter(|&m| m != LdcModel::Spline) {
        let truth = family(model);
        let f = fit(&falloff(1.0, &truth), ModelChoice::Auto).unwrap();
        let e = held_out_error(&f, &truth);
        assert!(
            f.model == model || e < 0.005,
            "generated by {model}, chose {} ({}), {:.3} % off",
            f.model,
            f.why,
            e * 100.0
        );
        assert!(e < 0.005, "{model} → {}: {:.3} %", f.model, e * 100.0);
        assert!(!f.why.is_empty());
    }
    // The brief's case: cos^1.7 in C0, a lobe mix in C180, and cos-power alone cannot
    // follow the lobe mix, so auto must not settle for it.
    let truth = [
        Params::CosPower { n: 1.7 },
        Params::CosPower { n: 1.2 },
        Params::Lobes {
            a: 0.6,
            n: 1.0,
            m: 8.0,
        },
        Params::CosPower { n: 1.2 },
    ];
    let f = fit(&falloff(1.0, &truth), ModelChoice::Auto).unwrap();
    assert_ne!(f.model, LdcModel::CosPower, "{}", f.why);
    assert!(held_out_error(&f, &truth) < 0.005, "{}", f.why);
    let lobes = fit(&falloff(1.0, &truth), ModelChoice::Named(LdcModel::Lobes)).unwrap();
    assert!(held_out_error(&lobes, &truth) < 0.005);
}

#[test]
fn the_table_blends_the_planes_with_elliptic_weights() {
    let truth = family(LdcModel::CosPower);
    let f = fit(
        &falloff(1.0, &truth),
        ModelChoice::Named(LdcModel::CosPower),
    )
    .unwrap();
    // C = 30° lies on the 5° grid: f = cos²30°·f_C0 + sin²30°·f_C90 = ¾·cos^1.7 + ¼·cos^2.5.
    for g in [20.0, 40.0, 60.0] {
        let want = 0.75 * cos(g).powf(1.7) + 0.25 * cos(g).powf(2.5);
        assert!((f.table.at(30.0, g) - want).abs() < 2e-6, "{g}");
    }
    // C = 225°: half of C180 (n = 0.8) and half of C270 (n = 1.2).
    let want = 0.5 * cos(50.0).powf(0.8) + 0.5 * cos(50.0).powf(1.2);
    assert!((f.table.at(225.0, 50.0) - want).abs() < 2e-6);
    assert_eq!(f.table.at(123.0, 0.0), 1.0);
}

#[test]
fn the_normal_luminance_is_the_mean_of_both_planes() {
    let mut d = falloff(100.0, &family(LdcModel::Lambertian));
    let k = d
        .vertical
        .angles_deg
        .iter()
        .position(|&a| a == 0.0)
        .unwrap();
    d.vertical.luminance[k] = 98.0;
    let f = fit(&d, ModelChoice::Named(LdcModel::Lambertian)).unwrap();
    assert_eq!(f.normal_readings, [100.0, 98.0]);
    assert!((f.normal_luminance - 99.0).abs() < 1e-12);
    let r = f
        .residuals
        .iter()
        .find(|r| r.plane == Plane::Vertical && r.angle_deg == 0.0)
        .unwrap();
    assert!((r.residual - (98.0 / 99.0 - 1.0)).abs() < 1e-12);
}

#[test]
fn the_nine_angle_data_set_is_fitted_at_an_optimum() {
    let d = Falloff::read_csv(Path::new("data/light_falloff_9_angles.csv")).unwrap();
    let f = fit(&d, ModelChoice::Named(LdcModel::CosPower)).unwrap();
    assert_eq!(f.residuals.len(), 18);
    // The C0 readings at 15…60°, and the fitted exponent must beat its neighbours.
    let y = [0.98, 0.92, 0.80, 0.62];
    let sse = |n: f64| -> f64 {
        [15.0, 30.0, 45.0, 60.0]
            .iter()
            .zip(y)
            .map(|(g, y)| (cos(*g).powf(n) - y).powi(2))
            .sum()
    };
    let Params::CosPower { n } = f.halves[0].params else {
        panic!()
    };
    assert!(sse(n) < sse(n + 1e-3) && sse(n) < sse(n - 1e-3), "n = {n}");
    let auto = fit(&d, ModelChoice::Auto).unwrap();
    assert!(auto.chosen().unwrap().cv_rms.is_some());
}

fn plane(angles: &[f64], values: &[f64]) -> PlaneData {
    PlaneData {
        angles_deg: angles.to_vec(),
        luminance: values.to_vec(),
    }
}

fn ok_plane() -> PlaneData {
    plane(&[-30.0, -15.0, 0.0, 15.0, 30.0], &[0.8, 0.9, 1.0, 0.9, 0.8])
}

fn with_horizontal(h: PlaneData) -> Falloff {
    Falloff {
        horizontal: h,
        vertical: ok_plane(),
    }
}

#[test]
fn every_class_of_bad_data_gets_its_error() {
    let auto = ModelChoice::Auto;
    let e = fit(&with_horizontal(PlaneData::default()), auto).unwrap_err();
    assert!(
        matches!(
            e,
            LdcError::EmptyPlane {
                plane: Plane::Horizontal
            }
        ),
        "{e}"
    );
    let e = fit(&with_horizontal(plane(&[0.0, 20.0, 10.0], &[1.0; 3])), auto).unwrap_err();
    assert!(matches!(e, LdcError::AnglesNotIncreasing { .. }), "{e}");
    let e = fit(&with_horizontal(plane(&[0.0, 20.0, 20.0], &[1.0; 3])), auto).unwrap_err();
    assert!(
        matches!(e, LdcError::AnglesNotIncreasing { angle, .. } if angle == 20.0),
        "{e}"
    );
    let e = fit(&with_horizontal(plane(&[-90.0, 0.0], &[0.1, 1.0])), auto).unwrap_err();
    assert!(matches!(e, LdcError::AngleOutOfRange { .. }), "{e}");
    let e = fit(&with_horizontal(plane(&[0.0, 95.0], &[1.0, 0.1])), auto).unwrap_err();
    assert!(matches!(e, LdcError::AngleOutOfRange { .. }), "{e}");
    for bad in [-0.1, f64::NAN, f64::INFINITY] {
        let e = fit(&with_horizontal(plane(&[0.0, 30.0], &[1.0, bad])), auto).unwrap_err();
        assert!(matches!(e, LdcError::BadLuminance { .. }), "{e}");
    }
    let e = fit(&with_horizontal(plane(&[-30.0, 30.0], &[0.8, 0.8])), auto).unwrap_err();
    assert!(matches!(e, LdcError::NoNormalReading { .. }), "{e}");
    let e = fit(
        &with_horizontal(plane(&[-30.0, 0.0, 30.0], &[0.8, 0.0, 0.8])),
        auto,
    )
    .unwrap_err();
    assert!(matches!(e, LdcError::ZeroNormalReading { .. }), "{e}");
    let e = fit(&with_horizontal(plane(&[0.0, 30.0], &[1.0])), auto).unwrap_err();
    assert!(matches!(e, LdcError::LengthMismatch { .. }), "{e}");
    // Two angles per half-plane: lobes (3 parameters) cannot be fitted, auto still works
    // with the models that can be cross-validated.
    let e = fit(
        &with_horizontal(ok_plane()),
        ModelChoice::Named(LdcModel::Lobes),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            LdcError::TooFewAngles {
                model: LdcModel::Lobes,
                got: 2,
                need: 3,
                ..
            }
        ),
        "{e}"
    );
    let f = fit(&with_horizontal(ok_plane()), auto).unwrap();
    let lobes = f
        .candidates
        .iter()
        .find(|c| c.model == LdcModel::Lobes)
        .unwrap();
    assert!(lobes.note.as_deref().unwrap_or("").contains("needs 3"));
    // A half-plane without any angle off the normal: no model but Lambertian can be named.
    let e = fit(
        &with_horizontal(plane(&[0.0, 15.0, 30.0], &[1.0, 0.9, 0.8])),
        ModelChoice::Named(LdcModel::CosPower),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            LdcError::TooFewAngles {
                half: HalfPlane::C180,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn a_csv_column_without_readings_is_an_empty_plane() {
    let d = Falloff::parse_csv(
        "angle_deg,horizontal,vertical\n-20,0.9,\n0,1,\n20,0.9,\n",
        Path::new("x.csv"),
    )
    .unwrap();
    let e = fit(&d, ModelChoice::Auto).unwrap_err();
    assert!(
        matches!(
            e,
            LdcError::EmptyPlane {
                plane: Plane::Vertical
            }
        ),
        "{e}"
    );
}

/// A distribution given as the relative luminance of each plane at its signed angle.
struct Skewed {
    name: &'static str,
    horizontal: fn(f64) -> f64,
    vertical: fn(f64) -> f64,
}

fn rad(x: f64) -> f64 {
    x.to_radians()
}

/// Smooth distributions whose two halves differ in shape as well as width, the kind a
/// diffuser over an off-centre LED array gives: the first is the one that was reported
/// (3 % off at held-out angles with the half-plane models alone), the others are ours.
const SKEWED: [Skewed; 5] = [
    Skewed {
        name: "cos^0.8·(1 + 0.1 sin γ) ; exp(−(γ/0.9)²)·(1 − 0.05 sin γ)",
        horizontal: |x| cos(x).powf(0.8) * (1.0 + 0.1 * rad(x).sin()),
        vertical: |x| (-(rad(x) / 0.9).powi(2)).exp() * (1.0 - 0.05 * rad(x).sin()),
    },
    Skewed {
        name: "cos^1.5·(1 + 0.15 sin γ) ; (0.7 cos + 0.3 cos⁶)·(1 + 0.08 sin γ)",
        horizontal: |x| cos(x).powf(1.5) * (1.0 + 0.15 * rad(x).sin()),
        vertical: |x| (0.7 * cos(x) + 0.3 * cos(x).powi(6)) * (1.0 + 0.08 * rad(x).sin()),
    },
    Skewed {
        name: "batwing cos^0.5·(1 + 0.3 sin²γ) ; exp(−(γ/1.1)⁴)·(1 − 0.1 sin γ)",
        horizontal: |x| cos(x).powf(0.5) * (1.0 + 0.3 * rad(x).sin().powi(2)),
        vertical: |x| (-(rad(x) / 1.1).powi(4)).exp() * (1.0 - 0.1 * rad(x).sin()),
    },
    Skewed {
        name: "cos^1.2 tilted by 10° ; exp(−(γ/0.7)²)·(1 + 0.05 sin 2γ)",
        horizontal: |x| cos(x - 10.0).powf(1.2) / cos(10.0).powf(1.2),
        vertical: |x| (-(rad(x) / 0.7).powi(2)).exp() * (1.0 + 0.05 * (2.0 * rad(x)).sin()),
    },
    Skewed {
        name: "Gaussian off the normal ; cos²·(1 + 0.12 sin γ − 0.05 sin²γ)",
        horizontal: |x| (-((rad(x) - 0.1) / 0.8).powi(2)).exp() / (-(0.1f64 / 0.8).powi(2)).exp(),
        vertical: |x| cos(x).powi(2) * (1.0 + 0.12 * rad(x).sin() - 0.05 * rad(x).sin().powi(2)),
    },
];

/// Nine readings per plane, −80° … 80° in 20° steps.
fn nine_angles(d: &Skewed) -> Falloff {
    let plane = |f: fn(f64) -> f64| {
        let angles: Vec<f64> = (-4..=4).map(|k| 20.0 * k as f64).collect();
        PlaneData {
            luminance: angles.iter().map(|&x| f(x)).collect(),
            angles_deg: angles,
        }
    };
    Falloff {
        horizontal: plane(d.horizontal),
        vertical: plane(d.vertical),
    }
}

/// The largest error of the IES file's candela at the angles between the readings (±10°,
/// 30°, 50°, 70° in both planes), relative to the normal intensity: the file written, read
/// back by the reader.
fn ies_held_out_error(f: &metamer::light::LdcFit, d: &Skewed) -> f64 {
    use metamer::light::ies::{self, IesInfo};
    let panel = metamer::light::Panel::new(0.5, 0.5, 1000.0).unwrap();
    let info = IesInfo {
        test: "held-out angles".into(),
        issue_date: "2026-12-02".into(),
        luminaire: d.name.into(),
        generation: "test".into(),
        extrapolation: None,
    };
    let text = ies::to_string(&f.table, &panel, &info);
    let (table, p) = ies::parse(&text, Path::new("skewed.ies")).unwrap();
    let i0 = panel.normal_intensity_cd();
    assert!((p.normal_intensity_cd - i0).abs() < 1e-9 * i0);
    let mut worst = 0.0f64;
    for (c, truth, sign) in [
        (0.0, d.horizontal, 1.0),
        (180.0, d.horizontal, -1.0),
        (90.0, d.vertical, 1.0),
        (270.0, d.vertical, -1.0),
    ] {
        for g in [10.0, 30.0, 50.0, 70.0] {
            let want = i0 * truth(sign * g) * cos(g);
            let got = p.normal_intensity_cd * table.at(c, g) * cos(g);
            worst = worst.max((got - want).abs() / i0);
        }
    }
    worst
}

/// Prints (with `--nocapture`) the table the light README gives: each model's held-out
/// score, auto's pick and its IES error at the angles between the readings, and what the
/// half-plane models alone would have given.
#[test]
fn skewed_distributions_are_reproduced_at_held_out_angles_in_the_ies_table() {
    use metamer::light::fit::cv::{choose, Score};
    println!(
        "| distribution | {} | auto | IES error | half-plane models alone | IES error |",
        LdcModel::ALL.map(|m| m.name()).join(" | ")
    );
    for d in &SKEWED {
        let f = fit(&nine_angles(d), ModelChoice::Auto).unwrap();
        let e = ies_held_out_error(&f, d);
        // The rule applied to the parametric candidates alone: the choice before the
        // plane families existed.
        let scores: Vec<Score> = f
            .candidates
            .iter()
            .filter(|c| !c.model.per_plane())
            .map(|c| Score {
                model: c.model,
                parameters: c.parameters,
                cv_rms: c.cv_rms,
            })
            .collect();
        let old = scores[choose(&scores).unwrap().0].model;
        let old_e = ies_held_out_error(&fit(&nine_angles(d), ModelChoice::Named(old)).unwrap(), d);
        let loo: Vec<String> = f
            .candidates
            .iter()
            .map(|c| c.cv_rms.map_or("-".into(), |v| format!("{v:.4}")))
            .collect();
        println!(
            "| {} | {} | {} | {:.2} % | {old} | {:.2} % |",
            d.name,
            loo.join(" | "),
            f.model,
            e * 100.0,
            old_e * 100.0
        );
        assert!(
            e < 0.01,
            "{}: {} chosen ({}), {:.2} % of the normal intensity off",
            d.name,
            f.model,
            f.why,
            e * 100.0
        );
        // The half-plane models alone cannot: that is why the plane families exist.
        assert!(old_e > 0.01, "{}: {old} {old_e}", d.name);
        // The tilted lobe is the one no closed form here follows: only the curve through
        // the readings predicts its held-out angles.
        if d.name.contains("tilted") {
            assert_eq!(f.model, LdcModel::Spline, "{}", f.why);
        }
    }
}

#[test]
fn a_cos_power_truth_is_still_fitted_by_cos_power() {
    let truth = family(LdcModel::CosPower);
    let nine = |noise: f64| {
        // Nine readings per plane, −80° … 80° in 20° steps.
        let plane = |pos: &Params, neg: &Params| {
            let angles: Vec<f64> = (-4..=4).map(|k| 20.0 * k as f64).collect();
            PlaneData {
                luminance: angles
                    .iter()
                    .map(|&a| if a >= 0.0 { pos } else { neg }.eval(a.abs()))
                    .collect(),
                angles_deg: angles,
            }
        };
        let mut d = Falloff {
            horizontal: plane(&truth[0], &truth[2]),
            vertical: plane(&truth[1], &truth[3]),
        };
        // Readings to 3 decimals, as a meter shows them: noise the richer models could
        // follow, but must not be chosen for.
        for p in [&mut d.horizontal, &mut d.vertical] {
            for (k, v) in p.luminance.iter_mut().enumerate() {
                *v = ((*v + noise * if k % 2 == 0 { 1.0 } else { -1.0 }) * 1000.0).round() / 1000.0;
            }
        }
        d
    };
    for noise in [0.0, 0.002] {
        let f = fit(&nine(noise), ModelChoice::Auto).unwrap();
        assert_eq!(f.model, LdcModel::CosPower, "noise {noise}: {}", f.why);
    }
}
