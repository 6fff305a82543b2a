//! The names of the measured planes and of the four half-planes of the C-plane system.
//!
//! The horizontal plane is C0–C180 (positive angles towards the emitter's `edge_u`), the
//! vertical plane C90–C270 (positive towards `edge_v`).

use serde::{Deserialize, Serialize};

/// A plane the fall-off is measured in: the fit's readings and the box plan's fall-off
/// steps name it alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Plane {
    /// Rotation about the vertical axis: C = 0° (positive angles, towards the emitter's
    /// `edge_u`, the back of the box) and C = 180°.
    Horizontal,
    /// Rotation about the horizontal axis: C = 90° (positive angles, towards `edge_v`,
    /// downwards) and C = 270°.
    Vertical,
}

impl Plane {
    /// (C, γ) in degrees of a signed angle in this plane.
    pub fn c_gamma(self, angle_deg: f64) -> (f64, f64) {
        let c = match (self, angle_deg >= 0.0) {
            (Plane::Horizontal, true) => 0.0,
            (Plane::Horizontal, false) => 180.0,
            (Plane::Vertical, true) => 90.0,
            (Plane::Vertical, false) => 270.0,
        };
        (c, angle_deg.abs())
    }

    pub fn name(self) -> &'static str {
        match self {
            Plane::Horizontal => "horizontal",
            Plane::Vertical => "vertical",
        }
    }
}

impl std::fmt::Display for Plane {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A half-plane of the C-plane system.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum HalfPlane {
    C0,
    C90,
    C180,
    C270,
}

impl HalfPlane {
    pub const ALL: [HalfPlane; 4] = [
        HalfPlane::C0,
        HalfPlane::C90,
        HalfPlane::C180,
        HalfPlane::C270,
    ];

    pub fn c_deg(self) -> f64 {
        match self {
            HalfPlane::C0 => 0.0,
            HalfPlane::C90 => 90.0,
            HalfPlane::C180 => 180.0,
            HalfPlane::C270 => 270.0,
        }
    }

    /// The measured plane this half lies in and the sign of its angles there.
    pub fn plane(self) -> (Plane, f64) {
        match self {
            HalfPlane::C0 => (Plane::Horizontal, 1.0),
            HalfPlane::C180 => (Plane::Horizontal, -1.0),
            HalfPlane::C90 => (Plane::Vertical, 1.0),
            HalfPlane::C270 => (Plane::Vertical, -1.0),
        }
    }

    pub fn index(self) -> usize {
        match self {
            HalfPlane::C0 => 0,
            HalfPlane::C90 => 1,
            HalfPlane::C180 => 2,
            HalfPlane::C270 => 3,
        }
    }
}

impl std::fmt::Display for HalfPlane {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (plane, sign) = self.plane();
        let side = if sign > 0.0 { "+" } else { "−" };
        write!(f, "C{} ({plane} {side})", self.c_deg())
    }
}
