//! The stages of an experiment, by name.

use serde::Serialize;

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

    /// Whether the stage takes readings in a journalled session: whose directory is moved
    /// aside, never cleared, when its inputs change, and which resumes after Ctrl-C.
    pub fn measures(self) -> bool {
        matches!(self, Stage::Box | Stage::Display | Stage::DisplaySpots)
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
