//! From the four stages' readings to the measured scene: per-tile mean spectra, the light's
//! distribution, the measured materials, the spot readings; checked for outliers and
//! spread; written as `scene.json` (the renderers' format: one emitter with per-tile
//! absolute spectra and the fitted C-γ table, the provenance inside), `light.json` (the LDC
//! fit), `light.svg` (its chart), `light.ies` and `light.ldt` (the panel's photometry) and
//! `summary.json` (everything reduced, with the provenance: journals'
//! SHA-256, date, instruments with serial numbers, fit residuals, outliers). The measured
//! scene is then rendered (radiosity) and compared with the box's own spot readings
//! ([`super::compare`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::adaptive::spatial::complete_spectra;
use super::adaptive::AdaptiveSummary;
use super::compare::{compare_render, CompareError, RenderComparison};
use super::falloff::{fit_light, light_files, LightFilesError};
use super::plan::{BoxPlan, BoxStage, BoxStep, Geometry, Plane, Target};
use super::scene::{scene_json, BoxContents};
use super::stats::{group, mean_spectrum, pooled_noise_of, GroupStats, StatsError};
use crate::color::{colorchecker, ColorCheckerSet, Outside, Spectrum, Xyz};
use crate::light::fit::{LdcError, LdcFit, LdcModel, Residual};
use crate::output::{OutputError, OutputPolicy};
use crate::render::scene::DistributionFile;
use crate::session::{CostReport, Entry, InstrumentRecord};
use crate::validation::repeatability;

/// What each stage journal's header says besides its plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoxDetails {
    /// The instruments as named by the user (`i1pro`, `sim:cs100a?time_scale=0`).
    pub spectral: String,
    pub spot: String,
}

/// Every stage's journal path and entries, complete.
pub struct StageEntries {
    /// Each stage's first journal and the entries of all its rounds.
    pub stages: BTreeMap<BoxStage, (PathBuf, Vec<Entry<BoxStep>>)>,
    /// An adaptive stage's journals after its first, in order.
    pub later_rounds: BTreeMap<BoxStage, Vec<PathBuf>>,
    /// What the adaptive plan read and decided; None for the fixed plan.
    pub adaptive: Option<AdaptiveSummary>,
}

/// A group of readings flagged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Flagged {
    pub stage: BoxStage,
    /// `tile 2,3`, `spot 7`.
    pub what: String,
    /// Repeats (1-based) left out of the mean as outliers.
    pub outliers: Vec<usize>,
    /// The kept readings spread more than the instrument's noise allows.
    pub spread_exceeds_noise: bool,
    pub sd_y: f64,
    pub noise_y: f64,
}

/// A reduced target.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reduced {
    pub what: String,
    pub stats: GroupStats,
}

/// A journal and its digest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JournalDigest {
    pub stage: BoxStage,
    pub file: PathBuf,
    pub sha256: String,
}

/// Where the measured scene comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// When the scene was assembled, UTC, ISO 8601.
    pub date: String,
    pub journals: Vec<JournalDigest>,
    /// By role, with model, serial number, firmware and connection.
    pub instruments: BTreeMap<String, InstrumentRecord>,
    pub instrument_specs: BoxDetails,
    /// The LDC model the scene's emitter carries, why, its residual RMS and per angle.
    pub distribution_fit: DistributionFit,
    pub outliers: Vec<Flagged>,
    /// ColorChecker patches the plan did not measure, taken from the nominal data.
    pub nominal_patches: Vec<usize>,
    /// Band values of the mean spectra moved into the renderer's range: radiance below 0
    /// (noise in bands where the light has almost nothing) and reflectance outside [0, 1].
    pub clamped_values: usize,
    /// The chart frame's reflectance is the nominal 0.03, not measured.
    pub nominal_frame_reflectance: f64,
    /// Tiles not read, [row, col], whose spectra are the adaptive plan's spatial model's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub predicted_tiles: Vec<[usize; 2]>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistributionFit {
    pub model: LdcModel,
    pub why: String,
    /// RMS of the relative-luminance residuals over every off-normal angle.
    pub rms: Option<f64>,
    pub residuals: Vec<Residual>,
}

