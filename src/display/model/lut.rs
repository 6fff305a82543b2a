//! A 3D look-up table over a measured grid of drive values with tetrahedral interpolation
//! (Kasson, Nin, Plouffe, Hafner, "Performing color space conversions with three-dimensional
//! linear interpolation", J. Electronic Imaging 4(3), 1995). It assumes neither constant
//! channel chromaticity nor additivity: every grid node is a measurement.
//!
//! The grid axes are first mapped through per-channel shaper curves (the channel's ramp, as
//! in PLCC), so the interpolation runs in a space where an additive display is linear and
//! tetrahedral interpolation is then exact; between nodes a non-additive display is
//! approximated piecewise linearly. Outside the cube the boundary tetrahedra continue
//! linearly, which lets the inverse (Newton on the piecewise-linear map) report how far a
//! target lies out of gamut.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use super::error::FitError;
use super::plcc::{black_and_primaries, ramp_points, singular};
use super::samples::Sample;
use super::samples::{SortedSamples, CHANNEL_NAMES, SAME_DRIVE};
use super::trc::fit_power_gamma;
use super::{condition_number, DisplayModel, FastInverse, Inverse, ModelKind, Trc, MAX_CONDITION};
use crate::color::Xyz;

/// Ramp levels from which the shaper interpolates the ramp instead of fitting a power law.
const TABLE_SHAPER_LEVELS: usize = 8;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Lut3d {
    /// Drive levels of the grid per channel, increasing from 0 to 1.
    pub levels: [Vec<f64>; 3],
    /// Drive → shaped coordinate per channel.
    pub shaper: [Trc; 3],
    /// XYZ (cd/m²) at node (i, j, k), index (i·n_g + j)·n_b + k.
    pub nodes: Vec<[f64; 3]>,
    #[serde(skip)]
    shaped: [Vec<f64>; 3],
    #[serde(skip)]
    fast: [FastInverse; 3],
    /// Largest |Y| of the nodes: the scale of the inverse's convergence test.
    #[serde(skip)]
    scale: f64,
    /// The inverse's start: black and the inverse of the matrix of the full-on primaries
    /// minus black (None when singular).
    #[serde(skip)]
    start: ([f64; 3], Option<Matrix3<f64>>),
}

impl Lut3d {
    pub fn prepare(&mut self) -> Result<(), String> {
        for (c, name) in CHANNEL_NAMES.iter().enumerate() {
            let n = self.levels[c].len();
            if n < 2 {
                return Err(format!("the {name} axis has fewer than 2 levels"));
            }
            if self.levels[c].iter().any(|l| !(0.0..=1.0).contains(l)) {
                return Err(format!("the {name} axis has a level outside 0–1"));
            }
            self.shaper[c]
                .check()
                .map_err(|e| format!("the {name} shaper is unusable: {e}"))?;
            self.shaped[c] = self.levels[c]
                .iter()
                .map(|&d| self.shaper[c].eval(d))
                .collect();
            if self.shaped[c]
                .windows(2)
                .any(|w| w[1] <= w[0] || !w[1].is_finite())
            {
                return Err(format!(
                    "the {name} shaper is flat between grid levels; its ramp does not rise"
                ));
            }
        }
        self.fast = std::array::from_fn(|c| FastInverse::new(&self.shaper[c]));
        let count: usize = self.levels.iter().map(Vec::len).product();
        if self.nodes.len() != count {
            return Err(format!(
                "{} nodes for a {}×{}×{} grid",
                self.nodes.len(),
                self.levels[0].len(),
                self.levels[1].len(),
                self.levels[2].len()
            ));
        }
        if self.nodes.iter().flatten().any(|v| !v.is_finite()) {
            return Err("a grid node's XYZ is not a finite number".into());
        }
        self.scale = self.nodes.iter().map(|n| n[1].abs()).fold(1e-12, f64::max);
        let black = self.node([0, 0, 0]);
        let last = self.levels.clone().map(|l| l.len() - 1);
        let m = Matrix3::from_columns(&[
            self.node([last[0], 0, 0]) - black,
            self.node([0, last[1], 0]) - black,
            self.node([0, 0, last[2]]) - black,
        ]);
        self.start = (black.into(), m.try_inverse());
        Ok(())
    }

    fn node(&self, i: [usize; 3]) -> Vector3<f64> {
        let (ng, nb) = (self.levels[1].len(), self.levels[2].len());
        Vector3::from(self.nodes[(i[0] * ng + i[1]) * nb + i[2]])
    }

