//! Opening a screen by the name the command line and the logs use: `window[:N]` (a
//! full-screen window on monitor N) or `virtual[:PRESET]` (a simulated monitor; a preset's
//! name alone, `ips-lcd`, names it too, as `metamer lab --display` takes it).

use super::virtual_display::{Preset, VirtualDisplay};
use super::window::{WindowDisplay, WindowError};
use super::Screen;

/// A screen could not be named or opened.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The text names no backend.
    #[error("unknown display '{spec}': expected window, window:N (monitor number from 0), virtual or virtual:PRESET (presets: {presets})")]
    UnknownSpec { spec: String, presets: String },
    /// The window backend failed.
    #[error(transparent)]
    Window(#[from] WindowError),
}

/// Which screen a display name names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ScreenSpec {
    /// A full-screen window on monitor N (0 = the first the X server lists).
    Window { monitor: usize },
    /// The simulated monitor of the given preset.
    Virtual(Preset),
}

impl ScreenSpec {
    /// Parses `window`, `window:N`, `virtual`, `virtual:PRESET` (`virtual` is `ips-lcd`), and
    /// a preset's name alone (`ips-lcd` is `virtual:ips-lcd`: no other screen has it).
    pub fn parse(spec: &str) -> Result<ScreenSpec, OpenError> {
        let unknown = || OpenError::UnknownSpec {
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
            ("window", None) => Ok(ScreenSpec::Window { monitor: 0 }),
            ("window", Some(n)) => n
                .parse()
                .map(|monitor| ScreenSpec::Window { monitor })
                .map_err(|_| unknown()),
            ("virtual", None) => Ok(ScreenSpec::Virtual(Preset::IpsLcd)),
            ("virtual", Some(p)) => p.parse().map(ScreenSpec::Virtual).map_err(|_| unknown()),
            (p, None) => p.parse().map(ScreenSpec::Virtual).map_err(|_| unknown()),
            _ => Err(unknown()),
        }
    }

    /// The canonical text of this spec (`window` becomes `window:0`).
    pub fn canonical(&self) -> String {
        match self {
            ScreenSpec::Window { monitor } => format!("window:{monitor}"),
            ScreenSpec::Virtual(p) => format!("virtual:{}", p.name()),
        }
    }

    /// Opens the screen (the window backend connects to `$DISPLAY`).
    pub fn open(&self) -> Result<Box<dyn Screen>, OpenError> {
        Ok(match self {
            ScreenSpec::Window { monitor } => Box::new(WindowDisplay::open(None, *monitor)?),
            ScreenSpec::Virtual(p) => Box::new(VirtualDisplay::preset(*p)),
        })
    }
}

impl std::str::FromStr for ScreenSpec {
    type Err = OpenError;
    fn from_str(text: &str) -> Result<ScreenSpec, OpenError> {
        ScreenSpec::parse(text)
    }
}

impl std::fmt::Display for ScreenSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.canonical())
    }
}

/// Written as its canonical text (`virtual:ips-lcd`, `window:0`), the form the stages'
/// files and option hashes have always held.
impl serde::Serialize for ScreenSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.canonical())
    }
}

impl<'de> serde::Deserialize<'de> for ScreenSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<ScreenSpec, D::Error> {
        let text = String::deserialize(d)?;
        ScreenSpec::parse(&text).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_round_trip() {
        assert_eq!(
            ScreenSpec::parse("window").unwrap(),
            ScreenSpec::Window { monitor: 0 }
        );
        assert_eq!(
            ScreenSpec::parse("window:2").unwrap(),
            ScreenSpec::Window { monitor: 2 }
        );
        assert_eq!(
            ScreenSpec::parse("virtual").unwrap(),
            ScreenSpec::Virtual(Preset::IpsLcd)
        );
        for p in Preset::ALL {
            let spec = format!("virtual:{}", p.name());
            assert_eq!(ScreenSpec::parse(&spec).unwrap().canonical(), spec);
        }
        // A preset's name alone is unambiguous: no other screen has it.
        assert_eq!(
            ScreenSpec::parse("wide-gamut-ccfl").unwrap(),
            ScreenSpec::Virtual(Preset::WideGamutCcfl)
        );
        for bad in [
            "",
            "window:",
            "window:x",
            "virtual:oled",
            "screen:1",
            "oled",
        ] {
            let e = ScreenSpec::parse(bad).unwrap_err().to_string();
            assert!(
                e.contains("expected window, window:N") && e.contains("wide-gamut-ccfl"),
                "{bad}: {e}"
            );
        }
    }
}