/// The files written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Files {
    pub scene: PathBuf,
    pub light: PathBuf,
    pub light_chart: PathBuf,
    pub ies: PathBuf,
    pub ldt: PathBuf,
    pub summary: PathBuf,
}

/// Everything a finished measurement reduced to.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    pub tiles: Vec<Reduced>,
    pub falloff: Vec<Reduced>,
    pub materials: Vec<Reduced>,
    pub spots: Vec<Reduced>,
    /// Mean spot reading of each patch in the plan's order, cd/m².
    pub spot_xyz: Vec<(usize, Xyz)>,
    pub light: LdcFit,
    /// The measured scene rendered against the box's spot readings.
    pub render: RenderComparison,
    pub provenance: Provenance,
    pub files: Files,
    /// Each stage measured in this call, by name: its budget before its first reading and
    /// what it took (a stage complete before this call has none).
    #[serde(default)]
    pub cost: BTreeMap<String, CostReport>,
    /// What the adaptive plan read, predicted and decided; None for the fixed plan.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<AdaptiveSummary>,
}

/// The readings could not become a scene.
#[derive(Debug, thiserror::Error)]
pub enum AssembleError {
    #[error("{what}: {source}")]
    Stats {
        what: String,
        #[source]
        source: StatsError,
    },
    #[error("the light's fall-off: {0}")]
    Falloff(#[from] LdcError),
    #[error(transparent)]
    LightFiles(#[from] LightFilesError),
    #[error("the {0} stage's readings are missing")]
    Missing(BoxStage),
    #[error("the light's spatial model cannot be fitted to the {0} tile(s) read: it needs 6 that span the panel")]
    TooFewTiles(usize),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Compare(#[from] CompareError),
    #[error(transparent)]
    Output(#[from] OutputError),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> AssembleError + '_ {
    move |source| AssembleError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Groups entries by target in first-seen order.
fn by_target(entries: &[Entry<BoxStep>]) -> Vec<(Target, Vec<&Entry<BoxStep>>)> {
    let mut groups: Vec<(Target, Vec<&Entry<BoxStep>>)> = Vec::new();
    for e in entries {
        match groups.iter_mut().find(|(t, _)| *t == e.data.target) {
            Some((_, g)) => g.push(e),
            None => groups.push((e.data.target.clone(), vec![e])),
        }
    }
    groups
}

fn what(target: &Target) -> String {
    match target {
        Target::Tile { row, col } => format!("tile {row},{col}"),
        Target::Falloff { plane, angle_deg } => format!("falloff {} {angle_deg}°", plane.name()),
        Target::Wall => "wall paper".into(),
        Target::Patch { patch } => format!("reflectance {patch}"),
        Target::Spot { patch } => format!("spot {patch}"),
    }
}

/// A stage's groups reduced, with their flags and (for spectral stages) mean spectra.
struct StageReduced {
    reduced: Vec<Reduced>,
    spectra: Vec<Option<Spectrum>>,
    targets: Vec<Target>,
}

fn reduce(
    stage: BoxStage,
    entries: &[Entry<BoxStep>],
    spectral: bool,
    flags: &mut Vec<Flagged>,
) -> Result<StageReduced, AssembleError> {
    let mut out = StageReduced {
        reduced: Vec::new(),
        spectra: Vec::new(),
        targets: Vec::new(),
    };
    let groups = by_target(entries);
    // The tiles, many targets read alike, are tested against the figure pooled over the
    // other tiles, as the spots' intervals take theirs.
    let pooled = (stage == BoxStage::Tiles).then(|| pooled_noise_of(&groups));
    for (j, (target, group_entries)) in groups.into_iter().enumerate() {
        let w = what(&target);
        let readings: Vec<_> = group_entries.iter().map(|e| &e.reading).collect();
        let noise = repeatability::stated(&readings[0].instrument, group_entries[0].mode);
        let noise = pooled.as_ref().map_or(noise, |p| p[j]);
        let err = |source| AssembleError::Stats {
            what: format!("{stage} {w}"),
            source,
        };
        let stats = group(&readings, noise).map_err(err)?;
        let spectrum = if spectral {
            Some(mean_spectrum(&readings, &stats).map_err(err)?)
        } else {
            None
        };
        if !stats.outliers.is_empty() || stats.spread_exceeds_noise {
            flags.push(Flagged {
                stage,
                what: w.clone(),
                outliers: stats.outliers.iter().map(|i| i + 1).collect(),
                spread_exceeds_noise: stats.spread_exceeds_noise,
                sd_y: stats.sd_y,
                noise_y: stats.noise_y,
            });
        }
        out.reduced.push(Reduced { what: w, stats });
        out.spectra.push(spectrum);
        out.targets.push(target);
    }
    Ok(out)
}

/// `s` with every value clamped into [lo, hi], counting the values moved.
fn clamped(s: &Spectrum, lo: f64, hi: f64, count: &mut usize) -> Spectrum {
    let values = s
        .values()
        .iter()
        .map(|&v| {
            let c = v.clamp(lo, hi);
            *count += usize::from(c != v);
            c
        })
        .collect();
    let mut out = Spectrum::new(s.wavelengths_nm().to_vec(), values)
        .unwrap_or_else(|_| s.clone())
        .with_outside(s.outside());
    if let Some(q) = s.quantity() {
        out = out.with_quantity(q);
    }
    out
}

/// SHA-256 of a file in hex.
pub fn sha256_file(path: &Path) -> Result<String, AssembleError> {
    crate::digest::sha256_file(path).map_err(io(path))
}

/// `YYYY-MM-DDTHH:MM:SSZ` of seconds since the Unix epoch.
pub fn iso_date(unix_s: f64) -> String {
    let secs = unix_s.max(0.0) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let (y, m, d) = crate::calendar::civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

fn write_json(
    policy: &OutputPolicy,
    path: &Path,
    value: &impl Serialize,
) -> Result<(), AssembleError> {
    let text =
        serde_json::to_string_pretty(value).map_err(|e| io(path)(std::io::Error::other(e)))?;
    Ok(policy.write(path, (text + "\n").as_bytes())?)
}

/// Reduces the readings, writes `scene.json`, `light.json` and `summary.json` into `dir`
/// under `policy` (the journals are its inputs), renders the scene and compares it with the
/// spot readings.
pub fn assemble(
    policy: &OutputPolicy,
    dir: &Path,
    plan: &BoxPlan,
    entries: &StageEntries,
    instruments: &BTreeMap<String, InstrumentRecord>,
    details: &BoxDetails,
    cost: &BTreeMap<String, CostReport>,
) -> Result<Summary, AssembleError> {
    let (stages, flags) = reduce_stages(entries)?;
    let light = fit_light(&falloff_readings(&stages.falloff))?;
    let g = &plan.geometry;
    let materials = measured_materials(g, &stages.tiles, &stages.materials)?;
    let date = iso_date(metamer_drivers::instrument::now_s());
    let provenance = Provenance {
        date: date.clone(),
        journals: journal_digests(entries)?,
        instruments: instruments.clone(),
        instrument_specs: details.clone(),
        distribution_fit: DistributionFit {
            model: light.model,
            why: light.why.clone(),
            rms: light.chosen().and_then(|c| c.rms),
            residuals: light.residuals.clone(),
        },
        outliers: flags,
        nominal_patches: materials.nominal_patches,
        clamped_values: materials.clamped_values,
        nominal_frame_reflectance: super::scene::FRAME_REFLECTANCE,
        predicted_tiles: materials.predicted_tiles,
    };
    let contents = BoxContents {
        wall: materials.wall,
        patches: materials.patches,
        tiles: materials.tiles,
        distribution: DistributionFile::CGamma {
            table: light.table.clone(),
        },
        provenance: Some(
            serde_json::to_value(&provenance).map_err(|e| io(dir)(std::io::Error::other(e)))?,
        ),
    };
    let scene = scene_json(
        "measured validation box",
        "The validation box as measured by metamer measure-box: per-tile spectra, the fitted light distribution, measured materials.",
        g,
        &contents,
    );
    let mut policy = policy.clone();
    policy.inputs(entries.stages.values().map(|(p, _)| p.as_path()));
    policy.inputs(
        entries
            .later_rounds
            .values()
            .flatten()
            .map(PathBuf::as_path),
    );
    let files = write_scene_files(&policy, dir, &scene, &light, g, &date[..10])?;
    let spot_xyz = spot_xyz(&stages.spots);
    let render = compare_render(&scene, &spot_xyz)?;
    let summary = Summary {
        tiles: stages.tiles.reduced,
        falloff: stages.falloff.reduced,
        materials: stages.materials.reduced,
        spots: stages.spots.reduced,
        spot_xyz,
        light,
        render,
        provenance,
        files,
        cost: cost.clone(),
        adaptive: entries.adaptive.clone(),
    };
    write_json(&policy, &summary.files.summary, &summary)?;
    Ok(summary)
}

/// The four stages, each reduced.
struct Stages {
    tiles: StageReduced,
    falloff: StageReduced,
    materials: StageReduced,
    spots: StageReduced,
}

/// Every stage's groups reduced, and the groups flagged for outliers or spread.
fn reduce_stages(entries: &StageEntries) -> Result<(Stages, Vec<Flagged>), AssembleError> {
    let get = |stage: BoxStage| {
        entries
            .stages
            .get(&stage)
            .map(|(_, e)| e.as_slice())
            .ok_or(AssembleError::Missing(stage))
    };
    let mut flags = Vec::new();
    let tiles = reduce(BoxStage::Tiles, get(BoxStage::Tiles)?, true, &mut flags)?;
    let falloff = reduce(
        BoxStage::Falloff,
        get(BoxStage::Falloff)?,
        false,
        &mut flags,
    )?;
    let materials = reduce(
        BoxStage::Materials,
        get(BoxStage::Materials)?,
        true,
        &mut flags,
    )?;
    let spots = reduce(BoxStage::Spots, get(BoxStage::Spots)?, false, &mut flags)?;
    let stages = Stages {
        tiles,
        falloff,
        materials,
        spots,
    };
    Ok((stages, flags))
}

/// The fall-off's mean luminance as (plane, signed angle, cd/m²).
fn falloff_readings(falloff: &StageReduced) -> Vec<(Plane, f64, f64)> {
    falloff
        .targets
        .iter()
        .zip(&falloff.reduced)
        .filter_map(|(t, r)| match t {
            Target::Falloff { plane, angle_deg } => Some((*plane, *angle_deg, r.stats.xyz[1])),
            _ => None,
        })
        .collect()
}

/// The box's measured spectra, clamped into their physical range.
struct Materials {
    /// Each tile's radiance, row by row.
    tiles: Vec<Spectrum>,
    wall: Spectrum,
    /// The 24 patches' reflectance, measured or (where not measured) nominal.
    patches: Vec<Spectrum>,
    /// The patches not measured (1–24).
    nominal_patches: Vec<usize>,
    /// Values clamped: negative radiance, reflectance outside 0–1.
    clamped_values: usize,
    /// Tiles not read, whose spectra the spatial model gives.
    predicted_tiles: Vec<[usize; 2]>,
}

/// The tiles' and the materials' spectra of the reduced stages.
fn measured_materials(
    g: &Geometry,
    tiles: &StageReduced,
    materials: &StageReduced,
) -> Result<Materials, AssembleError> {
    let mut clamped_values = 0;
    let mut tile_spectra: Vec<Option<Spectrum>> = vec![None; g.rows * g.cols];
    for (t, s) in tiles.targets.iter().zip(&tiles.spectra) {
        if let (Target::Tile { row, col }, Some(s)) = (t, s) {
            tile_spectra[row * g.cols + col] = Some(
                clamped(s, 0.0, f64::INFINITY, &mut clamped_values).with_outside(Outside::Zero),
            );
        }
    }
    let predicted_tiles: Vec<[usize; 2]> = (0..g.rows * g.cols)
        .filter(|&k| tile_spectra[k].is_none())
        .map(|k| [k / g.cols, k % g.cols])
        .collect();
    if !predicted_tiles.is_empty() {
        let read = tile_spectra.iter().flatten().count();
        let all = complete_spectra(g, &tile_spectra).ok_or(AssembleError::TooFewTiles(read))?;
        tile_spectra = all
            .iter()
            .map(|s| Some(clamped(s, 0.0, f64::INFINITY, &mut clamped_values)))
            .collect();
    }
    let tile_spectra: Vec<Spectrum> = tile_spectra
        .into_iter()
        .collect::<Option<_>>()
        .ok_or(AssembleError::Missing(BoxStage::Tiles))?;
    let nominal = colorchecker(ColorCheckerSet::BabelColorAverage);
    let mut patches: Vec<Option<Spectrum>> = vec![None; 24];
    let mut wall = None;
    for (t, s) in materials.targets.iter().zip(&materials.spectra) {
        let s = s
            .as_ref()
            .map(|s| clamped(s, 0.0, 1.0, &mut clamped_values).with_outside(Outside::HoldEnds));
        match t {
            Target::Wall => wall = s,
            Target::Patch { patch } => patches[patch - 1] = s,
            _ => {}
        }
    }
    let wall = wall.ok_or(AssembleError::Missing(BoxStage::Materials))?;
    let nominal_patches: Vec<usize> = (1..=24).filter(|k| patches[k - 1].is_none()).collect();
    let patches: Vec<Spectrum> = patches
        .into_iter()
        .zip(nominal)
        .map(|(m, n)| m.unwrap_or(n))
        .collect();
    Ok(Materials {
        tiles: tile_spectra,
        wall,
        patches,
        nominal_patches,
        clamped_values,
        predicted_tiles,
    })
}

/// Each stage journal's SHA-256.
fn journal_digests(entries: &StageEntries) -> Result<Vec<JournalDigest>, AssembleError> {
    let mut journals = Vec::new();
    for (stage, (path, _)) in &entries.stages {
        let later = entries.later_rounds.get(stage).into_iter().flatten();
        for path in std::iter::once(path).chain(later) {
            journals.push(JournalDigest {
                stage: *stage,
                file: path.clone(),
                sha256: sha256_file(path)?,
            });
        }
    }
    Ok(journals)
}

/// Writes `scene.json`, `light.json` and the light's chart, IES and EULUMDAT files into
/// `dir`; `summary.json` is checked with them and written last, by the caller.
fn write_scene_files(
    policy: &OutputPolicy,
    dir: &Path,
    scene: &serde_json::Value,
    light: &LdcFit,
    g: &Geometry,
    date: &str,
) -> Result<Files, AssembleError> {
    policy.dir(dir)?;
    let files = Files {
        scene: dir.join("scene.json"),
        light: dir.join("light.json"),
        light_chart: dir.join("light.svg"),
        ies: dir.join("light.ies"),
        ldt: dir.join("light.ldt"),
        summary: dir.join("summary.json"),
    };
    // Every file is made and every target checked before any is written, so a fault or a
    // refusal leaves no half set.
    let light_texts = light_files(light, g, date)?;
    for path in [
        &files.scene,
        &files.light,
        &files.light_chart,
        &files.ies,
        &files.ldt,
    ] {
        policy.check(path)?;
    }
    policy.check(&files.summary)?;
    write_json(policy, &files.scene, scene)?;
    write_json(policy, &files.light, light)?;
    for (name, text) in &light_texts {
        policy.write(&dir.join(name), text.as_bytes())?;
    }
    Ok(files)
}

/// The spot meter's mean XYZ of each ColorChecker patch.
fn spot_xyz(spots: &StageReduced) -> Vec<(usize, Xyz)> {
    spots
        .targets
        .iter()
        .zip(&spots.reduced)
        .filter_map(|(t, r)| match t {
            Target::Spot { patch } => Some((*patch, r.stats.xyz)),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::iso_date;

    #[test]
    fn dates_are_civil_utc() {
        assert_eq!(iso_date(0.0), "1970-01-01T00:00:00Z");
        // 2000-03-01 is day 11017 after the epoch (30 years incl. 7 leap days + Jan + Feb 29).
        assert_eq!(
            iso_date(11_017.0 * 86_400.0 + 3661.0),
            "2000-03-01T01:01:01Z"
        );
        assert_eq!(iso_date(1_700_000_000.0), "2023-11-14T22:13:20Z");
    }
}