    /// A table from grid levels, shapers and node values, checked as a loaded one is.
    pub fn from_parts(
        levels: [Vec<f64>; 3],
        shaper: [Trc; 3],
        nodes: Vec<[f64; 3]>,
    ) -> Result<Lut3d, String> {
        let mut lut = Lut3d {
            levels,
            shaper,
            nodes,
            shaped: Default::default(),
            fast: Default::default(),
            scale: 1.0,
            start: ([0.0; 3], None),
        };
        lut.prepare()?;
        Ok(lut)
    }

    /// The four nodes (flat indices) and weights whose weighted sum is the forward value at
    /// `rgb`: the forward map is linear in the node values, which a fit of the nodes uses.
    pub fn weights(&self, rgb: [f64; 3]) -> [(usize, f64); 4] {
        let s = std::array::from_fn(|c| self.shaper[c].eval(rgb[c]));
        let (cell, f, _) = self.locate(s);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| f[b].total_cmp(&f[a]));
        let index =
            |v: [usize; 3]| (v[0] * self.levels[1].len() + v[1]) * self.levels[2].len() + v[2];
        // value = n0 + Σ f[axis]·(n_next − n_prev) along the sorted axes.
        let mut corner = cell;
        let mut out = [(index(corner), 1.0), (0, 0.0), (0, 0.0), (0, 0.0)];
        for (step, &axis) in order.iter().enumerate() {
            out[step].1 -= f[axis];
            corner[axis] += 1;
            out[step + 1] = (index(corner), f[axis]);
        }
        out
    }

    /// How many of the table's tetrahedra are folded, and how many it has. A folded one maps
    /// shaped drive to XYZ with the orientation opposite to the primaries' (or flat), so
    /// colours near it have more than one drive, or none, and no single-valued inverse
    /// (Newton's here, an ICC B2A0 table) can follow the model there. A display adds light
    /// with every channel, so its own map is one-to-one: a fold is the fit's.
    pub fn folded_tetrahedra(&self) -> (usize, usize) {
        let dims = self.levels.clone().map(|l| l.len());
        let folded = folded_paths(dims, |i| self.node(i)).len();
        (folded, 6 * dims.iter().map(|n| n - 1).product::<usize>())
    }

    /// Cell and fractions of a shaped point (fractions outside 0–1 beyond the cube).
    fn locate(&self, s: [f64; 3]) -> ([usize; 3], [f64; 3], [f64; 3]) {
        let mut cell = [0; 3];
        let mut frac = [0.0; 3];
        let mut width = [0.0; 3];
        for c in 0..3 {
            let a = &self.shaped[c];
            let i = a.partition_point(|&v| v <= s[c]).clamp(1, a.len() - 1) - 1;
            cell[c] = i;
            width[c] = a[i + 1] - a[i];
            frac[c] = (s[c] - a[i]) / width[c];
        }
        (cell, frac, width)
    }

    /// Value and Jacobian (per shaped unit) of the interpolation at a shaped point.
    fn eval_shaped(&self, s: [f64; 3]) -> (Vector3<f64>, Matrix3<f64>) {
        let (cell, f, width) = self.locate(s);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| f[b].total_cmp(&f[a]));
        let mut corner = cell;
        let mut prev = self.node(corner);
        let mut value = prev;
        let mut jac = Matrix3::zeros();
        for &axis in &order {
            corner[axis] += 1;
            let next = self.node(corner);
            let edge = next - prev;
            value += edge * f[axis];
            jac.set_column(axis, &(edge / width[axis]));
            prev = next;
        }
        (value, jac)
    }
}

impl DisplayModel for Lut3d {
    fn name(&self) -> &'static str {
        ModelKind::Lut.name()
    }

    fn forward(&self, rgb: [f64; 3]) -> Xyz {
        let s = std::array::from_fn(|c| self.shaper[c].eval(rgb[c]));
        let v = self.eval_shaped(s).0;
        Xyz::new(v[0], v[1], v[2])
    }

    fn inverse(&self, xyz: Xyz) -> Inverse {
        let target = Vector3::new(xyz.x, xyz.y, xyz.z);
        let scale = self.scale;
        // Start from the linear map through black and the three full-on primaries.
        let (black, start) = &self.start;
        let mut s: Vector3<f64> = start.map_or(Vector3::repeat(0.5), |inv| {
            inv * (target - Vector3::from(*black))
        });
        let (mut value, mut jac) = self.eval_shaped(s.into());
        let mut err = (value - target).norm();
        for _ in 0..60 {
            if err <= 1e-12 * scale {
                break;
            }
            let Some(inv) = jac.try_inverse() else { break };
            let step = inv * (target - value);
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..30 {
                let trial = s + step * t;
                let (v, j) = self.eval_shaped(trial.into());
                let e = (v - target).norm();
                if e < err {
                    s = trial;
                    value = v;
                    jac = j;
                    err = e;
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                break;
            }
        }
        Inverse::from_outputs(&self.fast, s.into())
    }
}

