//! Validation: readings of the same 24 ColorChecker patches from two sources (the real box,
//! the display showing the rendering, the simulation) compared in CIELAB with the display's
//! white as reference white, as in the paper (JND ΔE*ab ≈ 2.3; CIEDE2000 reported too).
//!
//! One comparison, [`assess`]: a test side against a reference side, patch by patch, with
//! the readings' uncertainty propagated ([`propagate`]); [`Comparison`] is its point
//! estimates and [`compare`] the same comparison of two plain lists of XYZ taken as exact.
//! A comparison is named test first, `display_vs_box` (the display tested against the
//! box), as its summary reads; `validation.json` and `validation.csv` keep their older
//! keys (`box_vs_display`, `box_vs_simulation`).
//! [`job::validate`], the one entry of `metamer validate` and the experiment's validation
//! stage, reads measured files ([`readings`]), compares the sides and writes the report
//! ([`figures`], [`report`], [`export`]).

pub mod assess;
mod chart;
mod compare;
pub mod comparisons;
pub mod cost_curve;
pub mod covariance;
#[cfg(test)]
mod coverage;
mod error;
pub mod export;
pub mod figures;
pub mod inversion;
pub mod job;
pub mod montecarlo;
pub mod plausible;
pub mod propagate;
pub mod readings;
pub mod repeatability;
pub mod report;
mod report_data;
pub mod sequential;
pub mod uncertain;
pub mod verdict;

pub use assess::{assess, AssessOptions, Assessment, JndVerdict, PatchAssessment, JND_DE76};
pub use chart::write_delta_e_chart;
pub use compare::{compare, Comparison, PatchComparison};
pub use error::ValidationError;
pub use export::write_report_files;
pub use propagate::Propagation;
pub use readings::{read_readings, ReadingSet, ReadingsError};
pub use report::{render_html, ReportInput};
