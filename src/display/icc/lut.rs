//! A LUT model as A2B0 (device → PCS) and B2A0 (PCS → device) tags: `lut16Type` in a
//! version 2.4 profile, `lutAtoBType` / `lutBtoAType` (ICC.1:2010 10.10, 10.11) in a version
//! 4 profile. The tables are the same; only their container differs. LittleCMS reads a
//! version 4 profile's lut16 B2A0 but cannot write it back (its version 4 writer takes a
//! lutBtoA, whose B curves must come before the matrix), so a program that re-embeds such a
//! profile through LittleCMS fails; the lutAtoB/lutBtoA form it saves as it read it.
//!
//! The model interpolates its grid tetrahedrally in the space of its shapers, so between
//! two of its levels it is linear in the shaped coordinate. A2B0 puts a CLUT node on every
//! model level and splits each model cell into the same number of equal parts in the shaped
//! coordinate; the input tables take a drive value to its place among those nodes, linearly
//! in the shaped coordinate. A reader that interpolates tetrahedrally (LittleCMS does, for
//! three inputs) then evaluates the model exactly wherever every axis has the same number of
//! levels: each sub-cell lies inside one of the model's tetrahedra or is split along the same
//! diagonal planes. A reader that interpolates trilinearly sees a finer grid of the model's
//! own values.
//!
//! B2A0 uses the lut16 matrix (PCS XYZ → an estimate of each channel's linear light: the
//! inverse of the primaries' matrix, so a display that adds its channels has its gamut on the
//! grid's faces), input tables that place the nodes at the A2B0 node positions (plus one node
//! beyond each end, where the model's gamut reaches past the primaries), a CLUT of the
//! model's inverse as shaped coordinates (linear in light, where the inverse is smooth) and
//! output tables that are the shapers' inverse. Nodes outside the gamut hold the model's
//! unclipped inverse (within a margin), so colours inside the gamut next to its surface
//! interpolate between true solutions instead of clipped ones; the output tables clip.

use moxcms::{
    LutDataType, LutMultidimensionalType, LutStore, LutType, LutWarehouse, Matrix3d, ToneReprCurve,
    Vector3d,
};

use super::encode::{unit_u16, xyz_u16, IccError, CURVE_ENTRIES};
use super::pcs::{self, Mat3, Pcs};
use crate::color::Xyz;
use crate::display::model::{DisplayModel, Lut3d};

/// Most CLUT nodes per axis A2B0's subdivision aims at (33³ × 3 × 2 bytes ≈ 215 kB): its
/// nodes hold the model exactly, so more buy nothing from a tetrahedral reader.
const TARGET_POINTS: usize = 33;
/// The same for B2A0, whose CLUT samples the model's inverse. That inverse is piecewise
/// linear too, but its kinks (the images of the model's cell faces) are not on this grid's
/// planes unless the display adds its channels, so only density helps: on a real laptop
/// panel whose table bends hard in the dark, 37 nodes per axis left LittleCMS's inverse 0.072
/// mean ΔE00 from the model's, 61 nodes 0.036, 85 nodes 0.025. 61–65 nodes per axis
/// (≤ 67³ × 3 × 2 bytes ≈ 1.8 MB, the size of a high-quality ArgyllCMS LUT profile).
const B2A_TARGET_POINTS: usize = 67;
/// lut16Type allows at most 255 grid points per axis (one byte).
const MAX_POINTS: usize = 255;
/// B2A0's CLUT holds shaped coordinates from −MARGIN to 1 + MARGIN of the channel's range.
const MARGIN: f64 = 0.25;
/// Output table entries of B2A0: with MARGIN 1/4 the ends of the valid range fall on
/// entries 682 and 3410 exactly, so the clip is a corner of the table, not a ramp.
const OUTPUT_ENTRIES: usize = 4093;
/// Samples per cube edge when finding how far the model's gamut reaches past its primaries.
const SURFACE_SAMPLES: usize = 17;

/// The model's shaped coordinate of channel `c`, 0 at drive 0 and 1 at full drive.
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
    /// Drive → normalised shaped coordinate (continued beyond 0–1 as the shaper is).
    fn forward(&self, d: f64) -> f64 {
        (self.lut.shaper[self.c].eval(d) - self.lo) / self.span
    }
    /// Normalised shaped coordinate → drive, clipped to 0–1.
    fn drive(&self, s: f64) -> f64 {
        self.lut.shaper[self.c]
            .inverse(self.lo + s.clamp(0.0, 1.0) * self.span)
            .clamp(0.0, 1.0)
    }
    /// The model's levels as normalised shaped coordinates.
    fn levels(&self) -> Vec<f64> {
        self.lut.levels[self.c]
            .iter()
            .map(|&d| self.forward(d))
            .collect()
    }
}

