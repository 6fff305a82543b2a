//! IES and EULUMDAT files: round trips to file precision and the flux of analytic
//! distributions (Lambertian: π·L₀·A; cos^n: 2π·L₀·A/(n + 2)).

use std::f64::consts::PI;
use std::path::Path;

use metamer::light::fit::Params;
use metamer::light::ies::{self, IesInfo};
use metamer::light::ldt::{self, LdtInfo};
use metamer::light::{fit, flux_lm, CGammaTable, Falloff, LdcModel, ModelChoice, Panel, PlaneData};

fn ies_info() -> IesInfo {
    IesInfo {
        test: "round trip".into(),
        issue_date: "2026-12-01".into(),
        luminaire: "test panel".into(),
        generation: "test".into(),
    }
}

fn ldt_info() -> LdtInfo {
    LdtInfo {
        luminaire: "test panel".into(),
        file_name: "t.ldt".into(),
        date_user: "2026-12-01 test".into(),
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
