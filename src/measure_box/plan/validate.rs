//! The plan's checks, one per part of the plan in the order the fields are named: the
//! repeat counts, the fall-off angles, the patches, the tile grid, the box's geometry.
//! The first bad field is named.

use super::{invalid, BoxPlan, BoxPlanError, Geometry, MAX_REPEATS, MAX_TILES_PER_SIDE};
use crate::validation::sequential::RepeatRule;

impl BoxPlan {
    /// Checks every field; the first bad one is named.
    pub fn validate(&self) -> Result<(), BoxPlanError> {
        self.check_repeats()?;
        self.check_spot_rule()?;
        check_falloff_angles(&self.falloff_angles_deg)?;
        check_patches(&self.patches)?;
        check_grid(&self.geometry, self.falloff_tile)?;
        self.check_adaptive()?;
        self.geometry.check_walls()
    }

    fn check_repeats(&self) -> Result<(), BoxPlanError> {
        for (field, n) in [
            ("repeats", self.repeats),
            ("material_repeats", self.material_repeats),
            ("falloff_repeats", self.falloff_repeats),
        ] {
            if !(1..=MAX_REPEATS).contains(&n) {
                return Err(invalid(
                    field,
                    format!("must be between 1 and {MAX_REPEATS}, got {n}"),
                ));
            }
        }
        Ok(())
    }
}

impl BoxPlan {
    /// A spot rule the box can follow: a spot's verdict needs the display's reading,
    /// measured later, so only a fixed count or a width, and a width with its white.
    fn check_spot_rule(&self) -> Result<(), BoxPlanError> {
        let Some(rule) = &self.spot_rule else {
            return Ok(());
        };
        rule.check(MAX_REPEATS)
            .map_err(|m| invalid("spot_rule", m))?;
        match rule {
            RepeatRule::Verdict { .. } => Err(invalid(
                "spot_rule",
                "a verdict needs the display's reading of the spot, measured after the box: use \"width\" or \"fixed\"",
            )),
            RepeatRule::Width { .. } => match self.spot_white {
                Some(w) if w.iter().all(|v| v.is_finite()) && w[1] > 0.0 && w.iter().all(|&v| v >= 0.0) => Ok(()),
                Some(w) => Err(invalid("spot_white", format!("must be a white's X, Y, Z with Y > 0, got {w:?}"))),
                None => Err(invalid("spot_white", "a width rule needs the white its CIELAB is relative to (the display's X, Y, Z in cd/m²)")),
            },
            RepeatRule::Fixed { .. } => Ok(()),
        }
    }
}

impl BoxPlan {
    /// An adaptive rule whose figures are figures and whose caps leave room for the first
    /// pass.
    fn check_adaptive(&self) -> Result<(), BoxPlanError> {
        let Some(rule) = &self.adaptive else {
            return Ok(());
        };
        if !(1..=MAX_REPEATS).contains(&rule.tile_repeats) {
            return Err(invalid(
                "adaptive.tile_repeats",
                format!(
                    "must be between 1 and {MAX_REPEATS}, got {}",
                    rule.tile_repeats
                ),
            ));
        }
        for (field, v) in [
            ("adaptive.tile_effect_jnd", rule.tile_effect_jnd),
            ("adaptive.angle_agreement", rule.angle_agreement),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= 10.0) {
                return Err(invalid(
                    field,
                    format!("must be above 0 and at most 10, got {v}"),
                ));
            }
        }
        for (field, cap, stage) in [
            ("adaptive.max_tiles", rule.max_tiles, super::BoxStage::Tiles),
            (
                "adaptive.max_falloff",
                rule.max_falloff,
                super::BoxStage::Falloff,
            ),
        ] {
            let first = self.first_pass(stage).len();
            if cap < first {
                return Err(invalid(
                    field,
                    format!("must be at least the first pass's {first}, got {cap}"),
                ));
            }
        }
        Ok(())
    }
}

