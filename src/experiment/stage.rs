//! The stages of an experiment, by name.

use serde::Serialize;

use super::cache::Product;
use super::{box_stage, display, display_spots, reproduction, simulation, validate};

const fn always(file: &'static str) -> Product {
    Product { file, always: true }
}

const fn sometimes(file: &'static str) -> Product {
    Product {
        file,
        always: false,
    }
}

/// The stages, in the order they run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Stage {
    Box,
    Simulation,
    Display,
    Reproduction,
    DisplaySpots,
    Validation,
}

impl Stage {
    pub const ALL: [Stage; 6] = [
        Stage::Box,
        Stage::Simulation,
        Stage::Display,
        Stage::Reproduction,
        Stage::DisplaySpots,
        Stage::Validation,
    ];

    /// The stage's name and directory.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Box => "box",
            Stage::Simulation => "simulation",
            Stage::Display => "display",
            Stage::Reproduction => "reproduction",
            Stage::DisplaySpots => "display-spots",
            Stage::Validation => "validation",
        }
    }

    /// The files of the stage that later stages, the report or the command read: a stage
    /// record that does not vouch for each of them is not trusted.
    pub fn products(self) -> &'static [Product] {
        const BOX: &[Product] = &[
            always(box_stage::SCENE_FILE),
            always(box_stage::SPOTS_FILE),
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
        match self {
            Stage::Box => BOX,
            Stage::Simulation => SIMULATION,
            Stage::Display => DISPLAY,
            Stage::Reproduction => REPRODUCTION,
            Stage::DisplaySpots => DISPLAY_SPOTS,
            Stage::Validation => VALIDATION,
        }
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Stage {
    type Err = String;
    fn from_str(s: &str) -> Result<Stage, String> {
        Stage::ALL
            .into_iter()
            .find(|st| st.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Stage::ALL.iter().map(|s| s.name()).collect();
                format!("unknown stage '{s}' (stages: {})", names.join(", "))
            })
    }
}
