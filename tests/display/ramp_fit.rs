//! Ramp-only patch sets (the paper's and PsychoPy's plan: black, white and 16 steps of each
//! primary, no mixtures): which model `--model auto` picks, judged as a rendering uses the
//! profile, by the inverse round trip through the true display on mixed colours.

use crate::support::oracle::{COLPROF, XICCLU};
use metamer::color::{delta_e2000, Xyz};
use metamer::display::characterize::plan::{colorchecker_srgb, random_patches};
use metamer::display::characterize::plan::{RANDOM_VERIFICATION, VERIFICATION_SEED};
use metamer::display::{fit_profile, select_model, write_ti3, FitOptions, ModelKind, Sample};
use metamer::rig::{Preset, VirtualPanel};
use metamer_drivers::cs100a::emulator::{SIGMA_XY, SIGMA_Y_REL};
use metamer_drivers::noise::{stream_seed, SplitMix64};

/// Black, white and 16 steps of each primary (1/16 … 16/16 of full drive, as 8-bit codes).
fn ramp_codes() -> Vec<[u8; 3]> {
    let mut codes = vec![[0, 0, 0], [255, 255, 255]];
    for c in 0..3 {
        for k in 1..=16u32 {
            let mut rgb = [0u8; 3];
            rgb[c] = ((255 * k) as f64 / 16.0).round() as u8;
            codes.push(rgb);
        }
    }
    codes
}

/// The mixed colours a rendering needs: `characterize`'s verification set (24 seeded random
/// drive triplets and the 24 ColorChecker colours as sRGB).
fn mixed_targets() -> Vec<[u8; 3]> {
    let mut t = random_patches(RANDOM_VERIFICATION, VERIFICATION_SEED);
    t.extend(colorchecker_srgb().into_iter().map(|(_, rgb)| rgb));
    t
}

fn measure(panel: &VirtualPanel, codes: &[[u8; 3]]) -> Vec<Sample> {
    codes
        .iter()
        .map(|&c| Sample {
            rgb: c.map(|v| f64::from(v) / 255.0),
            xyz: panel.xyz(c),
        })
        .collect()
}

/// The readings as the simulated CS-100A gives them (1σ 0.1 % of Y, 0.0005 in x and y,
/// drawn in the emulator's order), one seeded stream per patch.
fn with_meter_noise(patches: &[Sample], seed: u64) -> Vec<Sample> {
    patches
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let Xyz { x, y, z } = p.xyz;
            let sum = x + y + z;
            let mut rng = SplitMix64::new(stream_seed(seed, i as u64, 0));
            let lum = y * (1.0 + SIGMA_Y_REL * rng.normal());
            let cx = x / sum + SIGMA_XY * rng.normal();
            let cy = y / sum + SIGMA_XY * rng.normal();
            Sample {
                rgb: p.rgb,
                xyz: Xyz::new(cx / cy * lum, lum, (1.0 - cx - cy) / cy * lum),
            }
        })
        .collect()
}

/// Mean ΔE00 of the round trip: the target's true XYZ → the model's inverse → the drive
/// shown (8-bit) on the true display → its XYZ, relative to the display's true white.
fn inverse_error(panel: &VirtualPanel, inverse: &dyn Fn(Xyz) -> [f64; 3]) -> f64 {
    let white = panel.xyz([255; 3]);
    let targets = mixed_targets();
    let sum: f64 = targets
        .iter()
        .map(|&code| {
            let t = panel.xyz(code);
            let shown = panel.xyz_of_drive(inverse(t));
            delta_e2000(shown.to_lab(white), t.to_lab(white))
        })
        .sum();
    sum / targets.len() as f64
}

fn model_error(panel: &VirtualPanel, kind: ModelKind, patches: &[Sample]) -> Option<f64> {
    let profile = fit_profile(kind, patches, None).ok()?;
    Some(inverse_error(panel, &|t| profile.inverse(t).rgb))
}