/// Grid levels of channel `c`: drive values that occur together with another channel on
/// (single-channel ramp levels do not), plus 0 and 1.
fn grid_levels(patches: &[Sample], c: usize) -> Vec<f64> {
    let mut v: Vec<f64> = patches
        .iter()
        .filter(|p| (0..3).any(|o| o != c && p.rgb[o] > SAME_DRIVE))
        .map(|p| p.rgb[c])
        .chain([0.0, 1.0])
        .collect();
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| (*a - *b).abs() < SAME_DRIVE);
    v
}

/// Whether the patches hold every combination of their grid levels (what [`fit_lut`]
/// needs). Decided without allocating the grid when it has more cells than there are
/// patches, which a scattered set (every patch its own level) always has.
pub fn has_full_grid(patches: &[Sample]) -> bool {
    let levels: [Vec<f64>; 3] = std::array::from_fn(|c| grid_levels(patches, c));
    let cells = levels
        .iter()
        .map(Vec::len)
        .try_fold(1usize, |a, n| a.checked_mul(n));
    if cells.is_none_or(|c| c > patches.len()) {
        return false;
    }
    let index = |c: usize, d: f64| levels[c].iter().position(|&l| (l - d).abs() < SAME_DRIVE);
    let (ng, nb) = (levels[1].len(), levels[2].len());
    let mut seen = vec![false; cells.unwrap_or(0)];
    for p in patches {
        if let (Some(i), Some(j), Some(k)) =
            (index(0, p.rgb[0]), index(1, p.rgb[1]), index(2, p.rgb[2]))
        {
            seen[(i * ng + j) * nb + k] = true;
        }
    }
    seen.into_iter().all(|s| s)
}

/// Whether the set is a measured grid that the grid LUT stores as it is: a full grid
/// ([`has_full_grid`]) whose levels include every ramp level. Ramps finer than the grid
/// (say 17 levels beside a 3³ grid) hold detail the grid would drop, so such a set is
/// fitted by the scattered LUT, which keeps every patch.
pub fn is_measured_grid(set: &SortedSamples, patches: &[Sample]) -> bool {
    has_full_grid(patches)
        && (0..3).all(|c| {
            let grid = grid_levels(patches, c);
            set.ramps[c]
                .iter()
                .all(|(d, _)| grid.iter().any(|l| (l - d).abs() < SAME_DRIVE))
        })
}

