//! How the display spots put each patch in front of the meter: the paper's way (the
//! reproduced image where it lies, the meter re-aimed at every patch), the image slid so
//! each patch in turn lies under a meter that stays put, or each patch's drive values over
//! the whole screen.
//!
//! **Under the meter.** The meter is aimed once, at the middle of the screen, where the
//! display was characterized (characterize asks for the middle of the white screen; a
//! simulated meter reads the uniform screen the same anywhere), and stays there. Before
//! each reading the image is slid by whole pixels so that its patch's spot comes under
//! the meter: the drive values are moved, never resampled, and the display reads them
//! where its characterization read its patches. What the slide uncovers is black, the
//! colour a screen shows around an image that does not fill it (`Screen::show_image`): an
//! edge or mirror fill would show picture content the rendering never had. One placement
//! for the whole stage, against one per patch.

use super::plan::{PatchAim, SpotStep};
use super::SpotsShown;
use crate::experiment::reproduction::PatchRegion;
use crate::rig::Placement;
use crate::session::{Cost, Operator, OperatorError, Prepare, SessionPlan};

/// Where the meter stays when the image moves under it: the middle of the screen, as
/// fractions of its width and height, where the display was characterized.
pub const METER_AT: [f64; 2] = [0.5, 0.5];

/// The operator's one request when the image moves under the meter.
pub const AIM_AT_MIDDLE: &str = "aim the meter at the middle of the screen, where the display \
     was characterized, and leave it there: the image moves so that each patch in turn lies \
     under it";

/// Each patch's aim when the image, `width × height` pixels placed at `placement`, is slid
/// so that the patch's spot lies under the meter at [`METER_AT`]: the meter's spot, with
/// the patch's radius, and the slide in whole pixels of the image (the patch's centre
/// lands within half a pixel of the meter's).
pub fn aims_under_meter(
    placement: &Placement,
    size: (usize, usize),
    regions: &[PatchRegion],
) -> Vec<PatchAim> {
    let (w, h) = (size.0 as f64, size.1 as f64);
    // The meter's point in the image's pixels.
    let at = [
        (METER_AT[0] - placement.left) / placement.width * w,
        (METER_AT[1] - placement.top) / placement.height * h,
    ];
    regions
        .iter()
        .map(|r| {
            let spot = r.on_screen(placement);
            let slide = [(at[0] - r.x * w).round(), (at[1] - r.y * h).round()];
            PatchAim {
                patch: r.patch,
                x: METER_AT[0],
                y: METER_AT[1],
                radius: spot.radius,
                prompt: AIM_AT_MIDDLE.to_string(),
                shift: Some(slide.map(|v| v as i64)),
            }
        })
        .collect()
}

/// The plan on the image moved under a meter that stays put (aimed once, outside the
/// plan): every patch, `repeats` times, each reading preceded by its patch's slide, so a
/// session resumed mid-patch puts the image back where that patch's readings need it. The
/// slides are steps' data, so the fingerprint covers them. An aim without a slide stays
/// where the image was shown.
pub fn under_meter_plan(aims: &[PatchAim], repeats: usize) -> SessionPlan<SpotStep> {
    let patches = aims.iter().map(|a| {
        let slide = Prepare::ShiftImage {
            by: a.shift.unwrap_or_default(),
        };
        (a.patch, slide.clone(), slide)
    });
    let mut plan = super::plan::patch_plan(patches, repeats);
    plan.options.insert(
        "shown".to_string(),
        SpotsShown::UnderMeter.record_name(true).to_string(),
    );
    plan.options
        .insert("meter at".to_string(), format!("{:?}", METER_AT));
    plan
}

/// The one placement of the image moved under the meter, at `placement_s` seconds.
pub fn aim_cost(placement_s: f64) -> Cost {
    Cost {
        placements: 1,
        operator_s: placement_s,
        wall_s: placement_s,
        assumptions: vec![format!("{placement_s} s per placement")],
        ..Cost::default()
    }
}

/// Asks the operator to aim the meter at the middle of the screen: the placement and the
/// time it took, or None when the operator aborts.
pub(super) fn aim_at_middle(operator: &mut dyn Operator) -> Result<Option<Cost>, OperatorError> {
    Cost::ask_placement(operator, AIM_AT_MIDDLE)
}
