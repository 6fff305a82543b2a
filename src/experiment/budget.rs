//! The experiment's budget before its first stage: each measuring stage's plan costed as
//! if it ran in full ([`budget`]), and, once the stages have run, each one's budget and
//! what it took as its own files record them ([`recorded`]).
//!
//! Before anything runs some of what a stage's readings see is not known yet: the
//! simulation sets a simulated monitor's white, and the reproduction the display spots'
//! drive values. The budget then takes the preset's own white and each spot at its
//! ColorChecker patch's luminance factor of that white, and says so. Each stage costs its
//! own plan again right before its first reading, from what it then knows and for the
//! readings its journal still lacks; that is the estimate its files keep.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::display::DisplayOptions;
use super::display_spots::shown::aim_cost;
use super::display_spots::{
    image_plan, under_meter_plan, PatchAim, SpotStep, SpotsShown, RECORD_FILE,
};
use super::measure_box::MeasureBox;
use super::options::{BoxSource, ExperimentOptions};
use super::stage::Stage;
use crate::color::{colorchecker, reflectance_to_xyz, ColorCheckerSet, Illuminant, ObserverKind};
use crate::display::characterize::adaptive::run::first_pass;
use crate::display::characterize::plan::{Plan, PlanOptions, METER};
use crate::measure_box::plan::{BoxStage, SPECTRAL, SPOT};
use crate::measure_box::run::{BOX_LIGHT_ASSUMPTION, BOX_TARGET_CD_M2};
use crate::measure_box::BoxPlan;
use crate::rig::window::DEFAULT_SETTLE;
use crate::rig::{ScreenSpec, VirtualPanel};
use crate::session::budget::{estimate, srgb_assumption, srgb_luminance, Meter, SRGB_WHITE_CD_M2};
use crate::session::plan::{Prepare, Step};
use crate::session::{Cost, CostReport};

/// One measuring stage's budget, by the stage's directory name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageBudget {
    pub stage: String,
    pub cost: CostReport,
}

/// Each measuring stage of `opts` costed from its plan as if it ran in full (a box given
/// as files costs nothing), in the order they run.
pub fn budget(opts: &ExperimentOptions) -> Vec<StageBudget> {
    let placement_s = opts.run.placement_s();
    let mut out = Vec::new();
    let mut patches = BoxPlan::default().patches;
    if let BoxSource::Measure(m) = &opts.box_source {
        let plan = box_plan(m);
        patches = plan.patches.clone();
        out.push(stage(Stage::Box, box_cost(&plan, m, placement_s)));
    }
    out.push(stage(
        Stage::Display,
        display_cost(&opts.display, patches.len(), placement_s),
    ));
    out.push(stage(
        Stage::DisplaySpots,
        spots_cost(
            &opts.display,
            &patches,
            opts.repeats.max(1),
            spots_shown(opts),
            placement_s,
        ),
    ));
    out
}

fn stage(stage: Stage, estimate: Cost) -> StageBudget {
    StageBudget {
        stage: stage.name().to_string(),
        cost: CostReport {
            estimate,
            actual: None,
        },
    }
}

/// The sum of `costs`' estimates and, where every one has it, of what they took.
pub fn total(costs: &[StageBudget]) -> CostReport {
    let mut estimate = Cost::default();
    let mut actual = Some(Cost::default());
    for c in costs {
        estimate.add(&c.cost.estimate);
        actual = match (actual, &c.cost.actual) {
            (Some(mut sum), Some(a)) => {
                sum.add(a);
                Some(sum)
            }
            _ => None,
        };
    }
    CostReport { estimate, actual }
}

/// The box plan the stage measures: the plan file's, else the paper's; with the repeat
/// count asked for. A plan file that does not load is refused by the checks before the
/// first stage, so the paper's stands in here.
fn box_plan(m: &MeasureBox) -> BoxPlan {
    let mut plan = m
        .plan
        .as_deref()
        .and_then(|p| BoxPlan::load(p).ok())
        .unwrap_or_default();
    if let Some(n) = m.repeats {
        plan.repeats = n;
    }
    plan.choose_adaptive(m.adaptive);
    plan
}

