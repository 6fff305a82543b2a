//! ICC display profiles written from fitted models, read back by moxcms (the crate that
//! encodes them, but through its parser and curve evaluators) and, when installed, by
//! ArgyllCMS (`iccdump`, `xicclu`), an independent reader.
//!
//! Tolerances: the PCS numbers are 16-bit. A curve entry is a multiple of 1/65535 and a
//! colorant of 1/65536, so near black one step moves a* or b* by up to
//! 500·7.787·(1/65535)/0.96 ≈ 0.06 (the slope of CIELAB's linear segment): max ΔE00 0.05
//! for matrix/TRC over every patch, mean 0.005. The LUT profiles' A2B0 puts its nodes on
//! the model's levels, so tetrahedral interpolation (the readback's, and LittleCMS's)
//! follows the model to the same 16-bit limits. The D50 adaptation is exact in both (the
//! same Bradford matrix is in `chad`).

use std::path::{Path, PathBuf};
use std::process::Command;

use metamer::color::{delta_e2000, Xyz};
use metamer::display::icc::layout::{tags, HEADER};
use metamer::display::icc::{
    agreement, encode_icc, icc_white, inverse_agreement, pcs::D50, profile_pcs, IccForward,
    IccVersion,
};
use metamer::display::{fit_profile, read_measurement_file, ModelKind, Profile};
use moxcms::{ColorProfile, DataColorSpace, ProfileClass, ProfileVersion};

use crate::support::oracle::{ICCDUMP, XICCLU};
use crate::support::unused_dir;

/// A .ti3 as dispread writes it after dispcal: the measured patches, then the `CAL` table
/// of video-card curves that were loaded while measuring.
fn ti3() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dispread_cal.ti3")
}

fn fitted(kind: ModelKind) -> (Profile, Vec<[f64; 3]>) {
    let m = read_measurement_file(&ti3()).unwrap();
    assert_eq!(m.calibration.as_ref().map(Vec::len), Some(256));
    let drives = m.patches.iter().map(|p| p.rgb).collect();
    (fit_profile(kind, &m.patches, Some(&ti3())).unwrap(), drives)
}

fn lab_d50(xyz: impl Into<Xyz>) -> metamer::color::Lab {
    xyz.into().to_lab(D50)
}

const MATRIX_MODELS: [ModelKind; 3] = [
    ModelKind::Plcc,
    ModelKind::MatrixLsq,
    ModelKind::ShaperMatrix,
];

#[test]
fn matrix_profiles_carry_the_model_and_the_required_tags() {
    for kind in MATRIX_MODELS {
        let (profile, drives) = fitted(kind);
        let pcs = profile_pcs(&profile).unwrap();
        let white = icc_white(&profile);
        for version in [IccVersion::V4, IccVersion::V2_4] {
            let icc = encode_icc(&profile, version, "test display").unwrap();
            assert_eq!(icc.summary.clipped_black, [0.0; 3], "{kind}");
            let p = ColorProfile::new_from_slice(&icc.bytes).unwrap();
            assert_eq!(p.profile_class, ProfileClass::DisplayDevice);
            assert_eq!(p.color_space, DataColorSpace::Rgb);
            assert_eq!(p.pcs, DataColorSpace::Xyz);
            let expected = match version {
                IccVersion::V4 => ProfileVersion::V4_3,
                IccVersion::V2_4 => ProfileVersion::V2_4,
            };
            assert_eq!(p.version(), expected);
            // lumi: the model's white in cd/m² (s15Fixed16: 1/65536 steps), within its
            // fit of the measured 120.25.
            let lumi = p.luminance.unwrap();
            assert!((lumi.y - white[1]).abs() < 1e-4, "{}", lumi.y);
            assert!((lumi.y - 120.25).abs() < 1.5, "{}", lumi.y);
            // chad takes the model's white (Y = 1) to D50.
            let chad = p.chromatic_adaptation.unwrap().v;
            let w = white.map(|v| v / white[1]);
            for r in 0..3 {
                let v: f64 = (0..3).map(|c| chad[r][c] * w[c]).sum();
                assert!((v - D50[r]).abs() < 1e-4, "chad row {r}: {v}");
            }
            let wtpt = p.media_white_point.unwrap();
            let want = match version {
                IccVersion::V4 => D50,
                IccVersion::V2_4 => w,
            };
            assert!((wtpt.x - want[0]).abs() < 1e-4 && (wtpt.z - want[2]).abs() < 1e-4);
            // The forward transform by moxcms's colorants and curve evaluators.
            let mut worst = 0.0f64;
            let mut sum = 0.0;
            let f = IccForward::parse(&icc.bytes).unwrap();
            assert!(matches!(f, IccForward::Matrix { .. }));
            for &rgb in &drives {
                let de = delta_e2000(
                    lab_d50(pcs.to_pcs(profile.forward(rgb))),
                    lab_d50(f.pcs_xyz(rgb)),
                );
                worst = worst.max(de);
                sum += de;
            }
            let mean = sum / drives.len() as f64;
            assert!(
                worst < 0.05 && mean < 0.005,
                "{kind} {version}: {mean} {worst}"
            );
            // RGB 1,1,1 is the PCS white: the colorants sum to D50 (what qcms checks).
            let sum = [p.red_colorant, p.green_colorant, p.blue_colorant]
                .iter()
                .fold([0.0; 3], |a, c| [a[0] + c.x, a[1] + c.y, a[2] + c.z]);
            for k in 0..3 {
                assert!((sum[k] - D50[k]).abs() < 2e-4, "{kind} {version}: {sum:?}");
            }
            check_layout(&icc.bytes, false);
        }
    }
}