/// The set of `preset` read noise-free or with the meter's noise (`seed`).
fn ramp_set(preset: Preset, noise_seed: Option<u64>) -> (VirtualPanel, Vec<Sample>) {
    let panel = VirtualPanel::preset(preset);
    let clean = measure(&panel, &ramp_codes());
    let patches = match noise_seed {
        Some(seed) => with_meter_noise(&clean, seed),
        None => clean,
    };
    (panel, patches)
}

/// ArgyllCMS `colprof -qm -as` on the same set and its inverse (`xicclu -fb -iA -pX`), run as
/// an external program when it is installed; None (with the reason printed) otherwise.
fn colprof_error(panel: &VirtualPanel, patches: &[Sample], dir: &std::path::Path) -> Option<f64> {
    use std::process::Command;
    let colprof = COLPROF.find()?;
    let xicclu = XICCLU.find()?;
    std::fs::create_dir_all(dir).unwrap();
    write_ti3(
        &dir.join("ramps.ti3"),
        patches,
        "ramp-only set",
        &metamer::output::OutputPolicy::new(true),
    )
    .unwrap();
    let status = Command::new(colprof)
        .args(["-qm", "-as", "-D", "ramps", "ramps"])
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(status.status.success(), "{status:?}");
    let targets: Vec<Xyz> = mixed_targets().iter().map(|&c| panel.xyz(c)).collect();
    let input: String = targets
        .iter()
        .map(|t| format!("{:.8} {:.8} {:.8}\n", t[0], t[1], t[2]))
        .collect();
    let mut child = Command::new(xicclu)
        .args(["-v0", "-fb", "-iA", "-pX", "ramps.icc"])
        .current_dir(dir)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let rgbs: Vec<[f64; 3]> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .take(3)
                .map(|s| s.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(rgbs.len(), targets.len(), "{text}");
    let white = panel.xyz([255; 3]);
    let sum: f64 = targets
        .iter()
        .zip(&rgbs)
        .map(|(t, rgb)| {
            let shown = panel.xyz_of_drive(*rgb);
            delta_e2000(shown.to_lab(white), t.to_lab(white))
        })
        .sum();
    Some(sum / targets.len() as f64)
}

/// The ramp table: every display, noise-free and with the meter's noise, every model, auto's
/// pick and `colprof -as`.
/// `cargo test --release --test display -- --ignored --nocapture ramp_fit::print_ramp_table`.
#[test]
#[ignore]
fn print_ramp_table() {
    let out = std::path::PathBuf::from(
        std::env::var_os("METAMER_RAMP_OUT").unwrap_or_else(|| "target/ramp-fit".into()),
    );
    // METAMER_RAMP_SEEDS (e.g. "1,2,3,4,5,6") picks the meter seeds; 1, 2, 3 by default.
    let seeds: Vec<u64> = std::env::var("METAMER_RAMP_SEEDS")
        .map(|v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect())
        .unwrap_or_else(|_| vec![1, 2, 3]);
    for preset in Preset::ALL {
        for noise in std::iter::once(None).chain(seeds.iter().map(|&s| Some(s))) {
            let (panel, patches) = ramp_set(preset, noise);
            let mut line = format!(
                "{} {}:",
                panel.name(),
                noise.map_or("noise-free".to_string(), |s| format!("noisy seed {s}"))
            );
            let dir = out.join(format!(
                "{}-{}",
                panel.name(),
                noise.map_or("clean".to_string(), |s| format!("noisy{s}"))
            ));
            if let Some(e) = colprof_error(&panel, &patches, &dir) {
                line += &format!(" colprof-as {e:.3}");
            }
            for kind in ModelKind::ALL {
                if let Some(e) = model_error(&panel, kind, &patches) {
                    line += &format!(" {kind} {e:.3}");
                }
            }
            let sel = select_model(&patches, 5, &FitOptions::default()).unwrap();
            line += &format!(" auto→{} | cv", sel.model);
            for c in &sel.candidates {
                if let Ok(e) = &c.cv_mean_de00 {
                    line += &format!(" {} {e:.3}", c.model);
                }
            }
            println!("{line}");
        }
    }
}

/// How much of the white's departure from additivity a mixture gets, from its channels'
/// luminance fractions.
type WhiteShare = Box<dyn Fn([f64; 3]) -> f64>;

/// The study behind PLVC's spread of the white's departure over mixtures: each real
/// monitor's `.ti3` file in `METAMER_REAL_TI3` (default `/tmp/real-ti3`; other people's
/// data, not in the repository) fitted with PLVC on its single-channel patches and judged on
/// its mixed ones, with each way of sharing the departure:
/// `cargo test --release --test display -- --ignored --nocapture
/// ramp_fit::print_white_share_study`.
#[test]
#[ignore]
fn print_white_share_study() {
    use metamer::display::read_measurement_file;
    let dir = std::path::PathBuf::from(
        std::env::var_os("METAMER_REAL_TI3").unwrap_or_else(|| "/tmp/real-ti3".into()),
    );
    let dir = dir.as_path();
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ti3"))
        .collect();
    files.sort();
    for f in files {
        let m = read_measurement_file(&f).unwrap();
        let single = |p: &Sample| {
            p.rgb.iter().filter(|&&v| v > 1e-6).count() <= 1
                || p.rgb.iter().all(|&v| v >= 1.0 - 1e-6)
        };
        let fit: Vec<Sample> = m.patches.iter().copied().filter(|p| single(p)).collect();
        let held: Vec<Sample> = m.patches.iter().copied().filter(|p| !single(p)).collect();
        let profile = fit_profile(ModelKind::Plvc, &fit, None).unwrap();
        let model = profile.model();
        let w = profile.white_xyz;
        let k = model.forward([0.0; 3]);
        let add_white = model.forward([1.0; 3]);
        let dw: [f64; 3] = std::array::from_fn(|i| profile.white_xyz[i] - add_white[i]);
        let prim_y: [f64; 3] = std::array::from_fn(|c| {
            let mut e = [0.0; 3];
            e[c] = 1.0;
            model.forward(e)[1] - k[1]
        });
        let lvl = |rgb: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|c| {
                let mut e = [0.0; 3];
                e[c] = rgb[c];
                ((model.forward(e)[1] - k[1]) / prim_y[c]).clamp(0.0, 1.0)
            })
        };
        let variants: Vec<(&str, WhiteShare)> = vec![
            ("plain", Box::new(|_l| 0.0)),
            (
                "pairs",
                Box::new(|l: [f64; 3]| (l[0] * l[1] + l[1] * l[2] + l[0] * l[2]) / 3.0),
            ),
            ("triple", Box::new(|l: [f64; 3]| l[0] * l[1] * l[2])),
            (
                "sum-minus-max",
                Box::new(|l: [f64; 3]| (l[0] + l[1] + l[2] - l[0].max(l[1]).max(l[2])) / 2.0),
            ),
            ("min", Box::new(|l: [f64; 3]| l[0].min(l[1]).min(l[2]))),
        ];
        let set = metamer::display::model::samples::SortedSamples::new(&fit);
        let prim: Vec<Xyz> = (0..3).map(|c| set.primaries[c].unwrap()).collect();
        let kk = set.black.unwrap();
        let addw: [f64; 3] =
            std::array::from_fn(|i| prim[0][i] + prim[1][i] + prim[2][i] - 2.0 * kk[i]);
        let ade = delta_e2000(Xyz::from_array(addw).to_lab(w), profile.white_xyz.to_lab(w));
        let mut line = format!(
            "{}: fit {} held {} white-add ΔY {:+.2}% ΔE00 {ade:.2}",
            &f.file_name().unwrap().to_string_lossy()[..12],
            fit.len(),
            held.len(),
            100.0 * dw[1] / profile.white_xyz[1]
        );
        for (name, wf) in &variants {
            let e: f64 = held
                .iter()
                .map(|p| {
                    let a = model.forward(p.rgb);
                    let s = wf(lvl(p.rgb));
                    let x: [f64; 3] = std::array::from_fn(|i| a[i] + s * dw[i]);
                    delta_e2000(Xyz::from_array(x).to_lab(w), p.xyz.to_lab(w))
                })
                .sum::<f64>()
                / held.len() as f64;
            line += &format!(" {name} {e:.3}");
        }
        println!("{line}");
    }
}

