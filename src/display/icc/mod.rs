//! A fitted display profile as an ICC display profile (class `mntr`, RGB data, XYZ PCS),
//! encoded with the moxcms crate and laid out again ([`layout`]: tags on 4-byte boundaries,
//! the file a multiple of 4 bytes, ICC.1:2010 §7), so colour-managed software can use the
//! characterization.
//!
//! The profile's white is the model's own full drive (R = G = B = 1), as in ArgyllCMS's
//! profiles: PCS values are the model's XYZ divided by that white's luminance and adapted to
//! D50 by Bradford ([`pcs`]), so RGB 1,1,1 is the PCS white exactly and the colorants sum to
//! D50 (readers such as Firefox's qcms refuse a profile whose colorants do not). `chad` holds
//! the adaptation, `lumi` that white's XYZ in cd/m², `wtpt` D50 (version 4) or the white with
//! Y = 1 (version 2.4). Where the fit's white differs from the measured one, a reader's
//! relative colorimetry is relative to the model's white; converted back to absolute XYZ
//! through `chad` and `lumi` it is the model's prediction.
//!
//! The matrix models (XYZ = XYZ₀ + M·TRC(rgb)) become matrix/TRC profiles. ICC has no black
//! offset there, but XYZ₀ = M·k for k = M⁻¹·XYZ₀, so the curves TRC + k with M carry it
//! exactly; each curve is then scaled to end at 1 and its column of M by the same factor.
//! A black outside the primaries' cone (a component of k below 0) cannot be stored in a
//! curve that must stay in 0–1: that component is clipped, and [`IccSummary`] says by how
//! much the profile then departs from the model. The LUT models become A2B0 and B2A0 tags
//! ([`lut`]) — `lutAtoBType` / `lutBtoAType` in version 4, which LittleCMS can save again
//! after reading, `lut16Type` in version 2.4, which has nothing else — plus matrix/TRC tags
//! that approximate the model for readers that use nothing else.
//!
//! `lumi` holds the white's luminance as an s15Fixed16Number (ICC.1:2010 luminanceTag, an
//! XYZType), whose largest value is 32767 + 65535/65536: a brighter white is refused
//! ([`IccError::Luminance`]) rather than clamped, since a reader would take the clamped
//! value for the display's.

mod encode;
pub mod layout;
mod lut;
pub mod pcs;
mod readback;
mod v2;

use moxcms::{
    ColorProfile, DataColorSpace, Matrix3d, ProfileClass, ProfileText, RenderingIntent,
    ToneReprCurve, Xyzd,
};

use super::model::ModelParams;
use super::profile::Profile;
use crate::color::Xyz;
use encode::{unit_u16, CURVE_ENTRIES};
pub use encode::{IccError, MAX_S15_FIXED16};
pub use pcs::Pcs;
pub use readback::{agreement, inverse_agreement, Agreement, IccForward, IccInverse, IccReadError};

const COPYRIGHT: &str = "No copyright: measured data, use freely";

/// The ICC version to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IccVersion {
    /// ICC.1:2010 (version 4.3), text as `multiLocalizedUnicodeType`.
    V4,
    /// ICC.1:2001-04 (version 2.4), for software that reads only version 2; text as
    /// `textDescriptionType` / `textType`.
    V2_4,
}

impl std::str::FromStr for IccVersion {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "4" | "4.3" | "v4" => Ok(IccVersion::V4),
            "2" | "2.4" | "v2" | "v2.4" => Ok(IccVersion::V2_4),
            other => Err(format!("unknown ICC version '{other}' (known: 4, 2.4)")),
        }
    }
}

impl std::fmt::Display for IccVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            IccVersion::V4 => "4.3",
            IccVersion::V2_4 => "2.4",
        })
    }
}

/// What was written and how well it represents the model.
#[derive(Clone, Debug)]
pub struct IccSummary {
    pub version: IccVersion,
    /// "matrix/TRC", "lutAtoB A2B0, lutBtoA B2A0 + matrix/TRC" (version 4) or "lut16
    /// A2B0/B2A0 + matrix/TRC" (version 2.4).
    pub form: &'static str,
    /// The curves' black components that had to be clipped at 0 (R, G, B; PCS Y units),
    /// zero when the black lies inside the primaries' cone.
    pub clipped_black: [f64; 3],
}

/// The encoded profile and its summary.
#[derive(Clone, Debug)]
pub struct IccProfile {
    pub bytes: Vec<u8>,
    pub summary: IccSummary,
}

/// The white of a profile's ICC form: the model at full drive, cd/m².
pub fn icc_white(profile: &Profile) -> Xyz {
    profile.forward([1.0; 3])
}

/// The PCS of a profile's ICC form: its white ([`icc_white`]) adapted to D50.
pub fn profile_pcs(profile: &Profile) -> Result<Pcs, IccError> {
    let white = icc_white(profile);
    Pcs::new(white).ok_or(IccError::White(white.y))
}

