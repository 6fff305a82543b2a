//! Validation of a parsed scene file into the render-ready [`Scene`]: geometry, spectra on
//! the 1 nm grid, the emitters' tile spectra and distributions, and the limits.

use std::sync::Arc;

use super::super::geometry::{Rect, Vec3, VecOps};
use super::super::spectral::{cmf_bins, constant_bins};
use super::file::{CameraFile, DistributionFile, EmitterFile, SceneFile};
use super::loader::{err, Loader, SpectrumFiles, R};
use super::model::{
    Camera, Distribution, Emitter, Scene, Surface, MAX_EMITTERS, MAX_LUMINANCE_CD_M2, MAX_SURFACES,
    MAX_TILES, MAX_TILES_PER_SIDE, MAX_TILE_SPECTRA,
};
use super::reader::PathError;
use crate::color::{ObserverKind, K_M};

/// The whole scene: its sizes first, then the surfaces, the emitters, the camera and the
/// meter, then what only the whole can show (emitters hidden in a surface, no light).
pub fn scene(file: &SceneFile, files: SpectrumFiles) -> R<Scene> {
    check_sizes(file)?;
    let mut loader = Loader::new(files);
    let mut warnings = Vec::new();
    let surfaces = surfaces(file, &mut loader, &mut warnings)?;
    let cmf = cmf_bins(ObserverKind::Cie1931);
    let emitters = emitters(file, &mut loader, &cmf[1], &mut warnings)?;
    let camera = match &file.camera {
        Some(c) => Some(camera(c)?),
        None => None,
    };
    let meter_acceptance_deg = match &file.meter {
        Some(m) => Some(meter_acceptance(m.acceptance_deg)?),
        None => None,
    };
    let scene = Scene {
        name: file.name.clone(),
        surfaces,
        emitters,
        camera,
        meter_acceptance_deg,
        cmf,
        provenance: file.provenance.clone(),
        warnings,
    };
    super::hidden::check(&scene.surfaces, &scene.emitters)?;
    check_emits_light(&scene)?;
    Ok(scene)
}

/// The counts of surfaces, emitters and tiles, before anything is allocated for them.
fn check_sizes(file: &SceneFile) -> R<()> {
    if file.surfaces.len() > MAX_SURFACES {
        return err(
            "surfaces",
            format!(
                "{} surfaces; a scene may have at most {MAX_SURFACES}",
                file.surfaces.len()
            ),
        );
    }
    if file.emitters.is_empty() {
        return err("emitters", "at least one emitter is needed");
    }
    if file.emitters.len() > MAX_EMITTERS {
        return err(
            "emitters",
            format!(
                "{} emitters; a scene may have at most {MAX_EMITTERS}",
                file.emitters.len()
            ),
        );
    }
    // Tile counts first: nothing is allocated for a grid before its size is known to fit.
    let mut tiles = 0usize;
    for (i, e) in file.emitters.iter().enumerate() {
        for (what, n) in [("rows", e.rows), ("cols", e.cols)] {
            if n == 0 || n > MAX_TILES_PER_SIDE {
                return err(
                    format!("emitters[{i}].{what}"),
                    format!("must be 1–{MAX_TILES_PER_SIDE}, got {n}"),
                );
            }
        }
        tiles += e.rows * e.cols;
        if tiles > MAX_TILES {
            return err(
                format!("emitters[{i}]"),
                format!("the scene's emitters have more than {MAX_TILES} tiles in all"),
            );
        }
    }
    Ok(())
}

