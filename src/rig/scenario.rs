//! The light in the simulated box: it decides which colours a display can show at all, so
//! every simulated chain (`lab`, `experiment`, `measure-box` on simulated instruments)
//! names it the same way.

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::color::{Illuminant, Spectrum};
use crate::rig::{Preset, VirtualPanel};

/// A named light for the simulated box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scenario {
    /// The paper's set-up: the box's light is a display showing white, here the `ips-lcd`
    /// virtual display's white (`data/display_white_ips_lcd.csv`), so the ColorChecker
    /// colours in the box lie inside that display's gamut.
    #[default]
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

    /// The nominal scene of the same box under this light, relative to the repository's
    /// root.
    pub fn scene(self) -> &'static str {
        match self {
            Scenario::DisplayWhite => "data/scenes/validation-box.json",
            Scenario::LedRgb1 => "data/scenes/validation-box-led-rgb1.json",
        }
    }

    /// The light's spectral radiance, in arbitrary units (callers scale it).
    pub fn spectrum(self) -> Spectrum {
        match self {
            Scenario::DisplayWhite => VirtualPanel::preset(Preset::IpsLcd).spectrum([255; 3]),
            Scenario::LedRgb1 => Illuminant::LedRgb1.spectrum(),
        }
    }
}

impl std::fmt::Display for Scenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
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
                format!("unknown box light '{s}' (known: {})", known.join(", "))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::{radiance_to_xyz, ObserverKind};

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
            "unknown box light 'sodium' (known: display-white, led-rgb1)"
        );
    }

    /// Each light has the chromaticity its source gives: the ips-lcd preset's white
    /// (0.3100, 0.3260) and LED-RGB1's (0.4557, 0.4211, CIE 015:2018).
    #[test]
    fn the_lights_have_their_published_chromaticities() {
        for (s, x, y, tol) in [
            (Scenario::DisplayWhite, 0.3100, 0.3260, 1e-4),
            (Scenario::LedRgb1, 0.4557, 0.4211, 5e-4),
        ] {
            let xyy = radiance_to_xyz(&s.spectrum(), ObserverKind::Cie1931).to_xyy();
            assert!(
                (xyy.x - x).abs() < tol && (xyy.y - y).abs() < tol,
                "{s}: {xyy:?}"
            );
        }
    }
}