fn box_cost(plan: &BoxPlan, m: &MeasureBox, placement_s: f64) -> Cost {
    let meters: BTreeMap<String, Meter> = [
        (SPECTRAL.to_string(), Meter::of_spec(&m.spectral)),
        (SPOT.to_string(), Meter::of_spec(&m.spot)),
    ]
    .into();
    let mut cost = Cost::default();
    for s in BoxStage::ALL {
        cost.add(&estimate(
            &plan.round_plan(s, 0, plan.most_steps(s), &BTreeMap::new()),
            &|_| false,
            &meters,
            &|_| BOX_TARGET_CD_M2,
            BOX_LIGHT_ASSUMPTION,
            placement_s,
        ));
    }
    if let Some(rule) = &plan.adaptive {
        cost.assumptions.push(format!(
            "the adaptive plan at its caps, {} tiles and {} fall-off angles",
            rule.max_tiles, rule.max_falloff
        ));
    }
    cost
}

/// A patch's luminance (cd/m²) from its drive values.
type PatchLight = Box<dyn Fn([u8; 3]) -> f64>;

/// A patch's luminance on the stage's screen before the simulation sets a simulated
/// monitor's white (its preset's), or on an sRGB display for a real one; and what that
/// assumes.
fn screen_light(screen: &ScreenSpec) -> (PatchLight, String) {
    match screen {
        ScreenSpec::Virtual(p) => {
            let panel = VirtualPanel::preset(*p);
            let said = format!(
                "a patch's luminance as the simulated {} shows it at its preset's white (the simulation sets it later)",
                screen.canonical()
            );
            (Box::new(move |rgb| panel.xyz(rgb).y), said)
        }
        ScreenSpec::Window { .. } => (
            Box::new(|rgb| srgb_luminance(rgb, SRGB_WHITE_CD_M2)),
            srgb_assumption(SRGB_WHITE_CD_M2),
        ),
    }
}

/// The display's patches: the fixed plan's; or the adaptive plan's at its cap, its first
/// pass as planned, the patches it chooses after it (not known before its readings) read
/// like the first pass's in turn, and one held-out patch for each of the `targets` (or as
/// many as its rule holds out).
fn display_cost(d: &DisplayOptions, targets: usize, placement_s: f64) -> Cost {
    let defaults = PlanOptions::default();
    let options = PlanOptions::for_model(d.model, defaults.ramp_steps, defaults.repeats, None);
    let settle = match d.screen {
        ScreenSpec::Virtual(_) => std::time::Duration::ZERO,
        ScreenSpec::Window { .. } => DEFAULT_SETTLE,
    };
    let Ok(plan) = Plan::new(options) else {
        return Cost::default();
    };
    let mut plan = plan.session_plan(&d.screen.canonical(), settle);
    let mut cap_said = None;
    if let Some(rule) = &d.adaptive {
        let Ok(first) = first_pass(options) else {
            return Cost::default();
        };
        let targets = rule.held_out_count(targets);
        let cap = rule.max_readings.max(first.len()) + targets;
        let template = plan.steps.first().cloned();
        plan.steps = first
            .iter()
            .cycle()
            .take(cap)
            .filter_map(|p| {
                let mut step = template.clone()?;
                step.label = p.label.clone();
                step.prepare = Prepare::Show { rgb: p.rgb };
                step.data = p.clone();
                Some(step)
            })
            .collect();
        cap_said = Some(format!(
            "the adaptive plan at its cap, {} fit readings ({} in the first pass, the rest read like it) and {targets} held out",
            rule.max_readings.max(first.len()),
            first.len()
        ));
    }
    let meters = [(METER.to_string(), Meter::of_spec(&d.spot))].into();
    let (light, said) = screen_light(&d.screen);
    let of_step = |s: &Step<_>| match s.prepare {
        Prepare::Show { rgb } => light(rgb),
        _ => light([255; 3]),
    };
    let mut cost = estimate(&plan, &|_| false, &meters, &of_step, &said, placement_s);
    cost.assumptions.extend(cap_said);
    cost
}

