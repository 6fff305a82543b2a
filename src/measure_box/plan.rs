//! What a box measurement measures: the plan file (counts, angles, geometry) with its
//! validation, and the four stages as session plans.
//!
//! The default plan is the paper's: every tile of the 5 × 5 light source with the
//! spectral instrument; the centre tile's luminance at nine angles in the horizontal and
//! nine in the vertical plane with the spot meter; the reflectance of the wall paper and
//! of the 24 ColorChecker patches with the spectral instrument on its lamp; the 24 patches
//! with the spot meter from the viewpoint.
//!
//! The fall-off is read with the spot meter, not the spectral instrument: the fit needs
//! only luminance, a spot meter is aimed from a distance (its 1° cone sees only the centre
//! tile from every angle), while a contact instrument tilted against the panel sees an
//! area and light from the neighbouring tiles.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_drivers::MeasureMode;
use serde::{Deserialize, Serialize};

pub use crate::light::fit::Plane;

use super::adaptive::rule::AdaptiveRule;
use crate::color::COLORCHECKER_NAMES;
use crate::session::{Prepare, SessionPlan, Step};
use crate::validation::sequential::RepeatRule;

/// The journal's session kind.
pub const SESSION_KIND: &str = "measure-box";
/// The role of the spectral instrument (the i1Pro).
pub const SPECTRAL: &str = "spectral";
/// The role of the spot meter (the CS-100A).
pub const SPOT: &str = "spot";

/// The four stages, in the order a full session takes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxStage {
    Tiles,
    Falloff,
    Materials,
    Spots,
}

impl BoxStage {
    pub const ALL: [BoxStage; 4] = [
        BoxStage::Tiles,
        BoxStage::Falloff,
        BoxStage::Materials,
        BoxStage::Spots,
    ];

    pub fn name(self) -> &'static str {
        match self {
            BoxStage::Tiles => "tiles",
            BoxStage::Falloff => "falloff",
            BoxStage::Materials => "materials",
            BoxStage::Spots => "spots",
        }
    }

    /// Whether an adaptive plan reads the stage in rounds ([`super::adaptive`]).
    pub fn in_rounds(self) -> bool {
        matches!(self, BoxStage::Tiles | BoxStage::Falloff)
    }

    /// The stage's journal inside the output directory.
    pub fn journal(self, dir: &Path) -> PathBuf {
        dir.join(format!("{}.jsonl", self.name()))
    }
}

impl std::fmt::Display for BoxStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for BoxStage {
    type Err = String;
    fn from_str(s: &str) -> Result<BoxStage, String> {
        BoxStage::ALL
            .into_iter()
            .find(|st| st.name() == s)
            .ok_or_else(|| format!("unknown stage '{s}' (known: tiles, falloff, materials, spots)"))
    }
}

/// What one step measures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "target", rename_all = "snake_case")]
pub enum Target {
    /// A light tile's spectral radiance along its normal.
    Tile { row: usize, col: usize },
    /// The fall-off tile's luminance seen from `angle_deg` in `plane`.
    Falloff { plane: Plane, angle_deg: f64 },
    /// The wall paper's reflectance.
    Wall,
    /// A ColorChecker patch's reflectance (1–24).
    Patch { patch: usize },
    /// A ColorChecker patch seen by the spot meter from the viewpoint (1–24).
    Spot { patch: usize },
}

impl Target {
    /// Whether `other` reads what this target reads: the same target, or the fall-off's
    /// normal in either plane (one direction, whatever the C-plane).
    pub fn same_reading(&self, other: &Target) -> bool {
        match (self, other) {
            (Target::Falloff { angle_deg: a, .. }, Target::Falloff { angle_deg: b, .. })
                if *a == 0.0 && *b == 0.0 =>
            {
                true
            }
            _ => self == other,
        }
    }
}

/// One step's data in the journal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoxStep {
    pub stage: BoxStage,
    #[serde(flatten)]
    pub target: Target,
    /// 0-based.
    pub repeat: usize,
}

