//! What every display model is: forward (drive RGB 0–1 → absolute XYZ cd/m²) and inverse
//! (XYZ → drive RGB, reporting out-of-gamut targets instead of clipping silently).

use crate::color::Xyz;

/// A target whose channel output (R′, G′, B′ in Eq. 9, normalised so full drive gives 1)
/// lies further than this outside the range that drive values 0–1 produce is out of gamut.
/// It is judged on the output, not on the drive value, because a TRC's inverse magnifies
/// rounding near black (d = v^(1/γ) turns −10⁻⁷ into −7·10⁻⁴ for γ = 2.2); 10⁻⁵ of full
/// output is above float32 image precision and measurement rounding, far below a visible
/// difference.
pub const GAMUT_TOLERANCE: f64 = 1e-5;

/// A display's colorimetric behaviour.
pub trait DisplayModel: Send + Sync {
    fn name(&self) -> &'static str;
    /// Drive values 0–1 → absolute XYZ, cd/m².
    fn forward(&self, rgb: [f64; 3]) -> Xyz;
    /// XYZ → drive values; never clips silently (see [`Inverse`]).
    fn inverse(&self, xyz: Xyz) -> Inverse;
}

/// The drive values for a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inverse {
    /// Clipped to 0..=1.
    pub rgb: [f64; 3],
    /// The model's solution before clipping.
    pub unclipped: [f64; 3],
    /// The target needs a channel output outside what drive values 0–1 give, by more than
    /// [`GAMUT_TOLERANCE`] of full output.
    pub out_of_gamut: bool,
}