/// The mixture study's table (the ramp-only plan plus a grid):
/// `cargo test --release --test display -- --ignored --nocapture ramp_fit::print_mixture_study`.
#[test]
#[ignore]
fn print_mixture_study() {
    use metamer::display::budget::{run_mixture_study, MIXTURE_MODELS};
    for trials in [1usize, 3] {
        let points =
            run_mixture_study(&Preset::ALL, &MIXTURE_MODELS, trials, 1, &|_, _| {}).unwrap();
        for p in points {
            println!(
                "trials {trials} {} {} grid {} patches {}: mean {:.3} p95 {:.3} ({:.0} ms)",
                p.preset, p.model, p.cube, p.patches, p.mean_de00, p.p95_de00, p.fit_ms
            );
        }
    }
}

/// On the 50-patch ramp-only sets of the three simulated displays, read with the meter's
/// noise (seeds 1 and 5), `auto`'s pick reproduces mixed colours (through the true display)
/// within 5 % of the best model's error: the held-out patches are all single-channel, so
/// this checks that the choice does not rest on them alone. On the ideal CRT with seed 5 the
/// one white reading misses the additive sum by ΔE00 1.17 from noise alone; judged against
/// the tolerance without that noise, it set aside every model but PLVC (0.246 against
/// `shaper-matrix`'s 0.002).
#[test]
fn auto_on_ramps_picks_within_5_percent_of_the_best_model() {
    for (preset, seed) in Preset::ALL.into_iter().flat_map(|p| [(p, 1), (p, 5)]) {
        let (panel, patches) = ramp_set(preset, Some(seed));
        let errors: Vec<(ModelKind, f64)> = ModelKind::ALL
            .iter()
            .filter_map(|&k| model_error(&panel, k, &patches).map(|e| (k, e)))
            .collect();
        let best = errors.iter().map(|e| e.1).fold(f64::INFINITY, f64::min);
        let sel = select_model(&patches, 5, &FitOptions::default()).unwrap();
        let picked = errors.iter().find(|e| e.0 == sel.model).unwrap().1;
        assert!(
            picked <= 1.05 * best,
            "{} seed {seed}: auto took {} ({picked:.3}), the best is {best:.3}: {errors:?}\n{sel}",
            panel.name(),
            sel.model
        );
    }
}