pub fn fit_lut(set: &SortedSamples, patches: &[Sample]) -> Result<Lut3d, FitError> {
    let kind = ModelKind::Lut;
    let (black, m) = black_and_primaries(set, kind)?;
    let cond = condition_number(&m);
    if cond > MAX_CONDITION {
        return Err(singular(cond));
    }
    let levels: [Vec<f64>; 3] = std::array::from_fn(|c| grid_levels(patches, c));
    let index = |c: usize, d: f64| levels[c].iter().position(|&l| (l - d).abs() < SAME_DRIVE);
    let (nr, ng, nb) = (levels[0].len(), levels[1].len(), levels[2].len());
    let mut sums = vec![([0.0; 3], 0usize); nr * ng * nb];
    for p in patches {
        if let (Some(i), Some(j), Some(k)) =
            (index(0, p.rgb[0]), index(1, p.rgb[1]), index(2, p.rgb[2]))
        {
            let slot = &mut sums[(i * ng + j) * nb + k];
            for q in 0..3 {
                slot.0[q] += p.xyz[q];
            }
            slot.1 += 1;
        }
    }
    let missing: Vec<usize> = (0..sums.len()).filter(|&i| sums[i].1 == 0).collect();
    if let Some(&first) = missing.first() {
        let (i, j, k) = (first / (ng * nb), first / nb % ng, first % nb);
        let show = |v: &[f64]| {
            v.iter()
                .map(|d| format!("{d:.3}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        return Err(FitError::Missing {
            model: kind,
            what: format!(
                "a full grid of patches: {} of the {}×{}×{} combinations of the levels r: {}, \
                 g: {}, b: {} are not measured (first: r,g,b = {:.3},{:.3},{:.3})",
                missing.len(),
                nr,
                ng,
                nb,
                show(&levels[0]),
                show(&levels[1]),
                show(&levels[2]),
                levels[0][i],
                levels[1][j],
                levels[2][k]
            ),
        });
    }
    // With only black and full drive on an axis nothing tells the shaper's curvature, and
    // the tetrahedra would interpolate light linearly in drive (ΔE00 ≈ 46 on a γ 2.2
    // display, `metamer budget`): refuse rather than mislead.
    if let Some(c) = (0..3).find(|&c| set.intermediate_levels(c) == 0) {
        return Err(FitError::Missing {
            model: kind,
            what: format!(
                "a {} ramp with at least one level between 0 and 1 for the shaper curve",
                CHANNEL_NAMES[c]
            ),
        });
    }
    let shaper: [Trc; 3] = std::array::from_fn(|c| {
        let pts = ramp_points(set, black, &m, c);
        if set.intermediate_levels(c) >= TABLE_SHAPER_LEVELS {
            Trc::table_from_ramp(&pts)
        } else {
            Trc::Power {
                gamma: fit_power_gamma(&pts),
            }
        }
    });
    let mut lut = Lut3d {
        levels,
        shaper,
        nodes: sums
            .into_iter()
            .map(|(s, n)| s.map(|v| v / n as f64))
            .collect(),
        shaped: Default::default(),
        fast: Default::default(),
        scale: 1.0,
        start: ([0.0; 3], None),
    };
    lut.prepare().map_err(|message| FitError::Failed {
        model: kind,
        message,
    })?;
    Ok(lut)
}

/// The folded tetrahedra of an n₀×n₁×n₂ table whose node at grid index i is `node(i)`, each as
/// the four grid indices its path visits (from the cell's low corner one axis at a time, as
/// the interpolation's decomposition does). Folded means oriented against the full-on
/// primaries minus black, or flat; the three steps of the path are the edge matrix's columns.
pub(crate) fn folded_paths(
    dims: [usize; 3],
    node: impl Fn([usize; 3]) -> Vector3<f64>,
) -> Vec<[[usize; 3]; 4]> {
    let last = dims.map(|n| n - 1);
    let origin = node([0, 0, 0]);
    let reference = Matrix3::from_columns(&[
        node([last[0], 0, 0]) - origin,
        node([0, last[1], 0]) - origin,
        node([0, 0, last[2]]) - origin,
    ])
    .determinant()
    .signum();
    let orders = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut folded = Vec::new();
    for i in 0..last[0] {
        for j in 0..last[1] {
            for k in 0..last[2] {
                for order in orders {
                    let mut path = [[i, j, k]; 4];
                    let mut edges = Matrix3::zeros();
                    for (step, &axis) in order.iter().enumerate() {
                        path[step + 1] = path[step];
                        path[step + 1][axis] += 1;
                        edges.set_column(axis, &(node(path[step + 1]) - node(path[step])));
                    }
                    if edges.determinant() * reference <= 0.0 {
                        folded.push(path);
                    }
                }
            }
        }
    }
    folded
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×2×2 table of an additive display (node = i·R + j·G + k·B) folds nowhere. With the
    /// white moved to R + G − B, by hand: the tetrahedra reaching the white last along blue
    /// (orders r-g-b and g-r-b) end with the edge W − R − G = −B, so their edge matrix is
    /// (R, G, −B) and flips; along green the last edge is G − 2B and along red R − 2B,
    /// which keep det(R, G, B). So 2 of the 6 fold.
    #[test]
    fn a_white_pulled_behind_the_primaries_folds_two_tetrahedra_of_six() {
        let (r, g, b) = ([40.0, 20.0, 2.0], [35.0, 70.0, 10.0], [18.0, 8.0, 95.0]);
        let table = |white: [f64; 3]| {
            let mut nodes = Vec::new();
            for i in 0..2 {
                for j in 0..2 {
                    for k in 0..2 {
                        nodes.push(if (i, j, k) == (1, 1, 1) {
                            white
                        } else {
                            std::array::from_fn(|c| {
                                i as f64 * r[c] + j as f64 * g[c] + k as f64 * b[c]
                            })
                        });
                    }
                }
            }
            let axis = vec![0.0, 1.0];
            Lut3d::from_parts(
                [axis.clone(), axis.clone(), axis],
                std::array::from_fn(|_| Trc::Power { gamma: 1.0 }),
                nodes,
            )
            .unwrap()
        };
        let additive = table(std::array::from_fn(|c| r[c] + g[c] + b[c]));
        assert_eq!(additive.folded_tetrahedra(), (0, 6));
        let pulled = table(std::array::from_fn(|c| r[c] + g[c] - b[c]));
        assert_eq!(pulled.folded_tetrahedra(), (2, 6));
    }
}
