//! A deterministic solver for convex enclosures of Lambertian rectangles: the 24 meter
//! readings of the validation box almost exactly, with an error bound.
//!
//! The direct light is in closed form (Lambert's polygon formula per emitter tile, or
//! Gauss–Legendre for a directional tile), the indirect light is piecewise-constant
//! radiosity on a mesh aligned with every decal and tile edge, with exact point-to-element
//! form factors and no visibility (the scene must be convex, which [`qualifies`] checks),
//! solved per wavelength band. The meter gathers over its cone as the path tracer's spot
//! mode does. Readings on three successive refinements are extrapolated (Richardson) and
//! the extrapolations' disagreement is each patch's bound in ΔE*ab (a [`RenderedReading`]
//! with [`Uncertainty::Bound`]); the mesh is refined until every bound is below the target.

pub mod bound;
pub mod direct;
pub mod first_bounce;
pub mod form;
pub mod gather;
pub mod image;
pub mod lights;
pub mod mesh;
pub mod polygon;
pub mod probes;
pub mod solve;

use std::time::Instant;

use self::bound::extrapolate;
use self::gather::{footprint, reading, ConeRule};
use self::lights::Lights;
pub use self::mesh::NotConvex;
use self::mesh::{check_convex, elements, faces, Face, FaceKind, Mesh, MAX_ELEMENTS};
use self::solve::{sources, Bands, SolveFailure};
use super::deadline::Deadline;
use super::scene::Scene;
use super::spot::{patch_aim, RenderedReading, SpotError, Uncertainty};
use crate::color::Xyz;

/// Why the solver cannot run on a scene.
#[derive(Debug, thiserror::Error)]
pub enum RadiosityError {
    #[error(transparent)]
    NotConvex(#[from] NotConvex),
    #[error(transparent)]
    Spot(#[from] SpotError),
    #[error("{what} must be {need}, got {got}")]
    BadOption {
        what: &'static str,
        need: &'static str,
        got: f64,
    },
    #[error(
        "the scene is too detailed for the radiosity solver: {what} (at most {max} elements); \
         the path tracer has no such limit"
    )]
    TooDetailed { what: String, max: usize },
    #[error(
        "no result within the time limit of {seconds} s: it ran out {during} (a result \
         needs three mesh levels: give it a longer time limit)"
    )]
    TimeLimit { seconds: f64, during: String },
    #[error(
        "the light in the scene grows without bound after {sweeps} Gauss–Seidel sweeps: its \
         reflectances return more light than reaches them (a closed box needs an absorbing \
         surface when reflectances exceed 1)"
    )]
    Diverges { sweeps: usize },
    #[error("the reference white is not lit (Y = {0}): the meter sees no light from patch 19")]
    DarkWhite(f64),
    #[error("patch {patch}: the reading is not a finite number ({xyz:?})")]
    NonFinite { patch: usize, xyz: [f64; 3] },
}

/// Does the solver apply: Lambertian rectangles in a convex enclosure, meshed finely enough
/// for three levels within [`MAX_ELEMENTS`].
pub fn qualifies(scene: &Scene) -> Result<(), RadiosityError> {
    Prepared::for_probes(scene).map(|_| ())
}

/// Options of a radiosity run.
#[derive(Clone, Copy, Debug)]
pub struct RadiosityOptions {
    pub target_de: f64,
    pub white: Option<Xyz>,
    /// Spacing of the wavelength nodes the system is solved at.
    pub band_nm: usize,
    /// Element size of level 1 (m; default half the longest face edge); level m divides
    /// it by m.
    pub base_m: Option<f64>,
    /// Convergence order assumed by the extrapolation.
    pub order: f64,
    /// The finest level tried before giving up on the target.
    pub max_level: usize,
    /// No further level is started after this many seconds.
    pub max_seconds: f64,
    pub direct_rule: ConeRule,
    pub indirect_rule: ConeRule,
}

impl Default for RadiosityOptions {
    fn default() -> Self {
        RadiosityOptions {
            target_de: 0.1,
            white: None,
            band_nm: 5,
            base_m: None,
            order: 2.0,
            max_level: 12,
            max_seconds: 600.0,
            direct_rule: ConeRule {
                radial: 4,
                azimuthal: 8,
            },
            indirect_rule: ConeRule {
                radial: 2,
                azimuthal: 4,
            },
        }
    }
}