/// The white sets a model aside for missing it only beyond what the meter's noise allows:
/// on the ideal CRT (additive by construction) read with the meter's noise, no seed of six
/// sets any candidate aside, although the white misses the additive sum by up to ΔE00 1.4
/// there; with that white read 15 % darker than the sum (a real panel's white fell 7.6 %
/// short in one of the DisplayCAL files the benches use), every candidate whose matrix is
/// the primaries' is set aside and PLVC, which passes through the white, is chosen.
#[test]
fn the_white_sets_models_aside_only_beyond_the_noise() {
    for seed in 1..=6 {
        let (_, patches) = ramp_set(Preset::IdealCrt, Some(seed));
        let sel = select_model(&patches, 5, &FitOptions::default()).unwrap();
        assert!(
            sel.candidates.iter().all(|c| c.set_aside.is_none()),
            "seed {seed}:\n{sel}"
        );
        let noise = sel.mixtures.additivity_noise_de00.unwrap().0;
        assert!(noise > 0.3 && noise < 1.5, "seed {seed}: {noise}\n{sel}");
    }
    let (_, mut patches) = ramp_set(Preset::IdealCrt, Some(1));
    let black = patches.iter().find(|p| p.rgb == [0.0; 3]).unwrap().xyz;
    for p in patches.iter_mut().filter(|p| p.rgb == [1.0; 3]) {
        p.xyz = Xyz::from(std::array::from_fn::<f64, 3, _>(|k| {
            black[k] + 0.85 * (p.xyz[k] - black[k])
        }));
    }
    let sel = select_model(&patches, 5, &FitOptions::default()).unwrap();
    for kind in [ModelKind::Plcc, ModelKind::PlccGamma, ModelKind::Gog] {
        let c = sel.candidates.iter().find(|c| c.model == kind).unwrap();
        assert!(c.set_aside.is_some(), "{kind}:\n{sel}");
    }
    assert_eq!(sel.model, ModelKind::Plvc, "{sel}");
    let m = &sel.mixtures;
    assert!(m.additivity_de00.unwrap() > m.allowance_de00, "{sel}");
}

