//! The matrix-plus-curves form of paper Eq. 9: XYZ − XYZ₀ = M·[R′ G′ B′]ᵀ with R′ = TRC_R(R)
//! etc. PLCC, PLCC with a power law, GOG/GOGO and the all-patch matrix differ only in how M,
//! XYZ₀ and the curves are fitted; they share this forward and inverse.

use serde::{Deserialize, Serialize};

use crate::color::Xyz;

use super::{DisplayModel, FastInverse, Inverse, ModelKind, Trc, GAMUT_TOLERANCE};

/// Black offset, matrix and one curve per channel.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MatrixTrc {
    /// XYZ₀, cd/m².
    pub black: Xyz,
    /// Rows X, Y, Z; columns R, G, B (cd/m² per unit R′, G′, B′).
    pub matrix: [[f64; 3]; 3],
    pub trc: [Trc; 3],
    #[serde(skip)]
    inverse_matrix: [[f64; 3]; 3],
    #[serde(skip)]
    fast: [FastInverse; 3],
    #[serde(skip)]
    kind: Option<ModelKind>,
}

/// 2-norm condition number of a 3×3 matrix (∞ when singular).
pub fn condition_number(m: &[[f64; 3]; 3]) -> f64 {
    // The SVD's iteration does not terminate on NaN entries.
    if m.iter().flatten().any(|v| !v.is_finite()) {
        return f64::INFINITY;
    }
    let mat = nalgebra::Matrix3::from_fn(|r, c| m[r][c]);
    let sv = mat.singular_values();
    let (max, min) = (sv.max(), sv.min());
    if min > 0.0 && max.is_finite() {
        max / min
    } else {
        f64::INFINITY
    }
}

/// Largest condition number accepted for M; real displays' primaries give 2–20, so beyond
/// this the primaries are (nearly) linearly dependent and the inverse amplifies noise.
pub const MAX_CONDITION: f64 = 1e4;

impl MatrixTrc {
    /// Builds the model; `Err(condition number)` when M cannot be inverted safely.
    pub fn new(
        kind: ModelKind,
        black: Xyz,
        matrix: [[f64; 3]; 3],
        trc: [Trc; 3],
    ) -> Result<Self, f64> {
        let mut m = MatrixTrc {
            black,
            matrix,
            trc,
            inverse_matrix: [[0.0; 3]; 3],
            fast: Default::default(),
            kind: None,
        };
        m.prepare(kind)?;
        Ok(m)
    }

    /// Computes the derived inverse after loading; `Err(condition number)` when singular.
    pub fn prepare(&mut self, kind: ModelKind) -> Result<(), f64> {
        let cond = condition_number(&self.matrix);
        if cond > MAX_CONDITION {
            return Err(cond);
        }
        let inv = nalgebra::Matrix3::from_fn(|r, c| self.matrix[r][c])
            .try_inverse()
            .ok_or(f64::INFINITY)?;
        self.inverse_matrix = std::array::from_fn(|r| std::array::from_fn(|c| inv[(r, c)]));
        self.fast = std::array::from_fn(|c| FastInverse::new(&self.trc[c]));
        self.kind = Some(kind);
        Ok(())
    }

    /// R′, G′, B′ for a drive triple.
    pub fn linear(&self, rgb: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|c| self.trc[c].eval(rgb[c]))
    }
}

fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

impl DisplayModel for MatrixTrc {
    fn name(&self) -> &'static str {
        self.kind.map_or("matrix-trc", ModelKind::name)
    }

    fn forward(&self, rgb: [f64; 3]) -> Xyz {
        self.black + Xyz::from(mul(&self.matrix, self.linear(rgb)))
    }

    fn inverse(&self, xyz: Xyz) -> Inverse {
        let d = std::array::from_fn(|c| xyz[c] - self.black[c]);
        let lin = mul(&self.inverse_matrix, d);
        Inverse::from_outputs(&self.fast, lin)
    }
}

impl Inverse {
    /// The inverse through per-channel curves for channel outputs `out`: out of gamut when
    /// an output leaves the curve's range over drive 0–1 by more than [`GAMUT_TOLERANCE`].
    pub fn from_outputs(curves: &[FastInverse; 3], out: [f64; 3]) -> Inverse {
        let unclipped: [f64; 3] = std::array::from_fn(|c| curves[c].inverse(out[c]));
        let out_of_gamut = (0..3).any(|c| {
            let (lo, hi) = curves[c].range;
            let tol = GAMUT_TOLERANCE * (hi - lo).abs();
            out[c].is_nan() || out[c] < lo - tol || out[c] > hi + tol
        });
        Inverse {
            rgb: unclipped.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) }),
            unclipped,
            out_of_gamut,
        }
    }
}
