//! The adaptive characterization plan against the fixed one on the simulated monitors, with
//! the simulated CS-100A and i1Pro: readings taken, the model chosen, and the profile's
//! ΔE*ab against the monitor's noise-free truth at the targets (as the reproduction drives
//! them, 8-bit) and on the fixed plan's 48 held-out drive values. A study, run by hand
//! (`--ignored`); its table is in docs/benchmarks.md.

use std::path::Path;

use metamer::color::{delta_e76, Xyz};
use metamer::display::characterize::adaptive::{read_targets, Adaptive, Rule};
use metamer::display::characterize::plan::{Plan, Purpose};
use metamer::display::characterize::{
    characterize, Attend, Listener, Outcome, PlanOptions, Request, SimulatedMeter,
};
use metamer::display::gamut::GamutMapping;
use metamer::display::reproduce::reproduce_targets;
use metamer::display::{fit_profile, select_model, FitOptions, ModelKind, Profile, Sample};
use metamer::rig::{Preset, ScreenSpec, VirtualPanel};
use metamer::session::{NoProgress, ProgressSink, RunOptions};

struct Quiet(NoProgress);
impl Listener for Quiet {
    fn note(&mut self, _: &str) {}
    fn warning(&mut self, _: &str) {}
    fn progress(&mut self, _: bool) -> &mut dyn ProgressSink {
        &mut self.0
    }
}

/// The fit readings of a fixed plan's journal, as the models take them.
fn fit_samples(dir: &Path) -> Vec<Sample> {
    let text = std::fs::read_to_string(dir.join("log.jsonl")).unwrap();
    text.lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|l| l["type"] == "entry" && l["data"]["purpose"] == "fit")
        .map(|l| {
            let rgb: Vec<u8> = serde_json::from_value(l["data"]["rgb"].clone()).unwrap();
            let xyz: [f64; 3] = serde_json::from_value(l["reading"]["xyz"].clone()).unwrap();
            Sample::from_rgb8([rgb[0], rgb[1], rgb[2]], Xyz::from(xyz))
        })
        .collect()
}

/// Mean and max of `v`.
fn stats(v: &[f64]) -> (f64, f64) {
    (
        v.iter().sum::<f64>() / v.len().max(1) as f64,
        v.iter().copied().fold(0.0, f64::max),
    )
}

/// ΔE*ab against the truth: at the in-gamut targets (8-bit drive values as shown) and on
/// the fixed plan's held-out drive values.
fn truth_errors(
    profile: &Profile,
    panel: &VirtualPanel,
    targets: &[Xyz],
) -> ((f64, f64), (f64, f64)) {
    let white = panel.xyz([255; 3]);
    let lab = |x: Xyz| x.to_lab(white);
    let at_targets: Vec<f64> = reproduce_targets(profile, targets, GamutMapping::Clip)
        .iter()
        .zip(targets)
        .filter(|(d, _)| !d.out_of_gamut)
        .map(|(d, t)| {
            let code = d.rgb.map(|v| (v * 255.0).round() as u8);
            delta_e76(lab(panel.xyz(code)), lab(*t))
        })
        .collect();
    let fixed = Plan::new(PlanOptions::default()).unwrap();
    let held_out: Vec<f64> = fixed
        .distinct
        .iter()
        .filter(|p| p.purpose == Purpose::Verify)
        .map(|p| {
            delta_e76(
                lab(profile.forward(p.rgb.map(|c| f64::from(c) / 255.0))),
                lab(panel.xyz(p.rgb)),
            )
        })
        .collect();
    (stats(&at_targets), stats(&held_out))
}