/// How the display spots will be shown: as asked, but full-screen where no image will be
/// rendered to show.
fn spots_shown(opts: &ExperimentOptions) -> SpotsShown {
    let image = opts.simulation.image.is_some() || opts.simulation.external_image.is_some();
    if image {
        opts.spots_shown
    } else {
        SpotsShown::FullScreen
    }
}

/// The display spots: `patches` ColorChecker patches (1–24) read `repeats` times, on the
/// image (one placement per patch, or one for all with the image moved under the meter)
/// or full-screen; each at the patch's luminance factor (BabelColor average under D65) of
/// the display's white.
fn spots_cost(
    d: &DisplayOptions,
    patches: &[usize],
    repeats: usize,
    shown: SpotsShown,
    placement_s: f64,
) -> Cost {
    let chart = colorchecker(ColorCheckerSet::BabelColorAverage);
    let d65 = Illuminant::D65.spectrum();
    let factor = |patch: usize| {
        chart.get(patch.wrapping_sub(1)).map_or(1.0, |s| {
            reflectance_to_xyz(s, &d65, ObserverKind::Cie1931).y / 100.0
        })
    };
    let aims: Vec<PatchAim> = patches
        .iter()
        .map(|&patch| PatchAim {
            patch,
            x: 0.5,
            y: 0.5,
            radius: 0.0,
            prompt: format!("aim the meter at patch {patch}"),
            // The slides are known only once the image is reproduced; a slide costs no
            // operator's time, whatever its size.
            shift: None,
        })
        .collect();
    let mut plan = match shown {
        SpotsShown::UnderMeter => under_meter_plan(&aims, repeats),
        _ => image_plan(&aims, repeats),
    };
    if shown == SpotsShown::FullScreen {
        for s in &mut plan.steps {
            s.prepare = Prepare::Show { rgb: [255; 3] };
        }
    }
    let meters = [("spot".to_string(), Meter::of_spec(&d.spot))].into();
    let (light, said) = screen_light(&d.screen);
    let white = light([255; 3]);
    let of_step = |s: &Step<SpotStep>| white * factor(s.data.patch);
    let said =
        format!("{said}; a display spot at its ColorChecker patch's luminance factor of the white");
    let mut cost = estimate(&plan, &|_| false, &meters, &of_step, &said, placement_s);
    if shown == SpotsShown::UnderMeter {
        cost.add(&aim_cost(placement_s));
    }
    cost
}

/// Each measuring stage's budget and what it took, as its own files in `dir` keep them
/// (`box/summary.json`, `display/summary.json`, `display-spots/display-spots.json`); a
/// stage whose files keep none has its entry of `planned`, with nothing taken.
pub fn recorded(dir: &Path, planned: &[StageBudget]) -> Vec<StageBudget> {
    planned
        .iter()
        .map(|p| StageBudget {
            stage: p.stage.clone(),
            cost: kept(&p.stage, &dir.join(&p.stage)).unwrap_or_else(|| p.cost.clone()),
        })
        .collect()
}

/// The budget and cost the files of measuring stage `stage` (by its directory name) in
/// `stage_dir` keep; None when they keep none (not run, or run before budgets were kept).
pub fn kept(stage: &str, stage_dir: &Path) -> Option<CostReport> {
    match stage {
        s if s == Stage::Box.name() => read::<BoxCost>(&stage_dir.join("summary.json"))
            .filter(|b| !b.cost.is_empty())
            .map(|b| {
                let mut estimate = Cost::default();
                let mut actual = Cost::default();
                for c in b.cost.values() {
                    estimate.add(&c.estimate);
                    if let Some(a) = &c.actual {
                        actual.add(a);
                    }
                }
                CostReport {
                    estimate,
                    actual: Some(actual),
                }
            }),
        s if s == Stage::Display.name() => {
            read::<OneCost>(&stage_dir.join("summary.json")).and_then(|c| c.cost)
        }
        _ => read::<OneCost>(&stage_dir.join(RECORD_FILE)).and_then(|c| c.cost),
    }
}