/// The box and where things are in it, in metres in the frame of the validation box
/// (x left → right, y up, z into the box; the light on the left wall x = 0, the chart on the
/// right wall).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Geometry {
    /// Edge of the cubic box.
    pub size_m: f64,
    /// The light opening on the left wall: [y_min, y_max, z_min, z_max].
    pub light_m: [f64; 4],
    /// Tile grid of the light: rows (row 0 at the top), columns (column 0 at the front).
    pub rows: usize,
    pub cols: usize,
    /// The optical centre of the spot meter (and camera), outside the box's open front.
    pub viewpoint_m: [f64; 3],
    /// The spot meter's acceptance angle (full cone).
    pub acceptance_deg: f64,
}

impl Default for Geometry {
    fn default() -> Self {
        Geometry {
            size_m: 0.5,
            light_m: [0.1, 0.4, 0.1, 0.4],
            rows: 5,
            cols: 5,
            viewpoint_m: [-0.4, 0.25, -0.3],
            acceptance_deg: 1.0,
        }
    }
}

/// The plan file: every field optional, the paper's plan where left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoxPlan {
    /// Readings of each tile and each spot.
    pub repeats: usize,
    /// Readings of each reflectance (the i1Pro's reflectance is quiet; the paper read each
    /// once).
    pub material_repeats: usize,
    /// Readings at each fall-off angle.
    pub falloff_repeats: usize,
    /// Signed fall-off angles, degrees, used in both planes; 0 is the normal.
    pub falloff_angles_deg: Vec<f64>,
    /// The tile whose fall-off is measured, [row, col]; default the centre tile.
    pub falloff_tile: Option<[usize; 2]>,
    /// The ColorChecker patches to read (reflectance and spots), 1–24.
    pub patches: Vec<usize>,
    pub geometry: Geometry,
    /// How many times each spot is read: None, `repeats` times (the paper's plan); a
    /// `width` rule reads each spot until its 95 % half-width in CIELAB relative to
    /// `spot_white` is reached ([`crate::validation::sequential`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spot_rule: Option<RepeatRule>,
    /// The white (XYZ, cd/m²) the spots' CIELAB is relative to for a `width` rule: the
    /// display's white, as in the validation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spot_white: Option<[f64; 3]>,
    /// Read the tiles and the fall-off in rounds by this rule ([`super::adaptive`]); None:
    /// every tile and angle, as the paper did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<AdaptiveRule>,
}

impl Default for BoxPlan {
    fn default() -> Self {
        BoxPlan {
            repeats: 5,
            material_repeats: 1,
            falloff_repeats: 1,
            falloff_angles_deg: (-4..=4).map(|k| 20.0 * f64::from(k)).collect(),
            falloff_tile: None,
            patches: (1..=24).collect(),
            geometry: Geometry::default(),
            spot_rule: None,
            spot_white: None,
            adaptive: None,
        }
    }
}

/// A plan that cannot be measured; each names the field.
#[derive(Debug, thiserror::Error)]
pub enum BoxPlanError {
    #[error("cannot read the plan {}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a valid plan: {source} (fields: repeats, material_repeats, falloff_repeats, falloff_angles_deg, falloff_tile, patches, geometry {{size_m, light_m, rows, cols, viewpoint_m, acceptance_deg}}, spot_rule, spot_white, adaptive {{tile_repeats, tile_effect_jnd, max_tiles, angle_agreement, max_falloff}})", path.display())]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("plan: {field}: {message}")]
    Invalid { field: String, message: String },
}

fn invalid(field: &str, message: impl Into<String>) -> BoxPlanError {
    BoxPlanError::Invalid {
        field: field.into(),
        message: message.into(),
    }
}

/// The most tiles a light may be divided into per side: beyond it the grid is finer than a
/// contact instrument's aperture (≈ 4 mm on a 300 mm panel).
pub const MAX_TILES_PER_SIDE: usize = 64;
/// The most readings of one thing.
pub const MAX_REPEATS: usize = crate::validation::sequential::MOST_LOOKS;