#[test]
#[ignore = "a study: cargo test --release --test display -- --ignored --nocapture adaptive_plan::print_adaptive_table"]
fn print_adaptive_table() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let targets = read_targets(&root.join("tests/data/docs/colorchecker-targets.csv")).unwrap();
    println!("| display | meter | model | plan | readings | model chosen | ΔE*ab at in-gamut targets, mean / max | ΔE*ab on the 48 held-out, mean / max |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for preset in Preset::ALL {
        let panel = VirtualPanel::preset(preset);
        for meter in ["cs100a", "i1pro"] {
            for (model, auto) in [
                (ModelKind::Lut, false),
                (ModelKind::Plcc, false),
                (ModelKind::Lut, true),
            ] {
                for adaptive in [false, true] {
                    let out = std::env::temp_dir().join(format!(
                        "metamer-adaptive-study-{}-{meter}-{model}-{auto}-{adaptive}-{}",
                        preset.name(),
                        std::process::id()
                    ));
                    let _ = std::fs::remove_dir_all(&out);
                    let request = Request {
                        out: out.clone(),
                        screen: ScreenSpec::Virtual(preset),
                        virtual_white_cd_m2: None,
                        instrument: format!("sim:{meter}?time_scale=0&seed=11").as_str().into(),
                        speed: None,
                        plan: PlanOptions::for_model(model, 9, 1, None),
                        adaptive: adaptive.then(|| Adaptive {
                            rule: Rule::default(),
                            targets: targets.clone(),
                            auto,
                        }),
                        model,
                        settle: Some(std::time::Duration::ZERO),
                        resume: false,
                        force: false,
                        attend: Attend::Terminal { unattended: true },
                        simulated_meter: SimulatedMeter::Warn,
                        run: RunOptions::default(),
                    };
                    let Outcome::Finished(summary) =
                        characterize(&request, &mut Quiet(NoProgress)).unwrap()
                    else {
                        panic!("a simulated session finishes")
                    };
                    // The fixed plan with auto: its fit readings chosen from as `fit --model
                    // auto` chooses from readings.ti3's.
                    let profile = if auto && !adaptive {
                        let samples = fit_samples(&out);
                        let chosen = select_model(&samples, 5, &FitOptions::default()).unwrap();
                        fit_profile(chosen.model, &samples, None).unwrap()
                    } else {
                        Profile::load(&summary.files.profile).unwrap()
                    };
                    let (t, h) = truth_errors(&profile, &panel, &targets);
                    println!(
                        "| {} | {meter} | {} | {} | {} | {} | {:.2} / {:.2} | {:.2} / {:.2} |",
                        preset.name(),
                        if auto {
                            "auto".to_string()
                        } else {
                            model.to_string()
                        },
                        if adaptive { "adaptive" } else { "fixed" },
                        summary.readings,
                        profile.model,
                        t.0,
                        t.1,
                        h.0,
                        h.1
                    );
                    std::fs::remove_dir_all(&out).unwrap();
                }
            }
        }
    }
}

/// The held-out set's count: the lean measuring plan's rule (stop at ΔE*ab 2, at most 56
/// fit readings) on each simulated monitor and meter seed, the held-out ΔE*ab (mean / max
/// over the held-out patches, against the meter's readings) of all 24, of every second
/// target's and of the 12 the models agree on least, beside the noise-free error at the
/// in-gamut targets they estimate. The fit is the same in all three (the held-out set is
/// read after it), so the profile and its error at the targets are too.
#[test]
#[ignore = "a study: cargo test --release --test display -- --ignored --nocapture adaptive_plan::print_held_out_table"]
fn print_held_out_table() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let targets = read_targets(&root.join("tests/data/docs/colorchecker-targets.csv")).unwrap();
    println!("| display | seed | at the targets, noise-free: mean / max | held out, all 24: mean / max | every second (12) | the 12 least certain |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for preset in Preset::ALL {
        let panel = VirtualPanel::preset(preset);
        for seed in [1, 2, 3] {
            let run = |held_out: Option<usize>| {
                let out = std::env::temp_dir().join(format!(
                    "metamer-held-out-{}-{seed}-{held_out:?}-{}",
                    preset.name(),
                    std::process::id()
                ));
                let _ = std::fs::remove_dir_all(&out);
                let request = Request {
                    out: out.clone(),
                    screen: ScreenSpec::Virtual(preset),
                    virtual_white_cd_m2: None,
                    instrument: format!("sim:cs100a?time_scale=0&seed={seed}")
                        .as_str()
                        .into(),
                    speed: None,
                    plan: PlanOptions::for_model(ModelKind::Lut, 9, 1, None),
                    adaptive: Some(Adaptive {
                        rule: Rule {
                            stop_de: 2.0,
                            max_readings: 56,
                            held_out,
                            ..Rule::default()
                        },
                        targets: targets.clone(),
                        auto: false,
                    }),
                    model: ModelKind::Lut,
                    settle: Some(std::time::Duration::ZERO),
                    resume: false,
                    force: false,
                    attend: Attend::Terminal { unattended: true },
                    simulated_meter: SimulatedMeter::Warn,
                    run: RunOptions::default(),
                };
                let Outcome::Finished(summary) =
                    characterize(&request, &mut Quiet(NoProgress)).unwrap()
                else {
                    panic!("a simulated session finishes")
                };
                let profile = Profile::load(&summary.files.profile).unwrap();
                std::fs::remove_dir_all(&out).unwrap();
                (summary, profile)
            };
            let (all, profile) = run(None);
            let (least, _) = run(Some(12));
            let (truth, _) = truth_errors(&profile, &panel, &targets);
            let de = |v: &metamer::display::characterize::finish::Summary| {
                (v.verification.de76.mean, v.verification.de76.max)
            };
            let second: Vec<f64> = all
                .verification
                .patches
                .iter()
                .step_by(2)
                .map(|p| p.de76)
                .collect();
            let (a, s, l) = (de(&all), stats(&second), de(&least));
            println!(
                "| {} | {seed} | {:.2} / {:.2} | {:.2} / {:.2} | {:.2} / {:.2} | {:.2} / {:.2} |",
                preset.name(),
                truth.0,
                truth.1,
                a.0,
                a.1,
                s.0,
                s.1,
                l.0,
                l.1
            );
        }
    }
}
