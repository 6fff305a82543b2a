//! `metamer color …` end to end: values against independent references, and the errors a
//! user sees for bad input.

use std::path::{Path, PathBuf};
use std::process::Command;

use metamer::color::{delta_e2000, delta_e76, Lab};
use metamer::numeric_csv::NumericCsv;

use crate::support::oracle::COLOUR_SCIENCE;
use crate::support::{fresh_dir, metamer_in_root, stderr, test_data};

fn sharma_pairs() -> Vec<Vec<f64>> {
    NumericCsv::read(
        &test_data("sharma2005_ciede2000.csv"),
        &["L1", "a1", "b1", "L2", "a2", "b2", "de00"],
    )
    .unwrap()
    .rows
    .into_iter()
    .map(|(_, v)| v)
    .collect()
}

#[test]
fn ciede2000_matches_all_34_sharma_pairs_both_ways() {
    let pairs = sharma_pairs();
    assert_eq!(pairs.len(), 34);
    for (i, v) in pairs.iter().enumerate() {
        let p = Lab::new(v[0], v[1], v[2]);
        let q = Lab::new(v[3], v[4], v[5]);
        // The table is rounded to 4 decimals; 1e-4 is the issue's tolerance.
        let d = delta_e2000(p, q);
        assert!((d - v[6]).abs() < 1e-4, "pair {}: {d} vs {}", i + 1, v[6]);
        let r = delta_e2000(q, p);
        assert!((r - v[6]).abs() < 1e-4, "pair {} reversed: {r}", i + 1);
    }
}

