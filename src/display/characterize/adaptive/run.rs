//! Measuring an adaptive plan on the session engine: the first pass in `log.jsonl`, each
//! batch in `log.batch-N.jsonl`, the held-out set in `log.verify.jsonl`, each journal a
//! session of its own whose steps follow from the journals before it. Resuming walks the
//! journals in order, fits the same models to the same readings, so finds the same next
//! batch, and continues the first journal that is not complete.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use metamer_drivers::{Forwarding, Instrument, InstrumentInfo, MeasureMode, Reading};

use super::choice::{decide, held_out_targets, verification_codes, Decision};
use super::fitted::Fitted;
use super::report::{AdaptiveReport, Batch};
use super::rule::Adaptive;
use crate::display::characterize::finish::{files, finish, MeasuredBy};
use crate::display::characterize::plan::{
    DriveStep, Plan, PlanOptions, Purpose, METER, SESSION_KIND,
};
use crate::display::characterize::run::{
    estimate, log_path, resuming_note, CharacterizeError, LogDetails, Options, Outcome,
};
use crate::display::characterize::verify::usable;
use crate::display::model::{ModelKind, Sample};
use crate::output::OutputPolicy;
use crate::rig::Screen;
use crate::session::{
    Answer, Cost, CostReport, InstrumentRecord, Operator, Prepare, ProgressSink, Rig, RunEnd,
    RunOptions, Session, SessionPlan, Step,
};

/// Levels per channel of the first pass's sparse grid: the cube's corners, edge and face
/// centres and its centre, the mixtures a first fit of every model can be judged on.
pub const SPARSE_GRID: usize = 3;
/// The noise stream of journal j's step k is j·2¹⁶ + k: no two readings of the session
/// draw the same simulated noise.
const NOISE_STRIDE: u64 = 1 << 16;

/// The journal of the adaptive plan's journal `j` in `dir`: 0 the first pass, then the
/// batches; the held-out set's is [`verify_path`].
pub fn journal_path(dir: &Path, j: usize) -> PathBuf {
    if j == 0 {
        log_path(dir)
    } else {
        dir.join(format!("log.batch-{j}.jsonl"))
    }
}

pub fn verify_path(dir: &Path) -> PathBuf {
    dir.join("log.verify.jsonl")
}

/// The first pass: the fixed plan's fit patches with the sparse grid, without its held-out
/// set (which the adaptive plan puts at and around the targets).
pub fn first_pass(plan: PlanOptions) -> Result<Vec<DriveStep>, CharacterizeError> {
    let plan = Plan::new(PlanOptions {
        grid_steps: SPARSE_GRID,
        ..plan
    })?;
    Ok(plan
        .patches
        .into_iter()
        .filter(|p| p.purpose == Purpose::Fit)
        .enumerate()
        .map(|(i, p)| DriveStep { index: i, ..p })
        .collect())
}

/// An instrument whose noise stream is moved by `offset` readings.
struct Shifted<'a> {
    inner: &'a mut dyn Instrument,
    offset: u64,
}

impl Forwarding for Shifted<'_> {
    fn inner(&self) -> &dyn Instrument {
        &*self.inner
    }
    fn inner_mut(&mut self) -> &mut dyn Instrument {
        &mut *self.inner
    }
    fn seek_noise(&mut self, index: u64) {
        self.inner.seek_noise(index.wrapping_add(self.offset));
    }
}

/// What the run so far has: every complete journal's readings, new readings taken in this
/// call, and whether the operator has aimed the meter.
struct Progress<'a> {
    options: &'a Options,
    base: BTreeMap<String, String>,
    settle: Duration,
    details: LogDetails,
    taken: Vec<(DriveStep, Reading)>,
    new: usize,
    aimed: bool,
    out: Option<OutputPolicy>,
    /// Each journal's budget, made just before it was read (the batches are chosen from the
    /// readings before them, so no budget of the whole exists beforehand), summed.
    estimate: Cost,
    /// What the journals' sessions took, summed.
    spent: Cost,
}

