//! An ICC display profile read back by moxcms and evaluated from its tags: matrix/TRC
//! through moxcms's own curve evaluators, A2B0 and B2A0 by the lut16Type definition
//! (ICC.1:2010 10.9: matrix for XYZ input, input tables, CLUT, output tables) with
//! tetrahedral interpolation in the CLUT, as LittleCMS interpolates three inputs. The
//! lutAtoB / lutBtoA tags of a version 4 profile are read as the same stages in their own
//! order (10.10: A curves, CLUT, B curves; 10.11: B curves, matrix, M curves, CLUT, A
//! curves), in the forms this program writes (identity where lut16 has no stage). It tells
//! whether a written profile says what the model says.

use crate::color::Xyz;
use moxcms::{
    ColorProfile, LutDataType, LutMultidimensionalType, LutStore, LutWarehouse, ToneCurveEvaluator,
    ToneReprCurve,
};

/// Why a profile could not be read back.
#[derive(Debug, thiserror::Error)]
pub enum IccReadError {
    #[error("moxcms cannot parse the profile: {0}")]
    Parse(String),
    #[error("the profile has neither rXYZ/gXYZ/bXYZ with rTRC/gTRC/bTRC nor an A2B0 tag")]
    NoForward,
    #[error("the profile has no B2A0 tag")]
    NoInverse,
    #[error("the profile's {0} is malformed")]
    Malformed(&'static str),
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

/// Three `curveType` curves as tables over 0–1 (an empty curve is the identity).
fn curve_tables(
    curves: &[ToneReprCurve],
    what: &'static str,
) -> Result<[Vec<f64>; 3], IccReadError> {
    let table = |c: &ToneReprCurve| match c {
        ToneReprCurve::Lut(v) if v.is_empty() => Ok(vec![0.0, 1.0]),
        ToneReprCurve::Lut(v) if v.len() >= 2 => {
            Ok(v.iter().map(|&x| x as f64 / 65535.0).collect())
        }
        _ => Err(IccReadError::Malformed(what)),
    };
    match curves {
        [a, b, c] => Ok([table(a)?, table(b)?, table(c)?]),
        _ => Err(IccReadError::Malformed(what)),
    }
}

/// Whether three curves are the identity.
fn identity(curves: &[ToneReprCurve]) -> bool {
    curves.iter().all(|c| match c {
        ToneReprCurve::Lut(v) => v.is_empty() || v.as_slice() == [0, 65535],
        ToneReprCurve::Parametric(p) => p.as_slice() == [1.0],
    })
}

/// Linear interpolation in a table over 0–1.
fn interpolate(t: &[f64], x: f64) -> f64 {
    let p = x.clamp(0.0, 1.0) * (t.len() - 1) as f64;
    let i = (p.floor() as usize).min(t.len() - 2);
    let f = p - i as f64;
    t[i] * (1.0 - f) + t[i + 1] * f
}

/// One lut16Type tag, or a lutAtoB/lutBtoA tag of the same stages: matrix (XYZ input
/// only), input tables, CLUT, output tables, all as normalised 0–1 values.
pub struct Lut16 {
    matrix: [[f64; 3]; 3],
    input: [Vec<f64>; 3],
    points: usize,
    clut: Vec<[f64; 3]>,
    output: [Vec<f64>; 3],
}

impl Lut16 {
    fn read(lut: &LutDataType, what: &'static str) -> Result<Lut16, IccReadError> {
        let points = lut.num_clut_grid_points as usize;
        if lut.num_input_channels != 3 || lut.num_output_channels != 3 || points < 2 {
            return Err(IccReadError::Malformed(what));
        }
        let input = table(&lut.input_table, 3, what)?;
        let output = table(&lut.output_table, 3, what)?;
        let flat = table(&lut.clut_table, 1, what)?.remove(0);
        if flat.len() != 3 * points.pow(3) || input.iter().chain(&output).any(|t| t.len() < 2) {
            return Err(IccReadError::Malformed(what));
        }
        let clut = flat.chunks(3).map(|n| [n[0], n[1], n[2]]).collect();
        let [i0, i1, i2]: [Vec<f64>; 3] = input.try_into().expect("three tables");
        let [o0, o1, o2]: [Vec<f64>; 3] = output.try_into().expect("three tables");
        Ok(Lut16 {
            matrix: lut.matrix.v,
            input: [i0, i1, i2],
            points,
            clut,
            output: [o0, o1, o2],
        })
    }

    /// A lutAtoB (`a_to_b`) or lutBtoA tag whose stages are lut16's: for lutAtoB, A curves,
    /// CLUT and B curves with no matrix or M curves; for lutBtoA, identity B curves, a
    /// matrix without offset, M curves, CLUT and A curves.
    fn read_mab(
        lut: &LutMultidimensionalType,
        a_to_b: bool,
        what: &'static str,
    ) -> Result<Lut16, IccReadError> {
        let points = lut.grid_points[0] as usize;
        let Some(LutStore::Store16(flat)) = &lut.clut else {
            return Err(IccReadError::Malformed(what));
        };
        if lut.num_input_channels != 3
            || lut.num_output_channels != 3
            || points < 2
            || lut.grid_points[..3].iter().any(|&p| p as usize != points)
            || flat.len() != 3 * points.pow(3)
            || lut.bias.v != [0.0; 3]
        {
            return Err(IccReadError::Malformed(what));
        }
        let (matrix, input, output) = if a_to_b {
            if !lut.m_curves.is_empty() && !identity(&lut.m_curves) {
                return Err(IccReadError::Malformed(what));
            }
            let identity3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            (
                identity3,
                curve_tables(&lut.a_curves, what)?,
                curve_tables(&lut.b_curves, what)?,
            )
        } else {
            if !identity(&lut.b_curves) {
                return Err(IccReadError::Malformed(what));
            }
            (
                lut.matrix.v,
                curve_tables(&lut.m_curves, what)?,
                curve_tables(&lut.a_curves, what)?,
            )
        };
        let clut = flat
            .chunks(3)
            .map(|n| std::array::from_fn(|c| n[c] as f64 / 65535.0))
            .collect();
        Ok(Lut16 {
            matrix,
            input,
            points,
            clut,
            output,
        })
    }

    /// Normalised input 0–1 → normalised output 0–1; `matrix` applies it first (only a
    /// tag with XYZ input may use it).
    fn eval(&self, v: [f64; 3], matrix: bool) -> [f64; 3] {
        let v = if matrix {
            std::array::from_fn(|r| (0..3).map(|c| self.matrix[r][c] * v[c]).sum())
        } else {
            v
        };
        let n = self.points;
        let s: [f64; 3] =
            std::array::from_fn(|c| interpolate(&self.input[c], v[c]) * (n - 1) as f64);
        let base: [usize; 3] = std::array::from_fn(|c| (s[c].floor() as usize).min(n - 2));
        let f: [f64; 3] = std::array::from_fn(|c| s[c] - base[c] as f64);
        let index = |i: [usize; 3]| (i[0] * n + i[1]) * n + i[2];
        // Tetrahedral: walk from the cell's low corner along the axes in decreasing
        // order of their fractions (Kasson et al. 1995; LittleCMS's 3-input kernel).
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| f[b].total_cmp(&f[a]));
        let mut corner = base;
        let mut prev = self.clut[index(corner)];
        let mut out = prev;
        for &axis in &order {
            corner[axis] += 1;
            let next = self.clut[index(corner)];
            for q in 0..3 {
                out[q] += f[axis] * (next[q] - prev[q]);
            }
            prev = next;
        }
        std::array::from_fn(|c| interpolate(&self.output[c], out[c]))
    }
}

/// Device RGB → PCS XYZ of a parsed profile: its A2B0 when it has one (as ICC readers
/// choose), else its matrix/TRC.
pub enum IccForward {
    Matrix {
        /// Columns: rXYZ, gXYZ, bXYZ.
        colorants: [[f64; 3]; 3],
        curves: [Box<dyn ToneCurveEvaluator + Send + Sync>; 3],
    },
    Lut16(Lut16),
}

impl IccForward {
    pub fn parse(bytes: &[u8]) -> Result<IccForward, IccReadError> {
        let p =
            ColorProfile::new_from_slice(bytes).map_err(|e| IccReadError::Parse(e.to_string()))?;
        match &p.lut_a_to_b_perceptual {
            Some(LutWarehouse::Lut(lut)) => {
                return Ok(IccForward::Lut16(Lut16::read(lut, "A2B0 lut16")?))
            }
            Some(LutWarehouse::Multidimensional(lut)) => {
                return Ok(IccForward::Lut16(Lut16::read_mab(
                    lut,
                    true,
                    "A2B0 lutAtoB",
                )?))
            }
            None => {}
        }
        Self::matrix(&p)
    }