/// Node positions (normalised shaped coordinates) along one axis: every level, and
/// `parts[j]` equal steps inside cell j.
fn subdivide(levels: &[f64], parts: &[usize]) -> Vec<f64> {
    let mut out = vec![levels[0]];
    for (j, &m) in parts.iter().enumerate() {
        let (a, b) = (levels[j], levels[j + 1]);
        out.extend((1..=m).map(|q| {
            if q == m {
                b
            } else {
                a + (b - a) * q as f64 / m as f64
            }
        }));
    }
    out
}

/// How many parts each cell of each axis is split into so that every axis has the same
/// node count `n`: equal parts when the axes have equal level counts (the case where a
/// tetrahedral reader is exact), otherwise `n − 1` steps shared among the cells as evenly
/// as whole numbers allow.
fn parts(counts: [usize; 3], target: usize) -> (usize, [Vec<usize>; 3]) {
    let cells = counts.map(|l| l - 1);
    if cells.iter().all(|&c| c == cells[0]) {
        let m = ((target - 1) / cells[0]).max(1);
        let n = cells[0] * m + 1;
        if n <= MAX_POINTS {
            return (n, cells.map(|c| vec![m; c]));
        }
    }
    let n = (*counts.iter().max().expect("three axes"))
        .max(target)
        .min(MAX_POINTS);
    let share = |c: usize| -> Vec<usize> {
        if c >= n - 1 {
            // More cells than nodes (a table of over 255 levels): one step per cell is
            // impossible, so the caller resamples uniformly.
            return Vec::new();
        }
        let (base, extra) = ((n - 1) / c, (n - 1) % c);
        (0..c).map(|j| base + usize::from(j < extra)).collect()
    };
    (n, cells.map(share))
}

/// Position 0–1 of `s` among increasing node positions `nodes`, linear between them and
/// clipped at the ends.
fn place(nodes: &[f64], s: f64) -> f64 {
    let n = nodes.len();
    if s <= nodes[0] {
        return 0.0;
    }
    if s >= nodes[n - 1] {
        return 1.0;
    }
    let i = nodes.partition_point(|&v| v <= s).clamp(1, n - 1) - 1;
    let f = (s - nodes[i]) / (nodes[i + 1] - nodes[i]);
    (i as f64 + f) / (n - 1) as f64
}

/// Node positions of each axis (normalised shaped coordinates): every model level, each
/// cell split to reach about `target` nodes.
fn a2b_nodes(axes: &[Axis; 3], target: usize) -> [Vec<f64>; 3] {
    let levels: [Vec<f64>; 3] = std::array::from_fn(|c| axes[c].levels());
    let (n, split) = parts(levels.clone().map(|l| l.len()), target);
    std::array::from_fn(|c| {
        if split[c].is_empty() {
            (0..n)
                .map(|i| {
                    levels[c][0]
                        + (levels[c][levels[c].len() - 1] - levels[c][0]) * i as f64
                            / (n - 1) as f64
                })
                .collect()
        } else {
            subdivide(&levels[c], &split[c])
        }
    })
}

/// One tag's tables in the order of `lut16Type`: a matrix on PCS XYZ input (identity for
/// device input), three input tables, the CLUT (`points` per axis, 16-bit), three output
/// tables, all as 16-bit fractions of 0–1.
pub(super) struct Tables {
    matrix: Mat3,
    input: Vec<u16>,
    points: usize,
    clut: Vec<u16>,
    output: Vec<u16>,
}

/// A flat run of three equal tables as three curves (`curveType`).
fn curves(flat: Vec<u16>) -> Vec<ToneReprCurve> {
    let n = flat.len() / 3;
    flat.chunks(n)
        .map(|c| ToneReprCurve::Lut(c.to_vec()))
        .collect()
}

/// Three identity curves: two entries, 0 and full scale.
fn identity_curves() -> Vec<ToneReprCurve> {
    vec![ToneReprCurve::Lut(vec![0, 65535]); 3]
}

impl Tables {
    /// `lut16Type` (ICC.1:2001-04 6.5.7, ICC.1:2010 10.9).
    pub(super) fn lut16(self) -> LutWarehouse {
        LutWarehouse::Lut(LutDataType {
            num_input_channels: 3,
            num_output_channels: 3,
            num_clut_grid_points: self.points as u8,
            matrix: Matrix3d { v: self.matrix },
            num_input_table_entries: (self.input.len() / 3) as u16,
            num_output_table_entries: (self.output.len() / 3) as u16,
            input_table: LutStore::Store16(self.input),
            clut_table: LutStore::Store16(self.clut),
            output_table: LutStore::Store16(self.output),
            lut_type: LutType::Lut16,
        })
    }

