//! Patch display backends (issue 5 item 4): one trait for "show exactly these 8-bit drive
//! values on the measured area", implemented by a real full-screen window on a monitor
//! (`window[:N]`, see [`super::window`]) and by a simulated monitor that the simulated
//! instruments measure (`virtual[:PRESET]`, see [`super::virtual_display`]).

use std::sync::Arc;
use std::time::Duration;

use metamer_drivers::Stimulus;

use super::virtual_display::{Preset, VirtualDisplay};
use super::window::{WindowDisplay, WindowError};

/// Something that shows uniform colour patches in front of an instrument.
pub trait PatchDisplay {
    /// The display as named on the command line and in logs: `virtual:ips-lcd`, `window:0`.
    fn spec(&self) -> String;
    /// A longer human description (monitor name and geometry, preset parameters).
    fn describe(&self) -> String;
    /// Shows the 8-bit drive values `rgb` over the whole measured area. Returns once the
    /// display system has the new colour, which is before a physical panel has settled:
    /// the caller waits [`PatchDisplay::default_settle`] (or the user's choice) before
    /// measuring.
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), PatchDisplayError>;
    /// The wait between showing a patch and measuring it when the user gives none.
    fn default_settle(&self) -> Duration;
    /// Conditions the user should know before measuring (e.g. an active video LUT).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// What a simulated instrument aimed at this display sees, for displays that are
    /// themselves simulated; `None` for real screens.
    fn stimulus(&self) -> Option<Arc<dyn Stimulus>>;
}

/// A patch display could not be opened or could not show a patch.
#[derive(Debug, thiserror::Error)]
pub enum PatchDisplayError {
    /// The `--display` text names no backend.
    #[error("unknown display '{spec}': expected window, window:N (monitor number from 0), virtual or virtual:PRESET (presets: {presets})")]
    UnknownSpec { spec: String, presets: String },
    /// The window backend failed.
    #[error(transparent)]
    Window(#[from] WindowError),
}

/// Which display `--display` names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DisplaySpec {
    /// A full-screen window on monitor N (0 = the first the X server lists).
    Window { monitor: usize },
    /// The simulated monitor of the given preset.
    Virtual(Preset),
}

impl DisplaySpec {
    /// Parses `window`, `window:N`, `virtual`, `virtual:PRESET` (`virtual` is `ips-lcd`).
    pub fn parse(spec: &str) -> Result<DisplaySpec, PatchDisplayError> {
        let unknown = || PatchDisplayError::UnknownSpec {
            spec: spec.to_string(),
            presets: Preset::ALL
                .iter()
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(", "),
        };
        let (kind, arg) = match spec.split_once(':') {
            Some((k, a)) => (k, Some(a)),
            None => (spec, None),
        };
        match (kind, arg) {
            ("window", None) => Ok(DisplaySpec::Window { monitor: 0 }),
            ("window", Some(n)) => n
                .parse()
                .map(|monitor| DisplaySpec::Window { monitor })
                .map_err(|_| unknown()),
            ("virtual", None) => Ok(DisplaySpec::Virtual(Preset::IpsLcd)),
            ("virtual", Some(p)) => p.parse().map(DisplaySpec::Virtual).map_err(|_| unknown()),
            _ => Err(unknown()),
        }
    }

    /// The canonical text of this spec (`window` becomes `window:0`).
    pub fn canonical(&self) -> String {
        match self {
            DisplaySpec::Window { monitor } => format!("window:{monitor}"),
            DisplaySpec::Virtual(p) => format!("virtual:{}", p.name()),
        }
    }

    /// Opens the display (the window backend connects to `$DISPLAY`).
    pub fn open(&self) -> Result<Box<dyn PatchDisplay>, PatchDisplayError> {
        Ok(match self {
            DisplaySpec::Window { monitor } => Box::new(WindowDisplay::open(None, *monitor)?),
            DisplaySpec::Virtual(p) => Box::new(VirtualDisplay::preset(*p)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_round_trip() {
        assert_eq!(
            DisplaySpec::parse("window").unwrap(),
            DisplaySpec::Window { monitor: 0 }
        );
        assert_eq!(
            DisplaySpec::parse("window:2").unwrap(),
            DisplaySpec::Window { monitor: 2 }
        );
        assert_eq!(
            DisplaySpec::parse("virtual").unwrap(),
            DisplaySpec::Virtual(Preset::IpsLcd)
        );
        for p in Preset::ALL {
            let spec = format!("virtual:{}", p.name());
            assert_eq!(DisplaySpec::parse(&spec).unwrap().canonical(), spec);
        }
        for bad in ["", "window:", "window:x", "virtual:oled", "screen:1"] {
            let e = DisplaySpec::parse(bad).unwrap_err().to_string();
            assert!(
                e.contains("expected window, window:N") && e.contains("wide-gamut-ccfl"),
                "{bad}: {e}"
            );
        }
    }
}