/// ICC.1:2010 §7: every tag's data on a 4-byte boundary inside the file, the file a
/// multiple of 4 bytes long and as long as its header says, the tag count what the table
/// holds, and the tags a display profile needs.
fn check_layout(bytes: &[u8], lut: bool) {
    let be = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(be(0), bytes.len(), "header size");
    assert_eq!(bytes.len() % 4, 0, "file size {}", bytes.len());
    let count = be(HEADER);
    let t = tags(bytes).unwrap();
    assert_eq!(t.len(), count);
    let table_end = HEADER + 4 + 12 * count;
    let mut spans = Vec::new();
    for i in 0..count {
        let (sig, offset, size) = (
            String::from_utf8_lossy(&bytes[HEADER + 4 + 12 * i..HEADER + 8 + 12 * i]).to_string(),
            be(HEADER + 8 + 12 * i),
            be(HEADER + 12 + 12 * i),
        );
        assert_eq!(offset % 4, 0, "{sig} at {offset}");
        assert!(offset >= table_end && offset + size <= bytes.len(), "{sig}");
        spans.push((offset, offset + size, sig));
    }
    spans.sort();
    for w in spans.windows(2) {
        assert!(w[0].1 <= w[1].0, "{} overlaps {}", w[0].2, w[1].2);
    }
    let sigs: Vec<&str> = spans.iter().map(|s| s.2.as_str()).collect();
    let mut need = vec![
        "desc", "cprt", "wtpt", "lumi", "chad", "rXYZ", "gXYZ", "bXYZ", "rTRC", "gTRC", "bTRC",
    ];
    if lut {
        need.extend(["A2B0", "B2A0"]);
    }
    for n in need {
        assert!(sigs.contains(&n), "no {n} in {sigs:?}");
    }
}

#[test]
fn lut_profiles_carry_the_model_in_a2b0_and_invert_it_in_b2a0() {
    let (profile, drives) = fitted(ModelKind::Lut);
    for version in [IccVersion::V4, IccVersion::V2_4] {
        let icc = encode_icc(&profile, version, "test display").unwrap();
        let p = ColorProfile::new_from_slice(&icc.bytes).unwrap();
        assert!(p.lut_a_to_b_perceptual.is_some() && p.lut_b_to_a_perceptual.is_some());
        let a = agreement(&icc.bytes, &profile, &drives).unwrap();
        assert!(a.max_de00 < 0.1 && a.mean_de00 < 0.01, "{version}: {a:?}");
        // B2A0 then the model gives back each patch's colour (all inside the gamut).
        let b = inverse_agreement(&icc.bytes, &profile, &drives).unwrap();
        assert!(b.max_de00 < 0.3 && b.mean_de00 < 0.03, "{version}: {b:?}");
        // The matrix/TRC tags a reader without LUT support uses: the model's shapers and
        // primaries, RGB 1,1,1 at the PCS white.
        let m = IccForward::parse_matrix(&icc.bytes).unwrap();
        let w = m.pcs_xyz([1.0; 3]);
        for k in 0..3 {
            assert!((w[k] - D50[k]).abs() < 5e-4, "{w:?}");
        }
        let pcs = profile_pcs(&profile).unwrap();
        let worst = drives
            .iter()
            .map(|&d| {
                delta_e2000(
                    lab_d50(pcs.to_pcs(profile.forward(d))),
                    lab_d50(m.pcs_xyz(d)),
                )
            })
            .fold(0.0, f64::max);
        assert!(
            worst < 3.0,
            "matrix/TRC tags of the LUT profile: max ΔE00 {worst}"
        );
        eprintln!("lut {version}: A2B0 {a:?}, B2A0 {b:?}, matrix/TRC tags max ΔE00 {worst:.3}");
        check_layout(&icc.bytes, true);
    }
}

