//! What a stopping rule looks up before it decides a step: the readings of the thing the
//! step reads, taken in the steps before it.

use metamer_color::Xyz;

use super::super::plan::Step;
use super::super::record::Entry;

/// The patch step `index` reads (`patch_of` names each step's; None: no patch), the index
/// of that patch's first step, and the XYZ of its readings from there up to `index`.
pub fn patch_so_far<D>(
    index: usize,
    steps: &[Step<D>],
    entries: &[Option<Entry<D>>],
    patch_of: impl Fn(&Step<D>) -> Option<usize>,
) -> Option<(usize, usize, Vec<Xyz>)> {
    let patch = steps.get(index).and_then(&patch_of)?;
    let first = steps
        .iter()
        .position(|s| patch_of(s) == Some(patch))
        .unwrap_or(index);
    let readings = entries[first..index]
        .iter()
        .flatten()
        .map(|e| e.reading.xyz)
        .collect();
    Some((patch, first, readings))
}
