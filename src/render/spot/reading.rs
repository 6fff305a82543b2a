//! One rendered meter reading of a patch, whichever renderer made it: the patch, its
//! absolute XYZ, its CIELAB against the run's reference white, and how sure the renderer
//! is of it. The path tracer states a 95 % confidence half-width from its estimate's
//! standard error; the radiosity solver a bound from its mesh refinement. Both are a
//! ΔE*ab, but they are different statements (a validation turns them into CIELAB
//! uncertainties differently), so the kind is kept with the number.
//!
//! The JSON of `metamer render spots --json` names the number by its kind (`de_ci95` with
//! `XYZ_stderr` and `samples`, or `de_bound` with `regular`), which is what the
//! validation's reader of that output looks for; the [`Serialize`] impl keeps those names
//! and their order.

use serde::ser::{Serialize, SerializeStruct, Serializer};

use crate::color::Xyz;

/// One simulated 1° meter reading of a ColorChecker patch.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedReading {
    /// The patch, 1–24.
    pub patch: usize,
    /// Absolute XYZ, cd/m².
    pub xyz: Xyz,
    /// CIELAB against the run's reference white.
    pub lab: [f64; 3],
    pub uncertainty: Uncertainty,
}

/// How sure a renderer is of a reading, in ΔE*ab of its CIELAB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Uncertainty {
    /// The path tracer's: the 95 % confidence half-width of ΔE*ab, 1.96 times the RMS
    /// ΔE*ab of the mean propagated from the covariance of the mean XYZ.
    HalfWidth95 {
        de: f64,
        /// The estimate it rests on; None where it was not recorded (a
        /// `simulation.json` keeps only the half-width).
        sampling: Option<Sampling>,
    },
    /// The radiosity solver's: ΔE*ab between the extrapolated estimate and its
    /// alternatives from the last mesh levels.
    Bound {
        de: f64,
        /// The last levels converged monotonically: false means the bound is a rough
        /// figure. None where it was not recorded (a `simulation.json`).
        regular: Option<bool>,
    },
}

/// What a path-traced estimate rests on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Standard error of the mean XYZ.
    pub xyz_stderr: [f64; 3],
    /// Cone samples averaged.
    pub samples: u64,
}

impl Uncertainty {
    /// The ΔE*ab a reader should allow for the reading: the half-width or the bound.
    pub fn de_ab(&self) -> f64 {
        match *self {
            Uncertainty::HalfWidth95 { de, .. } | Uncertainty::Bound { de, .. } => de,
        }
    }
}

impl RenderedReading {
    /// A reading of `patch` with its CIELAB against `white`, as both renderers compute it.
    pub fn new(patch: usize, xyz: Xyz, white: Xyz, uncertainty: Uncertainty) -> Self {
        let lab = xyz.to_lab(white);
        RenderedReading {
            patch,
            xyz,
            lab: lab.to_array(),
            uncertainty,
        }
    }
}

impl Serialize for RenderedReading {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self.uncertainty {
            Uncertainty::HalfWidth95 { de, sampling } => {
                let mut s = serializer
                    .serialize_struct("RenderedReading", if sampling.is_some() { 6 } else { 4 })?;
                s.serialize_field("patch", &self.patch)?;
                s.serialize_field("XYZ", &self.xyz)?;
                if let Some(sm) = sampling {
                    s.serialize_field("XYZ_stderr", &sm.xyz_stderr)?;
                }
                s.serialize_field("Lab", &self.lab)?;
                s.serialize_field("de_ci95", &de)?;
                if let Some(sm) = sampling {
                    s.serialize_field("samples", &sm.samples)?;
                }
                s.end()
            }
            Uncertainty::Bound { de, regular } => {
                let mut s = serializer
                    .serialize_struct("RenderedReading", if regular.is_some() { 5 } else { 4 })?;
                s.serialize_field("patch", &self.patch)?;
                s.serialize_field("XYZ", &self.xyz)?;
                s.serialize_field("Lab", &self.lab)?;
                s.serialize_field("de_bound", &de)?;
                if let Some(r) = regular {
                    s.serialize_field("regular", &r)?;
                }
                s.end()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(uncertainty: Uncertainty) -> RenderedReading {
        RenderedReading {
            patch: 3,
            xyz: Xyz::new(1.5, 2.0, 0.25),
            lab: [10.0, -1.0, 0.5],
            uncertainty,
        }
    }

    #[test]
    fn each_kind_is_written_under_the_names_the_render_json_always_had() {
        let path = reading(Uncertainty::HalfWidth95 {
            de: 0.08,
            sampling: Some(Sampling {
                xyz_stderr: [0.01, 0.02, 0.005],
                samples: 4096,
            }),
        });
        assert_eq!(
            serde_json::to_string(&path).unwrap(),
            r#"{"patch":3,"XYZ":[1.5,2.0,0.25],"XYZ_stderr":[0.01,0.02,0.005],"Lab":[10.0,-1.0,0.5],"de_ci95":0.08,"samples":4096}"#
        );
        let bound = reading(Uncertainty::Bound {
            de: 0.03,
            regular: Some(false),
        });
        assert_eq!(
            serde_json::to_string(&bound).unwrap(),
            r#"{"patch":3,"XYZ":[1.5,2.0,0.25],"Lab":[10.0,-1.0,0.5],"de_bound":0.03,"regular":false}"#
        );
        assert_eq!(
            (path.uncertainty.de_ab(), bound.uncertainty.de_ab()),
            (0.08, 0.03)
        );
    }

    #[test]
    fn what_was_not_recorded_is_left_out() {
        let r = reading(Uncertainty::HalfWidth95 {
            de: 0.08,
            sampling: None,
        });
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            r#"{"patch":3,"XYZ":[1.5,2.0,0.25],"Lab":[10.0,-1.0,0.5],"de_ci95":0.08}"#
        );
        let r = reading(Uncertainty::Bound {
            de: 0.08,
            regular: None,
        });
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            r#"{"patch":3,"XYZ":[1.5,2.0,0.25],"Lab":[10.0,-1.0,0.5],"de_bound":0.08}"#
        );
    }

    #[test]
    fn the_lab_is_against_the_white_given() {
        let w = Xyz::new(95.047, 100.0, 108.883);
        let r = RenderedReading::new(
            19,
            w,
            w,
            Uncertainty::Bound {
                de: 0.0,
                regular: Some(true),
            },
        );
        assert!(
            (r.lab[0] - 100.0).abs() < 1e-9 && r.lab[1].abs() < 1e-9,
            "{:?}",
            r.lab
        );
    }
}
