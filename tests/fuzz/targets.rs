//! The parsers under test, each with its seed files and a check of what it accepted: a
//! parser may refuse any input, but what it accepts must be usable (finite readings, a
//! profile whose inverse and gamut mapping answer).

use std::path::{Path, PathBuf};

use metamer::color::{check_xyz, Outside, SpectralTable};
use metamer::display::gamut::{map_to_gamut, GamutMapping};
use metamer::display::measurements::{parse_ti3, read_measurement_file};
use metamer::display::{fit_profile, ModelKind, Profile};
use metamer::image::{read_xyz_image, write_xyz_image, XyzImage};
use metamer::numeric_csv::NumericCsv;
use metamer::render::scene::Scene;
use metamer_drivers::i1pro::synthetic::eeprom_image;
use metamer_drivers::link::replay::Transcript;
use metamer_protocols::cs100a::{parse_command, parse_reply, Reply};
use metamer_protocols::i1pro::calibration::Calibration;
use metamer_protocols::i1pro::eeprom::Eeprom;
use metamer_protocols::i1pro::{Model, Revision};

/// What a target says about an input it did not crash on: `Err` is a lie (an accepted input
/// whose result is unusable), with what is wrong.
pub type Check = Result<(), String>;

pub struct Target {
    pub name: &'static str,
    pub seeds: Vec<Vec<u8>>,
    pub run: fn(&[u8], &Path) -> Check,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn read(rel: &str) -> Vec<u8> {
    std::fs::read(root().join(rel)).unwrap_or_else(|e| panic!("seed {rel}: {e}"))
}

fn files_in(rel: &str, ext: &str) -> Vec<Vec<u8>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(root().join(rel))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    paths.sort();
    paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

/// Writes the input to a file named `name` in the scratch directory.
pub fn scratch(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn finite_xyz(what: &str, xyz: metamer::color::Xyz) -> Check {
    check_xyz(xyz).map_err(|e| format!("{what} accepted: {e}"))
}

fn cs100a(bytes: &[u8], _: &Path) -> Check {
    let _ = parse_command(bytes);
    if let Ok(Reply::Measurement { value, .. }) = parse_reply(bytes) {
        for v in [value.luminance, value.x, value.y].into_iter().flatten() {
            if !v.is_finite() {
                return Err(format!("reply accepted with a value of {v}"));
            }
        }
    }
    Ok(())
}

fn transcript(bytes: &[u8], _: &Path) -> Check {
    let _ = Transcript::parse("fuzz.jsonl", &String::from_utf8_lossy(bytes));
    Ok(())
}

fn ti3(bytes: &[u8], _: &Path) -> Check {
    if let Ok(m) = parse_ti3(&String::from_utf8_lossy(bytes), Path::new("fuzz.ti3")) {
        for p in &m.patches {
            finite_xyz("a .ti3 patch", p.xyz)?;
            if p.rgb.iter().any(|d| !(0.0..=1.0).contains(d)) {
                return Err(format!("a .ti3 patch with drive {:?} accepted", p.rgb));
            }
        }
    }
    Ok(())
}

fn measurement_csv(bytes: &[u8], dir: &Path) -> Check {
    let path = scratch(dir, "m.csv", bytes);
    if let Ok(m) = read_measurement_file(&path) {
        for p in &m.patches {
            finite_xyz("a CSV patch", p.xyz)?;
        }
    }
    let _ = NumericCsv::parse(&String::from_utf8_lossy(bytes), &path, &["X", "Y", "Z"]);
    Ok(())
}

fn spectral_csv(bytes: &[u8], _: &Path) -> Check {
    if let Ok(t) = SpectralTable::parse(&String::from_utf8_lossy(bytes), "fuzz.csv") {
        for i in 0..t.columns.len() {
            let _ = t.spectrum(i);
        }
        let _ = t.all(Outside::Zero);
    }
    Ok(())
}

fn scene(bytes: &[u8], dir: &Path) -> Check {
    let path = scratch(dir, "scene.json", bytes);
    let _ = Scene::load(&path);
    Ok(())
}

fn profile(bytes: &[u8], dir: &Path) -> Check {
    let path = scratch(dir, "profile.json", bytes);
    let Ok(p) = Profile::load(&path) else {
        return Ok(());
    };
    let white = p.white_xyz;
    // An in-gamut grey, a colour out of every gamut, black, and a far too bright one.
    for target in [
        p.white_xyz.map(|v| 0.2 * v),
        metamer::color::Xyz::new(0.9 * p.white_xyz[1], 0.05 * p.white_xyz[1], 0.01),
        metamer::color::Xyz::default(),
        p.white_xyz.map(|v| 10.0 * v),
    ] {
        let inv = p.inverse(target);
        let rgb = map_to_gamut(
            GamutMapping::NearestLab,
            &|d| p.forward(d),
            inv.unclipped,
            target,
            white,
        );
        if rgb.iter().any(|v| !(0.0..=1.0).contains(v)) {
            return Err(format!("drive values {rgb:?} for XYZ {target:?}"));
        }
    }
    Ok(())
}

fn image(bytes: &[u8], dir: &Path, name: &str) -> Check {
    let path = scratch(dir, name, bytes);
    if let Ok(img) = read_xyz_image(&path) {
        if img.pixels.len() != img.width * img.height {
            return Err(format!(
                "{}×{} image with {} pixels",
                img.width,
                img.height,
                img.pixels.len()
            ));
        }
        if img.pixels.iter().flatten().any(|v| !v.is_finite()) {
            return Err("an image with a non-finite pixel accepted".into());
        }
    }
    Ok(())
}

fn pfm(bytes: &[u8], dir: &Path) -> Check {
    image(bytes, dir, "image.pfm")
}

fn exr(bytes: &[u8], dir: &Path) -> Check {
    image(bytes, dir, "image.exr")
}

fn eeprom(bytes: &[u8], _: &Path) -> Check {
    for (rev, model) in [(Revision::AToD, Model::I1Pro), (Revision::E, Model::I1Pro2)] {
        if let Ok(e) = Eeprom::parse(bytes, rev) {
            let _ = Calibration::from_eeprom(&e, model);
        }
    }
    Ok(())
}

/// What a photometric file reader accepted must be a usable distribution: finite, ≥ 0
/// everywhere it is asked, and finite photometry.
fn photometric(
    read: &Result<
        (metamer::light::CGammaTable, metamer::light::Photometry),
        metamer::light::PhotometryError,
    >,
) -> Check {
    let Ok((table, photometry)) = read else {
        return Ok(());
    };
    for c in [0.0, 45.0, 90.0, 135.0, 180.0, 270.0, 359.9] {
        for g in [0.0, 30.0, 60.0, 89.9, 90.0] {
            let v = table.at(c, g);
            if !v.is_finite() || v < 0.0 {
                return Err(format!("a distribution of {v} at C {c}°, γ {g}"));
            }
        }
    }
    let p = photometry;
    for v in [p.width_m, p.height_m, p.area_m2, p.normal_intensity_cd] {
        if !v.is_finite() {
            return Err(format!("photometry accepted with a value of {v}"));
        }
    }
    Ok(())
}

fn ies(bytes: &[u8], _: &Path) -> Check {
    photometric(&metamer::light::ies::parse(
        &String::from_utf8_lossy(bytes),
        Path::new("fuzz.ies"),
    ))
}

fn ldt(bytes: &[u8], _: &Path) -> Check {
    photometric(&metamer::light::ldt::parse(
        &String::from_utf8_lossy(bytes),
        Path::new("fuzz.ldt"),
    ))
}

/// IES and EULUMDAT text as the program writes them: a symmetric cos-power panel and an
/// asymmetric table of four C-planes.
fn seed_photometric() -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
    use metamer::light::ies::IesInfo;
    use metamer::light::ldt::LdtInfo;
    use metamer::light::{CGammaTable, Panel};
    let gamma: Vec<f64> = (0..=18).map(|i| 5.0 * i as f64).collect();
    let cos = |n: f64| -> Vec<f64> { gamma.iter().map(|g| g.to_radians().cos().powf(n)).collect() };
    let symmetric = CGammaTable::symmetric(gamma.clone(), cos(0.7)).unwrap();
    let asymmetric = CGammaTable::new(
        vec![0.0, 90.0, 180.0, 270.0],
        gamma.clone(),
        vec![cos(0.9), cos(1.4), cos(0.6), cos(1.1)],
    )
    .unwrap();
    let panel = Panel {
        width_m: 0.3,
        height_m: 0.3,
        normal_luminance_cd_m2: 1000.0,
    };
    let ies_info = IesInfo {
        test: "fuzz seed".into(),
        issue_date: "2026-12-01".into(),
        luminaire: "panel".into(),
        generation: "metamer".into(),
        extrapolation: None,
    };
    let ldt_info = LdtInfo {
        luminaire: "panel".into(),
        file_name: "seed.ldt".into(),
        date_user: "2026-12-01 fuzz".into(),
        extrapolation: None,
    };
    let tables = [symmetric, asymmetric];
    (
        tables
            .iter()
            .map(|t| metamer::light::ies::to_string(t, &panel, &ies_info).into_bytes())
            .collect(),
        tables
            .iter()
            .map(|t| metamer::light::ldt::to_string(t, &panel, &ldt_info).into_bytes())
            .collect(),
    )
}

fn seed_images(dir: &Path) -> (Vec<u8>, Vec<u8>) {
    let img = XyzImage {
        width: 3,
        height: 2,
        pixels: (0..6)
            .map(|i| [i as f32, 0.5 * i as f32, 100.0 + i as f32])
            .collect(),
    };
    let p = dir.join("seed.pfm");
    let e = dir.join("seed.exr");
    write_xyz_image(&p, &img, &metamer::output::OutputPolicy::new(true)).unwrap();
    write_xyz_image(&e, &img, &metamer::output::OutputPolicy::new(true)).unwrap();
    (std::fs::read(p).unwrap(), std::fs::read(e).unwrap())
}

fn seed_profiles(dir: &Path) -> Vec<Vec<u8>> {
    let m = read_measurement_file(&root().join("tests/data/dispread_analytic.ti3")).unwrap();
    [ModelKind::Plcc, ModelKind::PlccGamma, ModelKind::Gog]
        .iter()
        .filter_map(|&k| fit_profile(k, &m.patches, None).ok())
        .map(|p| {
            let path = dir.join("seed-profile.json");
            p.save(&path, &metamer::output::OutputPolicy::new(true))
                .unwrap();
            std::fs::read(path).unwrap()
        })
        .collect()
}

/// Every target with its seeds; `dir` is scratch space for seeds that are written files.
pub fn all(dir: &Path) -> Vec<Target> {
    let (pfm_seed, exr_seed) = seed_images(dir);
    let (ies_seeds, ldt_seeds) = seed_photometric();
    let mut transcripts = files_in("protocols/cs100a/transcripts", "jsonl");
    transcripts.extend(files_in("protocols/i1pro/transcripts", "jsonl"));
    vec![
        Target {
            name: "cs100a reply",
            seeds: [
                "OK00, 100.0,.3127,.3290\r\n",
                "OK13,+0.012,.3000,.3100\r\n",
                "OK12,-999999,.4000,.4000\r\n",
                "OK11, 12.50,.0000,.0000\r\n",
                "ER10\r\n",
                "MES\r\n",
                "MDS,04\r\n",
            ]
            .iter()
            .map(|s| s.as_bytes().to_vec())
            .collect(),
            run: cs100a,
        },
        Target {
            name: "transcript",
            seeds: transcripts,
            run: transcript,
        },
        Target {
            name: ".ti3",
            seeds: vec![
                read("tests/data/dispread_analytic.ti3"),
                read("tests/data/displaycal_spectral_cal.ti3"),
            ],
            run: ti3,
        },
        Target {
            name: "measurement CSV",
            seeds: vec![
                b"r,g,b,X,Y,Z\n1,1,1,95.05,100,108.9\n0,0,0,0.1,0.1,0.12\n".to_vec(),
                b"\xef\xbb\xbf# made by hand\nX,Y,Z\n1,2,3\n".to_vec(),
            ],
            run: measurement_csv,
        },
        Target {
            name: "spectral CSV",
            seeds: vec![
                read("data/light_falloff_9_angles.csv"),
                read("data/paper_white_reflectance.csv"),
                b"nm,a,b\n380,0.1,0.2\n390,0.3,0.4\n".to_vec(),
            ],
            run: spectral_csv,
        },
        Target {
            name: "scene JSON",
            seeds: files_in("data/scenes", "json"),
            run: scene,
        },
        Target {
            name: "profile JSON",
            seeds: seed_profiles(dir),
            run: profile,
        },
        Target {
            name: "PFM",
            seeds: vec![pfm_seed],
            run: pfm,
        },
        Target {
            name: "EXR",
            seeds: std::iter::once(exr_seed.clone())
                .chain(
                    crate::exr_class::corrupt(&exr_seed)
                        .into_iter()
                        .map(|c| c.1),
                )
                .collect(),
            run: exr,
        },
        Target {
            name: "i1Pro EEPROM",
            seeds: vec![
                eeprom_image(Revision::AToD, &[]).unwrap(),
                eeprom_image(Revision::E, &[]).unwrap(),
            ],
            run: eeprom,
        },
        Target {
            name: "IES",
            seeds: ies_seeds,
            run: ies,
        },
        Target {
            name: "LDT",
            seeds: ldt_seeds,
            run: ldt,
        },
    ]
    .into_iter()
    .chain(crate::targets_session::all(dir))
    .collect()
}