/// On the noise-free ideal CRT every model reproduces the held-out ramps exactly, so the
/// ramps cannot tell them apart and the simplest (`plcc-gamma`) is chosen. With the white
/// read 1 % darker than the sum (ΔE00 0.22 from it, far beyond the 0.03 rms that the
/// ramps' own curvature passes for noise), only PLVC passes through the white, and the
/// white breaks the tie for it; the report says so.
#[test]
fn the_white_breaks_a_tie_on_the_ramps() {
    let (_, patches) = ramp_set(Preset::IdealCrt, None);
    let sel = select_model(&patches, 5, &FitOptions::default()).unwrap();
    assert_eq!(sel.model, ModelKind::PlccGamma, "{sel}");
    let mut darker = patches.clone();
    let black = darker.iter().find(|p| p.rgb == [0.0; 3]).unwrap().xyz;
    for p in darker.iter_mut().filter(|p| p.rgb == [1.0; 3]) {
        p.xyz = Xyz::from(std::array::from_fn::<f64, 3, _>(|k| {
            black[k] + 0.99 * (p.xyz[k] - black[k])
        }));
    }
    let sel = select_model(&darker, 5, &FitOptions::default()).unwrap();
    assert_eq!(sel.model, ModelKind::Plvc, "{sel}");
    assert!(sel.white_decided, "{sel}");
    let miss = sel.mixtures.additivity_de00.unwrap();
    assert!(miss > 0.15 && miss < 0.3, "{sel}");
    let report = sel.to_string();
    assert!(
        report.contains("misses the measured white least"),
        "{report}"
    );
}

/// The fit report on a ramp-only set says that mixtures were not measured, quotes the
/// white's departure from the additive sum R + G + B − 2K (computed here from the true
/// display) and recommends a grid.
#[test]
fn the_fit_report_on_ramps_says_mixtures_were_not_measured() {
    let (panel, patches) = ramp_set(Preset::WideGamutCcfl, None);
    let profile = fit_profile(ModelKind::Plvc, &patches, None).unwrap();
    let d = profile.diagnostics();
    assert_eq!(d.few_mixtures, Some(0));
    let w = panel.xyz([255; 3]);
    let k = panel.xyz([0; 3]);
    let (r, g, b) = (
        panel.xyz([255, 0, 0]),
        panel.xyz([0, 255, 0]),
        panel.xyz([0, 0, 255]),
    );
    let sum: [f64; 3] = std::array::from_fn(|i| r[i] + g[i] + b[i] - 2.0 * k[i]);
    let white = w;
    let de = delta_e2000(Xyz::from_array(sum).to_lab(white), w.to_lab(white));
    assert!(de > 0.1, "the preset's crosstalk shows at white: {de}");
    let v = &d.verdict;
    assert!(v.contains("Mixed colours were not measured"), "{v}");
    assert!(
        v.contains(&format!("differs by ΔE00 {de:.2}")),
        "{de:.2}: {v}"
    );
    // What to measure, in the library's words; the command that reads it names the flag.
    assert!(v.contains("measure a grid of 5 steps per axis"), "{v}");
    // A set with a grid says nothing of the kind.
    let mut with_grid = patches.clone();
    with_grid.extend(measure(&panel, &grid_codes(3)));
    let profile = fit_profile(ModelKind::Lut, &with_grid, None).unwrap();
    assert_eq!(profile.diagnostics().few_mixtures, None);
    assert!(!profile.diagnostics().verdict.contains("not measured"));
}

