//! A fitted display profile as an ICC display profile (class `mntr`, RGB data, XYZ PCS),
//! encoded with the moxcms crate, so colour-managed software can use the characterization.
//!
//! The matrix models (XYZ = XYZ₀ + M·TRC(rgb)) become matrix/TRC profiles. ICC has no black
//! offset there, but XYZ₀ = M·k for k = M⁻¹·XYZ₀, so the curves TRC + k with M carry it
//! exactly; each curve is then scaled to end at 1 and its column of M by the same factor.
//! A black outside the primaries' cone (a component of k below 0) cannot be stored in a
//! curve that must stay in 0–1: that component is clipped, and [`IccSummary`] says by how
//! much the profile then departs from the model. The LUT models become `lut16Type` A2B0
//! (the model sampled on a 33³ grid in the axes of its shapers) and B2A0 (the model's
//! inverse, clipped to the drive cube, on a 33³ grid in cube roots of PCS XYZ) tags, which
//! both ICC versions accept.
//!
//! PCS values are the model's XYZ divided by the white's luminance and adapted to D50 by
//! Bradford ([`pcs`]): relative colorimetry. `chad` holds that adaptation, `lumi` the
//! white's absolute XYZ in cd/m², `wtpt` D50 (version 4) or the display white with Y = 1
//! (version 2.4).

pub mod pcs;
mod readback;
mod v2;

use moxcms::{
    ColorProfile, DataColorSpace, LutDataType, LutStore, LutType, LutWarehouse, Matrix3d,
    ProfileClass, ProfileText, RenderingIntent, ToneReprCurve, Xyzd,
};

use super::model::{DisplayModel, Lut3d, MatrixTrc, ModelParams};
use super::profile::Profile;
pub use pcs::Pcs;
pub use readback::{agreement, Agreement, IccForward, IccReadError};

/// Entries of each matrix/TRC curve and of each lut16 input table: with linear
/// interpolation between them a γ 2.2 curve is off by < 10⁻⁷ of full output.
const CURVE_ENTRIES: usize = 4096;
/// CLUT nodes per axis of A2B0 and B2A0.
const CLUT_POINTS: usize = 33;
/// B2A0's input covers PCS XYZ up to this multiple of D50, so colours a little brighter
/// than the white still find the nearest node instead of the clipped end.
const B2A_HEADROOM: f64 = 1.1;

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
    #[error("the ICC encoder refused the profile: {0}")]
    Encode(String),
}

