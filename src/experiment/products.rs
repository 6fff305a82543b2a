//! The files each stage of an experiment writes for later stages, the report or the
//! command: what a stage record must vouch for before the stage is re-used.

use super::cache::Product;
use super::stage::Stage;
use super::{display, display_spots, measure_box, reproduction, simulation, validate};

const fn always(file: &'static str) -> Product {
    Product { file, always: true }
}

const fn sometimes(file: &'static str) -> Product {
    Product {
        file,
        always: false,
    }
}

/// The files of the stage that later stages, the report or the command read: a stage
/// record that does not vouch for each of them is not trusted.
pub fn products(stage: Stage) -> &'static [Product] {
    const BOX: &[Product] = &[
        always(measure_box::SCENE_FILE),
        always(measure_box::SPOTS_FILE),
        sometimes("light.json"),
    ];
    const SIMULATION: &[Product] = &[
        always(simulation::SPOTS_FILE),
        always(simulation::SUMMARY_FILE),
        sometimes(simulation::IMAGE_FILE),
    ];
    const DISPLAY: &[Product] = &[
        always(display::PROFILE_FILE),
        always(display::SETTING_FILE),
        sometimes(display::SUMMARY_FILE),
    ];
    const REPRODUCTION: &[Product] = &[
        always(reproduction::FILE),
        sometimes(reproduction::IMAGE_FILE),
    ];
    const DISPLAY_SPOTS: &[Product] = &[
        always(display_spots::SPOTS_FILE),
        sometimes(display_spots::RECORD_FILE),
    ];
    const VALIDATION: &[Product] = &[always(validate::FILE)];
    match stage {
        Stage::Box => BOX,
        Stage::Simulation => SIMULATION,
        Stage::Display => DISPLAY,
        Stage::Reproduction => REPRODUCTION,
        Stage::DisplaySpots => DISPLAY_SPOTS,
        Stage::Validation => VALIDATION,
    }
}
