//! IES and EULUMDAT files: round trips to file precision and the flux of analytic
//! distributions (Lambertian: π·L₀·A; cos^n: 2π·L₀·A/(n + 2)).

use std::f64::consts::PI;
use std::path::Path;

use metamer::light::fit::Params;
use metamer::light::ies::{self, IesInfo};
use metamer::light::ldt::{self, LdtInfo};
use metamer::light::photometry::flux_beyond_lm;
use metamer::light::{fit, flux_lm, CGammaTable, Falloff, LdcModel, ModelChoice, Panel, PlaneData};

fn ies_info() -> IesInfo {
    IesInfo {
        test: "round trip".into(),
        issue_date: "2026-12-01".into(),
        luminaire: "test panel".into(),
        generation: "test".into(),
        extrapolation: None,
    }
}

fn ldt_info() -> LdtInfo {
    LdtInfo {
        luminaire: "test panel".into(),
        file_name: "t.ldt".into(),
        date_user: "2026-12-01 test".into(),
        extrapolation: None,
    }
}

/// An asymmetric fitted table: a different lobe mix in each half-plane.
fn asymmetric_table() -> CGammaTable {
    let truth = [
        (1.0, 1.7, 1.7),
        (0.3, 0.5, 4.0),
        (0.6, 1.0, 8.0),
        (0.8, 2.0, 20.0),
    ]
    .map(|(a, n, m)| Params::Lobes { a, n, m });
    let plane = |pos: &Params, neg: &Params| {
        let angles: Vec<f64> = (-8..=8).map(|k| 10.0 * k as f64).collect();
        let luminance = angles
            .iter()
            .map(|&a| if a >= 0.0 { pos } else { neg }.eval(a.abs()))
            .collect();
        PlaneData {
            angles_deg: angles,
            luminance,
        }
    };
    let f = Falloff {
        horizontal: plane(&truth[0], &truth[2]),
        vertical: plane(&truth[1], &truth[3]),
    };
    fit(&f, ModelChoice::Named(LdcModel::Lobes)).unwrap().table
}

fn cos_power_table(n: f64) -> CGammaTable {
    let g: Vec<f64> = (0..=90).map(f64::from).collect();
    let v = g.iter().map(|x| x.to_radians().cos().powf(n)).collect();
    CGammaTable::symmetric(g, v).unwrap()
}

/// Every candela value of `a` under `pa` against `b` under `pb`, relative to the peak.
fn same_candela(a: &CGammaTable, pa: &Panel, b: &CGammaTable, i0_b: f64) -> f64 {
    let mut worst = 0.0f64;
    let peak = pa.normal_intensity_cd();
    for &c in a.c_deg() {
        for &g in a.gamma_deg() {
            let want = pa.intensity_cd(a, c, g);
            let got = i0_b * b.at(c, g) * g.to_radians().cos().max(0.0);
            worst = worst.max((got - want).abs() / peak);
        }
    }
    worst
}

#[test]
fn ies_round_trip_keeps_the_candela_table() {
    let t = asymmetric_table();
    let panel = Panel::new(0.3, 0.2, 1500.0).unwrap();
    let text = ies::to_string(&t, &panel, &ies_info());
    assert!(text.starts_with("IES:LM-63-2019\r\n"));
    assert!(text.contains("\r\nTILT=NONE\r\n"));
    let (back, p) = ies::parse(&text, Path::new("t.ies")).unwrap();
    assert_eq!(back.c_deg(), t.c_deg());
    assert_eq!(back.gamma_deg(), t.gamma_deg());
    // 7 significant digits in the file.
    let e = same_candela(&t, &panel, &back, p.normal_intensity_cd);
    assert!(e < 1e-6, "{e}");
    assert!((p.normal_luminance_cd_m2().unwrap() - 1500.0).abs() < 1e-6);
    assert!((p.flux_lm - flux_lm(&t, &panel)).abs() < 1e-5 * p.flux_lm);
}

