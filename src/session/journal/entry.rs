//! What the journal checks of each entry it reads back: the step it records (a second
//! entry of a step is another session's work) and whether its reading is one an
//! instrument gave.

use metamer_drivers::Reading;

/// What the journal checks of an entry it reads back. Both have defaults: an entry that
/// names no step is never a duplicate, and one with nothing to check has no problem.
pub trait JournalEntry {
    /// The plan step the entry records: a second entry of a step is another session's
    /// work on the same file, set aside on resuming.
    fn step(&self) -> Option<usize> {
        None
    }
    /// Why the entry cannot be what a session wrote (a reading edited or damaged), if so.
    fn problem(&self) -> Option<String> {
        None
    }
}

/// Lines read as JSON values (tools that read any journal): the step is `index`.
impl JournalEntry for serde_json::Value {
    fn step(&self) -> Option<usize> {
        self.get("index")?
            .as_u64()
            .and_then(|i| usize::try_from(i).ok())
    }
}

/// How far a journalled XYZ may lie from the one its spectrum gives, relative to the
/// largest component: far above the rounding of a JSON round trip (10⁻¹⁵) and of a change
/// of the colour-matching tables' interpolation, far below any edit that changes a colour.
const SPECTRUM_TOLERANCE: f64 = 1e-3;

/// Why a journalled reading cannot be one an instrument gave: XYZ that is no number or
/// brighter than any light (1e308), or XYZ that does not follow from the reading's own
/// spectrum (one of them was edited). A small negative component is not refused: a
/// spectrometer's dark readings have them.
pub fn reading_problem(reading: &Reading) -> Option<String> {
    if let Err(
        e @ (metamer_color::Implausible::NotFinite(_)
        | metamer_color::Implausible::TooBright { .. }),
    ) = metamer_color::check_xyz(reading.xyz)
    {
        return Some(format!("not a measurement: {e}"));
    }
    let spectrum = reading.spectrum.as_ref()?;
    if let Some(v) = spectrum.values().iter().find(|v| !v.is_finite()) {
        return Some(format!("its spectrum holds {v}, not a measurement"));
    }
    let from_spectrum = Reading::xyz_of_spectrum(spectrum)?;
    let scale = from_spectrum
        .iter()
        .chain(&reading.xyz)
        .fold(0.0f64, |m, v| m.max(v.abs()));
    // A spectrum of 1e308s gives no finite XYZ (and a tolerance of infinity): apart.
    let apart = !scale.is_finite()
        || reading
            .xyz
            .iter()
            .zip(&from_spectrum)
            .any(|(a, b)| (a - b).abs() > SPECTRUM_TOLERANCE * scale + 1e-12);
    apart.then(|| {
        format!(
            "its X, Y, Z = {:?} do not follow from its spectrum, which gives {:?}: the line was edited or damaged; restore it, or delete the line to measure the step again",
            reading.xyz, from_spectrum
        )
    })
}
