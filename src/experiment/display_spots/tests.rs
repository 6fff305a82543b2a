//! The display spots' aiming wrapper and the verdict rule on a simulated monitor.

use super::*;
use crate::display::ModelKind;
use crate::rig::{Placement, VirtualPanel};
use crate::validation::readings::read_readings;

/// Each journal entry's patch and reading, in the order taken.
fn journalled(dir: &Path) -> Vec<(usize, [f64; 3])> {
    std::fs::read_to_string(dir.join(JOURNAL_FILE))
        .unwrap()
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v["type"] == "entry")
        .map(|v| {
            let xyz = &v["reading"]["xyz"];
            let x: Vec<f64> = serde_json::from_value(xyz.clone()).unwrap_or_default();
            (
                v["data"]["patch"].as_u64().unwrap() as usize,
                [x[0], x[1], x[2]],
            )
        })
        .collect()
}

/// The verdict rule on a simulated monitor: a patch whose box reading is the display's
/// own is decided at the least count, one whose box reading lies about the JND away is
/// read the most times; a session stopped after five readings and resumed journals
/// exactly the uninterrupted session's readings, and the rule is in the plan's
/// fingerprint (a fixed session's journal is refused).
#[test]
fn a_resumed_verdict_session_takes_the_uninterrupted_ones_readings() {
    let root = std::env::temp_dir().join(format!("metamer-display-verdict-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let setting = DisplaySetting {
        screen: "virtual:ips-lcd".parse().unwrap(),
        virtual_white_cd_m2: Some(100.0),
        white_xyz: Xyz::new(95.047, 100.0, 108.883),
        needed_white_cd_m2: 100.0,
        model: ModelKind::Lut,
    };
    let drives: Vec<PatchDrive> = [[128u8, 128, 128], [200, 60, 50], [60, 120, 200]]
        .iter()
        .enumerate()
        .map(|(i, rgb)| PatchDrive {
            patch: i + 1,
            target_xyz: Xyz::new(0.0, 0.0, 0.0),
            unclipped_rgb: [0.0; 3],
            out_of_gamut: false,
            rgb8: *rgb,
        })
        .collect();
    let spec = Spec::new("sim:cs100a?time_scale=0&seed=11");
    let run = RunOptions::default();
    let measure_in = |dir: &Path, rule: &DisplayRule, resume: bool, run: &RunOptions| {
        std::fs::create_dir_all(dir).unwrap();
        measure(
            dir,
            &SpotSession {
                setting: &setting,
                spot_spec: &spec,
                drives: &drives,
                image: None,
                shown: SpotsShown::Aimed,
                rule,
                resume,
                unattended: true,
                run,
            },
            &|_| {},
        )
    };
    // The display's own readings of the patches, as the box's: patch 3's moved along
    // L* by the JND, so its verdict stays undecided.
    let fixed = root.join("fixed");
    measure_in(&fixed, &DisplayRule::Fixed(4), false, &run).unwrap();
    let mut own = read_readings(&fixed.join(SPOTS_FILE)).unwrap();
    let white = setting.white_xyz;
    let p3 = own.patches.get_mut(&3).unwrap();
    let lab = p3.xyz.to_lab(white);
    let lower = crate::color::Lab::new(lab.l - 2.3, lab.a, lab.b).to_xyz(white);
    p3.xyz = lower;
    let rule = DisplayRule::verdict(0.1, 6, &own, white);

    let straight = root.join("straight");
    measure_in(&straight, &rule, false, &run).unwrap();
    let readings = journalled(&straight);
    let count = |k: usize| readings.iter().filter(|(p, _)| *p == k).count();
    assert_eq!((count(1), count(3)), (2, 6), "{readings:?}");

    let resumed = root.join("resumed");
    let stop = RunOptions {
        stop_after: Some(5),
        ..RunOptions::default()
    };
    assert!(measure_in(&resumed, &rule, false, &stop).is_err());
    assert_eq!(journalled(&resumed).len(), 5);
    measure_in(&resumed, &rule, true, &run).unwrap();
    assert_eq!(journalled(&resumed), readings);
    // The file states the pooled figure, its degrees of freedom and the rule's most.
    let back = read_readings(&resumed.join(SPOTS_FILE)).unwrap();
    let dof = 3 * (readings.len() - 3);
    assert_eq!(back.patches[&3].most, Some(6));
    assert_eq!(back.patches[&1].dof, Some(dof));
    // A fixed plan's journal is not resumed by the verdict rule.
    let e = measure_in(&fixed, &rule, true, &run)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("another session") && e.contains("against"),
        "{e}"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

/// A recheck that stops must reach the session: a wrapper that answered for the
/// operator would keep a reading the operator wanted gone.
struct Stopper;
impl Operator for Stopper {
    fn ask(&mut self, _: &str) -> Result<Answer, OperatorError> {
        Ok(Answer::Confirmed)
    }
    fn recheck(&mut self, _: &str) -> Result<Recheck, OperatorError> {
        Ok(Recheck::Stop)
    }
}

#[test]
fn the_aiming_wrapper_passes_on_the_reading_count_and_the_recheck() {
    let mut scripted = ScriptedOperator::confirming();
    let mut aiming = Aiming {
        aims: BTreeMap::new(),
        meter: None,
        inner: &mut scripted,
    };
    let readings = PlacementReadings { first: 1, of: 5 };
    aiming.ask_placement("aim at patch 3", readings).unwrap();
    assert_eq!(scripted.prompts, vec!["aim at patch 3 — 5 readings"]);

    let mut stopper = Stopper;
    let mut aiming = Aiming {
        aims: BTreeMap::new(),
        meter: None,
        inner: &mut stopper,
    };
    assert_eq!(aiming.recheck("Y differs").unwrap(), Recheck::Stop);
}

/// The patches' colours, their centres in pixels of a 60 × 40 image (each on a pixel
/// corner) and the grey around them.
const PATCHES: [([u8; 3], [usize; 2]); 3] = [
    ([200, 60, 50], [15, 10]),
    ([60, 120, 200], [45, 10]),
    ([128, 128, 128], [30, 30]),
];
const SURROUND: [u8; 3] = [40, 40, 40];

/// A 60 × 40 image of [`PATCHES`], each 10 × 10 pixels on [`SURROUND`], written as a PNG
/// into `dir`; with the patches' drive values and their regions (a spot of 3 px radius).
fn three_patches(dir: &Path) -> (PathBuf, Vec<PatchDrive>, Vec<PatchRegion>) {
    let (w, h) = (60usize, 40usize);
    let mut pixels = vec![SURROUND; w * h];
    for (rgb, [cx, cy]) in PATCHES {
        for y in cy - 5..cy + 5 {
            pixels[y * w + cx - 5..y * w + cx + 5].fill(rgb);
        }
    }
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join("image.png");
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().unwrap();
    writer.write_image_data(&pixels.concat()).unwrap();
    writer.finish().unwrap();
    std::fs::write(&file, bytes).unwrap();
    let drives = PATCHES
        .iter()
        .enumerate()
        .map(|(i, (rgb, _))| PatchDrive {
            patch: i + 1,
            target_xyz: Xyz::new(0.0, 0.0, 0.0),
            unclipped_rgb: [0.0; 3],
            out_of_gamut: false,
            rgb8: *rgb,
        })
        .collect();
    let regions = PATCHES
        .iter()
        .enumerate()
        .map(|(i, (_, [cx, cy]))| PatchRegion {
            patch: i + 1,
            row: 1,
            column: i + 1,
            x: *cx as f64 / w as f64,
            y: *cy as f64 / h as f64,
            radius: 3.0 / h as f64,
            pixels: 28,
            out_of_gamut_pixels: 0,
        })
        .collect();
    (file, drives, regions)
}

/// The slides that bring each patch under the meter at the middle, (30, 20) px, worked by
/// hand from the patches' centres; read with each patch's slide, a still meter sees that
/// patch's colour, and with another patch's slide that other patch's colour: a wrong
/// slide shows in the reading.
#[test]
fn a_slide_by_the_wrong_patch_reads_the_wrong_colour() {
    let dir = std::env::temp_dir().join(format!("metamer-slide-{}", std::process::id()));
    let (file, _, regions) = three_patches(&dir);
    let image = Drive8Image::read_png(&file).unwrap();
    let aims = shown::aims_under_meter(&Placement::WHOLE, (60, 40), &regions);
    let slides: Vec<[i64; 2]> = aims.iter().map(|a| a.shift.unwrap()).collect();
    assert_eq!(slides, vec![[15, 10], [-15, 10], [0, -10]]);
    assert!(aims
        .iter()
        .all(|a| [a.x, a.y] == shown::METER_AT && a.radius == 3.0 / 40.0));
    let mut display = crate::rig::VirtualDisplay::preset(crate::rig::Preset::IpsLcd);
    display.show_image(&image).unwrap();
    let world = display.stimulus().unwrap();
    let a = &aims[0];
    display.meter_aim().unwrap().set(Some(ScreenSpot {
        x: a.x,
        y: a.y,
        radius: a.radius,
    }));
    let seen = || match world.view() {
        metamer_drivers::View::Emissive(metamer_drivers::Light::Radiance(s)) => {
            metamer_color::radiance_to_xyz(&s, metamer_color::ObserverKind::Cie1931)
        }
        _ => panic!("a display emits"),
    };
    let panel = display.panel().clone();
    for (j, slide) in slides.iter().enumerate() {
        display.shift_image(*slide).unwrap();
        let got = seen();
        for (i, (rgb, _)) in PATCHES.iter().enumerate() {
            let want = panel.xyz(*rgb);
            let off = (got.y - want.y).abs() / want.y;
            if i == j {
                assert!(off < 1e-12, "patch {} read {got:?}, want {want:?}", i + 1);
            } else {
                assert!(off > 0.05, "patch {}'s slide read patch {}", j + 1, i + 1);
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The image moved under a still meter reads exactly what the meter aimed at each patch
/// reads (the same pixels under the spot, the same noise stream), in one placement
/// against one per patch; the slides are in the record and the plan, so an aimed
/// journal is not resumed by it, and a session stopped mid-patch and resumed slides the
/// image back and journals the uninterrupted session's readings.
#[test]
fn the_image_under_the_meter_reads_as_aiming_does_in_one_placement() {
    let root = std::env::temp_dir().join(format!("metamer-under-meter-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (file, drives, regions) = three_patches(&root.join("reproduction"));
    let setting = DisplaySetting {
        screen: "virtual:ips-lcd".parse().unwrap(),
        virtual_white_cd_m2: Some(100.0),
        white_xyz: Xyz::new(95.047, 100.0, 108.883),
        needed_white_cd_m2: 100.0,
        model: ModelKind::Lut,
    };
    let spec = Spec::new("sim:cs100a?time_scale=0&seed=11");
    let rule = DisplayRule::Fixed(2);
    let measure_in = |dir: &Path, shown: SpotsShown, resume: bool, run: &RunOptions| {
        std::fs::create_dir_all(dir).unwrap();
        measure(
            dir,
            &SpotSession {
                setting: &setting,
                spot_spec: &spec,
                drives: &drives,
                image: Some(ShownImage {
                    file: &file,
                    regions: &regions,
                }),
                shown,
                rule: &rule,
                resume,
                unattended: true,
                run,
            },
            &|_| {},
        )
    };
    let record = |dir: &Path| -> SpotRecord {
        serde_json::from_str(&std::fs::read_to_string(dir.join(RECORD_FILE)).unwrap()).unwrap()
    };
    let run = RunOptions::default();
    let aimed = root.join("aimed");
    measure_in(&aimed, SpotsShown::Aimed, false, &run).unwrap();
    let under = root.join("under");
    measure_in(&under, SpotsShown::UnderMeter, false, &run).unwrap();
    let readings = journalled(&under);
    assert_eq!(readings.len(), 6);
    assert_eq!(readings, journalled(&aimed));
    // Each patch's colour as the panel emits it, within the meter's noise.
    let panel = VirtualPanel::preset(crate::rig::Preset::IpsLcd).with_white_luminance(100.0);
    for (patch, xyz) in &readings {
        let want = panel.xyz(PATCHES[patch - 1].0);
        assert!(
            (xyz[1] / want.y - 1.0).abs() < 0.01,
            "{patch}: {xyz:?} {want:?}"
        );
    }
    let (a, u) = (record(&aimed), record(&under));
    assert_eq!(
        (a.shown.as_str(), u.shown.as_str()),
        ("image", "image moved under the meter")
    );
    let placements = |r: &SpotRecord| {
        let c = r.cost.as_ref().unwrap();
        (c.estimate.placements, c.actual.as_ref().unwrap().placements)
    };
    assert_eq!((placements(&a), placements(&u)), ((3, 3), (1, 1)));
    let slides: Vec<_> = u.aims.iter().map(|a| a.shift).collect();
    assert_eq!(
        slides,
        vec![Some([15, 10]), Some([-15, 10]), Some([0, -10])]
    );

    let e = measure_in(&aimed, SpotsShown::UnderMeter, true, &run)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("another session") && e.contains("meter at"),
        "{e}"
    );
    let resumed = root.join("resumed");
    let stop = RunOptions {
        stop_after: Some(3),
        ..RunOptions::default()
    };
    assert!(measure_in(&resumed, SpotsShown::UnderMeter, false, &stop).is_err());
    assert_eq!(journalled(&resumed).len(), 3);
    measure_in(&resumed, SpotsShown::UnderMeter, true, &run).unwrap();
    assert_eq!(journalled(&resumed), readings);
    std::fs::remove_dir_all(&root).unwrap();
}