/// The readings of one refinement level.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Level {
    pub level: usize,
    /// Element size of the level (m).
    pub h_m: f64,
    pub elements: usize,
    /// Gauss–Seidel sweeps of the slowest band chunk.
    pub sweeps: usize,
    pub seconds: f64,
    #[serde(skip)]
    pub patches: Vec<Xyz>,
    #[serde(skip)]
    pub white: Xyz,
}

/// All readings of a radiosity run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RadiosityResult {
    pub white: Xyz,
    pub seconds: f64,
    pub levels: Vec<Level>,
    /// Each with its bound ([`Uncertainty::Bound`], with whether it is regular; see
    /// [`bound`]).
    pub patches: Vec<RenderedReading>,
    /// Every bound is below the target (false if `max_level` or `max_seconds` came first).
    pub converged: bool,
}

/// The scene prepared once for all levels.
pub struct Prepared<'a> {
    pub scene: &'a Scene,
    pub lights: Lights<'a>,
    pub faces: Vec<Face<'a>>,
    pub decals: Vec<Vec<usize>>,
    /// The face of patch 19, white in the reference scene (None for probes only).
    pub white_face: Option<usize>,
}

impl RadiosityError {
    /// The time limit ran out before three levels: a longer limit would give a result.
    pub fn is_time_limit(&self) -> bool {
        matches!(self, RadiosityError::TimeLimit { .. })
    }
}