#[test]
fn a_black_outside_the_primaries_cone_is_clipped_and_reported() {
    // A bluish black with no red: k = M⁻¹·XYZ₀ has a negative red component.
    let (mut profile, _) = fitted(ModelKind::Plcc);
    let metamer::display::model::ModelParams::MatrixTrc(m) = &mut profile.parameters else {
        panic!("plcc is a matrix model");
    };
    m.black = Xyz::new(0.0, 0.0, 2.0);
    m.prepare(ModelKind::Plcc).unwrap();
    let icc = encode_icc(&profile, IccVersion::V4, "x").unwrap();
    assert!(icc.summary.clipped_black[0] > 0.0, "{:?}", icc.summary);
    let a = agreement(&icc.bytes, &profile, &[[0.0; 3]]).unwrap();
    assert!(a.max_de00 > 0.1, "the clipped black shows: {a:?}");
}

#[test]
fn argyll_reads_the_version_2_profiles_and_agrees_on_xyz() {
    let (Some(iccdump), Some(xicclu)) = (ICCDUMP.find(), XICCLU.find()) else {
        return;
    };
    let dir = unused_dir("argyll");
    std::fs::create_dir_all(&dir).unwrap();
    let devices = [
        [1.0, 1.0, 1.0],
        [0.0, 0.0, 0.0],
        [0.5, 0.2, 0.8],
        [0.1, 0.05, 0.02],
        [0.9, 0.6, 0.3],
    ];
    for (kind, tolerance, tag) in [
        (ModelKind::ShaperMatrix, 0.05, "'rTRC'"),
        (ModelKind::Lut, 0.1, "'A2B0'"),
    ] {
        let (profile, _) = fitted(kind);
        let icc = encode_icc(&profile, IccVersion::V2_4, "test display").unwrap();
        let path = dir.join(format!("{kind}.icc"));
        std::fs::write(&path, &icc.bytes).unwrap();
        let dump = Command::new(&iccdump)
            .args(["-v", "3"])
            .arg(&path)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&dump.stdout);
        assert!(dump.status.success() && !text.contains("Error"), "{text}");
        assert!(
            text.contains("Version      = 2.4") && text.contains("Display"),
            "{text}"
        );
        assert!(text.contains(tag) && text.contains("'lumi'") && text.contains("'chad'"));
        // -ff: float device values 0–1 in, -ir: relative colorimetric, -pX: PCS XYZ ×100.
        let mut child = Command::new(&xicclu)
            .args(["-v0", "-ff", "-ir", "-pX"])
            .arg(&path)
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let input: String = devices
            .iter()
            .map(|d| format!("{} {} {}\n", d[0], d[1], d[2]))
            .collect();
        std::io::Write::write_all(child.stdin.as_mut().unwrap(), input.as_bytes()).unwrap();
        let out = child.wait_with_output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        let rows: Vec<[f64; 3]> = text
            .lines()
            .map(|l| {
                let v: Vec<f64> = l
                    .split_whitespace()
                    .take(3)
                    .map(|x| x.parse().unwrap())
                    .collect();
                [v[0] / 100.0, v[1] / 100.0, v[2] / 100.0]
            })
            .collect();
        assert_eq!(rows.len(), devices.len(), "{text}");
        let pcs = profile_pcs(&profile).unwrap();
        let mut worst = 0.0f64;
        for (d, theirs) in devices.iter().zip(rows) {
            let ours = pcs.to_pcs(profile.forward(*d));
            let de = delta_e2000(lab_d50(ours), lab_d50(theirs));
            assert!(
                de < tolerance,
                "{kind} at {d:?}: ours {ours:?}, Argyll {theirs:?}: ΔE00 {de}"
            );
            worst = worst.max(de);
        }
        eprintln!("{kind}: Argyll's xicclu agrees to max ΔE00 {worst:.4}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn fit_writes_the_icc_profile_it_is_asked_for() {
    let dir = unused_dir("cli");
    std::fs::create_dir_all(&dir).unwrap();
    let bin = env!("CARGO_BIN_EXE_metamer");
    let out = Command::new(bin)
        .args(["fit", "--model", "shaper-matrix", "--measurements"])
        .arg(ti3())
        .arg("-o")
        .arg(dir.join("p.json"))
        .arg("--icc")
        .arg(dir.join("p.icc"))
        .args(["--icc-version", "2.4"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("ICC 2.4 profile (matrix/TRC)"), "{text}");
    let bytes = std::fs::read(dir.join("p.icc")).unwrap();
    assert_eq!(&bytes[8..12], &[2, 0x40, 0, 0]);
    assert_eq!(&bytes[36..40], b"acsp");
    let out = Command::new(bin)
        .args(["fit", "--measurements"])
        .arg(ti3())
        .arg("-o")
        .arg(dir.join("q.json"))
        .args(["--icc-version", "2.4"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--icc-version needs --icc"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The plcc profile of the test file with every XYZ it predicts multiplied so that its
/// white's largest component is `top` cd/m².
fn plcc_with_white_up_to(top: f64) -> Profile {
    let (mut profile, _) = fitted(ModelKind::Plcc);
    let w = icc_white(&profile);
    let s = top / w.x.max(w.y).max(w.z);
    let metamer::display::model::ModelParams::MatrixTrc(m) = &mut profile.parameters else {
        panic!("plcc is a matrix model");
    };
    m.black = m.black.map(|v| v * s);
    m.matrix = m.matrix.map(|row| row.map(|v| v * s));
    m.prepare(ModelKind::Plcc).unwrap();
    profile
}

/// `lumi` is an XYZType of s15Fixed16Numbers, whose largest value is 32767 + 65535/65536:
/// a white up to that is stored to 1/65536 cd/m², a brighter one is refused, not clamped.
#[test]
fn the_luminance_tag_holds_its_white_or_the_profile_is_refused() {
    let bright = plcc_with_white_up_to(32000.0);
    let icc = encode_icc(&bright, IccVersion::V4, "bright").unwrap();
    let lumi = tags(&icc.bytes)
        .unwrap()
        .into_iter()
        .find(|(sig, _)| sig == b"lumi")
        .expect("a lumi tag")
        .1;
    assert_eq!(&lumi[..4], b"XYZ ");
    let s15 = |at: usize| f64::from(i32::from_be_bytes(lumi[at..at + 4].try_into().unwrap()));
    let white = icc_white(&bright);
    for (k, at) in [8, 12, 16].into_iter().enumerate() {
        assert!(
            (s15(at) / 65536.0 - white[k]).abs() <= 0.5 / 65536.0,
            "lumi {k}: {} for {}",
            s15(at) / 65536.0,
            white[k]
        );
    }
    let too_bright = plcc_with_white_up_to(32768.0);
    for version in [IccVersion::V4, IccVersion::V2_4] {
        let e = encode_icc(&too_bright, version, "too bright")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("luminance tag") && e.contains("32767.99998"),
            "{e}"
        );
    }
}

/// A version 4 LUT profile carries its tables as lutAtoBType / lutBtoAType (ICC.1:2010
/// 10.10, 10.11; signatures 'mAB ' and 'mBA '), which LittleCMS saves again after reading
/// (icc_resave); version 2.4 has only lut16Type ('mft2').
#[test]
fn lut_profiles_use_the_tag_types_of_their_version() {
    let (profile, _) = fitted(ModelKind::Lut);
    for (version, a2b, b2a) in [
        (IccVersion::V4, b"mAB ", b"mBA "),
        (IccVersion::V2_4, b"mft2", b"mft2"),
    ] {
        let icc = encode_icc(&profile, version, "types").unwrap();
        let t = tags(&icc.bytes).unwrap();
        let kind = |want: &[u8; 4]| {
            let data = &t.iter().find(|(s, _)| s == want).expect("tag").1;
            <[u8; 4]>::try_from(&data[..4]).unwrap()
        };
        assert_eq!(&kind(b"A2B0"), a2b, "{version} A2B0");
        assert_eq!(&kind(b"B2A0"), b2a, "{version} B2A0");
    }
}