/// The surfaces: each rectangle, its reflectance and the patch it shows.
fn surfaces(file: &SceneFile, loader: &mut Loader, warnings: &mut Vec<String>) -> R<Vec<Surface>> {
    let mut surfaces = Vec::with_capacity(file.surfaces.len());
    for (i, s) in file.surfaces.iter().enumerate() {
        let p = format!("surfaces[{i}]");
        let rect = rect(&p, s.corner, s.edge_u, s.edge_v)?;
        let reflectance =
            loader.reflectance(&format!("{p}.reflectance"), &s.reflectance, warnings)?;
        if let Some(k) = s.patch {
            if !(1..=24).contains(&k) {
                return err(format!("{p}.patch"), format!("must be 1–24, got {k}"));
            }
        }
        surfaces.push(Surface {
            name: s.name.clone(),
            rect,
            reflectance,
            patch: s.patch,
        });
    }
    Ok(surfaces)
}

/// The emitters, with the count of distinct tile spectra over all of them bounded.
fn emitters(
    file: &SceneFile,
    loader: &mut Loader,
    ybar: &[f64],
    warnings: &mut Vec<String>,
) -> R<Vec<Emitter>> {
    let mut emitters = Vec::new();
    let mut distinct = 0;
    for (i, e) in file.emitters.iter().enumerate() {
        let em = emitter(&format!("emitters[{i}]"), e, loader, ybar, warnings)?;
        distinct += em.spectra.len();
        if distinct > MAX_TILE_SPECTRA {
            return err(
                format!("emitters[{i}].tiles"),
                format!(
                    "more than {MAX_TILE_SPECTRA} distinct tile spectra in the scene (tiles whose \
                     spectra are proportional share one)"
                ),
            );
        }
        emitters.push(em);
    }
    Ok(emitters)
}

/// The spot meter's acceptance angle.
fn meter_acceptance(a: f64) -> R<f64> {
    if !(a > 0.0 && a < 90.0) {
        return err("meter.acceptance_deg", "must be in (0, 90)");
    }
    Ok(a)
}

/// A scene whose every reading would be 0/0 is refused.
fn check_emits_light(scene: &Scene) -> R<()> {
    let intensity = scene.intensity_cd();
    if !(intensity > 0.0 && intensity.is_finite()) {
        return err(
            "emitters",
            format!(
                "the scene emits no light (luminous intensity {intensity} cd): every tile's \
                 gain or luminance is 0, so every reading would be 0/0"
            ),
        );
    }
    Ok(())
}

fn camera(c: &CameraFile) -> R<Camera> {
    let position = finite3("camera.position", c.position)?;
    let forward = finite3("camera.look_at", c.look_at)?.minus(position);
    if forward.length() == 0.0 || !forward.length().is_finite() {
        return err("camera.look_at", "must differ from position");
    }
    let forward = forward.normalized();
    let right = forward.cross(finite3("camera.up", c.up)?);
    if right.length().is_nan() || right.length() < 1e-9 {
        return err("camera.up", "must not be parallel to the view");
    }
    let right = right.normalized();
    let up = right.cross(forward);
    if !(c.vfov_deg > 0.0 && c.vfov_deg < 179.0) {
        return err("camera.vfov_deg", "must be in (0, 179)");
    }
    // The image buffer is width × height XYZ triples.
    for (what, n) in [("width", c.width), ("height", c.height)] {
        if n == 0 || n > 16_384 {
            return err(format!("camera.{what}"), "image size must be 1–16384");
        }
    }
    Ok(Camera {
        position,
        forward,
        right,
        up,
        vfov_deg: c.vfov_deg,
        width: c.width,
        height: c.height,
    })
}

fn finite3(path: &str, v: [f64; 3]) -> R<Vec3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vec3::from_array(v))
    } else {
        err(path, "must be finite numbers")
    }
}

fn rect(p: &str, c: [f64; 3], u: [f64; 3], v: [f64; 3]) -> R<Rect> {
    let c = finite3(&format!("{p}.corner"), c)?;
    let u = finite3(&format!("{p}.edge_u"), u)?;
    let v = finite3(&format!("{p}.edge_v"), v)?;
    if u.length() == 0.0 || v.length() == 0.0 {
        return err(format!("{p}.edge_u"), "edges must be non-zero");
    }
    if !(u.cross(v).length().is_finite() && u.cross(v).length() > 0.0) {
        return err(
            format!("{p}.edge_u"),
            "the area must be finite and non-zero",
        );
    }
    if u.dot(v).abs() > 1e-9 * u.length() * v.length() {
        return err(format!("{p}.edge_v"), "must be orthogonal to edge_u");
    }
    Ok(Rect::new(c, u, v))
}

