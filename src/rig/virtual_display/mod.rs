//! A simulated monitor for characterizing without hardware: it shows 8-bit
//! drive values and the simulated instruments measure what it emits through the drivers'
//! [`World`](metamer_drivers::World) trait (`open_instrument("sim:cs100a", Some(display.stimulus()))`).
//! It emits a spectrum ([`spectral`]: each channel's emission from the physics of the
//! panel's type), so a simulated spectrometer sees the spectrum and a simulated colorimeter
//! its CIE 1931 XYZ.
//!
//! The light model is built to break the PLCC model of the paper (Eq. 9) the way real
//! panels do, one fault at a time ([`panel`]):
//! - the emitted light is black plus one term per channel, `K + Σ_c L_c(v'_c)`;
//! - black `K` has its own chromaticity (LCD backlight leakage is bluish, not white);
//! - each channel's tone response (TRC) is a blend of a power law and a normalised
//!   logistic, so no single exponent fits it ([`PanelTrc`]);
//! - a channel's chromaticity drifts with its level, `xy_c(L) = xy_c + d_c (1 − L)`, where
//!   `L` is the channel's normalised luminance (at full drive it is exactly the primary);
//! - crosstalk: the effective drive of channel `c` is `v'_c = v_c + Σ_{d≠c} k_cd v_d (1 − v_c)`
//!   (1–3 % on the LCD presets): a driven channel leaks into its neighbours, so a
//!   "primary" carries a little of the others and mixtures are not additive, while full
//!   white is unaffected;
//! - drive values are quantised to 8 bits like a real 8-bit display.
//!
//! The channel maxima are solved so that full white has the preset's chromaticity and
//! luminance exactly (white = K + Σ_c P_c, with P_c the channels' terms at full drive).
//!
//! `ideal-crt` satisfies PLCC exactly (additive, constant chromaticity, power-law TRC,
//! small black); `ips-lcd` has moderate faults; `wide-gamut-ccfl` has wide primaries and
//! stronger drift and crosstalk ([`presets`]).

mod panel;
mod presets;
pub mod spectral;
#[cfg(test)]
mod tests;

use std::sync::{Arc, RwLock};
use std::time::Duration;

use metamer_drivers::{Light, View, World};

pub use panel::{quantize, VirtualPanel};
pub use presets::{PanelParams, PanelTrc, Preset};

use super::{MeterAim, Placement, Screen, ScreenError};
use crate::image::{Drive8Image, ScreenSpot};

/// What the panel shows: one colour everywhere, or an image filling the screen.
#[derive(Clone)]
enum Shown {
    Colour([u8; 3]),
    Image(Arc<Drive8Image>),
}

/// The panel plus what it shows now and where the meter looks; this is what a simulated
/// meter looks at.
struct LitPanel {
    panel: VirtualPanel,
    shown: RwLock<Shown>,
    aim: MeterAim,
}

/// The image last given to `show_image` and the slide it is shown at now, so a slide is
/// made from the image as given, never from one already slid.
#[derive(Default)]
struct Given {
    image: Option<Arc<Drive8Image>>,
    by: [i64; 2],
}

impl World for LitPanel {
    fn view(&self) -> View {
        let shown = self.shown.read().unwrap_or_else(|e| e.into_inner()).clone();
        let spectrum = match shown {
            Shown::Colour(rgb) => self.panel.spectrum(rgb),
            // The meter's spot averages the light of every pixel inside it; the panel's
            // response is not linear in the drive values, so spectra are averaged, not
            // drive values.
            Shown::Image(img) => {
                let counts = img.colours_in(self.aim.get());
                if counts.is_empty() {
                    self.panel.spectrum([0; 3])
                } else {
                    self.panel.mean_spectrum(&counts)
                }
            }
        };
        View::Emissive(Light::Radiance(spectrum))
    }
}

