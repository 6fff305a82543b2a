//! What the profile writers share: the error, the curve size and the 16-bit encodings.

/// Entries of each matrix/TRC curve and of each lut16 input table: with linear
/// interpolation between them a γ 2.2 curve is off by < 10⁻⁷ of full output.
pub(super) const CURVE_ENTRIES: usize = 4096;

/// Why an ICC profile could not be made or written.
#[derive(Debug, thiserror::Error)]
pub enum IccError {
    #[error(
        "the display white has no positive luminance (Y = {0}): an ICC profile is relative to it"
    )]
    White(f64),
    #[error(
        "the {channel} channel gives no output at full drive: its ICC curve cannot be normalised"
    )]
    DeadChannel { channel: &'static str },
    #[error(
        "the model's matrix cannot be inverted, so its black offset cannot be put into the curves"
    )]
    Singular,
    /// A white brighter than the luminance tag can hold.
    #[error(
        "the display white's XYZ has a component of {value} cd/m², more than the \
         {MAX_S15_FIXED16} cd/m² the ICC luminance tag can hold (an s15Fixed16Number): \
         the profile would state a dimmer display than the one measured"
    )]
    Luminance { value: f64 },
    #[error("the ICC encoder refused the profile: {0}")]
    Encode(String),
}

/// The largest s15Fixed16Number, 32767 + 65535/65536 (ICC.1:2010 basic number types):
/// the ceiling of every XYZNumber, `lumi`'s among them.
pub const MAX_S15_FIXED16: f64 = 32767.0 + 65535.0 / 65536.0;

/// 0–1 as a 16-bit fraction (curveType, lut16 tables and device values).
pub(super) fn unit_u16(v: f64) -> u16 {
    (v.clamp(0.0, 1.0) * 65535.0).round() as u16
}

/// PCS XYZ in the 16-bit encoding of lut16Type: 1.0 is 0x8000 (ICC.1:2010 Table 12 and
/// 10.9).
pub(super) fn xyz_u16(v: f64) -> u16 {
    (v * 32768.0).round().clamp(0.0, 65535.0) as u16
}