/// Luminance of a spectrum on the grid (cd/m² for a radiance in W·sr⁻¹·m⁻²·nm⁻¹).
fn luminance(s: &[f64], ybar: &[f64]) -> f64 {
    K_M * s.iter().zip(ybar).map(|(a, b)| a * b).sum::<f64>()
}

fn emitter(
    p: &str,
    e: &EmitterFile,
    loader: &mut Loader,
    ybar: &[f64],
    warnings: &mut Vec<String>,
) -> R<Emitter> {
    let rect = rect(p, e.corner, e.edge_u, e.edge_v)?;
    let n = e.rows * e.cols;
    let (mut gains, given) = tile_gains(p, e)?;
    let absolute = e.tiles.iter().any(|t| t.spectrum.is_some());
    let (spectra, tile_spectrum, scale) = if absolute {
        absolute_spectra(p, e, loader, ybar, &given, &mut gains)?
    } else {
        let (spectrum, scale) = relative_spectrum(p, e, loader, ybar)?;
        (vec![spectrum], vec![0; n], scale)
    };
    let mut brightest_tile: f64 = 0.0;
    for (k, g) in gains.iter().enumerate() {
        let lum = g * luminance(&spectra[tile_spectrum[k] as usize], ybar);
        brightest_tile = brightest_tile.max(lum);
        if lum.is_nan() || lum > MAX_LUMINANCE_CD_M2 {
            return err(
                format!("{p}.tiles[{}].gain", given[k].unwrap_or(0)),
                format!(
                    "gives the tile a luminance of {lum:e} cd/m², above {MAX_LUMINANCE_CD_M2:e}"
                ),
            );
        }
    }
    let dp = format!("{p}.distribution");
    let distribution = distribution(&dp, &e.distribution, loader)?;
    if let Distribution::Table(table) = &distribution {
        check_table_peak(&dp, &e.distribution, table, brightest_tile)?;
    }
    let reflectance = match &e.reflectance {
        Some(r) => loader.reflectance(&format!("{p}.reflectance"), r, warnings)?,
        None => constant_bins(0.0),
    };
    Ok(Emitter {
        axis_u: rect.edge_u.normalized(),
        axis_v: rect.edge_v.normalized(),
        rect,
        rows: e.rows,
        cols: e.cols,
        gains,
        tile_spectrum,
        spectra,
        scale,
        distribution,
        reflectance,
    })
}

/// Each tile's gain, row by row, and which entry of `tiles` gave it. No tiles listed: an
/// untiled panel, every tile at gain 1; else every tile must be listed once.
fn tile_gains(p: &str, e: &EmitterFile) -> R<(Vec<f64>, Vec<Option<usize>>)> {
    let n = e.rows * e.cols;
    let fill = if e.tiles.is_empty() { 1.0 } else { f64::NAN };
    let mut gains = vec![fill; n];
    let mut given: Vec<Option<usize>> = vec![None; n];
    for (i, t) in e.tiles.iter().enumerate() {
        let tp = format!("{p}.tiles[{i}]");
        if t.row >= e.rows {
            return err(format!("{tp}.row"), format!("must be < rows = {}", e.rows));
        }
        if t.col >= e.cols {
            return err(format!("{tp}.col"), format!("must be < cols = {}", e.cols));
        }
        if !(t.gain >= 0.0 && t.gain.is_finite()) {
            return err(format!("{tp}.gain"), "must be ≥ 0");
        }
        let k = t.row * e.cols + t.col;
        if given[k].is_some() {
            return err(tp, format!("tile ({}, {}) given twice", t.row, t.col));
        }
        given[k] = Some(i);
        gains[k] = t.gain;
    }
    if let Some(i) = gains.iter().position(|g| g.is_nan()) {
        return err(
            format!("{p}.tiles"),
            format!("tile ({}, {}) is missing", i / e.cols, i % e.cols),
        );
    }
    Ok((gains, given))
}

