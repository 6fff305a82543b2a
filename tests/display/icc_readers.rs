//! metamer's ICC profiles read by a colour management system that is not metamer's own:
//! LittleCMS, through Debian's `transicc` (liblcms2-utils). For each profile, on patches the
//! fit did not see:
//!
//! - forward (RGB → PCS XYZ, relative colorimetric): LittleCMS's XYZ, taken back to cd/m²
//!   through the profile's own white (`chad`, `lumi`), is judged against the measured XYZ as
//!   `metamer verify` judges the model (CIELAB relative to the measured white); the two mean
//!   ΔE00 must agree within 0.01;
//! - inverse (PCS XYZ → RGB): for the held-out colours inside the model's gamut, the drive
//!   values LittleCMS gives are put through the model and compared with the target; their
//!   mean ΔE00 must be within 0.05 of that of `metamer reproduce`'s drive values.
//!
//! `transicc` runs with `-c0` (no precalculated device link: LittleCMS evaluates the
//! profile's own tags) and `-t1` (relative colorimetric). Data: `tests/data/dispread_cal.ti3`
//! (a real dispread layout; every model, both ICC versions) and scattered sets of the
//! simulated displays. Skipped (with the reason printed) where `transicc` is not installed;
//! in CI (`CI` set) a missing `transicc` fails the test.
//!
//! `print_real_monitor_table` (ignored) does the same on `.ti3` files of real monitors in
//! `METAMER_REAL_TI3` (see benches/argyll/README.md) and prints the table.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use metamer::color::{delta_e2000, Xyz};
use metamer::display::characterize::plan::random_patches;
use metamer::display::gamut::GamutMapping;
use metamer::display::icc::{encode_icc, profile_pcs, IccVersion};
use metamer::display::reproduce::reproduce_targets;
use metamer::display::scattered::scattered_patches;
use metamer::display::{
    fit_profile, read_measurement_file, verify_profile, ModelKind, Profile, Sample,
};
use metamer::rig::{Preset, VirtualPanel};

use crate::support::fresh_dir;
use crate::support::oracle::TRANSICC;

/// LittleCMS's `transicc`, or None (the test skipped with the reason) where it is missing.
pub(crate) fn transicc_installed() -> bool {
    TRANSICC.find().is_some()
}

/// Runs `transicc -n -c0 -t1 ARGS` on one triple per line; its triples back.
pub(crate) fn transicc(args: &[&str], input: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut child = Command::new(TRANSICC.find().expect("probed by the test"))
        .args(["-n", "-c0", "-t1"])
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("transicc runs");
    let text: String = input
        .iter()
        .map(|v| format!("{:.6} {:.6} {:.6}\n", v[0], v[1], v[2]))
        .collect();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(text.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "transicc {args:?} failed");
    let rows: Vec<[f64; 3]> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .take(3)
                .map(|x| x.parse().expect("a number"))
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(rows.len(), input.len(), "transicc {args:?}: {rows:?}");
    rows
}

/// What LittleCMS makes of one profile on held-out patches, next to metamer's own figures.
#[derive(Debug)]
struct Reading {
    /// Mean ΔE00 to the measurements: `metamer verify`, then LittleCMS forward.
    verify: f64,
    forward: f64,
    /// Largest |ΔE00(LittleCMS) − ΔE00(model)| over the patches.
    forward_max_gap: f64,
    /// In-gamut held-out colours, and the mean ΔE00 of the model at the drive values of
    /// `metamer reproduce`, then of LittleCMS's B2A0 / inverted TRC.
    in_gamut: usize,
    reproduce: f64,
    inverse: f64,
    inverse_max: f64,
}

