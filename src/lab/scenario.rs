//! Which box the simulated lab measures: the light in the box decides which colours a
//! display can show at all.

use std::str::FromStr;

use serde::Serialize;

/// A named box for the lab.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scenario {
    /// The paper's set-up: the box's light is a display showing white, here the `ips-lcd`
    /// virtual display's white, so every ColorChecker colour in the box lies inside that
    /// display's gamut.
    DisplayWhite,
    /// The box lit by CIE LED-RGB1 (x 0.456, y 0.421): a warm light under which the
    /// saturated oranges, yellows and reds lie outside every virtual display's gamut — what
    /// an out-of-gamut light does to the validation.
    LedRgb1,
}

impl Scenario {
    pub const ALL: [Scenario; 2] = [Scenario::DisplayWhite, Scenario::LedRgb1];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::DisplayWhite => "display-white",
            Scenario::LedRgb1 => "led-rgb1",
        }
    }

    /// The name of its scene among the scenes built into the program.
    pub fn builtin_name(self) -> &'static str {
        match self {
            Scenario::DisplayWhite => "validation-box",
            Scenario::LedRgb1 => "validation-box-led-rgb1",
        }
    }

    /// The scene file, relative to the repository's root.
    pub fn scene(self) -> &'static str {
        match self {
            Scenario::DisplayWhite => "data/scenes/validation-box.json",
            Scenario::LedRgb1 => "data/scenes/validation-box-led-rgb1.json",
        }
    }
}

impl FromStr for Scenario {
    type Err = String;
    fn from_str(s: &str) -> Result<Scenario, String> {
        Scenario::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                let known: Vec<_> = Scenario::ALL.iter().map(|p| p.name()).collect();
                format!("unknown lab scenario '{s}' (known: {})", known.join(", "))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_scenes_exist() {
        for s in Scenario::ALL {
            assert_eq!(s.name().parse::<Scenario>().unwrap(), s);
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(s.scene());
            assert!(path.exists(), "{}", path.display());
        }
        let e = "sodium".parse::<Scenario>().unwrap_err();
        assert_eq!(
            e,
            "unknown lab scenario 'sodium' (known: display-white, led-rgb1)"
        );
    }
}
