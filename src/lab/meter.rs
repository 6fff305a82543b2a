//! Reading the simulated meter, for both sides of the lab.

use metamer_drivers::{Instrument, Request};

use super::error::LabError;

/// The mean XYZ of `repeats` (at least one) readings of whatever the meter sees now.
pub fn mean_reading(meter: &mut dyn Instrument, repeats: usize) -> Result<[f64; 3], LabError> {
    let repeats = repeats.max(1);
    let mut sum = [0.0; 3];
    for _ in 0..repeats {
        let r = meter.measure(&Request::default())?;
        sum.iter_mut().zip(r.xyz).for_each(|(s, v)| *s += v);
    }
    Ok(sum.map(|s| s / repeats as f64))
}