/// Where one journal ended: complete with its readings, or the outcome to return.
enum Measured {
    Complete,
    Incomplete(Outcome),
}

impl Progress<'_> {
    /// Measures what journal `path` (the `j`-th) lacks of `steps`, then adds its readings.
    #[allow(clippy::too_many_arguments)]
    fn measure(
        &mut self,
        j: u64,
        path: &Path,
        name: &str,
        steps: Vec<DriveStep>,
        display: &mut dyn Screen,
        instrument: &mut dyn Instrument,
        operator: &mut dyn Operator,
        progress: &mut dyn ProgressSink,
    ) -> Result<Measured, CharacterizeError> {
        let plan = self.session_plan(name, &steps);
        let mut shifted = Shifted {
            inner: instrument,
            offset: j * NOISE_STRIDE,
        };
        let instruments = [(METER.to_string(), InstrumentRecord::of(&shifted))].into();
        // A journal after the first exists only if the session measured into it before.
        let resume = self.options.resume || j > 0;
        let mut session: Session<LogDetails, DriveStep> =
            Session::open(path, plan, self.details.clone(), instruments, resume)?;
        if self.out.is_none() {
            let mut out = OutputPolicy::new(self.options.force || session.recovered > 0);
            out.input(session.journal_path());
            for f in files(&self.options.dir, session.journal_path()).outputs() {
                out.check(f)?;
            }
            self.out = Some(out);
        }
        if let Some(note) = resuming_note(&session) {
            progress.note(&note);
        }
        let total = session.plan().steps.len();
        let incomplete = |session: &Session<LogDetails, DriveStep>, taken: usize, end| {
            Measured::Incomplete(Outcome::Incomplete {
                end,
                done: taken + session.done(),
                total: taken + total,
                log: session.journal_path().to_path_buf(),
            })
        };
        if session.done() < total && !self.aimed && display.stimulus().is_none() {
            display.show([255; 3]).map_err(CharacterizeError::Aim)?;
            let prompt = format!(
                "aim the instrument at the middle of the white {}",
                display.describe()
            );
            if operator.ask(&prompt)? == Answer::Abort {
                let missing = total - session.done();
                return Ok(incomplete(
                    &session,
                    self.taken.len(),
                    RunEnd::Aborted { missing },
                ));
            }
            self.aimed = true;
        }
        let estimate = estimate(&session, display, &shifted, self.options, false);
        progress.note(&estimate.before(&format!("the display's patches ({name})")));
        self.estimate.add(&estimate);
        let before = session.done();
        let run = RunOptions {
            stop_after: self
                .options
                .run
                .stop_after
                .map(|n| n.saturating_sub(self.new)),
            interrupt: self.options.run.interrupt.clone(),
            placement_s: self.options.run.placement_s,
        };
        let end = {
            let mut rig = Rig {
                screen: Some(display),
                instruments: vec![(METER.to_string(), &mut shifted as &mut dyn Instrument)],
                operator: &mut *operator,
            };
            session.run(&mut rig, &run, progress)?
        };
        self.new += session.done() - before;
        self.spent.add(session.spent());
        let entries = match (end, session.complete_entries()) {
            (RunEnd::Complete, Some(entries)) => entries,
            (RunEnd::Complete, None) => {
                let missing = total - session.done();
                return Ok(incomplete(
                    &session,
                    self.taken.len(),
                    RunEnd::Stopped { missing },
                ));
            }
            (end, _) => return Ok(incomplete(&session, self.taken.len(), end)),
        };
        self.taken.extend(
            entries
                .into_iter()
                .map(|e| (e.data.clone(), e.reading.clone())),
        );
        Ok(Measured::Complete)
    }

    /// Journal `name`'s steps as a session plan: the colours shown and read in emissive
    /// mode, under the plan's options and the journal's name.
    fn session_plan(&self, name: &str, steps: &[DriveStep]) -> SessionPlan<DriveStep> {
        let mut options = self.base.clone();
        options.insert("journal".into(), name.into());
        SessionPlan {
            kind: SESSION_KIND.into(),
            options,
            steps: steps
                .iter()
                .map(|p| Step {
                    label: p.label.clone(),
                    role: METER.into(),
                    mode: MeasureMode::Emissive,
                    prepare: Prepare::Show { rgb: p.rgb },
                    settle: self.settle,
                    data: p.clone(),
                })
                .collect(),
        }
    }

    /// Fits `model` to every fit reading, verifies it on the held-out ones and writes the
    /// files, the summary with `report`.
    fn finish(
        mut self,
        model: ModelKind,
        info: &InstrumentInfo,
        report: AdaptiveReport,
    ) -> Result<Outcome, CharacterizeError> {
        let dir = self.options.dir.as_path();
        let readings: Vec<(&DriveStep, &Reading)> =
            self.taken.iter().map(|(s, r)| (s, r)).collect();
        let out = self.out.take().expect("the first journal set the policy");
        let summary = finish(
            dir,
            &log_path(dir),
            &readings,
            model,
            &MeasuredBy {
                display: &self.details.display,
                display_description: &self.details.display_description,
                instrument: &self.details.instrument,
                instrument_info: info,
                cost: &CostReport {
                    estimate: self.estimate.clone(),
                    actual: Some(self.spent.clone()),
                },
            },
            &out,
            Some(report),
        )?;
        Ok(Outcome::Finished(Box::new(summary)))
    }

    /// The fit readings so far, as the models take them.
    fn samples(&self) -> Vec<Sample> {
        self.taken
            .iter()
            .filter(|(p, r)| p.purpose == Purpose::Fit && usable(r))
            .map(|(p, r)| Sample::from_rgb8(p.rgb, r.xyz))
            .collect()
    }

    fn fit_readings(&self) -> usize {
        self.taken
            .iter()
            .filter(|(p, _)| p.purpose == Purpose::Fit)
            .count()
    }

    /// The next distinct patch number.
    fn next_patch(&self) -> usize {
        self.taken
            .iter()
            .map(|(p, _)| p.patch + 1)
            .max()
            .unwrap_or(0)
    }
}