/// What was written and how well it represents the model.
#[derive(Clone, Debug)]
pub struct IccSummary {
    pub version: IccVersion,
    /// "matrix/TRC" or "lut16 A2B0/B2A0".
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

/// The PCS of a profile: its white adapted to D50.
pub fn profile_pcs(profile: &Profile) -> Result<Pcs, IccError> {
    Pcs::new(profile.white_xyz).ok_or(IccError::White(profile.white_xyz[1]))
}

/// Encodes `profile` as an ICC display profile; `description` becomes its `desc` tag.
pub fn encode_icc(
    profile: &Profile,
    version: IccVersion,
    description: &str,
) -> Result<IccProfile, IccError> {
    let pcs = profile_pcs(profile)?;
    let white = profile.white_xyz;
    let mut icc = ColorProfile::default();
    icc.profile_class = ProfileClass::DisplayDevice;
    icc.color_space = DataColorSpace::Rgb;
    icc.pcs = DataColorSpace::Xyz;
    icc.rendering_intent = RenderingIntent::Perceptual;
    icc.white_point = xyzd(pcs::D50);
    icc.media_white_point = Some(xyzd(match version {
        IccVersion::V4 => pcs::D50,
        IccVersion::V2_4 => white.map(|v| v / white[1]),
    }));
    icc.chromatic_adaptation = Some(Matrix3d { v: pcs.chad });
    icc.luminance = Some(xyzd(white));
    icc.description = Some(ProfileText::PlainString(description.to_string()));
    icc.copyright = Some(ProfileText::PlainString(COPYRIGHT.to_string()));
    let (form, clipped_black) = match &profile.parameters {
        ModelParams::MatrixTrc(m) => {
            let clipped = matrix_trc(&mut icc, m, &pcs)?;
            ("matrix/TRC", clipped)
        }
        ModelParams::Lut(l) => {
            icc.lut_a_to_b_perceptual = Some(a2b(l, &pcs));
            icc.lut_b_to_a_perceptual = Some(b2a(l, &pcs));
            ("lut16 A2B0/B2A0", [0.0; 3])
        }
    };
    let bytes = icc.encode().map_err(|e| IccError::Encode(e.to_string()))?;
    let bytes = match version {
        // The encoder stamps the newest version it knows (4.4); the tags written are those of
        // ICC.1:2010 (4.3), which more readers accept.
        IccVersion::V4 => {
            let mut bytes = bytes;
            bytes[8..12].copy_from_slice(&0x0430_0000u32.to_be_bytes());
            bytes
        }
        IccVersion::V2_4 => {
            v2::to_version_2(&bytes, description, COPYRIGHT).map_err(IccError::Encode)?
        }
    };
    Ok(IccProfile {
        bytes,
        summary: IccSummary {
            version,
            form,
            clipped_black,
        },
    })
}

fn xyzd(v: [f64; 3]) -> Xyzd {
    Xyzd {
        x: v[0],
        y: v[1],
        z: v[2],
    }
}

const CHANNELS: [&str; 3] = ["red", "green", "blue"];

/// Sets colorants and curves; returns the clipped black components.
fn matrix_trc(icc: &mut ColorProfile, m: &MatrixTrc, pcs: &Pcs) -> Result<[f64; 3], IccError> {
    // Everything in PCS units: M_p = to_pcs·M, black_p = to_pcs·XYZ₀.
    let mp = pcs::mat_mul(pcs.matrix(), &m.matrix);
    let black_p = pcs.to_pcs(m.black);
    let k = pcs::mul(&pcs::inverse(&mp).ok_or(IccError::Singular)?, black_p);
    let mut clipped = [0.0; 3];
    let mut curves: Vec<ToneReprCurve> = Vec::with_capacity(3);
    let mut columns = [[0.0; 3]; 3];
    for c in 0..3 {
        let u: Vec<f64> = (0..CURVE_ENTRIES)
            .map(|i| m.trc[c].eval(i as f64 / (CURVE_ENTRIES - 1) as f64) + k[c])
            .collect();
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
        curves.push(ToneReprCurve::Lut(
            u.iter().map(|&v| unit_u16(v / scale)).collect(),
        ));
        columns[c] = std::array::from_fn(|r| mp[r][c] * scale);
    }
    icc.red_colorant = xyzd(columns[0]);
    icc.green_colorant = xyzd(columns[1]);
    icc.blue_colorant = xyzd(columns[2]);
    let mut curves = curves.into_iter();
    icc.red_trc = curves.next();
    icc.green_trc = curves.next();
    icc.blue_trc = curves.next();
    Ok(clipped)
}

/// 0–1 as a 16-bit fraction (curveType, lut16 tables and device values).
fn unit_u16(v: f64) -> u16 {
    (v.clamp(0.0, 1.0) * 65535.0).round() as u16
}

/// PCS XYZ in the 16-bit encoding of lut16Type: 1.0 is 0x8000 (ICC.1:2010 Table 12 and
/// 10.9).
fn xyz_u16(v: f64) -> u16 {
    (v * 32768.0).round().clamp(0.0, 65535.0) as u16
}

/// The LUT's shaper of channel `c` as 0–1 over drive 0–1, and its inverse.
struct Axis<'a> {
    lut: &'a Lut3d,
    c: usize,
    lo: f64,
    span: f64,
}