#[test]
fn ldt_round_trip_keeps_the_candela_table() {
    let t = asymmetric_table();
    let panel = Panel::new(0.3, 0.2, 1500.0).unwrap();
    let text = ldt::to_string(&t, &panel, &ldt_info());
    let (back, p) = ldt::parse(&text, Path::new("t.ldt")).unwrap();
    assert_eq!(back.c_deg(), t.c_deg());
    let e = same_candela(&t, &panel, &back, p.normal_intensity_cd);
    assert!(e < 1e-6, "{e}");
    assert!((p.area_m2 - 0.06).abs() < 1e-12);
    assert!((p.flux_lm - flux_lm(&t, &panel)).abs() < 1e-5 * p.flux_lm);
}

#[test]
fn lambertian_panel_flux_is_pi_l_a() {
    let t = cos_power_table(0.0);
    let panel = Panel::new(0.3, 0.3, 1000.0).unwrap();
    let want = PI * 1000.0 * 0.09;
    assert!((flux_lm(&t, &panel) - want).abs() < 1e-9 * want);
    let (_, p) = ies::parse(&ies::to_string(&t, &panel, &ies_info()), Path::new("l.ies")).unwrap();
    assert!((p.flux_lm - want).abs() < 1e-6 * want, "{}", p.flux_lm);
    let (_, p) = ldt::parse(&ldt::to_string(&t, &panel, &ldt_info()), Path::new("l.ldt")).unwrap();
    assert!((p.flux_lm - want).abs() < 1e-6 * want, "{}", p.flux_lm);
    assert_eq!(p.symmetry, "rotationally symmetric");
}

#[test]
fn cos_power_panel_flux_is_two_pi_l_a_over_n_plus_two() {
    let panel = Panel::new(0.5, 0.2, 300.0).unwrap();
    for n in [0.5, 1.0, 1.7, 4.0] {
        let want = 2.0 * PI * 300.0 * 0.1 / (n + 2.0);
        // The table is linear between 1° steps: its flux differs from the curve's by
        // ~h²/12·f'' ≈ 3·10⁻⁵·n relative.
        let t = cos_power_table(n);
        let got = flux_lm(&t, &panel);
        assert!((got - want).abs() < 2e-4 * want, "n = {n}: {got} vs {want}");
        let (_, p) =
            ldt::parse(&ldt::to_string(&t, &panel, &ldt_info()), Path::new("c.ldt")).unwrap();
        assert!(
            (p.flux_lm - want).abs() < 2e-4 * want,
            "n = {n}: {}",
            p.flux_lm
        );
    }
    // The same through the fit: cos^1.7 readings in both planes.
    let angles: Vec<f64> = (-6..=6)
        .map(|k| 15.0 * k as f64)
        .filter(|a: &f64| a.abs() < 90.0)
        .collect();
    let lum: Vec<f64> = angles
        .iter()
        .map(|a: &f64| a.to_radians().cos().powf(1.7))
        .collect();
    let plane = PlaneData {
        angles_deg: angles,
        luminance: lum,
    };
    let f = fit(
        &Falloff {
            horizontal: plane.clone(),
            vertical: plane,
        },
        ModelChoice::Named(LdcModel::CosPower),
    )
    .unwrap();
    let want = 2.0 * PI * 300.0 * 0.1 / 3.7;
    assert!((flux_lm(&f.table, &panel) - want).abs() < 2e-4 * want);
}