impl<'a> Prepared<'a> {
    /// For the meter readings: the scene must have patch 19 for the reference white.
    pub fn new(scene: &'a Scene) -> Result<Prepared<'a>, RadiosityError> {
        let mut p = Prepared::for_probes(scene)?;
        let s19 = scene.patch_surface(19).ok_or(SpotError::MissingPatch(19))?;
        p.white_face = p
            .faces
            .iter()
            .position(|f| f.kind == FaceKind::Surface(s19));
        Ok(p)
    }

    /// For illuminance probes: any convex scene.
    pub fn for_probes(scene: &'a Scene) -> Result<Prepared<'a>, RadiosityError> {
        let faces = faces(scene);
        // The convexity check compares every pair of faces: bound it first.
        if faces.len() > MAX_ELEMENTS {
            return Err(RadiosityError::TooDetailed {
                what: format!("{} faces", faces.len()),
                max: MAX_ELEMENTS,
            });
        }
        let decals = check_convex(&faces)?;
        let p = Prepared {
            scene,
            lights: Lights::new(scene),
            faces,
            decals,
            white_face: None,
        };
        let base = p.base(&RadiosityOptions::default());
        if elements(scene, &p.faces, &p.decals, base, 3, MAX_ELEMENTS).is_none() {
            return Err(RadiosityError::TooDetailed {
                what: "the third mesh level (tiles and decals cut every face)".into(),
                max: MAX_ELEMENTS,
            });
        }
        Ok(p)
    }

    /// The element size of level 1.
    pub fn base(&self, opts: &RadiosityOptions) -> f64 {
        opts.base_m.unwrap_or_else(|| {
            self.faces
                .iter()
                .map(|f| f.rect.edge_u.length().max(f.rect.edge_v.length()))
                .fold(0.0, f64::max)
                / 2.0
        })
    }
}

/// A solved level: the mesh and ℓ per emitter on the band grid.
pub struct Solved {
    pub mesh: Mesh,
    pub bands: Bands,
    pub l: Vec<Vec<f64>>,
    /// g/π per element for each light component: the system's source term.
    pub src: Vec<Vec<f64>>,
    pub sweeps: usize,
    /// The largest relative error the stopped iteration leaves in ℓ (an estimate).
    pub algebraic: f64,
}

/// Meshes and solves one level with the given reflectance per face (1 nm).
pub fn solve_level(
    p: &Prepared,
    refl: &[&[f64]],
    opts: &RadiosityOptions,
    level: usize,
    warm: Option<&Solved>,
    deadline: Deadline,
) -> Result<Solved, RadiosityError> {
    let time = || RadiosityError::TimeLimit {
        seconds: opts.max_seconds,
        during: format!("on mesh level {level}"),
    };
    let mesh = match warm {
        Some(w) => Mesh {
            elements: w.mesh.elements.clone(),
            form: w.mesh.form.clone(),
        },
        None => {
            let els = elements(
                p.scene,
                &p.faces,
                &p.decals,
                p.base(opts),
                level,
                MAX_ELEMENTS,
            )
            .ok_or_else(|| RadiosityError::TooDetailed {
                what: format!("mesh level {level}"),
                max: MAX_ELEMENTS,
            })?;
            Mesh::build(els, deadline).ok_or_else(time)?
        }
    };
    let bands = Bands::new(opts.band_nm);
    let nb = bands.len();
    let rho: Vec<f64> = mesh
        .elements
        .iter()
        .flat_map(|el| bands.bins.iter().map(move |&b| refl[el.face][b]))
        .collect();
    let src = sources(p.scene, &p.lights, &mesh, deadline).ok_or_else(time)?;
    let mut sweeps = 0;
    let mut algebraic: f64 = 0.0;
    let l = src
        .iter()
        .enumerate()
        .map(|(c, s)| {
            let warm_c = warm.map(|w| w.l[c].as_slice());
            let sol = solve::solve(&mesh, &rho, s, nb, warm_c, deadline).map_err(|f| match f {
                SolveFailure::Time => time(),
                SolveFailure::Diverges { sweeps } => RadiosityError::Diverges { sweeps },
            })?;
            sweeps = sweeps.max(sol.sweeps);
            algebraic = algebraic.max(sol.rel_err);
            Ok(sol.l)
        })
        .collect::<Result<_, RadiosityError>>()?;
    Ok(Solved {
        mesh,
        bands,
        l,
        src,
        sweeps,
        algebraic,
    })
}

/// The 24 readings and the white of one level.
pub fn run_level(
    p: &Prepared,
    opts: &RadiosityOptions,
    level: usize,
    deadline: Deadline,
) -> Result<Level, RadiosityError> {
    run_level_solved(p, opts, level, deadline).map(|(l, _)| l)
}

/// [`run_level`] with the level's solution, for an image of the same light.
fn run_level_solved(
    p: &Prepared,
    opts: &RadiosityOptions,
    level: usize,
    deadline: Deadline,
) -> Result<(Level, Solved), RadiosityError> {
    let start = Instant::now();
    let scene = p.scene;
    let refl: Vec<&[f64]> = p.faces.iter().map(|f| f.reflectance.as_slice()).collect();
    let solved = solve_level(p, &refl, opts, level, None, deadline)?;
    let mut patches = Vec::with_capacity(24);
    for k in 1..=24 {
        if deadline.passed() {
            return Err(RadiosityError::TimeLimit {
                seconds: opts.max_seconds,
                during: format!("on mesh level {level}"),
            });
        }
        let aim = patch_aim(scene, k)?;
        let fp = footprint(
            scene,
            &p.lights,
            &p.faces,
            &solved.mesh,
            &aim,
            opts.direct_rule,
            opts.indirect_rule,
        );
        patches.push(reading(
            scene,
            &p.lights,
            &fp,
            &refl,
            &solved.bands,
            &solved.l,
        ));
    }
    let white = match (opts.white, p.white_face) {
        (Some(w), _) => w,
        (None, None) => return Err(SpotError::MissingPatch(19).into()),
        (None, Some(wf)) => {
            let ones = vec![1.0; refl[wf].len()];
            let mut wrefl = refl.clone();
            wrefl[wf] = &ones;
            let ws = solve_level(p, &wrefl, opts, level, Some(&solved), deadline)?;
            let aim = patch_aim(scene, 19)?;
            let fp = footprint(
                scene,
                &p.lights,
                &p.faces,
                &ws.mesh,
                &aim,
                opts.direct_rule,
                opts.indirect_rule,
            );
            reading(scene, &p.lights, &fp, &wrefl, &ws.bands, &ws.l)
        }
    };
    let l = Level {
        level,
        h_m: p.base(opts) / level as f64,
        elements: solved.mesh.elements.len(),
        sweeps: solved.sweeps,
        seconds: start.elapsed().as_secs_f64(),
        patches,
        white,
    };
    Ok((l, solved))
}

/// The 24 readings, refined until every patch's bound is below the target.
pub fn render_spots_radiosity(
    scene: &Scene,
    opts: &RadiosityOptions,
    progress: &dyn Fn(&Level),
) -> Result<RadiosityResult, RadiosityError> {
    render_spots_radiosity_solved(scene, opts, progress).map(|(r, _)| r)
}

/// The solutions of the last two levels a reading came from, with their element sizes
/// (m), coarser first: what [`image::render_image_from`] extrapolates as the readings do.
pub type LastLevels = Vec<(Solved, f64)>;

/// [`render_spots_radiosity`] keeping the solutions its readings came from.
pub fn render_spots_radiosity_solved(
    scene: &Scene,
    opts: &RadiosityOptions,
    progress: &dyn Fn(&Level),
) -> Result<(RadiosityResult, LastLevels), RadiosityError> {
    let start = Instant::now();
    check_options(opts)?;
    let deadline = Deadline::after(opts.max_seconds);
    let p = Prepared::new(scene)?;
    let mut levels: Vec<Level> = Vec::new();
    let mut best: Option<(Vec<RenderedReading>, Xyz)> = None;
    // The solutions of the last two levels (coarser first), and of the two before the
    // last level when that one has to be dropped.
    let mut solutions: LastLevels = Vec::new();
    loop {
        let level = levels.len() + 1;
        // A finer level that does not fit in time or memory ends the refinement with the
        // last result; the first three are needed for any result at all.
        let l = match run_level_solved(&p, opts, level, deadline) {
            Ok((l, solved)) => {
                solutions.push((solved, l.h_m));
                if solutions.len() > 2 {
                    solutions.remove(0);
                }
                l
            }
            Err(RadiosityError::TimeLimit { .. } | RadiosityError::TooDetailed { .. })
                if best.is_some() =>
            {
                let (patches, white) = best.unwrap_or_default();
                return Ok((
                    RadiosityResult {
                        white,
                        seconds: start.elapsed().as_secs_f64(),
                        levels,
                        patches,
                        converged: false,
                    },
                    solutions,
                ));
            }
            Err(e) => return Err(e),
        };
        if !(l.white.is_finite() && l.white[1] > 0.0) {
            return Err(RadiosityError::DarkWhite(l.white[1]));
        }
        progress(&l);
        levels.push(l);
        if levels.len() < 3 {
            continue;
        }
        let (patches, white) = combine(&levels, opts);
        if let Some(r) = patches.iter().find(|r| {
            !(r.xyz.is_finite() && r.lab.iter().all(|x| x.is_finite()))
                || r.uncertainty.de_ab().is_nan()
        }) {
            return Err(RadiosityError::NonFinite {
                patch: r.patch,
                xyz: r.xyz.to_array(),
            });
        }
        let converged = patches
            .iter()
            .all(|r| r.uncertainty.de_ab() < opts.target_de);
        let out_of_time = deadline.passed();
        if converged || out_of_time || level >= opts.max_level.max(3) {
            return Ok((
                RadiosityResult {
                    white,
                    seconds: start.elapsed().as_secs_f64(),
                    levels,
                    patches,
                    converged,
                },
                solutions,
            ));
        }
        best = Some((patches, white));
    }
}

/// The options of a spot run, checked before any work.
fn check_options(opts: &RadiosityOptions) -> Result<(), RadiosityError> {
    if opts.max_seconds.is_nan() || opts.max_seconds <= 0.0 {
        return Err(RadiosityError::BadOption {
            what: "the time limit",
            need: "> 0 s",
            got: opts.max_seconds,
        });
    }
    if opts.target_de.is_nan() || opts.target_de <= 0.0 {
        return Err(RadiosityError::BadOption {
            what: "the ΔE*ab target",
            need: "> 0",
            got: opts.target_de,
        });
    }
    if let Some(b) = opts.base_m {
        if !(b > 0.0 && b.is_finite()) {
            return Err(RadiosityError::BadOption {
                what: "the base element size",
                need: "> 0 m",
                got: b,
            });
        }
    }
    if let Some(w) = opts.white {
        if !(w.is_finite() && w[1] > 0.0) {
            return Err(SpotError::BadWhite(w.to_array()).into());
        }
    }
    Ok(())
}

/// Readings and bounds from the last levels (three, or four for the step check).
pub fn combine(levels: &[Level], opts: &RadiosityOptions) -> (Vec<RenderedReading>, Xyz) {
    let last = &levels[levels.len().saturating_sub(4)..];
    let h: Vec<f64> = last.iter().map(|l| l.h_m).collect();
    let whites: Vec<Xyz> = last.iter().map(|l| l.white).collect();
    let mut white = last[last.len() - 1].white;
    let patches = (0..24)
        .map(|k| {
            let patch: Vec<Xyz> = last.iter().map(|l| l.patches[k]).collect();
            let e = extrapolate(&patch, &whites, &h, opts.order, opts.white);
            white = e.white;
            let uncertainty = Uncertainty::Bound {
                de: e.de_bound,
                regular: Some(e.regular),
            };
            RenderedReading::new(k + 1, e.xyz, e.white, uncertainty)
        })
        .collect();
    (patches, white)
}