/// Journal steps measuring `codes` for `purpose`, patches numbered from `start`.
fn steps_of(
    codes: &[[u8; 3]],
    start: usize,
    purpose: Purpose,
    label: impl Fn(usize) -> String,
) -> Vec<DriveStep> {
    codes
        .iter()
        .enumerate()
        .map(|(i, rgb)| DriveStep {
            index: i,
            patch: start + i,
            repeat: 0,
            rgb: *rgb,
            purpose,
            label: label(i),
        })
        .collect()
}

/// Every model fitted to the fit readings so far; a candidate counts near a reading it
/// misses by less than half the stopping figure beyond the reference's miss.
fn fit(p: &Progress, options: &Options, adaptive: &Adaptive) -> Result<Fitted, CharacterizeError> {
    Fitted::new(
        &p.samples(),
        options.model,
        adaptive.auto,
        adaptive.rule.stop_de / 2.0,
    )
    .map_err(|source| {
        crate::display::characterize::finish::FinishError::Fit {
            model: options.model,
            source,
        }
        .into()
    })
}

/// The options of every journal of an adaptive plan: the fixed plan's, and the rule and the
/// targets, so a journal is resumed only by the same rule on the same targets.
fn base_options(options: &Options, adaptive: &Adaptive, display: &str) -> BTreeMap<String, String> {
    let r = &adaptive.rule;
    let model = if adaptive.auto {
        "auto".to_string()
    } else {
        options.model.name().to_string()
    };
    [
        ("plan", "adaptive".to_string()),
        ("ramp_steps", options.plan.ramp_steps.to_string()),
        ("repeats", options.plan.repeats.to_string()),
        ("grid_steps", SPARSE_GRID.to_string()),
        ("display", display.to_string()),
        ("model", model),
        ("targets", adaptive.targets.len().to_string()),
        ("targets_sha256", adaptive.targets_sha256()),
        ("stop_de", r.stop_de.to_string()),
        ("max_readings", r.max_readings.to_string()),
        ("batch", r.batch.to_string()),
        ("seed", r.seed.to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

impl<'a> Progress<'a> {
    /// Nothing read yet, for `display` under `options` and the rule `adaptive`.
    fn new(options: &'a Options, adaptive: &Adaptive, display: &dyn Screen) -> Progress<'a> {
        let details = LogDetails {
            display: display.spec(),
            display_description: display.describe(),
            instrument: options.instrument.to_string(),
        };
        Progress {
            options,
            base: base_options(options, adaptive, &details.display),
            settle: options.settle.unwrap_or_else(|| display.default_settle()),
            details,
            taken: Vec::new(),
            new: 0,
            aimed: false,
            out: None,
            estimate: Cost::default(),
            spent: Cost::default(),
        }
    }
}

/// Characterizes `display` with `instrument` on the adaptive plan `adaptive`: measures what
/// its journals in `options.dir` lack, choosing each batch from the readings before it,
/// then fits, verifies on the held-out set and writes the profile, `.ti3`, report and
/// summary (with an [`AdaptiveReport`]).
pub fn run(
    options: &Options,
    adaptive: &Adaptive,
    display: &mut dyn Screen,
    instrument: &mut dyn Instrument,
    operator: &mut dyn Operator,
    progress: &mut dyn ProgressSink,
) -> Result<Outcome, CharacterizeError> {
    let first = first_pass(options.plan)?;
    adaptive.check(first.len())?;
    let mut p = Progress::new(options, adaptive, display);
    let dir = options.dir.as_path();
    macro_rules! measure {
        ($j:expr, $path:expr, $name:expr, $steps:expr) => {
            if let Measured::Incomplete(o) = p.measure(
                $j, $path, $name, $steps, display, instrument, operator, progress,
            )? {
                return Ok(o);
            }
        };
    }
    measure!(0, &journal_path(dir, 0), "first pass", first);
    let rule = adaptive.rule;
    let mut batches = Vec::new();
    let mut j = 0;
    let (fitted, stop, predicted_de) = loop {
        let fitted = fit(&p, options, adaptive)?;
        let drives = fitted.target_drives(&adaptive.targets);
        let measured: Vec<[u8; 3]> = p.taken.iter().map(|(s, _)| s.rgb).collect();
        let room = rule.max_readings.saturating_sub(p.fit_readings());
        let (decision, at) = decide(
            &drives,
            &|rgb| fitted.predicted(rgb),
            &measured,
            rule.stop_de,
            rule.batch,
            room,
        );
        let codes = match decision {
            Decision::Stop(reason) => break (fitted, reason, at),
            Decision::Batch(codes) => codes,
        };
        j += 1;
        let start = p.next_patch();
        let steps = steps_of(&codes, start, Purpose::Fit, |i| {
            format!("batch {j} patch {}", i + 1)
        });
        batches.push(Batch {
            after_readings: p.fit_readings(),
            predicted_de: at,
            model: fitted.model,
            patches: codes,
        });
        measure!(
            j as u64,
            &journal_path(dir, j),
            &format!("batch {j}"),
            steps
        );
    };
    let drives = fitted.target_drives(&adaptive.targets);
    let fit_codes: Vec<[u8; 3]> = p.taken.iter().map(|(s, _)| s.rgb).collect();
    let start = p.next_patch();
    let predicted: Vec<f64> = drives.iter().map(|d| fitted.predicted(*d)).collect();
    let chosen = held_out_targets(&predicted, rule.held_out);
    let chosen_drives: Vec<[f64; 3]> = chosen.iter().map(|&i| drives[i]).collect();
    let codes = verification_codes(&chosen_drives, &fit_codes, rule.seed);
    let held_out = steps_of(&codes, start, Purpose::Verify, |i| {
        format!("near target {}", chosen[i] + 1)
    });
    let verify_patches = held_out.len();
    measure!(j as u64 + 1, &verify_path(dir), "verify", held_out);
    let report = AdaptiveReport {
        rule,
        targets: adaptive.targets.len(),
        targets_sha256: adaptive.targets_sha256(),
        auto: adaptive.auto,
        batches,
        stop,
        predicted_de,
        candidates: std::iter::once(fitted.model)
            .chain(fitted.candidates.iter().map(|(k, _)| *k))
            .collect(),
        fit_readings: p.fit_readings(),
        verify_patches,
    };
    p.finish(fitted.model, &instrument.info(), report)
}

#[cfg(test)]
mod tests {
    use super::super::choice::StopReason;
    use super::super::rule::Rule;
    use super::*;
    use crate::display::characterize::{
        characterize, Attend, Listener, PlanOptions, Request, SimulatedMeter,
    };
    use crate::display::model::ModelKind;
    use crate::rig::{Preset, ScreenSpec};
    use crate::session::NoProgress;

    struct Quiet(NoProgress);
    impl Listener for Quiet {
        fn note(&mut self, _: &str) {}
        fn warning(&mut self, _: &str) {}
        fn progress(&mut self, _: bool) -> &mut dyn ProgressSink {
            &mut self.0
        }
    }

    /// The ColorChecker under D65 at a white of 100 cd/m² (tests/data/docs/colorchecker-targets.csv).
    fn targets() -> Vec<crate::color::Xyz> {
        let file =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/docs/colorchecker-targets.csv");
        super::super::rule::read_targets(&file).unwrap()
    }

    fn request(tag: &str, resume: bool, stop_after: Option<usize>) -> Request {
        let out =
            std::env::temp_dir().join(format!("metamer-adaptive-{tag}-{}", std::process::id()));
        if !resume {
            let _ = std::fs::remove_dir_all(&out);
        }
        Request {
            out,
            screen: ScreenSpec::Virtual(Preset::WideGamutCcfl),
            virtual_white_cd_m2: None,
            instrument: "sim:cs100a?time_scale=0&seed=5".into(),
            speed: None,
            plan: PlanOptions {
                ramp_steps: 5,
                repeats: 1,
                grid_steps: 0,
            },
            adaptive: Some(Adaptive {
                // A figure no fit on the simulated meter's noise reaches: the plan runs to
                // its cap, two batches after the first pass.
                rule: Rule {
                    stop_de: 0.01,
                    max_readings: 0,
                    batch: 6,
                    seed: 3,
                    held_out: None,
                },
                targets: targets(),
                auto: false,
            }),
            model: ModelKind::Lut,
            settle: Some(Duration::ZERO),
            resume,
            force: false,
            attend: Attend::Terminal { unattended: true },
            simulated_meter: SimulatedMeter::Warn,
            run: RunOptions {
                stop_after,
                interrupt: None,
                placement_s: None,
            },
        }
    }

    fn with_cap(mut r: Request) -> Request {
        let first = first_pass(r.plan).unwrap().len();
        if let Some(a) = &mut r.adaptive {
            a.rule.max_readings = first + 12;
        }
        r
    }

    /// Every journal's lines of entries (index, label, rgb, XYZ), journal by journal.
    fn journals(dir: &Path) -> Vec<(String, Vec<serde_json::Value>)> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".jsonl"))
            .collect();
        names.sort();
        names
            .into_iter()
            .map(|n| {
                let text = std::fs::read_to_string(dir.join(&n)).unwrap();
                let entries = text
                    .lines()
                    .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
                    .filter(|l| l["type"] == "entry")
                    .map(|l| {
                        serde_json::json!([
                            l["index"],
                            l["label"],
                            l["data"]["rgb"],
                            l["reading"]["xyz"]
                        ])
                    })
                    .collect();
                (n, entries)
            })
            .collect()
    }

    /// Interrupted in the middle of the first batch and again in the held-out set, then
    /// resumed: the same batches, the same readings in the same journals and the same
    /// verification as one uninterrupted run.
    #[test]
    fn a_resumed_adaptive_session_chooses_and_reads_what_an_uninterrupted_one_does() {
        let straight = with_cap(request("straight", false, None));
        let Outcome::Finished(a) = characterize(&straight, &mut Quiet(NoProgress)).unwrap() else {
            panic!("an uninterrupted simulated session finishes")
        };
        let report = a.adaptive.clone().unwrap();
        assert_eq!(report.batches.len(), 2, "{report:?}");
        assert_eq!(report.stop, StopReason::Cap);
        assert_eq!(report.verify_patches, 24);
        let first = first_pass(straight.plan).unwrap().len();
        assert_eq!(report.fit_readings, first + 12);
        assert_eq!(a.readings, first + 12 + 24);

        let mut done = 0;
        for stop in [first + 3, first + 12 + 5, usize::MAX] {
            let r = with_cap(request("split", done > 0, Some(stop - done)));
            let outcome = characterize(&r, &mut Quiet(NoProgress)).unwrap();
            match outcome {
                Outcome::Incomplete { done: d, .. } => {
                    assert_eq!(d, stop, "stopped after {stop}");
                    done = d;
                }
                Outcome::Finished(b) => {
                    assert_eq!(stop, usize::MAX);
                    assert_eq!(b.adaptive, a.adaptive);
                    assert_eq!(b.verification.de00.mean, a.verification.de00.mean);
                    assert_eq!(b.model, a.model);
                }
            }
        }
        let split = with_cap(request("split", true, None));
        assert_eq!(journals(&straight.out), journals(&split.out));
        assert_eq!(journals(&straight.out).len(), 4);
        // Another rule is another plan: the first journal refuses it.
        let mut other = with_cap(request("split", true, None));
        if let Some(a) = &mut other.adaptive {
            a.rule.batch = 5;
        }
        let e = characterize(&other, &mut Quiet(NoProgress))
            .unwrap_err()
            .to_string();
        assert!(e.contains("batch"), "{e}");
        std::fs::remove_dir_all(&straight.out).unwrap();
        std::fs::remove_dir_all(&split.out).unwrap();
    }

    /// A held-out count reads that many patches, each near another target, after the same
    /// fit readings as the full held-out set; the fit, and so the profile, is unchanged.
    #[test]
    fn a_held_out_count_reads_fewer_patches_after_the_same_fit() {
        let all = with_cap(request("held-all", false, None));
        let mut some = with_cap(request("held-some", false, None));
        if let Some(a) = &mut some.adaptive {
            a.rule.held_out = Some(8);
        }
        let finished = |r: &Request| match characterize(r, &mut Quiet(NoProgress)).unwrap() {
            Outcome::Finished(s) => s,
            _ => panic!("a simulated session finishes"),
        };
        let (a, b) = (finished(&all), finished(&some));
        assert_eq!(a.adaptive.as_ref().unwrap().verify_patches, 24);
        assert_eq!(b.adaptive.as_ref().unwrap().verify_patches, 8);
        assert_eq!(b.readings + 16, a.readings);
        let (ja, jb) = (journals(&all.out), journals(&some.out));
        assert_eq!(ja.len(), jb.len());
        for ((na, ea), (nb, eb)) in ja.iter().zip(&jb) {
            assert_eq!(na, nb);
            if na != "log.verify.jsonl" {
                assert_eq!(ea, eb, "{na}");
            }
        }
        let verify = &jb.last().unwrap().1;
        let targets: Vec<usize> = verify
            .iter()
            .map(|e| {
                let label = e[1].as_str().unwrap();
                label.strip_prefix("near target ").unwrap().parse().unwrap()
            })
            .collect();
        assert_eq!(targets.len(), 8);
        assert!(targets.windows(2).all(|w| w[0] < w[1]), "{targets:?}");
        assert!(targets.iter().all(|t| (1..=24).contains(t)), "{targets:?}");
        let load = |s: &crate::display::characterize::finish::Summary| {
            crate::display::Profile::load(&s.files.profile).unwrap()
        };
        let (pa, pb) = (load(&a), load(&b));
        for rgb in [[0.2, 0.5, 0.8], [1.0, 1.0, 1.0], [0.9, 0.1, 0.3]] {
            assert_eq!(pa.forward(rgb), pb.forward(rgb));
        }
        std::fs::remove_dir_all(&all.out).unwrap();
        std::fs::remove_dir_all(&some.out).unwrap();
    }
}