/// Found by the fuzz harness: a count of 2³² horizontal angles made the IES reader ask for
/// 34 GB before it found the file holds a few hundred numbers.
#[test]
fn an_ies_count_larger_than_the_file_ends_at_the_end_of_the_file() {
    let panel = Panel::new(0.3, 0.2, 1500.0).unwrap();
    let text = ies::to_string(&asymmetric_table(), &panel, &ies_info());
    let lines: Vec<&str> = text.split("\r\n").collect();
    let tilt = lines.iter().position(|l| *l == "TILT=NONE").unwrap();
    let mut fields: Vec<&str> = lines[tilt + 1].split_whitespace().collect();
    fields[4] = "4294967296";
    let counts = fields.join(" ");
    let mut broken = lines.clone();
    broken[tilt + 1] = &counts;
    let e = ies::parse(&broken.join("\r\n"), Path::new("big.ies"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("the file ends before"), "{e}");
}

/// Found by the fuzz harness: EULUMDAT numbers that are not finite (an opening of `inf` mm,
/// a lamp flux of 1e308 lm) were accepted into the photometry.
#[test]
fn an_ldt_with_a_non_finite_opening_or_overflowing_intensities_is_refused() {
    let panel = Panel::new(0.3, 0.2, 1500.0).unwrap();
    let text = ldt::to_string(&asymmetric_table(), &panel, &ldt_info());
    let with_lines = |edits: &[(usize, &str)]| {
        let mut lines: Vec<&str> = text.split("\r\n").collect();
        for &(k, value) in edits {
            lines[k - 1] = value;
        }
        lines.join("\r\n")
    };
    for (line, value) in [(17, "inf"), (16, "NaN"), (17, "-inf")] {
        let e = ldt::parse(&with_lines(&[(line, value)]), Path::new("o.ldt"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("not a finite size"),
            "line {line} = {value}: {e}"
        );
    }
    // Line 29: the one lamp set's flux, and line 24 the conversion factor, which scale
    // every cd/klm value.
    let e = ldt::parse(
        &with_lines(&[(24, "1000"), (29, "1e308")]),
        Path::new("f.ldt"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("too large to use") || e.contains("must be finite"),
        "{e}"
    );
}

/// ∫ over γ ≥ γ₀ of a Lambertian panel's intensity I₀·cos γ: 2π·I₀·∫cos γ sin γ dγ =
/// π·I₀·cos²γ₀, so a quarter of the flux above 60° and all of it above 0°.
#[test]
fn flux_beyond_an_angle_is_pi_i0_cos2() {
    let t = cos_power_table(0.0);
    let panel = Panel::new(0.3, 0.3, 1000.0).unwrap();
    let i0 = 90.0;
    for g in [0.0f64, 37.5, 60.0, 89.0] {
        let want = PI * i0 * g.to_radians().cos().powi(2);
        let got = flux_beyond_lm(&t, &panel, g);
        assert!((got - want).abs() < 1e-9 * i0, "{g}°: {got} vs {want}");
    }
    assert!((flux_beyond_lm(&t, &panel, 0.0) - flux_lm(&t, &panel)).abs() < 1e-9);
}

/// Readings of 0.5 + 0.5·cos γ at every `step`° to `h_max` in the horizontal and `v_max` in
/// the vertical plane.
fn half_cos_falloff(h_max: i32, v_max: i32, step: i32) -> Falloff {
    let plane = |max: i32| {
        let angles: Vec<f64> = (-max / step..=max / step)
            .map(|k| f64::from(k * step))
            .collect();
        PlaneData {
            luminance: angles
                .iter()
                .map(|a| 0.5 + 0.5 * a.to_radians().cos())
                .collect(),
            angles_deg: angles,
        }
    };
    Falloff {
        horizontal: plane(h_max),
        vertical: plane(v_max),
    }
}

/// Readings to 85° in one plane and 60° in the other leave 60–90° to the model in two
/// half-planes (no reading reaches 90°: the light is seen from the front): the fit says how
/// far each half-plane was read, and the IES file says it in `[OTHER]` and
/// `[_MEASURED_GAMMA]`, the EULUMDAT file in its report line (8), both read back.
#[test]
fn written_files_say_where_the_table_is_extrapolated() {
    let f = fit(&half_cos_falloff(85, 60, 5), ModelChoice::Auto).unwrap();
    assert_eq!(f.measured_to_deg, Some([85.0, 60.0, 85.0, 60.0]));
    let e = f.extrapolation().unwrap();
    assert_eq!(e.beyond_deg, 60.0);
    assert!(
        e.sentence().contains("gamma above 60 deg")
            && e.sentence()
                .contains("C0 85 deg, C90 60 deg, C180 85 deg, C270 60 deg"),
        "{}",
        e.sentence()
    );
    let panel = Panel::new(0.3, 0.3, 1000.0).unwrap();
    let info = IesInfo {
        extrapolation: Some(e.clone()),
        ..ies_info()
    };
    let text = ies::to_string(&f.table, &panel, &info);
    assert!(
        text.contains("\r\n[_MEASURED_GAMMA] C0 0-85 C90 0-60 C180 0-85 C270 0-60\r\n"),
        "{text}"
    );
    let (_, p) = ies::parse(&text, Path::new("x.ies")).unwrap();
    let other = p.labels.iter().find(|(k, _)| k == "OTHER").unwrap();
    assert!(other
        .1
        .starts_with("gamma above 60 deg up to 90 deg is not measured"));
    let ldt_text = ldt::to_string(
        &f.table,
        &panel,
        &LdtInfo {
            extrapolation: Some(e),
            ..ldt_info()
        },
    );
    let line8 = ldt_text.lines().nth(7).unwrap();
    assert_eq!(
        line8,
        format!(
            "fit of readings to gamma 60 deg; above, extrapolated by the {} model",
            f.model
        )
    );
    assert!(line8.chars().count() <= 78);
    let (_, p) = ldt::parse(&ldt_text, Path::new("x.ldt")).unwrap();
    assert!(p.labels.iter().any(|(k, v)| k == "report" && v == line8));

    let far = fit(&half_cos_falloff(85, 85, 5), ModelChoice::Auto).unwrap();
    assert_eq!(far.extrapolation().unwrap().beyond_deg, 85.0);
}

/// `light fit` as the guide gives it, with a Lambertian model named so that the figures
/// are known by hand: the readings reach 60°, so the output says that 60–90° is not
/// measured, and that π·I₀·cos²60° = 70.6858 lm of the π·I₀ = 282.7433 lm (I₀ = 90 cd),
/// 25.0 %, come from there.
#[test]
fn light_fit_says_what_it_extrapolates() {
    let dir = crate::support::unused_dir("extrapolated");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = crate::support::root().join("data/light_falloff_9_angles.csv");
    let arg = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let out = crate::support::metamer(&[
        "light",
        "fit",
        "--falloff",
        csv.to_str().unwrap(),
        "--model",
        "lambertian",
        "-o",
        &arg("LIGHT.json"),
        "--ies",
        &arg("light.ies"),
        "--ldt",
        &arg("light.ldt"),
        "--width-m",
        "0.3",
        "--height-m",
        "0.3",
        "--luminance",
        "1000",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains(
            "note: gamma above 60 deg up to 90 deg is not measured: there the table is the \
             lambertian model's extrapolation (readings reach 60 deg in C0, C90, C180 and \
             C270)"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("flux 282.7433 lm"), "{stdout}");
    assert!(
        stdout.contains(
            "of which 70.6858 lm (25.0 %) above γ = 60°, where the table is extrapolated"
        ),
        "{stdout}"
    );
    let ies_text = std::fs::read_to_string(dir.join("light.ies")).unwrap();
    assert!(
        ies_text.contains("[OTHER] gamma above 60 deg"),
        "{ies_text}"
    );
    let show = crate::support::metamer(&["light", "show", &arg("light.ldt")]);
    let shown = String::from_utf8_lossy(&show.stdout);
    assert!(
        shown.contains("fit of readings to gamma 60 deg; above, extrapolated by the lambertian"),
        "{shown}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