    /// The matrix/TRC tags alone, as a reader that knows nothing else uses them.
    pub fn parse_matrix(bytes: &[u8]) -> Result<IccForward, IccReadError> {
        let p =
            ColorProfile::new_from_slice(bytes).map_err(|e| IccReadError::Parse(e.to_string()))?;
        Self::matrix(&p)
    }

    fn matrix(p: &ColorProfile) -> Result<IccForward, IccReadError> {
        let (Some(r), Some(g), Some(b)) = (&p.red_trc, &p.green_trc, &p.blue_trc) else {
            return Err(IccReadError::NoForward);
        };
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
        Ok(IccForward::Matrix {
            colorants: std::array::from_fn(|r| std::array::from_fn(|k| c[k][r])),
            curves: [eval(r)?, eval(g)?, eval(b)?],
        })
    }

    /// PCS XYZ (D50, white Y = 1) for drive values 0–1.
    pub fn pcs_xyz(&self, rgb: [f64; 3]) -> Xyz {
        let v: [f64; 3] = match self {
            IccForward::Matrix { colorants, curves } => {
                let lin: [f64; 3] =
                    std::array::from_fn(|c| curves[c].evaluate_value(rgb[c] as f32) as f64);
                std::array::from_fn(|r| (0..3).map(|c| colorants[r][c] * lin[c]).sum())
            }
            IccForward::Lut16(lut) => lut.eval(rgb, false).map(|v| v * 65535.0 / 32768.0),
        };
        v.into()
    }
}

/// PCS XYZ → device RGB through a profile's B2A0.
pub struct IccInverse(Lut16);

impl IccInverse {
    pub fn parse(bytes: &[u8]) -> Result<IccInverse, IccReadError> {
        let p =
            ColorProfile::new_from_slice(bytes).map_err(|e| IccReadError::Parse(e.to_string()))?;
        match &p.lut_b_to_a_perceptual {
            Some(LutWarehouse::Lut(lut)) => Ok(IccInverse(Lut16::read(lut, "B2A0 lut16")?)),
            Some(LutWarehouse::Multidimensional(lut)) => {
                Ok(IccInverse(Lut16::read_mab(lut, false, "B2A0 lutBtoA")?))
            }
            _ => Err(IccReadError::NoInverse),
        }
    }