/// Tiles with their own absolute spectral radiance: the distinct spectra, each tile's
/// entry among them (its gain times the proportion to that entry), and the scale 1.
fn absolute_spectra(
    p: &str,
    e: &EmitterFile,
    loader: &mut Loader,
    ybar: &[f64],
    given: &[Option<usize>],
    gains: &mut [f64],
) -> R<(Vec<Vec<f64>>, Vec<u32>, f64)> {
    if e.spectrum.is_some() {
        return err(
            format!("{p}.spectrum"),
            "must be absent when the tiles carry their own (absolute) spectra",
        );
    }
    if e.luminance_cd_m2.is_some() {
        return err(
            format!("{p}.luminance_cd_m2"),
            "must be absent when the tiles carry absolute spectra: their luminance follows \
             from the spectra",
        );
    }
    let mut spectra: Vec<Vec<f64>> = Vec::new();
    let mut sums: Vec<f64> = Vec::new();
    let mut tile_spectrum = vec![0u32; given.len()];
    for (k, g) in given.iter().enumerate() {
        let i = g.expect("every tile is given");
        let sp = format!("{p}.tiles[{i}].spectrum");
        let Some(s) = &e.tiles[i].spectrum else {
            return err(
                sp,
                "missing: when one tile has a spectrum, every tile of the emitter needs one",
            );
        };
        let s = loader.spectrum(&sp, s)?;
        if s.iter().any(|v| *v < 0.0) {
            return err(sp, "a spectral radiance must be ≥ 0");
        }
        let lum = luminance(&s, ybar);
        if lum.is_nan() || lum > MAX_LUMINANCE_CD_M2 {
            return err(
                sp,
                format!("luminance {lum:e} cd/m² is above {MAX_LUMINANCE_CD_M2:e}"),
            );
        }
        // Proportional spectra share one entry: the radiosity solver solves once per
        // entry, and a measured box's tiles often differ by brightness only.
        let sum: f64 = s.iter().sum();
        let found = spectra.iter().zip(&sums).position(|(c, cs)| {
            *cs > 0.0 && {
                let r = sum / cs;
                let tol = 1e-12 * s.iter().cloned().fold(0.0, f64::max);
                c.iter().zip(&s).all(|(a, b)| (r * a - b).abs() <= tol)
            }
        });
        match found {
            Some(c) => {
                gains[k] *= sum / sums[c];
                tile_spectrum[k] = c as u32;
            }
            None => {
                if spectra.len() == MAX_TILE_SPECTRA {
                    return err(
                        sp,
                        format!("more than {MAX_TILE_SPECTRA} distinct tile spectra"),
                    );
                }
                tile_spectrum[k] = spectra.len() as u32;
                sums.push(sum);
                spectra.push(s);
            }
        }
    }
    Ok((spectra, tile_spectrum, 1.0))
}

