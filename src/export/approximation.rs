//! The Lambertian form of an emitter whose radiance depends on direction, and what it
//! changes.
//!
//! Mitsuba 3's `area` emitter and pbrt-v4's `diffuse` area light radiate the same radiance
//! in every direction of the front hemisphere; neither can give an area light an angular
//! distribution (pbrt-v4's `goniometric` light is a point light, and a point light is not
//! the box's 25 tiles). A `cos_power` or `c_gamma` emitter is therefore written as
//! Lambertian tiles, each with its radiance towards the point the validation looks at:
//! tile t gets the gain g_t · f(ω_t), ω_t the direction from the tile's centre to the
//! centre of the 24 ColorChecker patches (the mean of their centres; without patches, the
//! mean of every surface's centre). The patches' direct light leaves the tiles along
//! directions near ω_t, so it changes least under this choice; light reaching the other
//! walls, at larger angles, is too bright (f falls with the angle), and reaches the
//! patches after a bounce.
//!
//! Aimed at the chart alone, the form sends the walls far more light than the scene does
//! (on the measured box the patches come out about 20 % too bright, ΔE*ab ≈ 5, from the
//! light the walls pass on). So when the radiosity solver can render the scene, the form
//! is fitted: the solver renders the 24 readings of the scene as it is and of the aimed
//! form, and every tile's gain is multiplied by the one factor c that makes the patches'
//! luminances agree in least squares, c = Σ Y·Y' / Σ Y'². Light transport is linear in
//! the emission, so the fitted form's readings are c times the aimed form's and no third
//! solve is needed. The per-patch ΔE*ab between the scene and the written form, both
//! against the exact scene's reference white, is stated in the README. Without the solver
//! (a scene it cannot render, or the measurement declined) the aimed form is written.

use std::time::Instant;

use super::error::ExportError;
use crate::color::Xyz;
use crate::render::geometry::Vec3;
use crate::render::method::Method;
use crate::render::radiosity::{render_spots_radiosity, RadiosityOptions};
use crate::render::scene::{Distribution, Scene};

/// The ΔE*ab bound the two radiosity solves are refined to: both share their mesh, so
/// their difference is known better than either reading.
const DIFFERENCE_TARGET_DE: f64 = 0.2;
/// Time allowed to each of the two solves.
const DIFFERENCE_MAX_SECONDS: f64 = 300.0;

/// How the scene's emitters are written.
#[derive(Clone, Debug)]
pub struct Approximation {
    /// Per emitter, per tile (`row * cols + col`): the gain written, the scene's gain
    /// times the directional factor towards [`Approximation::aim`] and the fitted factor
    /// (the scene's gain for a Lambertian emitter).
    pub gains: Vec<Vec<f64>>,
    /// Per emitter: written exactly (its distribution is Lambertian).
    pub exact: Vec<bool>,
    /// The point non-Lambertian tiles are aimed at, and whether it is the patches' centre.
    pub aim: [f64; 3],
    pub aim_is_chart: bool,
    /// The smallest and largest directional factor applied to a tile (None when every
    /// emitter is exact).
    pub factors: Option<(f64, f64)>,
    pub difference: Measured,
}

impl Approximation {
    /// Every emitter written as the scene states it.
    pub fn is_exact(&self) -> bool {
        self.exact.iter().all(|e| *e)
    }
}

/// What is known of the Lambertian form's effect on the 24 readings.
#[derive(Clone, Debug)]
pub enum Measured {
    /// Every emitter is Lambertian: nothing is approximated.
    NotNeeded,
    /// The request asked not to measure it.
    Skipped,
    /// The radiosity solver cannot render this scene (its reason).
    NotPossible(String),
    Done(Difference),
}

/// The 24 readings of the Lambertian form against those of the scene as it is.
#[derive(Clone, Debug)]
pub struct Difference {
    /// The factor every tile's aimed gain was multiplied by.
    pub fit_scale: f64,
    /// Max and mean ΔE*ab of the aimed form before the fit.
    pub aimed_de: (f64, f64),
    /// (patch, ΔE*ab) of the written (fitted) form, against the exact scene's white.
    pub per_patch: Vec<(usize, f64)>,
    pub max_de: f64,
    pub mean_de: f64,
    /// The smallest and largest Y(Lambertian form) / Y(scene) over the patches.
    pub luminance_ratio: (f64, f64),
    /// The radiosity solver's own bound on each side's readings (largest over patches).
    pub solver_bound_de: f64,
    pub seconds: f64,
}

