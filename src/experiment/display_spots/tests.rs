//! The display spots' aiming wrapper and the verdict rule on a simulated monitor.

use super::*;
use crate::display::ModelKind;
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