fn read_with_lcms(
    profile: &Profile,
    held_out: &[Sample],
    version: IccVersion,
    dir: &Path,
) -> Reading {
    let icc = encode_icc(profile, version, "metamer test display").unwrap();
    let path = dir.join(format!("{}-{version}.icc", profile.model));
    std::fs::write(&path, &icc.bytes).unwrap();
    let file = path.to_str().unwrap();
    let pcs = profile_pcs(profile).unwrap();
    let white = profile.white_xyz;
    let lab = |xyz: Xyz| xyz.to_lab(white);

    let rgb: Vec<[f64; 3]> = held_out.iter().map(|p| p.rgb.map(|v| v * 255.0)).collect();
    let theirs = transicc(&["-i", file, "-o", "*XYZ"], &rgb);
    let verify = verify_profile(profile, held_out).unwrap().de00.mean;
    let (mut sum, mut gap) = (0.0, 0.0f64);
    for (p, t) in held_out.iter().zip(&theirs) {
        let xyz = pcs.from_pcs(Xyz::from(t.map(|v| v / 100.0)));
        let de = delta_e2000(lab(xyz), lab(p.xyz));
        sum += de;
        gap = gap.max((de - delta_e2000(lab(profile.forward(p.rgb)), lab(p.xyz))).abs());
    }
    let forward = sum / held_out.len() as f64;

    let targets: Vec<Xyz> = held_out
        .iter()
        .map(|p| p.xyz)
        .filter(|&x| !profile.inverse(x).out_of_gamut)
        .collect();
    let ours = reproduce_targets(profile, &targets, GamutMapping::Clip);
    let pcs_in: Vec<[f64; 3]> = targets
        .iter()
        .map(|&x| pcs.to_pcs(x).map(|v| v * 100.0).to_array())
        .collect();
    let back = transicc(&["-i", "*XYZ", "-o", file], &pcs_in);
    let (mut r, mut inv, mut inv_max) = (0.0, 0.0, 0.0f64);
    for ((x, d), b) in targets.iter().zip(&ours).zip(&back) {
        r += delta_e2000(lab(profile.forward(d.rgb)), lab(*x));
        let de = delta_e2000(lab(profile.forward(b.map(|v| v / 255.0))), lab(*x));
        inv += de;
        inv_max = inv_max.max(de);
    }
    let n = targets.len().max(1) as f64;
    Reading {
        verify,
        forward,
        forward_max_gap: gap,
        in_gamut: targets.len(),
        reproduce: r / n,
        inverse: inv / n,
        inverse_max: inv_max,
    }
}

fn check(what: &str, r: &Reading) {
    eprintln!("{what}: {r:?}");
    assert!(
        (r.forward - r.verify).abs() <= 0.01,
        "{what}: LittleCMS forward mean ΔE00 {:.4}, metamer verify {:.4}",
        r.forward,
        r.verify
    );
    assert!(
        r.inverse - r.reproduce <= 0.05,
        "{what}: LittleCMS inverse mean ΔE00 {:.4}, metamer reproduce {:.4}",
        r.inverse,
        r.reproduce
    );
}

fn corner(rgb: [f64; 3]) -> bool {
    rgb.iter().all(|&v| v <= 1e-6 || v >= 1.0 - 1e-6)
}

/// The cube's corners and every other remaining patch to fit, the rest held out.
fn split(patches: &[Sample]) -> (Vec<Sample>, Vec<Sample>) {
    let (mut fit, mut held) = (Vec::new(), Vec::new());
    let mut other = 0usize;
    for p in patches {
        if corner(p.rgb) {
            fit.push(*p);
        } else {
            if other % 2 == 0 {
                fit.push(*p);
            } else {
                held.push(*p);
            }
            other += 1;
        }
    }
    (fit, held)
}