    fn grid(&self) -> [u8; 16] {
        let mut g = [0u8; 16];
        g[..3].fill(self.points as u8);
        g
    }

    /// `lutAtoBType` for device → PCS tables: A curves (the input tables), CLUT, B curves
    /// (the output tables); no matrix, which a device input does not take.
    pub(super) fn a_to_b(self) -> LutWarehouse {
        debug_assert!(self.matrix == IDENTITY, "device input takes no matrix");
        LutWarehouse::Multidimensional(LutMultidimensionalType {
            num_input_channels: 3,
            num_output_channels: 3,
            grid_points: self.grid(),
            a_curves: curves(self.input),
            clut: Some(LutStore::Store16(self.clut)),
            m_curves: Vec::new(),
            matrix: Matrix3d { v: IDENTITY },
            bias: Vector3d { v: [0.0; 3] },
            b_curves: curves(self.output),
        })
    }

    /// `lutBtoAType` for PCS → device tables: identity B curves, the matrix (no offset),
    /// M curves (the input tables), CLUT, A curves (the output tables): lut16's order with
    /// the curves lutBtoA requires first.
    pub(super) fn b_to_a(self) -> LutWarehouse {
        LutWarehouse::Multidimensional(LutMultidimensionalType {
            num_input_channels: 3,
            num_output_channels: 3,
            grid_points: self.grid(),
            b_curves: identity_curves(),
            matrix: Matrix3d { v: self.matrix },
            bias: Vector3d { v: [0.0; 3] },
            m_curves: curves(self.input),
            clut: Some(LutStore::Store16(self.clut)),
            a_curves: curves(self.output),
        })
    }
}

const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn unit(i: usize, n: usize) -> f64 {
    i as f64 / (n - 1) as f64
}

/// A2B0: drive → PCS XYZ with nodes on the model's levels.
pub(super) fn a2b(lut: &Lut3d, pcs: &Pcs) -> Tables {
    let axes: [Axis; 3] = std::array::from_fn(|c| Axis::new(lut, c));
    let nodes = a2b_nodes(&axes, TARGET_POINTS);
    let n = nodes[0].len();
    let mut input = Vec::with_capacity(3 * CURVE_ENTRIES);
    for (axis, at) in axes.iter().zip(&nodes) {
        input.extend(
            (0..CURVE_ENTRIES).map(|i| unit_u16(place(at, axis.forward(unit(i, CURVE_ENTRIES))))),
        );
    }
    // A node on a model level takes the level's drive itself, so the model is read at
    // its own node and not at a drive a round trip through the shaper moved.
    let drives: [Vec<f64>; 3] = std::array::from_fn(|c| {
        nodes[c]
            .iter()
            .map(|&s| {
                let levels = &lut.levels[c];
                levels
                    .iter()
                    .find(|&&d| (axes[c].forward(d) - s).abs() <= 1e-12)
                    .copied()
                    .unwrap_or_else(|| axes[c].drive(s))
            })
            .collect()
    });
    let mut clut = Vec::with_capacity(3 * n.pow(3));
    for &r in &drives[0] {
        for &g in &drives[1] {
            for &b in &drives[2] {
                clut.extend(pcs.to_pcs(lut.forward([r, g, b])).into_iter().map(xyz_u16));
            }
        }
    }
    Tables {
        matrix: IDENTITY,
        input,
        points: n,
        clut,
        output: [0, 65535].repeat(3),
    }
}

