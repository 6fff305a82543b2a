//! The display-spots session's plans, on the whole image (the meter aimed at each patch,
//! or the image moved under it) or each patch's colour full-screen, and their steps'
//! data: the patch read and where the meter is aimed.

use std::collections::BTreeMap;

use metamer_drivers::MeasureMode;
use serde::{Deserialize, Serialize};

use crate::experiment::reproduction::{PatchDrive, PatchRegion};
use crate::image::ScreenSpot;
use crate::rig::Placement;
use crate::session::{Prepare, SessionPlan, Step};

/// A display-spot step's own data in the journal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpotStep {
    pub patch: usize,
    pub repeat: usize,
}

/// Where the operator aims the meter for one patch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchAim {
    pub patch: usize,
    /// The spot on the screen (fractions of its width and height from the top-left).
    pub x: f64,
    pub y: f64,
    pub radius: f64,
    pub prompt: String,
    /// With the image moved under the meter: the slide, in the image's pixels (right,
    /// down), that puts the patch's spot under the meter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shift: Option<[i64; 2]>,
}

/// The plan on the whole image: every patch, `repeats` times; the meter is aimed before
/// each patch's first reading and stays there for the rest.
pub fn image_plan(aims: &[PatchAim], repeats: usize) -> SessionPlan<SpotStep> {
    let patches = aims.iter().map(|a| {
        let aim = Prepare::Operator {
            prompt: a.prompt.clone(),
        };
        (a.patch, aim, Prepare::None)
    });
    let mut plan = patch_plan(patches, repeats);
    plan.options
        .insert("shown".to_string(), "image".to_string());
    plan
}

/// The plan: every patch, `repeats` times, in patch order.
pub fn plan(drives: &[PatchDrive], repeats: usize) -> SessionPlan<SpotStep> {
    let patches = drives.iter().map(|d| {
        let show = Prepare::Show { rgb: d.rgb8 };
        (d.patch, show.clone(), show)
    });
    patch_plan(patches, repeats)
}

/// Every patch `repeats` times in the order given, each as (patch, what its first reading
/// needs, what each further reading needs).
pub(super) fn patch_plan(
    patches: impl Iterator<Item = (usize, Prepare, Prepare)>,
    repeats: usize,
) -> SessionPlan<SpotStep> {
    let mut steps = Vec::new();
    for (patch, first, rest) in patches {
        for repeat in 1..=repeats {
            steps.push(Step {
                label: format!("patch {patch} reading {repeat}"),
                role: "spot".into(),
                mode: MeasureMode::Emissive,
                prepare: if repeat == 1 {
                    first.clone()
                } else {
                    rest.clone()
                },
                settle: std::time::Duration::ZERO,
                data: SpotStep { patch, repeat },
            });
        }
    }
    let mut options = BTreeMap::new();
    options.insert("repeats".to_string(), repeats.to_string());
    SessionPlan {
        kind: "display-spots".into(),
        options,
        steps,
    }
}

/// The operator's request for patch `r` at `spot` on the screen.
pub fn aim_prompt(r: &PatchRegion, spot: ScreenSpot) -> String {
    format!(
        "aim the meter at patch {} (row {}, column {}) — at {:.1} % from the left, {:.1} % \
         from the top of the screen",
        r.patch,
        r.row,
        r.column,
        100.0 * spot.x,
        100.0 * spot.y
    )
}

/// Each patch's aim on the screen, for the image placed at `placement`.
pub fn aims_on(placement: &Placement, regions: &[PatchRegion]) -> Vec<PatchAim> {
    regions
        .iter()
        .map(|r| {
            let spot = r.on_screen(placement);
            PatchAim {
                patch: r.patch,
                x: spot.x,
                y: spot.y,
                radius: spot.radius,
                prompt: aim_prompt(r, spot),
                shift: None,
            }
        })
        .collect()
}