impl<'a> Axis<'a> {
    fn new(lut: &'a Lut3d, c: usize) -> Axis<'a> {
        let lo = lut.shaper[c].eval(0.0);
        Axis {
            lut,
            c,
            lo,
            span: lut.shaper[c].eval(1.0) - lo,
        }
    }
    fn forward(&self, d: f64) -> f64 {
        (self.lut.shaper[self.c].eval(d) - self.lo) / self.span
    }
    fn drive(&self, s: f64) -> f64 {
        self.lut.shaper[self.c]
            .inverse(self.lo + s * self.span)
            .clamp(0.0, 1.0)
    }
}

fn lut16(input: Vec<u16>, clut: Vec<u16>) -> LutWarehouse {
    LutWarehouse::Lut(LutDataType {
        num_input_channels: 3,
        num_output_channels: 3,
        num_clut_grid_points: CLUT_POINTS as u8,
        matrix: Matrix3d::IDENTITY,
        num_input_table_entries: CURVE_ENTRIES as u16,
        num_output_table_entries: 2,
        input_table: LutStore::Store16(input),
        clut_table: LutStore::Store16(clut),
        output_table: LutStore::Store16([0, 65535].repeat(3)),
        lut_type: LutType::Lut16,
    })
}

/// Grid node `i` of `CLUT_POINTS` as 0–1.
fn node(i: usize) -> f64 {
    i as f64 / (CLUT_POINTS - 1) as f64
}

/// A2B0: input tables are the LUT's shapers, so the CLUT nodes sit where the model is
/// close to linear; each node holds the model's PCS XYZ at the drive under it.
fn a2b(lut: &Lut3d, pcs: &Pcs) -> LutWarehouse {
    let axes: [Axis; 3] = std::array::from_fn(|c| Axis::new(lut, c));
    let mut input = Vec::with_capacity(3 * CURVE_ENTRIES);
    for axis in &axes {
        input.extend(
            (0..CURVE_ENTRIES)
                .map(|i| unit_u16(axis.forward(i as f64 / (CURVE_ENTRIES - 1) as f64))),
        );
    }
    let drives: [Vec<f64>; 3] =
        std::array::from_fn(|c| (0..CLUT_POINTS).map(|i| axes[c].drive(node(i))).collect());
    let mut clut = Vec::with_capacity(3 * CLUT_POINTS.pow(3));
    for &r in &drives[0] {
        for &g in &drives[1] {
            for &b in &drives[2] {
                clut.extend(pcs.to_pcs(lut.forward([r, g, b])).map(xyz_u16));
            }
        }
    }
    lut16(input, clut)
}

/// B2A0: input tables take each PCS component to the cube root of its share of
/// `B2A_HEADROOM`·D50 (nodes dense near black, where the eye is most sensitive); each
/// node holds the model's inverse, clipped to the drive cube.
fn b2a(lut: &Lut3d, pcs: &Pcs) -> LutWarehouse {
    let mut input = Vec::with_capacity(3 * CURVE_ENTRIES);
    for c in 0..3 {
        let full = B2A_HEADROOM * pcs::D50[c];
        input.extend((0..CURVE_ENTRIES).map(|i| {
            let x = i as f64 / (CURVE_ENTRIES - 1) as f64 * 65535.0 / 32768.0;
            unit_u16((x / full).min(1.0).cbrt())
        }));
    }
    let value = |c: usize, i: usize| B2A_HEADROOM * pcs::D50[c] * node(i).powi(3);
    let mut clut = Vec::with_capacity(3 * CLUT_POINTS.pow(3));
    for i in 0..CLUT_POINTS {
        for j in 0..CLUT_POINTS {
            for k in 0..CLUT_POINTS {
                let xyz = pcs.from_pcs([value(0, i), value(1, j), value(2, k)]);
                clut.extend(lut.inverse(xyz).rgb.map(unit_u16));
            }
        }
    }
    lut16(input, clut)
}