/// One relative spectrum for every tile, scaled to the emitter's luminance: the absolute
/// spectrum and the scale.
fn relative_spectrum(
    p: &str,
    e: &EmitterFile,
    loader: &mut Loader,
    ybar: &[f64],
) -> R<(Vec<f64>, f64)> {
    let sp = format!("{p}.spectrum");
    let relative = match &e.spectrum {
        Some(s) => loader.spectrum(&sp, s)?,
        None => constant_bins(1.0),
    };
    if relative.iter().any(|v| *v < 0.0) {
        return err(sp, "must be ≥ 0");
    }
    let lum = luminance(&relative, ybar) / K_M;
    if !(lum > 0.0 && lum.is_finite()) {
        return err(sp, "has no luminance (zero under ȳ)");
    }
    let lp = format!("{p}.luminance_cd_m2");
    let Some(l) = e.luminance_cd_m2 else {
        return err(
            lp,
            "missing: a relative spectrum needs the luminance it is scaled to \
             (or give every tile an absolute spectrum)",
        );
    };
    if !(l >= 0.0 && l.is_finite()) {
        return err(lp, "must be ≥ 0");
    }
    if l > MAX_LUMINANCE_CD_M2 {
        return err(lp, format!("must be at most {MAX_LUMINANCE_CD_M2:e}"));
    }
    // s from Eq. 8 summed on the same grid as every reading.
    let scale = l / (K_M * lum);
    Ok((relative.iter().map(|v| v * scale).collect(), scale))
}

/// The emitter's angular distribution (`dp`: its JSON path), a photometric file read
/// beside the scene file.
fn distribution(dp: &str, d: &DistributionFile, loader: &Loader) -> R<Distribution> {
    Ok(match d {
        DistributionFile::Lambertian => Distribution::Lambertian,
        DistributionFile::CosPower { exponent } => {
            if !(*exponent >= 0.0 && exponent.is_finite()) {
                return err(format!("{dp}.exponent"), "must be ≥ 0");
            }
            Distribution::CosPower(*exponent)
        }
        DistributionFile::CGamma { table } => Distribution::Table(Arc::new(table.clone())),
        DistributionFile::Ies { file } | DistributionFile::Ldt { file } => {
            let SpectrumFiles::Dir(dir) = loader.files else {
                return err(
                    format!("{dp}.file"),
                    "built-in scenes name no photometric file",
                );
            };
            let path = dir.join(file);
            let read = if matches!(d, DistributionFile::Ies { .. }) {
                crate::light::ies::read(&path)
            } else {
                crate::light::ldt::read(&path)
            };
            let (table, _) = read.map_err(|e| PathError {
                path: format!("{dp}.file"),
                message: e.to_string(),
            })?;
            Distribution::Table(Arc::new(table))
        }
    })
}

/// A light table is relative to the normal's luminance, so its largest value times the
/// brightest tile's luminance is the brightest the emitter looks from any side: above
/// [`MAX_LUMINANCE_CD_M2`] the renderers' sums overflow (and the solver then blamed the
/// reflectances). Said of the table's value, where it is, or of its file.
fn check_table_peak(
    dp: &str,
    file: &DistributionFile,
    table: &crate::light::CGammaTable,
    brightest_tile: f64,
) -> R<()> {
    let mut peak = (0.0f64, 0, 0);
    for (c, row) in table.values().iter().enumerate() {
        for (g, &v) in row.iter().enumerate() {
            if v > peak.0 {
                peak = (v, c, g);
            }
        }
    }
    let (f, c, g) = peak;
    let seen = f * brightest_tile;
    if seen <= MAX_LUMINANCE_CD_M2 {
        return Ok(());
    }
    let (c_deg, g_deg) = (table.c_deg()[c], table.gamma_deg()[g]);
    // Short: a path error's message is cut past 120 characters.
    let what = format!(
        "{f:e} (C {c_deg}°, γ {g_deg}°) makes a tile {seen:.1e} cd/m² there, above the \
         {MAX_LUMINANCE_CD_M2:e} cd/m² a scene may hold"
    );
    match file {
        DistributionFile::CGamma { .. } => err(format!("{dp}.table.values[{c}][{g}]"), what),
        DistributionFile::Ies { file } | DistributionFile::Ldt { file } => err(
            format!("{dp}.file"),
            format!("{file}: its relative luminance {what}"),
        ),
        _ => err(dp.to_string(), what),
    }
}

/// A built-in scene from its text.
pub fn builtin_scene(text: &str) -> R<Scene> {
    let file = SceneFile::from_json(text)?;
    scene(&file, SpectrumFiles::Builtin)
}