#[test]
fn littlecms_reads_every_model_of_a_dispread_file_as_metamer_does() {
    if !transicc_installed() {
        return;
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dispread_cal.ti3");
    let m = read_measurement_file(&path).unwrap();
    let (fit, held) = split(&m.patches);
    let dir = fresh_dir("icc-lcms");
    let mut fitted = 0;
    for kind in ModelKind::ALL {
        let Ok(profile) = fit_profile(kind, &fit, Some(&path)) else {
            continue;
        };
        fitted += 1;
        for version in [IccVersion::V4, IccVersion::V2_4] {
            let r = read_with_lcms(&profile, &held, version, &dir);
            assert!(r.in_gamut > held.len() / 2, "{kind}: {r:?}");
            check(&format!("dispread_cal.ti3 {kind} {version}"), &r);
        }
    }
    assert!(fitted >= 5, "only {fitted} models fit the file");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn littlecms_reads_lut_and_shaper_matrix_profiles_of_simulated_displays_as_metamer_does() {
    if !transicc_installed() {
        return;
    }
    let dir = fresh_dir("icc-lcms-sim");
    for preset in [Preset::IpsLcd, Preset::WideGamutCcfl] {
        let panel = VirtualPanel::preset(preset);
        let measure = |codes: Vec<[u8; 3]>| -> Vec<Sample> {
            codes
                .into_iter()
                .map(|c| Sample {
                    rgb: c.map(|v| f64::from(v) / 255.0),
                    xyz: panel.xyz(c),
                })
                .collect()
        };
        let fit = measure(scattered_patches(200, 3));
        let held = measure(random_patches(150, 11));
        for kind in [ModelKind::ShaperMatrix, ModelKind::Lut] {
            let profile = fit_profile(kind, &fit, None).unwrap();
            for version in [IccVersion::V4, IccVersion::V2_4] {
                let r = read_with_lcms(&profile, &held, version, &dir);
                check(&format!("{preset:?} {kind} {version}"), &r);
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The table of real monitors: `METAMER_REAL_TI3=DIR cargo test --release --test display
/// -- --ignored --nocapture icc_readers::print_real_monitor_table`; `METAMER_REAL_MODELS=lut,plcc` limits the models. The whole
/// table is printed, then every row is held to the limits `check` applies (forward within
/// 0.01 of verify, inverse within 0.05 of reproduce).
#[test]
#[ignore]
fn print_real_monitor_table() {
    let Some(dir) = std::env::var_os("METAMER_REAL_TI3") else {
        eprintln!("set METAMER_REAL_TI3 to a folder of .ti3 files");
        return;
    };
    assert!(transicc_installed());
    let work = fresh_dir("icc-real");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ti3"))
        .collect();
    files.sort();
    let only: Option<Vec<String>> = std::env::var("METAMER_REAL_MODELS")
        .ok()
        .map(|v| v.split(',').map(|m| m.trim().to_string()).collect());
    println!(
        "| file | model | ICC | held out | verify | LittleCMS forward | max gap | in gamut | \
         reproduce | LittleCMS inverse | inverse max |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut outside = Vec::new();
    for f in files {
        let m = read_measurement_file(&f).unwrap();
        let (fit, held) = split(&m.patches);
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        let short: String = name.chars().take(24).collect();
        for kind in ModelKind::ALL {
            if only
                .as_ref()
                .is_some_and(|o| !o.contains(&kind.to_string()))
            {
                continue;
            }
            let Ok(profile) = fit_profile(kind, &fit, Some(&f)) else {
                println!("| {short} | {kind} | — | refused | | | | | | | |");
                continue;
            };
            for version in [IccVersion::V4, IccVersion::V2_4] {
                let r = read_with_lcms(&profile, &held, version, &work);
                println!(
                    "| {short} | {kind} | {version} | {} | {:.4} | {:.4} | {:.4} | {} | {:.4} | \
                     {:.4} | {:.3} |",
                    held.len(),
                    r.verify,
                    r.forward,
                    r.forward_max_gap,
                    r.in_gamut,
                    r.reproduce,
                    r.inverse,
                    r.inverse_max
                );
                if (r.forward - r.verify).abs() > 0.01 || r.inverse - r.reproduce > 0.05 {
                    outside.push(format!("{name}, {kind}, ICC {version}"));
                }
            }
        }
    }
    std::fs::remove_dir_all(&work).ok();
    assert!(outside.is_empty(), "outside the limits: {outside:#?}");
}