impl BoxPlan {
    /// Reads and validates a plan file.
    pub fn load(path: &Path) -> Result<BoxPlan, BoxPlanError> {
        let text = metamer_color::text::read_text(path).map_err(|source| BoxPlanError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let json = |source| BoxPlanError::Json {
            path: path.to_path_buf(),
            source,
        };
        let value: serde_json::Value =
            serde_json::from_str(metamer_color::text::strip_bom(&text)).map_err(json)?;
        // serde reads a struct from an array too, field by field in order: `[1, 2, 3]`
        // would be three repeat counts and everything else left at its default.
        if !value.is_object() {
            return Err(json(serde::de::Error::custom(
                "a plan is a JSON object of named fields",
            )));
        }
        if value.get("geometry").is_some_and(|g| !g.is_object()) {
            return Err(json(serde::de::Error::custom(
                "geometry is a JSON object of named fields",
            )));
        }
        let plan: BoxPlan = serde_json::from_value(value).map_err(json)?;
        plan.validate()?;
        Ok(plan)
    }

    /// With `adaptive`, the adaptive plan: the plan's own rule, or the default one.
    pub fn choose_adaptive(&mut self, adaptive: bool) {
        if adaptive && self.adaptive.is_none() {
            self.adaptive = Some(AdaptiveRule::default());
        }
    }

    /// The most readings of each spot: the rule's, or `repeats`.
    pub fn spot_repeats(&self) -> usize {
        self.spot_rule
            .as_ref()
            .map_or(self.repeats, RepeatRule::most)
    }

    /// The tile whose fall-off is measured.
    pub fn falloff_tile(&self) -> [usize; 2] {
        self.falloff_tile
            .unwrap_or([self.geometry.rows / 2, self.geometry.cols / 2])
    }

    /// Every target of one stage, in the order the fixed plan reads them.
    pub fn targets(&self, stage: BoxStage) -> Vec<Target> {
        let g = &self.geometry;
        match stage {
            BoxStage::Tiles => (0..g.rows * g.cols)
                .map(|k| Target::Tile {
                    row: k / g.cols,
                    col: k % g.cols,
                })
                .collect(),
            BoxStage::Falloff => [Plane::Horizontal, Plane::Vertical]
                .into_iter()
                .flat_map(|plane| {
                    self.falloff_angles_deg
                        .iter()
                        .map(move |&angle_deg| Target::Falloff { plane, angle_deg })
                })
                .collect(),
            BoxStage::Materials => std::iter::once(Target::Wall)
                .chain(self.patches.iter().map(|&patch| Target::Patch { patch }))
                .collect(),
            BoxStage::Spots => self
                .patches
                .iter()
                .map(|&patch| Target::Spot { patch })
                .collect(),
        }
    }

    /// The first pass of a stage an adaptive plan reads in rounds ([`super::adaptive`]
    /// argues the choice): the tiles at the centre, corners and edge midpoints; the
    /// fall-off at the normal and, on each side, the outermost angle and every second one
    /// inwards, the normal read once (in the horizontal plane): it is one direction
    /// whatever the plane, and the fit takes it in both ([`super::falloff::falloff`]).
    /// Every target of another stage.
    pub fn first_pass(&self, stage: BoxStage) -> Vec<Target> {
        match stage {
            BoxStage::Tiles => {
                let three = |n: usize| {
                    let mut v = vec![0, n / 2, n.saturating_sub(1)];
                    v.dedup();
                    v
                };
                let cols = three(self.geometry.cols);
                three(self.geometry.rows)
                    .into_iter()
                    .flat_map(|row| cols.iter().map(move |&col| Target::Tile { row, col }))
                    .collect()
            }
            BoxStage::Falloff => {
                let first = first_angles(&self.falloff_angles_deg);
                [Plane::Horizontal, Plane::Vertical]
                    .into_iter()
                    .flat_map(|plane| {
                        first
                            .iter()
                            .filter(move |&&a| plane == Plane::Horizontal || a != 0.0)
                            .map(move |&angle_deg| Target::Falloff { plane, angle_deg })
                    })
                    .collect()
            }
            _ => self.targets(stage),
        }
    }

    /// Readings of each target of `stage`.
    pub fn stage_repeats(&self, stage: BoxStage) -> usize {
        match (stage, &self.adaptive) {
            (BoxStage::Tiles, Some(rule)) => rule.tile_repeats,
            (BoxStage::Tiles, None) => self.repeats,
            (BoxStage::Falloff, _) => self.falloff_repeats,
            (BoxStage::Materials, _) => self.material_repeats,
            (BoxStage::Spots, _) => self.spot_repeats(),
        }
    }

    /// The steps of one stage: every target, or an adaptive stage's first pass.
    pub fn steps(&self, stage: BoxStage) -> Vec<Step<BoxStep>> {
        let targets = match self.adaptive {
            Some(_) if stage.in_rounds() => self.first_pass(stage),
            _ => self.targets(stage),
        };
        self.steps_of(stage, &targets)
    }

    /// The steps that read `targets` of `stage`, each its repeats in a row.
    pub fn steps_of(&self, stage: BoxStage, targets: &[Target]) -> Vec<Step<BoxStep>> {
        let (role, mode) = match stage {
            BoxStage::Tiles => (SPECTRAL, MeasureMode::Emissive),
            BoxStage::Falloff | BoxStage::Spots => (SPOT, MeasureMode::Emissive),
            BoxStage::Materials => (SPECTRAL, MeasureMode::Reflective),
        };
        let mut steps = Vec::new();
        for target in targets {
            let prompt = self.prompt(target);
            for repeat in 0..self.stage_repeats(stage) {
                steps.push(Step {
                    label: label(target, repeat),
                    role: role.to_string(),
                    mode,
                    prepare: Prepare::Operator {
                        prompt: prompt.clone(),
                    },
                    settle: std::time::Duration::ZERO,
                    data: BoxStep {
                        stage,
                        target: target.clone(),
                        repeat,
                    },
                });
            }
        }
        steps
    }

    /// What the operator is asked to do for a target; the same for every repeat, so a
    /// reading after a calibration (the instrument moved to its tile) starts from the
    /// target again.
    pub fn prompt(&self, target: &Target) -> String {
        match target {
            Target::Tile { row, col } => format!(
                "place the i1Pro on tile row {row}, column {col} of the light on the left wall ({})",
                self.tile_place(*row, *col)
            ),
            Target::Falloff { plane, angle_deg } => {
                let [row, col] = self.falloff_tile();
                format!(
                    "aim the spot meter at the centre of tile row {row}, column {col} ({}) from {} in the {} plane ({})",
                    self.tile_place(row, col),
                    signed(*angle_deg),
                    plane.name(),
                    direction(*plane, *angle_deg)
                )
            }
            Target::Wall => {
                "place the i1Pro on the wall paper (the box's floor, away from the chart)".into()
            }
            Target::Patch { patch } => format!(
                "place the i1Pro on ColorChecker patch {patch} ({})",
                patch_name(*patch)
            ),
            Target::Spot { patch } => format!(
                "aim the spot meter from the viewpoint at ColorChecker patch {patch} ({}) on the right wall",
                patch_name(*patch)
            ),
        }
    }

    /// Where tile (row, col) of the light is, as the operator finds it looking into the box
    /// through its open front (the light on the left wall; row 0 at the top, column 0
    /// nearest the open front: `docs/validation-box.md`): `the top corner nearest the open
    /// front`, `3rd row from the top, 4th column from the open front`.
    pub fn tile_place(&self, row: usize, col: usize) -> String {
        let (rows, cols) = (self.geometry.rows, self.geometry.cols);
        let top = row == 0;
        let bottom = row + 1 == rows;
        let front = col == 0;
        let back = col + 1 == cols;
        let centre = |i: usize, n: usize| n % 2 == 1 && i == n / 2;
        if rows == 1 && cols == 1 {
            return "the whole light".into();
        }
        if rows > 1 && cols > 1 && (top || bottom) && (front || back) {
            let v = if top { "top" } else { "bottom" };
            let h = if front { "the open front" } else { "the back" };
            return format!("the {v} corner nearest {h}");
        }
        if centre(row, rows) && centre(col, cols) {
            return "the centre tile".into();
        }
        let vertical = match () {
            _ if rows == 1 => "the only row".to_string(),
            _ if top => "top row".to_string(),
            _ if bottom => "bottom row".to_string(),
            _ => format!("{} row from the top", ordinal(row + 1)),
        };
        let horizontal = match () {
            _ if cols == 1 => "the only column".to_string(),
            _ if front => "column nearest the open front".to_string(),
            _ if back => "column nearest the back".to_string(),
            _ => format!("{} column from the open front", ordinal(col + 1)),
        };
        format!("{vertical}, {horizontal}")
    }

    /// One stage as a session plan; its options are the stage and the plan's canonical
    /// JSON, plus the caller's (the simulated rig's seed), so a resume with another plan
    /// is refused naming what differs.
    pub fn session_plan(
        &self,
        stage: BoxStage,
        extra: &BTreeMap<String, String>,
    ) -> SessionPlan<BoxStep> {
        self.round_plan(stage, 0, self.steps(stage), extra)
    }

    /// Round `round` of an adaptive stage as a session plan reading `steps`: the first
    /// round is [`BoxPlan::session_plan`]'s, a later one names its round among the options.
    pub fn round_plan(
        &self,
        stage: BoxStage,
        round: usize,
        steps: Vec<Step<BoxStep>>,
        extra: &BTreeMap<String, String>,
    ) -> SessionPlan<BoxStep> {
        let mut options = extra.clone();
        options.insert("stage".into(), stage.name().into());
        if round > 0 {
            options.insert("round".into(), round.to_string());
        }
        let value = serde_json::to_value(self).unwrap_or(serde_json::Value::Null);
        options.insert("plan".into(), value.to_string());
        SessionPlan {
            kind: SESSION_KIND.into(),
            options,
            steps,
        }
    }

    /// One stage at its most: an adaptive stage at its rule's cap (which targets a later
    /// round reads is not known before, but each costs as one of them), what a budget
    /// before the first reading counts.
    pub fn most_steps(&self, stage: BoxStage) -> Vec<Step<BoxStep>> {
        let Some(rule) = self.adaptive.as_ref().filter(|_| stage.in_rounds()) else {
            return self.steps(stage);
        };
        let mut targets = self.first_pass(stage);
        let cap = match stage {
            BoxStage::Tiles => rule.max_tiles,
            _ => rule.max_falloff,
        };
        for t in self.targets(stage) {
            if targets.len() >= cap {
                break;
            }
            if !targets.iter().any(|r| r.same_reading(&t)) {
                targets.push(t);
            }
        }
        self.steps_of(stage, &targets)
    }
}

/// The normal and, on each side, the outermost angle and every second one inwards,
/// increasing.
fn first_angles(angles: &[f64]) -> Vec<f64> {
    let neg: Vec<f64> = angles.iter().copied().filter(|&a| a < 0.0).collect();
    let pos: Vec<f64> = angles.iter().copied().filter(|&a| a > 0.0).collect();
    let mut out: Vec<f64> = neg.iter().copied().step_by(2).collect();
    out.push(0.0);
    let mut right: Vec<f64> = pos.iter().rev().copied().step_by(2).collect();
    right.reverse();
    out.extend(right);
    out
}

/// `1st`, `2nd`, `3rd`, `4th`, … `11th`, `21st`.
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

fn signed(angle_deg: f64) -> String {
    if angle_deg > 0.0 {
        format!("+{angle_deg}°")
    } else {
        format!("{angle_deg}°")
    }
}

fn direction(plane: Plane, angle_deg: f64) -> &'static str {
    match (plane, angle_deg.partial_cmp(&0.0)) {
        (_, Some(std::cmp::Ordering::Equal)) => "on the normal",
        (Plane::Horizontal, Some(std::cmp::Ordering::Greater)) => "towards the back of the box",
        (Plane::Horizontal, _) => "towards the open front",
        (Plane::Vertical, Some(std::cmp::Ordering::Greater)) => "from below",
        (Plane::Vertical, _) => "from above",
    }
}

fn patch_name(patch: usize) -> &'static str {
    COLORCHECKER_NAMES.get(patch - 1).copied().unwrap_or("")
}

/// A step's label: `tile 2,3 #1`, `falloff horizontal +20° #1`, `patch 7 #1`, `spot 7 #2`.
fn label(target: &Target, repeat: usize) -> String {
    let what = match target {
        Target::Tile { row, col } => format!("tile {row},{col}"),
        Target::Falloff { plane, angle_deg } => {
            format!("falloff {} {}", plane.name(), signed(*angle_deg))
        }
        Target::Wall => "wall paper".into(),
        Target::Patch { patch } => format!("reflectance {patch}"),
        Target::Spot { patch } => format!("spot {patch}"),
    };
    format!("{what} #{}", repeat + 1)
}

mod validate;

#[cfg(test)]
mod angle_tests;

#[cfg(test)]
mod tests;