fn grid_codes(n: usize) -> Vec<[u8; 3]> {
    let level = |i: usize| (255.0 * i as f64 / (n - 1) as f64).round() as u8;
    let mut codes = Vec::new();
    for r in 0..n {
        for g in 0..n {
            for b in 0..n {
                codes.push([level(r), level(g), level(b)]);
            }
        }
    }
    codes
}

/// The selection chart names every candidate, prints each fitted one's held-out mean and
/// marks the choice.
#[test]
fn the_selection_chart_shows_each_candidates_held_out_error() {
    use metamer::display::select_chart::selection_svg;
    let (_, patches) = ramp_set(Preset::IpsLcd, Some(1));
    let sel = select_model(&patches, 5, &FitOptions::default()).unwrap();
    let svg = selection_svg(&sel).unwrap();
    for c in &sel.candidates {
        assert!(svg.contains(c.model.name()), "{}", c.model);
        match &c.cv_mean_de00 {
            Ok(e) => assert!(svg.contains(&format!("{e:.3}")), "{} {e}", c.model),
            Err(_) => assert!(svg.contains("not fitted"), "{}", c.model),
        }
    }
    let chosen = sel
        .candidates
        .iter()
        .find(|c| c.model == sel.model)
        .unwrap();
    let v = chosen.cv_mean_de00.as_ref().unwrap();
    assert!(svg.contains(&format!("{v:.3} chosen")), "{svg}");
}

/// characterize's default plan (ramps of 9: 7 grey steps are its only mixtures) says so and
/// what a grid buys; with a 5³ grid it is silent.
#[test]
fn a_plan_without_a_grid_recommends_one() {
    use metamer::display::characterize::{plan_advice, Plan, PlanOptions};
    let plan = Plan::new(PlanOptions::default()).unwrap();
    assert_eq!(plan.options.grid_steps, 0);
    let advice = plan_advice(&plan).unwrap();
    assert!(advice.contains("fits on 7 mixed patches"), "{advice}");
    assert!(
        advice.contains("4³ grid") && advice.contains("5³ grid"),
        "{advice}"
    );
    let grid = Plan::new(PlanOptions {
        grid_steps: 5,
        ..PlanOptions::default()
    })
    .unwrap();
    assert_eq!(plan_advice(&grid), None);
}

/// On the ramp-only set of the ideal CRT (additive, constant chromaticity, power laws: the
/// shaper-matrix family holds) read with the CS-100A's noise, the fitted matrix's columns
/// average the noise of every ramp reading: each primary's chromaticity is within three
/// standard errors of the mean of its 16 ramp readings (3 · 0.0005 / √16 in x and y) of
/// the preset's, those of ITU-R BT.709 (the preset's spectra reproduce them within 2·10⁻⁵).
/// Fitted in CIELAB, which counts the dim steps' chromaticity for less, seed 3's blue
/// missed by 0.00047.
#[test]
fn shaper_matrix_averages_the_ramps_noise_into_the_primaries() {
    use metamer::display::model::ModelParams;
    let bt709 = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];
    for seed in 1..=3 {
        let (_, patches) = ramp_set(Preset::IdealCrt, Some(seed));
        let profile = fit_profile(ModelKind::ShaperMatrix, &patches, None).unwrap();
        let ModelParams::MatrixTrc(m) = &profile.parameters else {
            panic!("shaper-matrix is a matrix model")
        };
        for (c, truth) in bt709.iter().enumerate() {
            let col = [m.matrix[0][c], m.matrix[1][c], m.matrix[2][c]];
            let sum: f64 = col.iter().sum();
            let xy = [col[0] / sum, col[1] / sum];
            let miss = (xy[0] - truth[0]).abs().max((xy[1] - truth[1]).abs());
            assert!(
                miss < 3.0 * SIGMA_XY / 16f64.sqrt(),
                "seed {seed}, channel {c}: {xy:?} against {truth:?}"
            );
        }
    }
}