/// The part of the box's `summary.json` this reads.
#[derive(Deserialize)]
struct BoxCost {
    #[serde(default)]
    cost: BTreeMap<String, CostReport>,
}

/// The part of the display's `summary.json` or `display-spots.json` this reads.
#[derive(Deserialize)]
struct OneCost {
    #[serde(default)]
    cost: Option<CostReport>,
}

fn read<T: serde::de::DeserializeOwned>(path: &Path) -> Option<T> {
    let text = std::fs::read_to_string(path).ok()?;
    serde_json::from_str(&text).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::characterize::adaptive::Rule;
    use crate::display::ModelKind;
    use crate::experiment::run::tests::given;
    use crate::session::budget::PLACEMENT_S;

    fn options(adaptive: Option<Rule>) -> ExperimentOptions {
        let mut o = given(Path::new("unused"), "scene.json".into(), "spots.csv".into());
        o.display.model = ModelKind::Lut;
        o.display.adaptive = adaptive;
        o
    }

    /// The adaptive display plan is budgeted at its cap: its fit readings and one held-out
    /// patch for each of the 24 colours, not the fixed plan's patches.
    #[test]
    fn the_adaptive_display_is_budgeted_at_its_cap() {
        let display = |b: &[StageBudget]| {
            b.iter()
                .find(|s| s.stage == Stage::Display.name())
                .unwrap()
                .cost
                .estimate
                .clone()
        };
        let fixed = display(&budget(&options(None)));
        let planned = Plan::new(PlanOptions::for_model(
            ModelKind::Lut,
            PlanOptions::default().ramp_steps,
            PlanOptions::default().repeats,
            None,
        ))
        .unwrap();
        assert_eq!(fixed.readings, planned.patches.len());
        let rule = Rule {
            max_readings: 70,
            ..Rule::default()
        };
        let adaptive = display(&budget(&options(Some(rule))));
        assert_eq!(adaptive.readings, 70 + 24);
        assert!(adaptive
            .assumptions
            .iter()
            .any(|a| a.contains("at its cap, 70 fit readings") && a.contains("24 held out")));
        // Below the first pass, the cap is the first pass.
        let first = first_pass(PlanOptions::for_model(
            ModelKind::Lut,
            PlanOptions::default().ramp_steps,
            PlanOptions::default().repeats,
            None,
        ))
        .unwrap()
        .len();
        let rule = Rule {
            max_readings: 1,
            ..Rule::default()
        };
        assert_eq!(display(&budget(&options(Some(rule)))).readings, first + 24);
    }

    /// The display spots' placements before the first reading: one per patch with the
    /// meter aimed at each (24), one for the image moved under the meter, none where each
    /// patch is shown full-screen; the readings are the same 24 × 3 in every way.
    #[test]
    fn the_image_under_the_meter_is_budgeted_at_one_placement() {
        let spots = |shown: SpotsShown| {
            let mut o = options(None);
            o.repeats = 3;
            o.spots_shown = shown;
            o.simulation.image =
                Some(crate::experiment::simulation::ImageSpec { size: 64, spp: 1 });
            let b = budget(&o);
            let c = &b
                .iter()
                .find(|s| s.stage == Stage::DisplaySpots.name())
                .unwrap()
                .cost
                .estimate;
            (c.readings, c.placements, c.operator_s)
        };
        let s = PLACEMENT_S;
        assert_eq!(spots(SpotsShown::Aimed), (72, 24, 24.0 * s));
        assert_eq!(spots(SpotsShown::UnderMeter), (72, 1, s));
        assert_eq!(spots(SpotsShown::FullScreen), (72, 0, 0.0));
    }
}