#[test]
fn delta_e_command_prints_json_in_row_order() {
    let dir = fresh_dir("delta_e");
    let file = dir.join("pairs.csv");
    let mut text = String::from("L1,a1,b1,L2,a2,b2\n");
    for v in sharma_pairs() {
        text += &format!("{},{},{},{},{},{}\n", v[0], v[1], v[2], v[3], v[4], v[5]);
    }
    std::fs::write(&file, text).unwrap();
    let o = metamer_in_root(&[
        "color",
        "delta-e",
        "--pairs",
        file.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = out.as_array().unwrap();
    assert_eq!(rows.len(), 34);
    for (row, v) in rows.iter().zip(sharma_pairs()) {
        assert!((row["de00"].as_f64().unwrap() - v[6]).abs() < 1e-4);
        // ΔE76 by hand: Euclidean distance.
        let d76 = ((v[0] - v[3]).powi(2) + (v[1] - v[4]).powi(2) + (v[2] - v[5]).powi(2)).sqrt();
        assert!((row["de76"].as_f64().unwrap() - d76).abs() < 1e-12);
    }
    let l1 = Lab::new(50.0, 2.5, 0.0);
    assert_eq!(delta_e76(l1, l1), 0.0);
}

#[test]
fn colorchecker_under_d65_matches_independent_reference() {
    // The reference sums linearly interpolated data over 380–780 nm (the validation box's
    // convention), which `--method linear` asks for.
    let o = metamer_in_root(&[
        "color",
        "xyz",
        "data/colorchecker_babelcolor_average.csv",
        "--quantity",
        "reflectance",
        "--illuminant",
        "D65",
        "--method",
        "linear",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let reference = NumericCsv::read(
        &test_data("colorchecker_d65_reference.csv"),
        &["patch", "X", "Y", "Z", "L", "a", "b"],
    )
    .unwrap();
    let lines: Vec<serde_json::Value> = String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 24);
    for (got, (_, want)) in lines.iter().zip(&reference.rows) {
        for k in 0..3 {
            let x = got["XYZ"][k].as_f64().unwrap();
            assert!(
                (x - want[1 + k]).abs() < 1e-5,
                "patch {}: {got} vs {want:?}",
                want[0]
            );
            let l = got["Lab"][k].as_f64().unwrap();
            assert!(
                (l - want[4 + k]).abs() < 1e-5,
                "patch {}: {got} vs {want:?}",
                want[0]
            );
        }
        let xyy = &got["xyY"];
        let sum = want[1] + want[2] + want[3];
        assert!((xyy[0].as_f64().unwrap() - want[1] / sum).abs() < 1e-7);
    }
}

#[test]
fn flat_half_reflectance_is_half_the_white() {
    // Hand derivation: R = 0.5 everywhere gives exactly Y = 50 and Lab L* = 116·0.5^(1/3) − 16.
    let dir = fresh_dir("flat");
    let file = dir.join("grey.csv");
    std::fs::write(&file, "nm,grey\n380,0.5\n780,0.5\n").unwrap();
    let o = metamer_in_root(&[
        "color",
        "xyz",
        file.to_str().unwrap(),
        "--quantity",
        "reflectance",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["XYZ"][1].as_f64().unwrap() - 50.0).abs() < 1e-9);
    let l = 116.0 * 0.5f64.cbrt() - 16.0;
    assert!((v["Lab"][0].as_f64().unwrap() - l).abs() < 1e-9);
    assert!(v["Lab"][1].as_f64().unwrap().abs() < 1e-9);
}

#[test]
fn radiance_gives_absolute_xyz_and_lab_only_with_a_white() {
    // A 1 nm line at 555 nm of 1 W·sr⁻¹·m⁻²·nm⁻¹: Y = 683 · ȳ(555) = 683 cd/m².
    let dir = fresh_dir("line");
    let file = dir.join("line.csv");
    std::fs::write(&file, "# line\nnm,L\n554,0\n555,1\n556,0\n").unwrap();
    let o = metamer_in_root(&["color", "xyz", file.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["XYZ"][1].as_f64().unwrap() - 683.0).abs() < 1e-9);
    assert!(v.get("Lab").is_none());
    let o = metamer_in_root(&[
        "color",
        "xyz",
        file.to_str().unwrap(),
        "--json",
        "--white",
        "683,683,683",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["Lab"][0].as_f64().unwrap() - 100.0).abs() < 1e-9);
}

/// The 24 ColorChecker patches lit by the `ips-lcd` display white, and the white, as an
/// i1Pro samples them (380–730 nm, 10 nm), in a spectral CSV.
fn i1pro_readings_csv(dir: &Path) -> PathBuf {
    use metamer::color::{colorchecker, ColorCheckerSet, SpectralTable};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let white = SpectralTable::read(&root.join("data/display_white_ips_lcd.csv"))
        .unwrap()
        .first();
    let cc = colorchecker(ColorCheckerSet::BabelColorAverage);
    let mut text = String::from("# ColorChecker under the ips-lcd white, 10 nm\nnm,white");
    for p in 1..=24 {
        text += &format!(",p{p}");
    }
    text.push('\n');
    for band in 0..36 {
        let nm = 380.0 + 10.0 * band as f64;
        let w = white.value_at(nm);
        text += &format!("{nm}");
        text += &format!(",{w:e}");
        for r in &cc {
            text += &format!(",{:e}", w * r.value_at(nm));
        }
        text.push('\n');
    }
    let file = dir.join("i1pro.csv");
    std::fs::write(&file, text).unwrap();
    file
}

/// colour-science's XYZ of each column of a spectral CSV: `sd_to_XYZ` with k = 683 and an
/// equal-energy illuminant by `method`, ×100 (it divides absolute values by 100). None
/// (the test skipped with the reason) where colour-science is missing.
fn colour_science(csv: &Path, method: &str) -> Option<Vec<[f64; 3]>> {
    let script = r##"
import json, sys, warnings
warnings.filterwarnings("ignore")
import colour
rows = [l.strip().split(",") for l in open(sys.argv[1]) if l.strip() and not l.startswith("#")]
nm = [float(r[0]) for r in rows[1:]]
cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
ones = colour.sd_ones(cmfs.shape)
out = []
for c in range(1, len(rows[0])):
    sd = colour.SpectralDistribution(dict(zip(nm, [float(r[c]) for r in rows[1:]])))
    out.append([100.0 * v for v in colour.sd_to_XYZ(sd, cmfs, ones, k=683, method=sys.argv[2])])
print(json.dumps(out))
"##;
    let python = COLOUR_SCIENCE.find()?;
    let o = Command::new(python)
        .args(["-c", script])
        .arg(csv)
        .arg(method)
        .output()
        .expect("python3 runs");
    assert!(
        o.status.success(),
        "colour-science's script failed: {}",
        stderr(&o)
    );
    Some(serde_json::from_slice(&o.stdout).unwrap())
}

#[test]
fn xyz_of_10nm_readings_is_colour_science_integration_and_near_astm_e308() {
    let dir = fresh_dir("i1pro");
    let csv = i1pro_readings_csv(&dir);
    let o = metamer_in_root(&["color", "xyz", csv.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let ours: Vec<[f64; 3]> = String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            std::array::from_fn(|k| v["XYZ"][k].as_f64().unwrap())
        })
        .collect();
    assert_eq!(ours.len(), 25);
    // Written into the test from colour-science 0.4.7 (`Integration`, as above) so the
    // comparison holds where the library is missing: the white.
    let white = [
        190.203_348_864_693_23,
        199.999_957_762_433_9,
        223.418_284_255_467_63,
    ];
    for k in 0..3 {
        assert!((ours[0][k] / white[k] - 1.0).abs() < 1e-9, "{:?}", ours[0]);
    }
    let Some(integration) = colour_science(&csv, "Integration") else {
        return;
    };
    let astm = colour_science(&csv, "ASTM E308").unwrap();
    for ((m, i), a) in ours.iter().zip(&integration).zip(&astm) {
        for k in 0..3 {
            assert!(
                (m[k] / i[k] - 1.0).abs() < 1e-9,
                "{m:?} vs Integration {i:?}"
            );
            assert!((m[k] / a[k] - 1.0).abs() < 3e-4, "{m:?} vs ASTM E308 {a:?}");
        }
    }
}

fn run_bad(name: &str, content: &str) -> (i32, String) {
    let dir = fresh_dir(name);
    let file = dir.join(format!("{name}.csv"));
    std::fs::write(&file, content).unwrap();
    let o = metamer_in_root(&["color", "xyz", file.to_str().unwrap()]);
    (o.status.code().unwrap(), stderr(&o))
}

/// Spectra nothing can be integrated from, refused with the file and line: no wavelength
/// is zero or less; one row has no wavelength step to sum over (CIE 15:2018 §7.1); and
/// samples that all lie outside the range summed would give zero (radiance) or a flat
/// spectrum held from a far end value (reflectance). The CIE tables span 360–830 nm (CIE
/// 15:2018 Table 1), the default method sums a 10 nm spectrum over all of it and a 1 nm
/// one, or any with `--method linear`, over 380–780 nm (paper Eq. 8).
#[test]
fn spectra_with_nothing_to_integrate_are_refused_with_their_line() {
    let (code, e) = run_bad("negative", "# c\nnm,v\n-400,1\n410,2\n");
    assert_eq!(code, 1, "{e}");
    assert!(
        e.contains("negative.csv:3: wavelength -400 nm: wavelengths are positive"),
        "{e}"
    );
    let (code, e) = run_bad("one_row", "nm,v\n\n555,0.01\n");
    assert_eq!(code, 1, "{e}");
    assert!(
        e.contains("one_row.csv:3: the spectrum has one row (555 nm)"),
        "{e}"
    );
    let infrared: String = (0..8).map(|i| format!("{},1\n", 900 + 10 * i)).collect();
    let (code, e) = run_bad("infrared", &format!("# far\nnm,v\n{infrared}"));
    assert_eq!(code, 1, "{e}");
    assert!(
        e.contains("infrared.csv:3: column 'v': its samples (900–970 nm) lie outside 360–830 nm"),
        "{e}"
    );
    // 790–800 nm lies inside the CIE tables but outside paper Eq. 8's 380–780 nm.
    let dir = fresh_dir("linear");
    let file = dir.join("near.csv");
    std::fs::write(&file, "nm,v\n790,1\n800,1\n").unwrap();
    let o = metamer_in_root(&["color", "xyz", file.to_str().unwrap(), "--method", "linear"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("near.csv:2: column 'v': its samples (790–800 nm) lie outside 380–780 nm")
            && e.contains("with --method linear"),
        "{e}"
    );
    // One sample inside is enough: 770–800 nm at 10 nm is summed as given.
    std::fs::write(&file, "nm,v\n770,1\n780,1\n790,1\n800,1\n").unwrap();
    let o = metamer_in_root(&["color", "xyz", file.to_str().unwrap(), "--method", "linear"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn bad_csvs_give_file_and_line_errors_with_exit_1() {
    let (code, e) = run_bad("missing_header", "# c\n400,1\n410,2\n");
    assert_eq!(code, 1);
    assert!(e.contains("missing_header.csv:2: missing header"), "{e}");
    let (code, e) = run_bad("non_numeric", "nm,v\n400,1\n410,x1\n");
    assert_eq!(code, 1);
    assert!(
        e.contains("non_numeric.csv:3: column 2 ('v'): 'x1' is not a number"),
        "{e}"
    );
    let (code, e) = run_bad("not_increasing", "nm,v\n400,1\n420,2\n410,3\n");
    assert_eq!(code, 1);
    assert!(
        e.contains("not_increasing.csv:4: wavelengths must increase: 410 nm follows 420 nm"),
        "{e}"
    );
    let (code, e) = run_bad("empty", "");
    assert_eq!(code, 1);
    assert!(e.contains("empty.csv: the file is empty"), "{e}");
    assert!(!e.contains("panicked") && !e.contains("backtrace"), "{e}");
}

#[test]
fn usage_errors_exit_2() {
    let o = metamer_in_root(&["color", "xyz", "data/illuminant_d65.csv", "--white", "1,2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("expected three comma-separated numbers"));
    let o = metamer_in_root(&[
        "color",
        "xyz",
        "data/illuminant_d65.csv",
        "--illuminant",
        "D75",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("unknown illuminant 'D75'"),
        "{}",
        stderr(&o)
    );
    let o = metamer_in_root(&[
        "color",
        "xyz",
        "data/illuminant_d65.csv",
        "--observer",
        "1950",
    ]);
    assert_eq!(o.status.code(), Some(2));
}