/// B2A0: PCS XYZ → drive through the lut16 matrix, input tables, CLUT and output tables.
pub(super) fn b2a(lut: &Lut3d, pcs: &Pcs) -> Result<Tables, IccError> {
    let axes: [Axis; 3] = std::array::from_fn(|c| Axis::new(lut, c));
    let at = |rgb: [f64; 3]| pcs.to_pcs(lut.forward(rgb));
    let black = at([0.0; 3]);
    let (q, points) = coordinates(lut, pcs)?;
    // Per channel: coordinate t = q·x, black at k, the channel's primary at k + gain; the
    // linear estimate l = (t − k) / gain is 0 at black and 1 at the primary.
    let k = pcs::mul(&q, black);
    let gain: [f64; 3] = std::array::from_fn(|c| {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        pcs::mul(&q, at(e))[c] - k[c]
    });
    let reach: [(f64, f64); 3] = std::array::from_fn(|c| {
        points.iter().fold((0.0f64, 1.0f64), |(lo, hi), x| {
            let l = (pcs::mul(&q, *x)[c] - k[c]) / gain[c];
            (lo.min(l), hi.max(l))
        })
    });
    let nodes = b2a_nodes(&axes, reach);
    let n = nodes[0].len();
    // Table input τ = t / top, so the top node's coordinate is 1.
    let top: [f64; 3] = std::array::from_fn(|c| k[c] + gain[c] * nodes[c][n - 1]);
    // The lut16 matrix acts on PCS values normalised to 0–1 (0x8000 is XYZ 1.0) and gives
    // the tables' normalised input: τ = q·x / top.
    let encoding = 65535.0 / 32768.0;
    let matrix: Mat3 =
        std::array::from_fn(|r| std::array::from_fn(|c| q[r][c] / top[r] * encoding));
    let mut input = Vec::with_capacity(3 * CURVE_ENTRIES);
    for c in 0..3 {
        input.extend((0..CURVE_ENTRIES).map(|i| {
            let t = unit(i, CURVE_ENTRIES) * top[c];
            unit_u16(place(&nodes[c], (t - k[c]) / gain[c]))
        }));
    }
    let qinv = pcs::inverse(&q).ok_or(IccError::Singular)?;
    let mut clut = Vec::with_capacity(3 * n.pow(3));
    for &lr in &nodes[0] {
        for &lg in &nodes[1] {
            for &lb in &nodes[2] {
                let l = [lr, lg, lb];
                let t: [f64; 3] = std::array::from_fn(|c| k[c] + gain[c] * l[c]);
                let xyz = pcs.from_pcs(pcs::mul(&qinv, t).into());
                let drive = lut.inverse(xyz).unclipped;
                clut.extend((0..3).map(|c| {
                    let s = axes[c].forward(drive[c]);
                    let s = if s.is_finite() { s } else { 0.0 };
                    unit_u16((s + MARGIN) / (1.0 + 2.0 * MARGIN))
                }));
            }
        }
    }
    let mut output = Vec::with_capacity(3 * OUTPUT_ENTRIES);
    for axis in &axes {
        output.extend((0..OUTPUT_ENTRIES).map(|i| {
            let s = unit(i, OUTPUT_ENTRIES) * (1.0 + 2.0 * MARGIN) - MARGIN;
            unit_u16(axis.drive(s))
        }));
    }
    Ok(Tables {
        matrix,
        input,
        points: n,
        clut,
        output,
    })
}

/// The matrix from PCS XYZ to the channels' coordinates (each primary's column minus
/// black, inverted), sheared so no coordinate goes negative in the gamut, and the gamut's
/// surface in PCS.
fn coordinates(lut: &Lut3d, pcs: &Pcs) -> Result<(Mat3, Vec<Xyz>), IccError> {
    let at = |rgb: [f64; 3]| pcs.to_pcs(lut.forward(rgb));
    let black = at([0.0; 3]);
    // Columns: each primary at full drive minus black, in PCS.
    let mut p = [[0.0; 3]; 3];
    for c in 0..3 {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        let v = at(e);
        for r in 0..3 {
            p[r][c] = v[r] - black[r];
        }
    }
    let mut q = pcs::inverse(&p).ok_or(IccError::Singular)?;
    // The gamut's surface in the matrix's coordinates. The lut16 matrix has no offset and
    // its outputs below 0 are clipped, so a channel whose coordinate goes negative
    // somewhere in the gamut (crosstalk, or a black outside the primaries' cone) gets a
    // share of Y added (Y ≥ 0 everywhere): the grid is then sheared, not cut.
    let surface = cube_surface();
    let points: Vec<Xyz> = surface.iter().map(|&d| at(d)).collect();
    for c in 0..3 {
        let low = points
            .iter()
            .filter(|x| x[1] > 1e-9)
            .map(|x| pcs::mul(&q, *x)[c] / x[1])
            .fold(0.0f64, f64::min);
        if low < 0.0 {
            q[c][1] += -1.05 * low + 1e-4;
        }
    }
    Ok((q, points))
}

/// Each axis's node positions (linear estimates): on the model's levels like A2B0's
/// (denser), plus one beyond each end the gamut reaches past, all axes as long as the
/// longest.
fn b2a_nodes(axes: &[Axis; 3], reach: [(f64, f64); 3]) -> [Vec<f64>; 3] {
    let inner = a2b_nodes(axes, B2A_TARGET_POINTS - 2);
    let nodes: [Vec<f64>; 3] = std::array::from_fn(|c| {
        let (lo, hi) = reach[c];
        let mut v = Vec::with_capacity(inner[c].len() + 2);
        if lo < -1e-6 {
            v.push(lo - 0.02);
        }
        v.extend(&inner[c]);
        if hi > 1.0 + 1e-6 {
            v.push(hi + 0.02);
        }
        v
    });
    // Axes may now differ in length; lut16 needs one count: pad the shorter ones at their
    // top end with nodes past the last (harmless: outside the gamut).
    let n = nodes.iter().map(Vec::len).max().expect("three axes");
    nodes.map(|mut v| {
        while v.len() < n {
            let last = *v.last().expect("never empty");
            v.push(last + 0.02);
        }
        v
    })
}

