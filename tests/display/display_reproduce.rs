//! `metamer fit` and `metamer reproduce` end to end on the dispread-format fixture, and the
//! reproduction library: targets, images (mirror, out-of-gamut count) and PNG depths.

use metamer::color::Xyz;
use metamer::display::gamut::GamutMapping;
use metamer::display::reproduce::{reproduce_image, reproduce_targets, write_drive_png};
use metamer::display::{fit_profile, read_measurements, ModelKind, Profile};
use metamer::image::XyzImage;

use crate::support::{
    dispread_analytic, fresh_dir, metamer, srgb_from_xyz, write_rgb_exr, XYZ_CHROMATICITIES,
};

/// The fixture's analytic display (see tests/display/display_fit.rs): black + Σ col·d^γ.
fn analytic(rgb: [f64; 3]) -> [f64; 3] {
    let black = [0.25, 0.26, 0.30];
    let cols = [
        [49.49, 25.51, 2.32],
        [42.91, 85.82, 14.30],
        [21.66, 8.66, 114.07],
    ];
    let gamma = [2.2, 2.3, 2.1];
    std::array::from_fn(|k| {
        black[k]
            + (0..3)
                .map(|c| cols[c][k] * rgb[c].powf(gamma[c]))
                .sum::<f64>()
    })
}