fn centre(points: impl Iterator<Item = Vec3>) -> Option<Vec3> {
    let (sum, n) = points.fold((Vec3::ZERO, 0usize), |(s, n), p| (s + p, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// Chooses each emitter's form and, when one is approximated and `measure` is set,
/// measures the difference.
pub fn choose(scene: &Scene, name: &str, measure: bool) -> Result<Approximation, ExportError> {
    let chart = centre(
        scene
            .surfaces
            .iter()
            .filter(|s| s.patch.is_some())
            .map(|s| s.rect.centre()),
    );
    let aim = chart
        .or_else(|| centre(scene.surfaces.iter().map(|s| s.rect.centre())))
        .unwrap_or(Vec3::ZERO);
    let mut gains = Vec::with_capacity(scene.emitters.len());
    let mut exact = Vec::with_capacity(scene.emitters.len());
    let mut factors: Option<(f64, f64)> = None;
    for (i, e) in scene.emitters.iter().enumerate() {
        if e.distribution == Distribution::Lambertian {
            gains.push(e.gains.clone());
            exact.push(true);
            continue;
        }
        let mut g = Vec::with_capacity(e.gains.len());
        for row in 0..e.rows {
            for col in 0..e.cols {
                let t = row * e.cols + col;
                let c = e.rect.point(
                    (col as f64 + 0.5) / e.cols as f64,
                    (row as f64 + 0.5) / e.rows as f64,
                );
                let to = aim - c;
                if to.length() == 0.0 || to.dot(e.rect.normal) <= 0.0 {
                    return Err(ExportError::Emitter {
                        scene: name.to_string(),
                        emitter: i,
                        what: format!(
                            "tile (row {row}, col {col}) does not face the point its Lambertian \
                             form is aimed at ({:?}), so no radiance towards it can stand in for \
                             its distribution",
                            aim.to_array()
                        ),
                    });
                }
                let f = e.directional(to.normalize());
                factors = Some(match factors {
                    None => (f, f),
                    Some((lo, hi)) => (lo.min(f), hi.max(f)),
                });
                g.push(e.gains[t] * f);
            }
        }
        gains.push(g);
        exact.push(false);
    }
    let mut approximation = Approximation {
        gains,
        exact,
        aim: aim.to_array(),
        aim_is_chart: chart.is_some(),
        factors,
        difference: Measured::NotNeeded,
    };
    if !approximation.is_exact() {
        approximation.difference = if measure {
            measure_difference(scene, name, &approximation)?
        } else {
            Measured::Skipped
        };
        if let Measured::Done(d) = &approximation.difference {
            for (g, exact) in approximation.gains.iter_mut().zip(&approximation.exact) {
                if !exact {
                    g.iter_mut().for_each(|x| *x *= d.fit_scale);
                }
            }
        }
    }
    Ok(approximation)
}

/// The scene as the export writes it: every emitter Lambertian with the chosen gains.
pub fn lambertian_form(scene: &Scene, approximation: &Approximation) -> Scene {
    let mut s = scene.clone();
    for (e, g) in s.emitters.iter_mut().zip(&approximation.gains) {
        e.distribution = Distribution::Lambertian;
        e.gains = g.clone();
    }
    s
}

fn measure_difference(
    scene: &Scene,
    name: &str,
    approximation: &Approximation,
) -> Result<Measured, ExportError> {
    if scene.patch_surface(1).is_none() {
        return Ok(Measured::NotPossible(
            "the scene has no ColorChecker patches to compare".into(),
        ));
    }
    if let Err(why) = Method::Radiosity.resolve(scene) {
        return Ok(Measured::NotPossible(why.to_string()));
    }
    let start = Instant::now();
    let failed = |e: crate::render::radiosity::RadiosityError| ExportError::Difference {
        scene: name.to_string(),
        message: e.to_string(),
    };
    let options = RadiosityOptions {
        target_de: DIFFERENCE_TARGET_DE,
        max_seconds: DIFFERENCE_MAX_SECONDS,
        ..RadiosityOptions::default()
    };
    let exact = render_spots_radiosity(scene, &options, &|_| {}).map_err(failed)?;
    let lambertian = lambertian_form(scene, approximation);
    let options = RadiosityOptions {
        white: Some(exact.white),
        ..options
    };
    let aimed = render_spots_radiosity(&lambertian, &options, &|_| {}).map_err(failed)?;
    let pairs: Vec<(Xyz, Xyz)> = exact
        .patches
        .iter()
        .zip(&aimed.patches)
        .map(|(a, b)| (a.xyz, b.xyz))
        .collect();
    let (num, den) = pairs.iter().fold((0.0, 0.0), |(n, d), (a, b)| {
        (n + a[1] * b[1], d + b[1] * b[1])
    });
    if !(num > 0.0 && den > 0.0) {
        return Ok(Measured::NotPossible(
            "the Lambertian form leaves every patch dark".into(),
        ));
    }
    let c = num / den;
    let white = exact.white;
    let de = |a: Xyz, b: Xyz, k: f64| {
        let (la, lb) = (a.to_lab(white), b.scaled(k).to_lab(white));
        ((la.l - lb.l).powi(2) + (la.a - lb.a).powi(2) + (la.b - lb.b).powi(2)).sqrt()
    };
    let n = pairs.len().max(1) as f64;
    let before: Vec<f64> = pairs.iter().map(|(a, b)| de(*a, *b, 1.0)).collect();
    let per_patch: Vec<(usize, f64)> = exact
        .patches
        .iter()
        .zip(&pairs)
        .map(|(r, (a, b))| (r.patch, de(*a, *b, c)))
        .collect();
    let ratio = pairs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |r, (a, b)| {
            let q = c * b[1] / a[1];
            (r.0.min(q), r.1.max(q))
        });
    let bound = exact
        .patches
        .iter()
        .chain(&aimed.patches)
        .map(|r| r.uncertainty.de_ab())
        .fold(0.0, f64::max);
    Ok(Measured::Done(Difference {
        fit_scale: c,
        aimed_de: (
            before.iter().cloned().fold(0.0, f64::max),
            before.iter().sum::<f64>() / n,
        ),
        max_de: per_patch.iter().map(|p| p.1).fold(0.0, f64::max),
        mean_de: per_patch.iter().map(|p| p.1).sum::<f64>() / n,
        per_patch,
        luminance_ratio: ratio,
        solver_bound_de: bound,
        seconds: start.elapsed().as_secs_f64(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lambertian_box_is_written_exactly() {
        let scene = Scene::builtin("validation-box-led-rgb1").unwrap();
        let a = choose(&scene, "led", true).unwrap();
        assert!(a.is_exact());
        assert!(matches!(a.difference, Measured::NotNeeded));
        assert_eq!(a.gains[0], scene.emitters[0].gains);
    }

    #[test]
    fn a_cos_power_tile_gets_its_radiance_towards_the_chart_centre() {
        let mut scene = Scene::builtin("validation-box-led-rgb1").unwrap();
        scene.emitters[0].distribution = Distribution::CosPower(2.0);
        let a = choose(&scene, "led", false).unwrap();
        assert!(!a.is_exact());
        assert!(matches!(a.difference, Measured::Skipped));
        let e = &scene.emitters[0];
        // By hand for tile (0, 0): cos θ between the normal and the line to the aim.
        let c = e.rect.point(0.5 / e.cols as f64, 0.5 / e.rows as f64);
        let d = (Vec3::from_array(a.aim) - c).normalize();
        let cos = d.dot(e.rect.normal);
        assert!((a.gains[0][0] - e.gains[0] * cos * cos).abs() < 1e-12);
        let (lo, hi) = a.factors.unwrap();
        assert!(0.0 < lo && lo <= hi && hi <= 1.0);
    }
}
