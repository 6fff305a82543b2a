//! Keeping a fitted table one-to-one. A display adds light with every channel, so the map
//! from drive to XYZ never folds; a table fitted to noisy readings can (the dark first cell
//! along an axis holds a step of well under 1 % of the primary, which noise in a few dark
//! readings outweighs), and where it folds no inverse follows it.
//!
//! The constraint is per lattice edge. Write each step of a tetrahedron's path in the
//! primaries' coordinates (P⁻¹·ΔXYZ, P the full-on primaries minus black): the step along
//! channel j is column j of the tetrahedron's edge matrix in that basis. When every column's
//! own component exceeds the sum of the others' magnitudes the matrix is column diagonally
//! dominant with a positive diagonal, so its determinant is positive (Gershgorin: every
//! eigenvalue has a positive real part) and the tetrahedron keeps the primaries'
//! orientation. "Own component ≥ Σ |others| + margin" is the four constraints "own ± one
//! other ± the third ≥ margin", each linear in the node values: the fit holds the edges of
//! every folded tetrahedron to them by a quadratic penalty (a hinge: only constraints short
//! of their margin pull), refits, and repeats until nothing folds. Edges of tetrahedra that never fold are left free, so a table that does not fold
//! is not changed at all. On the Surface Pro 2017's DisplayCAL set (the folding table this
//! was built for) the one-to-one table predicts held-out patches about 0.03 ΔE00 worse
//! than the folded one (4 %), and a smaller margin costs less: 0.2 of an additive step cost
//! 0.17 / 0.07 on two held-out halves, 0.05 cost 0.08 / 0.03, 0.01 cost 0.03 / 0.02.

use std::collections::{BTreeMap, BTreeSet};

use nalgebra::{Matrix3, Vector3};

use super::lut::folded_paths;

/// The margin an edge is held to, as a fraction of the step an additive display would take
/// there (the shaped coordinate's step): small, since every bit of margin costs accuracy,
/// but never zero, which would let the four pinned sign choices shrink an edge to nothing.
const MARGIN: f64 = 0.01;

/// Rounds in which a held constraint that the fit satisfies with room to spare is let go.
const HINGE_ROUNDS: usize = 8;

/// Refits before giving up (each either holds new edges or stiffens the penalty tenfold).
const ROUNDS: usize = 16;

/// One lattice edge held along its channel: the penalty is ρ·(u·(c_to − c_from) − target)²
/// on the corrections c.
pub(super) struct Held {
    pub from: usize,
    pub to: usize,
    pub u: [f64; 3],
    pub target: f64,
}

/// The outcome: the corrections, and how many edges had to be held.
pub(super) struct Unfolded {
    pub correction: Vec<[f64; 3]>,
    pub held_edges: usize,
}

/// The sign combinations of the two other channels in "own ≥ Σ|others| + margin".
const SIGNS: [[f64; 2]; 4] = [[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]];