/// Drive values on the cube's six faces, `SURFACE_SAMPLES` per edge.
fn cube_surface() -> Vec<[f64; 3]> {
    let n = SURFACE_SAMPLES;
    let mut out = Vec::with_capacity(6 * n * n);
    for axis in 0..3 {
        for end in [0.0, 1.0] {
            for i in 0..n {
                for j in 0..n {
                    let mut d = [0.0; 3];
                    d[axis] = end;
                    d[(axis + 1) % 3] = unit(i, n);
                    d[(axis + 2) % 3] = unit(j, n);
                    out.push(d);
                }
            }
        }
    }
    out
}

/// The matrix/TRC tags of a LUT model, for readers that only know matrix/TRC: each curve
/// the channel's shaper (0 at black, 1 at full drive), each colorant the primary at full
/// drive minus black, scaled per channel so that full drive on all three is the model's
/// white (a display that does not add its channels exactly needs a little of that), with
/// the black folded into the curves as for the matrix models.
pub(super) fn matrix_approximation(lut: &Lut3d) -> ([[f64; 3]; 3], Xyz, [Vec<f64>; 3]) {
    let axes: [Axis; 3] = std::array::from_fn(|c| Axis::new(lut, c));
    let black = lut.forward([0.0; 3]);
    let white = lut.forward([1.0; 3]);
    let mut m = [[0.0; 3]; 3];
    for c in 0..3 {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        let v = lut.forward(e);
        for r in 0..3 {
            m[r][c] = v[r] - black[r];
        }
    }
    let want: [f64; 3] = std::array::from_fn(|r| white[r] - black[r]);
    let scale = pcs::inverse(&m)
        .map(|inv| pcs::mul(&inv, want))
        .filter(|a| a.iter().all(|&v| v > 0.5 && v < 2.0))
        .unwrap_or([1.0; 3]);
    let matrix: Mat3 = std::array::from_fn(|r| std::array::from_fn(|c| m[r][c] * scale[c]));
    let curves = std::array::from_fn(|c| {
        (0..CURVE_ENTRIES)
            .map(|i| axes[c].forward(unit(i, CURVE_ENTRIES)))
            .collect()
    });
    (matrix, black, curves)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_axes_get_equal_parts_and_keep_every_level() {
        let (n, split) = parts([9, 9, 9], 33);
        assert_eq!(n, 33);
        assert!(split.iter().all(|s| s == &vec![4; 8]));
        let nodes = subdivide(&[0.0, 0.01, 0.1, 1.0], &[2, 2, 2]);
        let want = [0.0, 0.005, 0.01, 0.055, 0.1, 0.55, 1.0];
        assert_eq!(nodes.len(), want.len());
        for (a, b) in nodes.iter().zip(want) {
            assert!((a - b).abs() < 1e-15, "{nodes:?}");
        }
        // The levels themselves are nodes, bit for bit.
        assert_eq!((nodes[2], nodes[4], nodes[6]), (0.01, 0.1, 1.0));
        let (n, split) = parts([13, 13, 13], 33);
        assert_eq!((n, split[0].len(), split[0][0]), (25, 12, 2));
        let (n, _) = parts([40, 40, 40], 33);
        assert_eq!(n, 40);
    }

    #[test]
    fn unequal_axes_share_the_steps() {
        let (n, split) = parts([5, 9, 3], 33);
        assert_eq!(n, 33);
        for (s, cells) in split.iter().zip([4, 8, 2]) {
            assert_eq!(s.len(), cells);
            assert_eq!(s.iter().sum::<usize>(), 32);
        }
    }

    #[test]
    fn place_is_linear_between_nodes_and_clipped_outside() {
        let nodes = [0.0, 0.1, 1.0];
        assert!((place(&nodes, 0.05) - 0.25).abs() < 1e-15);
        assert_eq!(place(&nodes, 0.1), 0.5);
        assert!((place(&nodes, 0.55) - 0.75).abs() < 1e-15);
        assert_eq!(place(&nodes, -1.0), 0.0);
        assert_eq!(place(&nodes, 2.0), 1.0);
    }
}