#[test]
fn fit_and_reproduce_a_dispread_ti3_from_the_command_line() {
    let dir = fresh_dir("fitcli");
    let profile = dir.join("p.json");
    let out = metamer(&[
        "fit",
        "--measurements",
        dispread_analytic().to_str().unwrap(),
        "--model",
        "plcc-gamma",
        "-o",
        profile.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("verdict: PLCC's assumptions hold within ΔE00 0.5"),
        "{stdout}"
    );
    assert!(
        stdout.contains("white XYZ 114.310 120.250 130.990 cd/m²"),
        "{stdout}"
    );
    let targets = dir.join("t.csv");
    let inside = analytic([0.2, 0.5, 0.7]);
    std::fs::write(
        &targets,
        format!(
            "X,Y,Z\n{},{},{}\n240,250,260\n-1,-2,-3\n",
            inside[0], inside[1], inside[2]
        ),
    )
    .unwrap();
    let rgb = dir.join("rgb.csv");
    let out = metamer(&[
        "reproduce",
        "--profile",
        profile.to_str().unwrap(),
        "--xyz",
        targets.to_str().unwrap(),
        "-o",
        rgb.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("3 targets, 2 out of gamut (clipped)"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&rgb).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(text.lines().next(), Some("r,g,b,out_of_gamut"));
    for (got, want) in rows[0][..3].iter().zip([0.2, 0.5, 0.7]) {
        assert!((got - want).abs() < 1e-4, "{got} vs {want}");
    }
    assert_eq!(rows[0][3], 0.0);
    assert_eq!(rows[1], vec![1.0, 1.0, 1.0, 1.0]);
    assert_eq!(rows[2][3], 1.0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn command_line_errors() {
    let dir = fresh_dir("fitcli-err");
    let bad = dir.join("bad.ti3");
    let text = std::fs::read_to_string(dispread_analytic())
        .unwrap()
        .replace("3 12.5000 0.0000 0.0000", "3 12.5000 zero 0.0000");
    std::fs::write(&bad, text).unwrap();
    let out = metamer(&[
        "fit",
        "--measurements",
        bad.to_str().unwrap(),
        "-o",
        "x.json",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("bad.ti3:34: field RGB_G ('zero') is not a number"),
        "{stderr}"
    );
    let out = metamer(&[
        "reproduce",
        "--profile",
        "p.json",
        "-o",
        "x.png",
        "--bits",
        "12",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let out = metamer(&[
        "fit",
        "--measurements",
        "m.csv",
        "--model",
        "plcc",
        "--gamma",
        "2.2",
        "-o",
        "p.json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

fn profile() -> Profile {
    let patches = read_measurements(&dispread_analytic()).unwrap();
    fit_profile(ModelKind::PlccGamma, &patches, None).unwrap()
}

#[test]
fn targets_report_out_of_gamut_and_nearest_lab_stays_in_the_cube() {
    let p = profile();
    let targets = [analytic([0.3, 0.6, 0.9]).into(), Xyz::new(300.0, 10.0, 5.0)];
    let clipped = reproduce_targets(&p, &targets, GamutMapping::Clip);
    assert!(!clipped[0].out_of_gamut && clipped[1].out_of_gamut);
    for (got, want) in clipped[0].rgb.iter().zip([0.3, 0.6, 0.9]) {
        assert!((got - want).abs() < 1e-4);
    }
    let mapped = reproduce_targets(&p, &targets, GamutMapping::NearestLab);
    assert_eq!(mapped[0], clipped[0]);
    assert!(mapped[1].out_of_gamut);
    assert!(mapped[1].rgb.iter().all(|v| (0.0..=1.0).contains(v)));
}

#[test]
fn image_is_mirrored_counted_and_written_at_both_depths() {
    let p = profile();
    let drives = [[0.0, 0.4, 1.0], [1.0, 0.25, 0.0], [0.5, 0.5, 0.5]];
    let mut pixels: Vec<[f32; 3]> = drives
        .iter()
        .map(|&d| analytic(d).map(|v| v as f32))
        .collect();
    pixels.extend([[1000.0f32, 1000.0, 1000.0], [0.0, 0.0, 0.0], [0.0; 3]]);
    let img = XyzImage {
        width: 3,
        height: 2,
        pixels,
    };
    let plain = reproduce_image(&p, &img, false, GamutMapping::Clip);
    // the bright pixel and the two below-black (zero) ones are out of gamut
    assert_eq!(plain.out_of_gamut, 3);
    for (got, want) in plain.rgb.iter().zip(&drives) {
        for c in 0..3 {
            assert!(
                (f64::from(got[c]) - want[c]).abs() < 1e-3,
                "{got:?} vs {want:?}"
            );
        }
    }
    let mirrored = reproduce_image(&p, &img, true, GamutMapping::Clip);
    assert_eq!(mirrored.rgb[0], plain.rgb[2]);
    assert_eq!(mirrored.rgb[2], plain.rgb[0]);
    assert_eq!(mirrored.rgb[3], plain.rgb[5]);
    let dir = fresh_dir("repro-png");
    for bits in [8u8, 16] {
        let path = dir.join(format!("o{bits}.png"));
        write_drive_png(
            &path,
            &plain,
            bits,
            &metamer::output::OutputPolicy::new(true),
        )
        .unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (3, 2));
        let first: Vec<u32> = if bits == 8 {
            buf[..3].iter().map(|&b| u32::from(b)).collect()
        } else {
            buf[..6]
                .chunks(2)
                .map(|b| u32::from(u16::from_be_bytes([b[0], b[1]])))
                .collect()
        };
        let max = (1u32 << bits) - 1;
        // drive 0, 0.4, 1 → codes 0, 0.4·max (an integer for 255 and 65535), max; float32
        // XYZ near black leaves the power law's inverse a few 16-bit codes above 0
        // ((10⁻⁷)^(1/2.2) ≈ 7·10⁻⁴), a luminance of 10⁻⁷ of white
        let want = [0, 2 * max / 5, max];
        for (g, w) in first.iter().zip(want) {
            assert!(
                g.abs_diff(w) <= max / 1000,
                "{bits} bits: {first:?} vs {want:?}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn reproduce_an_exr_image_from_the_command_line() {
    let dir = fresh_dir("repro-exr");
    let profile_path = dir.join("p.json");
    profile()
        .save(&profile_path, &metamer::output::OutputPolicy::new(true))
        .unwrap();
    // 4×3: drive (x/3, y/2, 0.5) per pixel, and one pixel twice as bright as white
    let (w, h) = (4usize, 3usize);
    let drive = |x: usize, y: usize| [x as f64 / 3.0, y as f64 / 2.0, 0.5];
    let mut pixels: Vec<[f32; 3]> = (0..w * h)
        .map(|i| analytic(drive(i % w, i / w)).map(|v| v as f32))
        .collect();
    pixels[w * h - 1] = analytic([1.0; 3]).map(|v| 2.0 * v as f32);
    let exr = dir.join("i.exr");
    metamer::image::write_xyz_image(
        &exr,
        &XyzImage {
            width: w,
            height: h,
            pixels,
        },
        &metamer::output::OutputPolicy::new(true),
    )
    .unwrap();
    let png_path = dir.join("o.png");
    let out = metamer(&[
        "reproduce",
        "--profile",
        profile_path.to_str().unwrap(),
        "--image",
        exr.to_str().unwrap(),
        "-o",
        png_path.to_str().unwrap(),
        "--bits",
        "16",
        "--mirror",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("4×3 pixels converted") && stderr.contains("1 out of gamut"),
        "{stderr}"
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&png_path).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    let code = |x: usize, y: usize, c: usize| {
        let i = 2 * (3 * (y * w + x) + c);
        f64::from(u16::from_be_bytes([buf[i], buf[i + 1]])) / 65535.0
    };
    // mirrored: output column x shows input column w − 1 − x
    for y in 0..h {
        for x in 0..w {
            if (w - 1 - x, y) == (w - 1, h - 1) {
                assert_eq!([code(x, y, 0), code(x, y, 1), code(x, y, 2)], [1.0; 3]);
                continue;
            }
            let want = drive(w - 1 - x, y);
            for (c, want) in want.iter().enumerate() {
                let got = code(x, y, c);
                assert!((got - want).abs() < 2e-3, "({x},{y}) c{c}: {got} vs {want}");
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs `reproduce --image` at 16 bits; the drive values read back from the PNG, or the
/// refusal.
fn reproduce_exr(
    profile: &std::path::Path,
    exr: &std::path::Path,
) -> Result<Vec<[f64; 3]>, String> {
    let png_path = exr.with_extension("png");
    let out = metamer(&[
        "reproduce",
        "--profile",
        profile.to_str().unwrap(),
        "--image",
        exr.to_str().unwrap(),
        "-o",
        png_path.to_str().unwrap(),
        "--bits",
        "16",
        "--force",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    if !out.status.success() {
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        return Err(stderr);
    }
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&png_path).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    Ok(buf
        .chunks_exact(6)
        .map(|p| {
            std::array::from_fn(|c| {
                f64::from(u16::from_be_bytes([p[2 * c], p[2 * c + 1]])) / 65535.0
            })
        })
        .collect())
}

/// What an OpenEXR header says of its pixels is what `reproduce` shows: whiteLuminance
/// scales the values to cd/m², R, G, B without chromaticities are BT.709 with D65, only
/// the display window is shown, and a crop of it is refused naming both windows. Each file
/// holds, by construction, the analytic display's XYZ of known drive values.
#[test]
fn reproduce_reads_an_exr_header_as_openexr_defines_it() {
    let dir = fresh_dir("repro-exr-header");
    let profile_path = dir.join("p.json");
    profile()
        .save(&profile_path, &metamer::output::OutputPolicy::new(true))
        .unwrap();
    let (w, h) = (4usize, 3usize);
    let drive = |x: usize, y: usize| [0.2 + x as f64 / 5.0, 0.25 + y as f64 / 4.0, 0.5];
    let check = |name: &str, got: Vec<[f64; 3]>| {
        assert_eq!(got.len(), w * h, "{name}");
        for (i, d) in got.iter().enumerate() {
            let want = drive(i % w, i / w);
            for c in 0..3 {
                assert!(
                    (d[c] - want[c]).abs() < 2e-3,
                    "{name}: pixel {i} channel {c}: {} vs {}",
                    d[c],
                    want[c]
                );
            }
        }
    };

    // whiteLuminance 2: a value of 1 is 2 cd/m².
    let p = dir.join("half.exr");
    write_rgb_exr(
        &p,
        (w, h),
        (0, 0),
        (w, h),
        Some(XYZ_CHROMATICITIES),
        Some(2.0),
        |x, y| analytic(drive(x, y)).map(|v| (v / 2.0) as f32),
    );
    check(
        "whiteLuminance 2",
        reproduce_exr(&profile_path, &p).unwrap(),
    );

    // No chromaticities: linear BT.709 RGB.
    let p = dir.join("rec709.exr");
    write_rgb_exr(&p, (w, h), (0, 0), (w, h), None, None, |x, y| {
        srgb_from_xyz(analytic(drive(x, y)))
    });
    check(
        "no chromaticities",
        reproduce_exr(&profile_path, &p).unwrap(),
    );

    // Overscan: two more pixels on each side, far out of gamut, outside the display window.
    let p = dir.join("overscan.exr");
    write_rgb_exr(
        &p,
        (w + 4, h + 4),
        (-2, -2),
        (w, h),
        Some(XYZ_CHROMATICITIES),
        None,
        |x, y| {
            if (2..w + 2).contains(&x) && (2..h + 2).contains(&y) {
                analytic(drive(x - 2, y - 2)).map(|v| v as f32)
            } else {
                [1e4; 3]
            }
        },
    );
    check("overscan", reproduce_exr(&profile_path, &p).unwrap());

    // A crop: the file holds 4×3 pixels of an 8×6 frame.
    let p = dir.join("crop.exr");
    write_rgb_exr(
        &p,
        (w, h),
        (2, 1),
        (8, 6),
        Some(XYZ_CHROMATICITIES),
        None,
        |x, y| analytic(drive(x, y)).map(|v| v as f32),
    );
    let e = reproduce_exr(&profile_path, &p).unwrap_err();
    assert!(
        e.contains("crop.exr: its data window (2, 1)–(5, 3) does not cover its display window (0, 0)–(7, 5)"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