    /// Drive values 0–1 for a PCS XYZ (D50, white Y = 1).
    pub fn rgb(&self, pcs_xyz: Xyz) -> [f64; 3] {
        let scale = |v: f64| v * 32768.0 / 65535.0;
        self.0
            .eval([scale(pcs_xyz.x), scale(pcs_xyz.y), scale(pcs_xyz.z)], true)
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
    use crate::color::delta_e2000;
    let forward = IccForward::parse(bytes)?;
    let pcs = super::profile_pcs(profile).map_err(|_| IccReadError::Malformed("white"))?;
    let d50 = super::pcs::D50;
    let (mut sum, mut max) = (0.0, 0.0f64);
    for &rgb in drives {
        let ours = pcs.to_pcs(profile.forward(rgb)).to_lab(d50);
        let theirs = forward.pcs_xyz(rgb).to_lab(d50);
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

/// How closely a written profile's B2A0 inverts the model: for each drive triple, the
/// model's colour there goes through B2A0 and the drive it gives back through the model;
/// ΔE00 between the two colours (CIELAB relative to D50 in the PCS). Drive triples are
/// inside the gamut by construction.
pub fn inverse_agreement(
    bytes: &[u8],
    profile: &crate::display::Profile,
    drives: &[[f64; 3]],
) -> Result<Agreement, IccReadError> {
    use crate::color::delta_e2000;
    let inverse = IccInverse::parse(bytes)?;
    let pcs = super::profile_pcs(profile).map_err(|_| IccReadError::Malformed("white"))?;
    let d50 = super::pcs::D50;
    let (mut sum, mut max) = (0.0, 0.0f64);
    for &rgb in drives {
        let want = pcs.to_pcs(profile.forward(rgb));
        let back = pcs.to_pcs(profile.forward(inverse.rgb(want)));
        let de = delta_e2000(want.to_lab(d50), back.to_lab(d50));
        sum += de;
        max = max.max(de);
    }
    Ok(Agreement {
        points: drives.len(),
        mean_de00: sum / drives.len().max(1) as f64,
        max_de00: max,
    })
}
