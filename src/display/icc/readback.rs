//! An ICC display profile read back by moxcms and evaluated from its tags: matrix/TRC
//! through moxcms's own curve evaluators, lut16 A2B0 by the lut16Type definition
//! (ICC.1:2010 10.9: input tables, CLUT, output tables) with trilinear interpolation. It
//! tells whether a written profile says what the model says.

use moxcms::{ColorProfile, LutStore, LutWarehouse, ToneCurveEvaluator};

/// Why a profile could not be read back.
#[derive(Debug, thiserror::Error)]
pub enum IccReadError {
    #[error("moxcms cannot parse the profile: {0}")]
    Parse(String),
    #[error("the profile has neither rXYZ/gXYZ/bXYZ with rTRC/gTRC/bTRC nor a lut16 A2B0 tag")]
    NoForward,
    #[error("the profile's {0} is malformed")]
    Malformed(&'static str),
}

/// Device RGB → PCS XYZ of a parsed profile.
pub enum IccForward {
    Matrix {
        /// Columns: rXYZ, gXYZ, bXYZ.
        colorants: [[f64; 3]; 3],
        curves: [Box<dyn ToneCurveEvaluator + Send + Sync>; 3],
    },
    Lut16 {
        input: [Vec<f64>; 3],
        points: usize,
        clut: Vec<[f64; 3]>,
        output: [Vec<f64>; 3],
    },
}

fn table(
    store: &LutStore,
    channels: usize,
    what: &'static str,
) -> Result<Vec<Vec<f64>>, IccReadError> {
    let LutStore::Store16(v) = store else {
        return Err(IccReadError::Malformed(what));
    };
    if v.is_empty() || v.len() % channels != 0 {
        return Err(IccReadError::Malformed(what));
    }
    Ok(v.chunks(v.len() / channels)
        .map(|c| c.iter().map(|&x| x as f64 / 65535.0).collect())
        .collect())
}

/// Linear interpolation in a table over 0–1.
fn interpolate(t: &[f64], x: f64) -> f64 {
    let p = x.clamp(0.0, 1.0) * (t.len() - 1) as f64;
    let i = (p.floor() as usize).min(t.len() - 2);
    let f = p - i as f64;
    t[i] * (1.0 - f) + t[i + 1] * f
}

impl IccForward {
    pub fn parse(bytes: &[u8]) -> Result<IccForward, IccReadError> {
        let p =
            ColorProfile::new_from_slice(bytes).map_err(|e| IccReadError::Parse(e.to_string()))?;
        if let (Some(r), Some(g), Some(b)) = (&p.red_trc, &p.green_trc, &p.blue_trc) {
            let eval = |t: &moxcms::ToneReprCurve| {
                t.make_linear_evaluator()
                    .map_err(|_| IccReadError::Malformed("TRC curve"))
            };
            let col = |x: moxcms::Xyzd| [x.x, x.y, x.z];
            let c = [
                col(p.red_colorant),
                col(p.green_colorant),
                col(p.blue_colorant),
            ];
            return Ok(IccForward::Matrix {
                colorants: std::array::from_fn(|r| std::array::from_fn(|k| c[k][r])),
                curves: [eval(r)?, eval(g)?, eval(b)?],
            });
        }
        let Some(LutWarehouse::Lut(lut)) = &p.lut_a_to_b_perceptual else {
            return Err(IccReadError::NoForward);
        };
        let points = lut.num_clut_grid_points as usize;
        if lut.num_input_channels != 3 || lut.num_output_channels != 3 || points < 2 {
            return Err(IccReadError::Malformed("A2B0 lut16 shape"));
        }
        let input = table(&lut.input_table, 3, "A2B0 input tables")?;
        let output = table(&lut.output_table, 3, "A2B0 output tables")?;
        let flat = table(&lut.clut_table, 1, "A2B0 CLUT")?.remove(0);
        if flat.len() != 3 * points.pow(3) || input.iter().chain(&output).any(|t| t.len() < 2) {
            return Err(IccReadError::Malformed("A2B0 CLUT size"));
        }
        let clut = flat.chunks(3).map(|n| [n[0], n[1], n[2]]).collect();
        let [i0, i1, i2]: [Vec<f64>; 3] = input.try_into().expect("three tables");
        let [o0, o1, o2]: [Vec<f64>; 3] = output.try_into().expect("three tables");
        Ok(IccForward::Lut16 {
            input: [i0, i1, i2],
            points,
            clut,
            output: [o0, o1, o2],
        })
    }

    /// PCS XYZ (D50, white Y = 1) for drive values 0–1.
    pub fn pcs_xyz(&self, rgb: [f64; 3]) -> [f64; 3] {
        match self {
            IccForward::Matrix { colorants, curves } => {
                let lin: [f64; 3] =
                    std::array::from_fn(|c| curves[c].evaluate_value(rgb[c] as f32) as f64);
                std::array::from_fn(|r| (0..3).map(|c| colorants[r][c] * lin[c]).sum())
            }
            IccForward::Lut16 {
                input,
                points,
                clut,
                output,
            } => {
                let n = *points;
                let s: [f64; 3] =
                    std::array::from_fn(|c| interpolate(&input[c], rgb[c]) * (n - 1) as f64);
                let base: [usize; 3] = std::array::from_fn(|c| (s[c].floor() as usize).min(n - 2));
                let f: [f64; 3] = std::array::from_fn(|c| s[c] - base[c] as f64);
                let mut v = [0.0; 3];
                for corner in 0..8 {
                    let mut w = 1.0;
                    let mut idx = 0;
                    for c in 0..3 {
                        let up = (corner >> (2 - c)) & 1;
                        w *= if up == 1 { f[c] } else { 1.0 - f[c] };
                        idx = idx * n + base[c] + up;
                    }
                    for (o, x) in v.iter_mut().zip(clut[idx]) {
                        *o += w * x;
                    }
                }
                std::array::from_fn(|c| interpolate(&output[c], v[c]) * 65535.0 / 32768.0)
            }
        }
    }
}

/// How closely a written profile follows the model: ΔE00 between the profile's PCS XYZ and
/// the model's (adapted the same way), CIELAB relative to D50, over a set of drive values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    pub points: usize,
    pub mean_de00: f64,
    pub max_de00: f64,
}

/// Reads `bytes` back and compares them with `profile`'s model at each drive triple.
pub fn agreement(
    bytes: &[u8],
    profile: &crate::display::Profile,
    drives: &[[f64; 3]],
) -> Result<Agreement, IccReadError> {
    use crate::color::{delta_e2000, Xyz};
    let forward = IccForward::parse(bytes)?;
    let pcs = super::Pcs::new(profile.white_xyz).ok_or(IccReadError::Malformed("white"))?;
    let d50 = Xyz::from_array(super::pcs::D50);
    let (mut sum, mut max) = (0.0, 0.0f64);
    for &rgb in drives {
        let ours = Xyz::from_array(pcs.to_pcs(profile.forward(rgb))).to_lab(d50);
        let theirs = Xyz::from_array(forward.pcs_xyz(rgb)).to_lab(d50);
        let de = delta_e2000(ours, theirs);
        sum += de;
        max = max.max(de);
    }
    Ok(Agreement {
        points: drives.len(),
        mean_de00: sum / drives.len().max(1) as f64,
        max_de00: max,
    })
}