/// A simulated monitor as a [`Screen`]; it starts black. An image is shown pixel for pixel
/// over the whole screen (the simulated screen takes the image's size).
pub struct VirtualDisplay {
    lit: Arc<LitPanel>,
    given: Given,
}

impl VirtualDisplay {
    pub fn new(panel: VirtualPanel) -> VirtualDisplay {
        VirtualDisplay {
            lit: Arc::new(LitPanel {
                panel,
                shown: RwLock::new(Shown::Colour([0; 3])),
                aim: MeterAim::default(),
            }),
            given: Given::default(),
        }
    }

    pub fn preset(preset: Preset) -> VirtualDisplay {
        VirtualDisplay::new(VirtualPanel::preset(preset))
    }

    /// The same display with full white at `cd_m2` (see [`VirtualPanel::with_white_luminance`]).
    pub fn with_white_luminance(self, cd_m2: f64) -> VirtualDisplay {
        VirtualDisplay::new(self.lit.panel.with_white_luminance(cd_m2))
    }

    pub fn panel(&self) -> &VirtualPanel {
        &self.lit.panel
    }

    /// The drive values shown now: the colour, or the image's pixel under the meter's aim
    /// (its centre when not aimed).
    pub fn shown(&self) -> [u8; 3] {
        match &*self.lit.shown.read().unwrap_or_else(|e| e.into_inner()) {
            Shown::Colour(rgb) => *rgb,
            Shown::Image(img) => {
                let s = self.lit.aim.get().unwrap_or(ScreenSpot {
                    x: 0.5,
                    y: 0.5,
                    radius: 0.0,
                });
                let px = ((s.x * img.width as f64) as usize).min(img.width - 1);
                let py = ((s.y * img.height as f64) as usize).min(img.height - 1);
                img.at(px, py)
            }
        }
    }
}

impl Screen for VirtualDisplay {
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), ScreenError> {
        *self.lit.shown.write().unwrap_or_else(|e| e.into_inner()) = Shown::Colour(rgb);
        Ok(())
    }

    fn expected_cd_m2(&self, rgb: [u8; 3]) -> Option<f64> {
        Some(self.lit.panel.xyz(rgb).y)
    }

    fn spec(&self) -> String {
        format!("virtual:{}", self.lit.panel.name())
    }

    fn describe(&self) -> String {
        let p = self.lit.panel.params();
        format!(
            "simulated monitor '{}': white {:.1} cd/m² at x {:.4} y {:.4}, black {:.3} cd/m²",
            self.lit.panel.name(),
            p.white_cd_m2,
            p.white_xy[0],
            p.white_xy[1],
            p.black_cd_m2
        )
    }

    fn show_image(&mut self, image: &Drive8Image) -> Result<Placement, ScreenError> {
        let image = Arc::new(image.clone());
        self.given = Given {
            image: Some(image.clone()),
            by: [0, 0],
        };
        *self.lit.shown.write().unwrap_or_else(|e| e.into_inner()) = Shown::Image(image);
        Ok(Placement::WHOLE)
    }

    fn shift_image(&mut self, by: [i64; 2]) -> Result<(), ScreenError> {
        let Some(image) = &self.given.image else {
            return Err(ScreenError::NoImage {
                screen: self.spec(),
            });
        };
        let shown = self
            .lit
            .shown
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .clone();
        // Repeated readings of one spot slide by the same amount: nothing to redo.
        if self.given.by == by && matches!(shown, Shown::Image(_)) {
            return Ok(());
        }
        let slid = Arc::new(image.shifted(by));
        self.given.by = by;
        *self.lit.shown.write().unwrap_or_else(|e| e.into_inner()) = Shown::Image(slid);
        Ok(())
    }

    /// The simulated panel changes instantly.
    fn default_settle(&self) -> Duration {
        Duration::ZERO
    }

    fn stimulus(&self) -> Option<Arc<dyn World>> {
        Some(self.lit.clone())
    }

    fn meter_aim(&self) -> Option<MeterAim> {
        Some(self.lit.aim.clone())
    }
}
