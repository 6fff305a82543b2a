//! An instrument whose simulated noise for round j of an adaptive stage is drawn from
//! reading j·2¹⁶ onwards: each round's journal numbers its readings from 0, and without
//! the shift a round would repeat the first pass's noise.

use metamer_drivers::{
    CalibrationCondition, CalibrationOutcome, Capabilities, DriverError, Instrument,
    InstrumentInfo, MeasureMode, Reading, Request,
};

/// Readings a round may take before the next round's noise begins.
pub const ROUND_STRIDE: u64 = 1 << 16;

/// `inner`, its noise stream moved by `offset` readings.
pub struct RoundShifted<'a> {
    pub inner: &'a mut dyn Instrument,
    pub offset: u64,
}

impl Instrument for RoundShifted<'_> {
    fn info(&self) -> InstrumentInfo {
        self.inner.info()
    }
    fn capabilities(&self) -> Capabilities {
        self.inner.capabilities()
    }
    fn calibration_needed(
        &mut self,
        mode: MeasureMode,
    ) -> Result<Option<CalibrationCondition>, DriverError> {
        self.inner.calibration_needed(mode)
    }
    fn calibrate(
        &mut self,
        mode: MeasureMode,
        condition: &CalibrationCondition,
    ) -> Result<CalibrationOutcome, DriverError> {
        self.inner.calibrate(mode, condition)
    }
    fn measure(&mut self, request: &Request) -> Result<Reading, DriverError> {
        self.inner.measure(request)
    }
    fn set_option(&mut self, name: &str, value: &str) -> Result<(), DriverError> {
        self.inner.set_option(name, value)
    }
    fn option_values(&self) -> Vec<(String, String)> {
        self.inner.option_values()
    }
    fn seek_noise(&mut self, index: u64) {
        self.inner.seek_noise(index.wrapping_add(self.offset));
    }
    fn instrument_time_s(&self) -> Option<f64> {
        self.inner.instrument_time_s()
    }
}