/// Angles off the normal, increasing, with the normal and one on each side of it.
fn check_falloff_angles(a: &[f64]) -> Result<(), BoxPlanError> {
    if a.is_empty() {
        return Err(invalid("falloff_angles_deg", "needs at least one angle"));
    }
    if let Some(v) = a.iter().find(|v| !(v.is_finite() && v.abs() < 90.0)) {
        return Err(invalid(
            "falloff_angles_deg",
            format!("{v:?} is not an angle off the normal: each must lie in (−90°, 90°)"),
        ));
    }
    if let Some(w) = a.windows(2).find(|w| w[1] <= w[0]) {
        return Err(invalid(
            "falloff_angles_deg",
            format!("must increase strictly: {} follows {}", w[1], w[0]),
        ));
    }
    if !a.contains(&0.0) {
        return Err(invalid(
            "falloff_angles_deg",
            "must contain 0 (the normal: the distribution is relative to it)",
        ));
    }
    // The fit gives each half-plane (C0 and C90 on the positive side, C180 and C270
    // on the negative) a curve of its own, and even the simplest model needs one
    // reading off the normal in each: without it the fit fails after every stage has
    // been measured.
    if !(a.iter().any(|&v| v < 0.0) && a.iter().any(|&v| v > 0.0)) {
        let missing = if a.iter().any(|&v| v > 0.0) {
            "negative"
        } else {
            "positive"
        };
        return Err(invalid(
            "falloff_angles_deg",
            format!(
                "needs an angle on each side of the normal, and has no {missing} one: the fall-off fit makes a curve for each half-plane (positive angles are C0 and C90, negative ones C180 and C270), so {:?} cannot be fitted",
                a
            ),
        ));
    }
    Ok(())
}

/// ColorChecker patch numbers, each once.
fn check_patches(patches: &[usize]) -> Result<(), BoxPlanError> {
    if patches.is_empty() {
        return Err(invalid("patches", "needs at least one patch"));
    }
    for (i, &p) in patches.iter().enumerate() {
        if !(1..=24).contains(&p) {
            return Err(invalid(
                "patches",
                format!("{p} is not a patch number 1–24"),
            ));
        }
        if patches[..i].contains(&p) {
            return Err(invalid("patches", format!("patch {p} is listed twice")));
        }
    }
    Ok(())
}

/// The light's tile grid, and the fall-off tile on it.
fn check_grid(g: &Geometry, falloff_tile: Option<[usize; 2]>) -> Result<(), BoxPlanError> {
    for (field, n) in [("geometry.rows", g.rows), ("geometry.cols", g.cols)] {
        if !(1..=MAX_TILES_PER_SIDE).contains(&n) {
            return Err(invalid(
                field,
                format!("must be between 1 and {MAX_TILES_PER_SIDE}, got {n}"),
            ));
        }
    }
    if let Some([r, c]) = falloff_tile {
        if r >= g.rows || c >= g.cols {
            return Err(invalid(
                "falloff_tile",
                format!(
                    "tile [{r}, {c}] is outside the {} × {} grid",
                    g.rows, g.cols
                ),
            ));
        }
    }
    Ok(())
}

impl Geometry {
    /// The box's size, the light on its back wall, the viewpoint in front of it and the
    /// spot meter's acceptance.
    fn check_walls(&self) -> Result<(), BoxPlanError> {
        let g = self;
        // The chart (204 mm × 291 mm) must fit on the right wall.
        if !(g.size_m.is_finite() && (0.3..=5.0).contains(&g.size_m)) {
            return Err(invalid(
                "geometry.size_m",
                format!(
                    "must be between 0.3 m (the chart must fit) and 5 m, got {:?}",
                    g.size_m
                ),
            ));
        }
        let [y0, y1, z0, z1] = g.light_m;
        let inside = |v: f64| v.is_finite() && (0.0..=g.size_m).contains(&v);
        if !(inside(y0) && inside(y1) && inside(z0) && inside(z1) && y0 < y1 && z0 < z1) {
            return Err(invalid(
                "geometry.light_m",
                format!(
                    "[y_min, y_max, z_min, z_max] must be increasing pairs inside the {} m wall, got {:?}",
                    g.size_m, g.light_m
                ),
            ));
        }
        let v = g.viewpoint_m;
        if !(v.iter().all(|c| c.is_finite()) && v[2] < 0.0) {
            return Err(invalid(
                "geometry.viewpoint_m",
                format!(
                    "must be in front of the box's open front (z < 0), got {:?}",
                    g.viewpoint_m
                ),
            ));
        }
        if !(g.acceptance_deg > 0.0 && g.acceptance_deg <= 10.0) {
            return Err(invalid(
                "geometry.acceptance_deg",
                format!("must be in (0°, 10°], got {:?}", g.acceptance_deg),
            ));
        }
        Ok(())
    }
}