/// Refits `correction` (on an n³ grid over `base`) until the table `base + correction`
/// folds nowhere, calling `solve(held, ρ, start)` for each refit. `steps[c][i]` is the
/// share of channel c's full light between its grid levels i and i + 1 (the normalised
/// shaper's step). `stiffness` is the penalty weight, per squared fraction of a primary,
/// that makes a held edge about as costly as the readings; ρ starts at 100 times that.
/// Returns the least-folded fit found if folds remain after every round.
pub(super) fn unfold(
    grid: usize,
    steps: &[Vec<f64>; 3],
    base: &[[f64; 3]],
    correction: Vec<[f64; 3]>,
    stiffness: f64,
    mut solve: impl FnMut(&[Held], f64, &[[f64; 3]]) -> Vec<[f64; 3]>,
) -> Unfolded {
    let n = grid;
    let index = |v: [usize; 3]| (v[0] * n + v[1]) * n + v[2];
    let at = |nodes: &[[f64; 3]], i: usize| Vector3::from(nodes[i]);
    let black = at(base, 0);
    let primaries = Matrix3::from_columns(&[
        at(base, index([n - 1, 0, 0])) - black,
        at(base, index([0, n - 1, 0])) - black,
        at(base, index([0, 0, n - 1])) - black,
    ]);
    let table = |c: &[[f64; 3]]| -> Vec<[f64; 3]> {
        base.iter()
            .zip(c)
            .map(|(b, d)| std::array::from_fn(|k| b[k] + d[k]))
            .collect()
    };
    let folds = |c: &[[f64; 3]]| {
        let nodes = table(c);
        folded_paths([n; 3], |i| at(&nodes, index(i)))
    };
    let mut current = correction;
    let mut folded = folds(&current);
    let Some(to_primaries) = primaries.try_inverse().filter(|_| !folded.is_empty()) else {
        return Unfolded {
            correction: current,
            held_edges: 0,
        };
    };
    let mut best = (folded.len(), current.clone());
    // Edges (from, to) of tetrahedra that folded, with their channel.
    let mut held: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    // The constraints (edge, signs) the penalty pulls up to their margin.
    let mut binding: BTreeSet<(usize, usize, usize)> = BTreeSet::new();
    // "own ≥ Σ|others| + margin" is the four linear constraints own ± a ± b ≥ margin.
    let constraint = |from: usize, to: usize, axis: usize, combo: usize| {
        let base_step = at(base, to) - at(base, from);
        let level = [from / (n * n), from / n % n, from % n][axis];
        let margin = MARGIN * steps[axis][level];
        let mut u = to_primaries.row(axis).transpose();
        let others = (0..3).filter(|&o| o != axis);
        for (o, sign) in others.zip(SIGNS[combo]) {
            u += sign * to_primaries.row(o).transpose();
        }
        (u, margin, base_step)
    };
    let mut rho = 100.0 * stiffness;
    for round in 0..ROUNDS {
        hold_edges(&mut held, &folded, &index);
        let nodes = table(&current);
        let before = binding.len();
        // A hinge: a constraint short of its margin is pulled up to it, one past it is let
        // go (the readings want more than the margin there). The hinge can cycle (a
        // released constraint pulled back by the readings): after HINGE_ROUNDS the set only
        // grows, which ends the rounds at the price of pinning some edges at the margin.
        let sticky = round >= HINGE_ROUNDS;
        let step = |from: usize, to: usize| at(&nodes, to) - at(&nodes, from);
        let released = hinge(&mut binding, &held, &step, &constraint, sticky);
        let before = before - released;
        if binding.len() == before {
            rho *= 10.0;
        }
        let rows: Vec<Held> = binding
            .iter()
            .map(|&(from, to, combo)| {
                let (u, margin, base_step) = constraint(from, to, held[&(from, to)], combo);
                Held {
                    from,
                    to,
                    u: u.into(),
                    target: margin - u.dot(&base_step),
                }
            })
            .collect();
        current = solve(&rows, rho, &current);
        folded = folds(&current);
        if folded.len() < best.0 {
            best = (folded.len(), current.clone());
        }
        if folded.is_empty() {
            break;
        }
    }
    Unfolded {
        correction: best.1,
        held_edges: held.len(),
    }
}

/// Holds every edge of the `folded` paths (node triples, `index` to a node's number) with
/// the channel it steps along.
fn hold_edges(
    held: &mut BTreeMap<(usize, usize), usize>,
    folded: &[[[usize; 3]; 4]],
    index: &dyn Fn([usize; 3]) -> usize,
) {
    for path in folded {
        for step in 0..3 {
            let axis = (0..3)
                .find(|&a| path[step + 1][a] != path[step][a])
                .expect("each step of a path moves along one axis");
            held.insert((index(path[step]), index(path[step + 1])), axis);
        }
    }
}

/// One round of the hinge over the `held` edges' constraints: one short of its margin
/// (`constraint` of edge, channel and sign combination; `step` the edge's step now) joins
/// `binding`, one past it leaves unless `sticky`. Returns how many left.
fn hinge(
    binding: &mut BTreeSet<(usize, usize, usize)>,
    held: &BTreeMap<(usize, usize), usize>,
    step: &dyn Fn(usize, usize) -> Vector3<f64>,
    constraint: &dyn Fn(usize, usize, usize, usize) -> (Vector3<f64>, f64, Vector3<f64>),
    sticky: bool,
) -> usize {
    let mut released = 0;
    for (&(from, to), &axis) in held {
        let step = step(from, to);
        for combo in 0..SIGNS.len() {
            let (u, margin, _) = constraint(from, to, axis, combo);
            if u.dot(&step) < margin {
                binding.insert((from, to, combo));
            } else if !sticky && binding.remove(&(from, to, combo)) {
                released += 1;
            }
        }
    }
    released
}
