//! What a simulated instrument sees: light from a source in front of it, a surface under its
//! own lamp, its white calibration tile, or nothing at all (the sensor capped). A simulated
//! display or lab changes it from its own thread while the simulated instrument reads it, so
//! one session drives a simulated meter exactly as it drives a real one, calibration
//! positions included.

use std::sync::RwLock;

use metamer_color::{radiance_to_xyz, ObserverKind, Quantity, Spectrum, Xyz};

use crate::DriverError;

/// The light a simulated meter sees when no world is given: 100 cd/m² at the chromaticity
/// of CIE illuminant LED-RGB1 (x, y) = (0.45576, 0.42110), computed from
/// `data/illuminant_led_rgb1.csv` with the CIE 1931 2° observer by `metamer color xyz`
/// (checked by `tests/cs100a_sim.rs`).
pub const DEFAULT_STIMULUS_XYZ: Xyz =
    Xyz::new(108.229_360_132_203_85, 100.0, 29.242_246_576_178_09);

/// Light arriving from a source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// CIE 1931 XYZ in cd/m², for simulations that know only the colour.
    Xyz(Xyz),
    /// Spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹ (tagged [`Quantity::Radiance`]).
    Radiance(Spectrum),
}

impl Light {
    /// CIE 1931 XYZ in cd/m², from the radiance by the colour core (paper Eq. 8) when the
    /// light is spectral.
    pub fn xyz(&self) -> Xyz {
        match self {
            Light::Xyz(xyz) => *xyz,
            Light::Radiance(s) => radiance_to_xyz(s, ObserverKind::Cie1931),
        }
    }

    /// The spectral radiance, where the simulation knows it.
    pub fn radiance(&self) -> Option<&Spectrum> {
        match self {
            Light::Xyz(_) => None,
            Light::Radiance(s) => Some(s),
        }
    }
}

/// What the instrument is aimed at or placed on now.
#[derive(Clone, Debug, PartialEq)]
pub enum View {
    /// A light source (a display patch, a lit scene seen through a spot meter's optics).
    Emissive(Light),
    /// A surface of this reflectance (0–1, tagged [`Quantity::Reflectance`]) lit only by
    /// the instrument's own lamp, as in reflective measurements.
    Surface(Spectrum),
    /// The instrument's own white calibration tile.
    WhiteTile,
    /// The sensor capped: no light at all, as dark calibration needs.
    Capped,
}

impl View {
    /// Light of this CIE 1931 XYZ in cd/m².
    pub fn xyz(xyz: Xyz) -> View {
        View::Emissive(Light::Xyz(xyz))
    }

    /// Light of this spectral radiance; an untagged spectrum is taken as radiance.
    pub fn radiance(spectrum: Spectrum) -> Result<View, DriverError> {
        Ok(View::Emissive(Light::Radiance(tagged(
            spectrum,
            Quantity::Radiance,
        )?)))
    }

    /// A surface of this reflectance under the instrument's lamp; an untagged spectrum is
    /// taken as reflectance.
    pub fn surface(reflectance: Spectrum) -> Result<View, DriverError> {
        Ok(View::Surface(tagged(reflectance, Quantity::Reflectance)?))
    }

    /// The emitted light, None for a surface, the tile or a capped sensor (which give no
    /// light of their own: an instrument without a lamp sees them dark).
    pub fn light(&self) -> Option<&Light> {
        match self {
            View::Emissive(light) => Some(light),
            _ => None,
        }
    }
}

/// A bare XYZ is light of that colour, so code that knows only XYZ stays short.
impl From<Xyz> for View {
    fn from(xyz: Xyz) -> View {
        View::xyz(xyz)
    }
}

/// The array form of [`Xyz`], as tests and literal stimuli write it.
impl From<[f64; 3]> for View {
    fn from(xyz: [f64; 3]) -> View {
        View::xyz(xyz.into())
    }
}

fn tagged(spectrum: Spectrum, want: Quantity) -> Result<Spectrum, DriverError> {
    match spectrum.quantity() {
        None => Ok(spectrum.with_quantity(want)),
        Some(q) if q == want => Ok(spectrum),
        Some(q) => Err(DriverError::Simulation(format!(
            "a {q:?} spectrum was given where a {want:?} spectrum ({}) is needed",
            want.unit()
        ))),
    }
}

/// Everything a simulated instrument could be pointed at; it asks for the [`View`] each
/// time it measures or calibrates.
pub trait World: Send + Sync {
    fn view(&self) -> View;
}

/// A world set from another thread (the simulated lab moving the meter from patch to patch).
#[derive(Debug)]
pub struct SharedWorld {
    view: RwLock<View>,
}

impl SharedWorld {
    pub fn new(view: impl Into<View>) -> SharedWorld {
        SharedWorld {
            view: RwLock::new(view.into()),
        }
    }

    /// What the instrument sees from now on.
    pub fn set(&self, view: impl Into<View>) {
        *self.view.write().unwrap_or_else(|e| e.into_inner()) = view.into();
    }
}

impl World for SharedWorld {
    fn view(&self) -> View {
        self.view.read().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spectral_light_gets_its_xyz_from_the_colour_core() {
        // 1 W·sr⁻¹·m⁻²·nm⁻¹ in a 1 nm line at 555 nm, where ȳ = 1: Y = 683 cd/m².
        let line = Spectrum::new(vec![554.0, 555.0, 556.0], vec![0.0, 1.0, 0.0]).unwrap();
        let view = View::radiance(line).unwrap();
        let xyz = view.light().unwrap().xyz();
        assert!((xyz[1] - 683.0).abs() < 1e-9, "{xyz:?}");
        // x̄(555) = 0.512050 in the CIE 1931 table.
        assert!((xyz[0] / 683.0 - 0.512050).abs() < 1e-5, "{xyz:?}");
        let s = view.light().unwrap().radiance().unwrap();
        assert_eq!(s.quantity(), Some(Quantity::Radiance));
    }

    #[test]
    fn surfaces_tiles_and_caps_emit_nothing_and_tags_are_checked() {
        let grey = Spectrum::constant(380.0, 780.0, 0.5);
        let surface = View::surface(grey.clone()).unwrap();
        assert_eq!(surface.light(), None);
        assert_eq!(View::WhiteTile.light(), None);
        assert_eq!(View::Capped.light(), None);
        let e = View::radiance(grey.with_quantity(Quantity::Reflectance)).unwrap_err();
        assert!(e.to_string().contains("Reflectance spectrum"), "{e}");
    }

    #[test]
    fn a_shared_world_changes_from_another_thread() {
        let world = std::sync::Arc::new(SharedWorld::new([1.0, 2.0, 3.0]));
        let w = world.clone();
        std::thread::spawn(move || w.set(View::Capped))
            .join()
            .unwrap();
        assert_eq!(world.view(), View::Capped);
        world.set([4.0, 5.0, 6.0]);
        assert_eq!(
            world.view().light(),
            Some(&Light::Xyz(Xyz::new(4.0, 5.0, 6.0)))
        );
    }
}
