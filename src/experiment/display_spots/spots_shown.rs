//! The choice of how the display spots put each patch in front of the meter, apart from
//! the plans that carry it out ([`super::shown`]), so that the measuring plan can name it
//! without depending on them.

use serde::{Deserialize, Serialize};

/// How the display spots put each patch in front of the meter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpotsShown {
    /// The paper's: the reproduced image shown whole, the meter re-aimed at each patch
    /// (a placement per patch).
    #[default]
    Aimed,
    /// The reproduced image shown whole and slid so each patch in turn lies under the
    /// meter, aimed once at the middle of the screen (one placement).
    UnderMeter,
    /// Each patch's drive values over the whole screen: no re-aiming, but without the
    /// picture around the patch (the display's dependence on it is left out).
    FullScreen,
}

impl SpotsShown {
    pub const ALL: [SpotsShown; 3] = [
        SpotsShown::Aimed,
        SpotsShown::UnderMeter,
        SpotsShown::FullScreen,
    ];

    pub fn name(self) -> &'static str {
        match self {
            SpotsShown::Aimed => "aimed",
            SpotsShown::UnderMeter => "under-meter",
            SpotsShown::FullScreen => "full-screen",
        }
    }

    /// What `display-spots.json`'s `shown` and the journal's plan options call what was
    /// shown this way; `image` says whether a reproduced image was there to show.
    pub fn record_name(self, image: bool) -> &'static str {
        match (self, image) {
            (SpotsShown::Aimed, true) => "image",
            (SpotsShown::UnderMeter, true) => "image moved under the meter",
            _ => "patch colours",
        }
    }
}

impl std::fmt::Display for SpotsShown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A way to show the display spots that is not one of [`SpotsShown::ALL`].
#[derive(Debug, thiserror::Error)]
#[error("unknown way to show the display spots '{0}': aimed, under-meter or full-screen")]
pub struct UnknownSpotsShown(pub String);

impl std::str::FromStr for SpotsShown {
    type Err = UnknownSpotsShown;

    fn from_str(s: &str) -> Result<SpotsShown, UnknownSpotsShown> {
        SpotsShown::ALL
            .into_iter()
            .find(|w| w.name() == s)
            .ok_or_else(|| UnknownSpotsShown(s.to_string()))
    }
}
