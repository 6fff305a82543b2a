//! The adaptive plan's rule: a leaf, read by the plan and by the rounds' choices.

use serde::{Deserialize, Serialize};

/// The rule of the adaptive plan, its figures stated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdaptiveRule {
    /// Readings of each tile read; the tiles' scatter about the spatial model, which
    /// decides, is pooled across them (the plan's `repeats` stay the spots').
    pub tile_repeats: usize,
    /// Stop adding tiles when the unread tiles' predicted effect on every spot (ΔE*ab
    /// bounded by its lightness, relative to the JND of 2.3) is at most this.
    pub tile_effect_jnd: f64,
    /// The most tiles read.
    pub max_tiles: usize,
    /// Stop adding fall-off angles when the plausible distribution models agree within
    /// this fraction of the normal luminance at every unread angle of the plan: 0.01 moves
    /// a spot's light by at most 1 %, ΔL* ≤ 0.39, 0.17 JND.
    pub angle_agreement: f64,
    /// The most fall-off readings' angles (both planes together).
    pub max_falloff: usize,
}

impl Default for AdaptiveRule {
    fn default() -> Self {
        AdaptiveRule {
            tile_repeats: 2,
            tile_effect_jnd: 0.1,
            max_tiles: 11,
            angle_agreement: 0.01,
            max_falloff: 12,
        }
    }
}
