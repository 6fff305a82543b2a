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
    #[error("{}: not a valid plan: {source} (fields: repeats, material_repeats, falloff_repeats, falloff_angles_deg, falloff_tile, patches, geometry {{size_m, light_m, rows, cols, viewpoint_m, acceptance_deg}}, spot_rule, spot_white)", path.display())]
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

    /// The steps of one stage.
    pub fn steps(&self, stage: BoxStage) -> Vec<Step<BoxStep>> {
        let step = |target: Target, repeat: usize, role: &str, mode, prompt: String| Step {
            label: label(&target, repeat),
            role: role.to_string(),
            mode,
            prepare: Prepare::Operator { prompt },
            settle: std::time::Duration::ZERO,
            data: BoxStep {
                stage,
                target,
                repeat,
            },
        };
        let mut steps = Vec::new();
        match stage {
            BoxStage::Tiles => {
                for row in 0..self.geometry.rows {
                    for col in 0..self.geometry.cols {
                        for r in 0..self.repeats {
                            let t = Target::Tile { row, col };
                            let p = self.prompt(&t);
                            steps.push(step(t, r, SPECTRAL, MeasureMode::Emissive, p));
                        }
                    }
                }
            }
            BoxStage::Falloff => {
                for plane in [Plane::Horizontal, Plane::Vertical] {
                    for &angle_deg in &self.falloff_angles_deg {
                        for r in 0..self.falloff_repeats {
                            let t = Target::Falloff { plane, angle_deg };
                            let p = self.prompt(&t);
                            steps.push(step(t, r, SPOT, MeasureMode::Emissive, p));
                        }
                    }
                }
            }
            BoxStage::Materials => {
                let targets = std::iter::once(Target::Wall)
                    .chain(self.patches.iter().map(|&patch| Target::Patch { patch }));
                for t in targets {
                    for r in 0..self.material_repeats {
                        let p = self.prompt(&t);
                        steps.push(step(t.clone(), r, SPECTRAL, MeasureMode::Reflective, p));
                    }
                }
            }
            BoxStage::Spots => {
                for &patch in &self.patches {
                    for r in 0..self.spot_repeats() {
                        let t = Target::Spot { patch };
                        let p = self.prompt(&t);
                        steps.push(step(t, r, SPOT, MeasureMode::Emissive, p));
                    }
                }
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
        let mut options = extra.clone();
        options.insert("stage".into(), stage.name().into());
        let value = serde_json::to_value(self).unwrap_or(serde_json::Value::Null);
        options.insert("plan".into(), value.to_string());
        SessionPlan {
            kind: SESSION_KIND.into(),
            options,
            steps: self.steps(stage),
        }
    }
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
mod tests {
    use super::*;

    #[test]
    fn the_default_plan_is_the_papers() {
        let p = BoxPlan::default();
        p.validate().unwrap();
        // 25 tiles × 5, 2 planes × 9 angles, wall + 24 patches, 24 spots × 5.
        let counts: Vec<usize> = BoxStage::ALL.iter().map(|&s| p.steps(s).len()).collect();
        assert_eq!(counts, [125, 18, 25, 120]);
        let tiles = p.steps(BoxStage::Tiles);
        assert_eq!(
            tiles[5 * 13].prepare,
            Prepare::Operator {
                prompt: "place the i1Pro on tile row 2, column 3 of the light on the left wall \
                         (3rd row from the top, 4th column from the open front)"
                    .into()
            }
        );
        let place = |r, c| p.tile_place(r, c);
        assert_eq!(place(0, 0), "the top corner nearest the open front");
        assert_eq!(place(4, 4), "the bottom corner nearest the back");
        assert_eq!(place(2, 2), "the centre tile");
        assert_eq!(place(0, 2), "top row, 3rd column from the open front");
        assert_eq!(
            place(3, 0),
            "4th row from the top, column nearest the open front"
        );
        assert_eq!(ordinal(12), "12th");
        assert_eq!(ordinal(22), "22nd");
        assert_eq!(p.falloff_tile(), [2, 2]);
        assert_eq!(Plane::Vertical.c_gamma(-40.0), (270.0, 40.0));
        assert_eq!(Plane::Horizontal.c_gamma(20.0), (0.0, 20.0));
    }

    #[test]
    fn bad_plans_name_the_field() {
        let check = |json: &str, want: &str| {
            let dir = std::env::temp_dir().join(format!("metamer-boxplan-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join("plan.json");
            std::fs::write(&path, json).unwrap();
            let e = BoxPlan::load(&path).unwrap_err().to_string();
            assert!(e.contains(want), "{json}: {e}");
        };
        check(
            r#"{"repeats":0}"#,
            "plan: repeats: must be between 1 and 100, got 0",
        );
        check(r#"{"falloff_angles_deg":[-20,20]}"#, "must contain 0");
        check(r#"{"falloff_angles_deg":[0,95]}"#, "95.0 is not an angle");
        // A number no one can read in 309 digits.
        check(
            r#"{"falloff_angles_deg":[0,1e308]}"#,
            "falloff_angles_deg: 1e308 is not an angle",
        );
        check(r#"{"geometry":{"size_m":1e308}}"#, "and 5 m, got 1e308");
        // serde would read an array as the fields in order: three repeat counts.
        check(
            "[1, 2, 3]",
            "not a valid plan: a plan is a JSON object of named fields",
        );
        check(
            r#"{"geometry": [0.5]}"#,
            "not a valid plan: geometry is a JSON object of named fields",
        );
        check(r#"{"falloff_angles_deg":[0,20,10]}"#, "10 follows 20");
        check(
            r#"{"falloff_angles_deg":[0,20,40,60]}"#,
            "falloff_angles_deg: needs an angle on each side of the normal, and has no negative one",
        );
        check(
            r#"{"falloff_angles_deg":[-60,-30,0]}"#,
            "has no positive one",
        );
        check(r#"{"patches":[1,25]}"#, "25 is not a patch number");
        check(r#"{"patches":[3,3]}"#, "patch 3 is listed twice");
        check(
            r#"{"geometry":{"rows":0}}"#,
            "geometry.rows: must be between 1 and 64",
        );
        check(
            r#"{"geometry":{"light_m":[0.4,0.1,0.1,0.4]}}"#,
            "geometry.light_m",
        );
        check(r#"{"geometry":{"viewpoint_m":[0,0,1]}}"#, "z < 0");
        check(r#"{"falloff_tile":[5,0]}"#, "outside the 5 × 5 grid");
        check(r#"{"repeat":3}"#, "unknown field `repeat`");
        check(
            r#"{"spot_rule":{"rule":"width","half_width_jnd":0.2,"most":10}}"#,
            "plan: spot_white: a width rule needs the white",
        );
        check(
            r#"{"spot_rule":{"rule":"verdict","margin":0.1,"most":10}}"#,
            "plan: spot_rule: a verdict needs the display's reading",
        );
        check(
            r#"{"spot_rule":{"rule":"width","half_width_jnd":0.2,"most":1},"spot_white":[1,1,1]}"#,
            "plan: spot_rule: the most readings must be between 2 and 100, got 1",
        );
        check(r#"{"repeats":"x"}"#, "not a valid plan");
    }
}