/// Encodes `profile` as an ICC display profile; `description` becomes its `desc` tag.
pub fn encode_icc(
    profile: &Profile,
    version: IccVersion,
    description: &str,
) -> Result<IccProfile, IccError> {
    let pcs = profile_pcs(profile)?;
    let white = icc_white(profile);
    if let Some(&v) = white.to_array().iter().find(|&&v| v > MAX_S15_FIXED16) {
        return Err(IccError::Luminance { value: v });
    }
    let mut icc = ColorProfile::default();
    icc.profile_class = ProfileClass::DisplayDevice;
    icc.color_space = DataColorSpace::Rgb;
    icc.pcs = DataColorSpace::Xyz;
    icc.rendering_intent = RenderingIntent::Perceptual;
    icc.white_point = xyzd(pcs::D50);
    icc.media_white_point = Some(xyzd(match version {
        IccVersion::V4 => pcs::D50,
        IccVersion::V2_4 => white.map(|v| v / white.y),
    }));
    icc.chromatic_adaptation = Some(Matrix3d { v: pcs.chad });
    icc.luminance = Some(xyzd(white));
    icc.description = Some(ProfileText::PlainString(description.to_string()));
    icc.copyright = Some(ProfileText::PlainString(COPYRIGHT.to_string()));
    let (form, clipped_black) = match &profile.parameters {
        ModelParams::MatrixTrc(m) => {
            let curves = std::array::from_fn(|c| {
                (0..CURVE_ENTRIES)
                    .map(|i| m.trc[c].eval(i as f64 / (CURVE_ENTRIES - 1) as f64))
                    .collect()
            });
            let clipped = matrix_trc(&mut icc, &m.matrix, m.black, curves, &pcs)?;
            ("matrix/TRC", clipped)
        }
        ModelParams::Lut(l) => {
            let (a2b, b2a) = (lut::a2b(l, &pcs), lut::b2a(l, &pcs)?);
            let form = match version {
                IccVersion::V4 => {
                    icc.lut_a_to_b_perceptual = Some(a2b.a_to_b());
                    icc.lut_b_to_a_perceptual = Some(b2a.b_to_a());
                    "lutAtoB A2B0, lutBtoA B2A0 + matrix/TRC"
                }
                IccVersion::V2_4 => {
                    icc.lut_a_to_b_perceptual = Some(a2b.lut16());
                    icc.lut_b_to_a_perceptual = Some(b2a.lut16());
                    "lut16 A2B0/B2A0 + matrix/TRC"
                }
            };
            let (matrix, black, curves) = lut::matrix_approximation(l);
            matrix_trc(&mut icc, &matrix, black, curves, &pcs)?;
            (form, [0.0; 3])
        }
    };
    let bytes = icc.encode().map_err(|e| IccError::Encode(e.to_string()))?;
    let bytes = match version {
        // The encoder stamps the newest version it knows (4.4); the tags written are those of
        // ICC.1:2010 (4.3), which more readers accept.
        IccVersion::V4 => layout::relayout(&bytes, 0x0430_0000, |_| None),
        IccVersion::V2_4 => v2::to_version_2(&bytes, description, COPYRIGHT),
    }
    .map_err(IccError::Encode)?;
    Ok(IccProfile {
        bytes,
        summary: IccSummary {
            version,
            form,
            clipped_black,
        },
    })
}

fn xyzd(v: Xyz) -> Xyzd {
    Xyzd {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

const CHANNELS: [&str; 3] = ["red", "green", "blue"];

/// Sets colorants and curves for XYZ = black + matrix·curve(rgb) (absolute XYZ, curves 0 at
/// drive 0 and 1 at full drive, sampled at `CURVE_ENTRIES` drives); returns the clipped black
/// components.
fn matrix_trc(
    icc: &mut ColorProfile,
    matrix: &pcs::Mat3,
    black: Xyz,
    curves: [Vec<f64>; 3],
    pcs: &Pcs,
) -> Result<[f64; 3], IccError> {
    // Everything in PCS units: M_p = to_pcs·M, black_p = to_pcs·XYZ₀.
    let mp = pcs::mat_mul(pcs.matrix(), matrix);
    let black_p = pcs.to_pcs(black);
    let k = pcs::mul(&pcs::inverse(&mp).ok_or(IccError::Singular)?, black_p);
    let mut clipped = [0.0; 3];
    let mut trcs: Vec<ToneReprCurve> = Vec::with_capacity(3);
    let mut columns = [[0.0; 3]; 3];
    for (c, curve) in curves.iter().enumerate() {
        let u: Vec<f64> = curve.iter().map(|v| v + k[c]).collect();
        let scale = u.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(IccError::DeadChannel {
                channel: CHANNELS[c],
            });
        }
        let lowest = u.iter().copied().fold(f64::INFINITY, f64::min);
        if lowest < 0.0 {
            clipped[c] = -lowest * mp[1][c];
        }
        trcs.push(ToneReprCurve::Lut(
            u.iter().map(|&v| unit_u16(v / scale)).collect(),
        ));
        columns[c] = std::array::from_fn(|r| mp[r][c] * scale);
    }
    icc.red_colorant = xyzd(columns[0].into());
    icc.green_colorant = xyzd(columns[1].into());
    icc.blue_colorant = xyzd(columns[2].into());
    let mut trcs = trcs.into_iter();
    icc.red_trc = trcs.next();
    icc.green_trc = trcs.next();
    icc.blue_trc = trcs.next();
    Ok(clipped)
}
