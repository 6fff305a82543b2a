//! One call from a spectrum to its XYZ, xyY and (when a white is known) CIELAB: what
//! `metamer color xyz` prints.

use crate::{
    illuminant_white_over, radiance_to_xyz, reflectance_to_xyz, summation_range, Lab, ObserverKind,
    Quantity, Spectrum, XyY, Xyz,
};

/// The colorimetry of one spectrum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Description {
    pub xyz: Xyz,
    pub xyy: XyY,
    /// CIELAB against the white used, when one is known.
    pub lab: Option<Lab>,
    /// The reference white of `lab`.
    pub white: Option<Xyz>,
}

/// XYZ, xyY and CIELAB of a spectrum. For a reflectance the white defaults to the
/// illuminant's (the perfect diffuser under it, summed as the reflectance is); for a
/// radiance only `white` gives Lab.
pub fn describe(
    spectrum: &Spectrum,
    quantity: Quantity,
    illuminant: &Spectrum,
    observer: ObserverKind,
    white: Option<Xyz>,
) -> Description {
    let (xyz, default_white) = match quantity {
        // Eq. 8 with K_m holds for irradiance too: W·m⁻²·nm⁻¹ gives illuminance in lux.
        Quantity::Radiance | Quantity::Irradiance => (radiance_to_xyz(spectrum, observer), None),
        Quantity::Reflectance => (
            reflectance_to_xyz(spectrum, illuminant, observer),
            Some(illuminant_white_over(
                illuminant,
                observer,
                summation_range(spectrum),
            )),
        ),
    };
    let white = white.or(default_white);
    Description {
        xyz,
        xyy: xyz.to_xyy(),
        lab: white.map(|w| xyz.to_lab(w)),
        white,
    }
}
