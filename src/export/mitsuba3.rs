//! The scene as Mitsuba 3 XML (`scene.xml`) with its spectra as `.spd` files
//! (`spectra/*.spd`: one "wavelength value" pair a line, the format of
//! `spectrum_from_file` in mitsuba3's `src/core/spectrum.cpp`).
//!
//! - Every rectangle is a `rectangle` shape ([-1, 1]² in local x, y, normal +z) whose
//!   `to_world` matrix maps x to `edge_u`/2, y to `edge_v`/2, z to the unit normal and the
//!   origin to the centre, so its front face is the scene's (the mapping of
//!   `benches/mitsuba/validation_box.py`, checked there on the emitter). Surfaces are
//!   `diffuse` BSDFs, one-sided in Mitsuba as in metamer.
//! - Tabulated spectra are irregular spectra read from the `.spd` files: linear between
//!   samples and zero outside the table (`IrregularContinuousDistribution::eval_pdf` in
//!   `include/mitsuba/core/distr_1d.h`); a constant spectrum is written as a `value`
//!   (uniform), because an irregular spectrum refuses an all-zero table.
//! - Each emitter tile is a `rectangle` with an `area` emitter of its absolute radiance.
//! - The film is a `specfilm` whose three channels X, Y, Z have the scene's CIE 1931
//!   colour-matching functions times K_m = 683 on 380–780 nm as their response functions.
//!   specfilm stores the unnormalised ∫ L(λ)·srf(λ) dλ per channel (measured on the
//!   emitter in `benches/mitsuba/README.md`) and names its channels in alphabetical order
//!   (`src/films/specfilm.cpp`), so a pixel is XYZ in cd/m² by the scene's own table.
//!   `hdrfilm` with `pixel_format="xyz"` would instead divide by Mitsuba's ∫ȳ and use
//!   Mitsuba's own CIE table over 360–830 nm; it is not used, so nothing but the scene's
//!   table stands between the render and metamer's numbers. A box filter makes a pixel
//!   the mean over its footprint, as metamer's image is.
//! - The sensor is a `perspective` camera with `fov_axis` y (the scene's vertical field),
//!   placed with `lookat` at the scene camera's position, view and up.

use std::collections::HashMap;
use std::fmt::Write;
use std::path::PathBuf;

use super::approximation::Approximation;
use super::common::{grid_nm, num, tiles, xml_comment, File};
use crate::render::scene::{Camera, Scene};

/// The scene file's name in the export.
pub const SCENE_FILE: &str = "scene.xml";

/// The `.spd` files written so far, one per distinct spectrum.
struct Spectra {
    files: Vec<File>,
    seen: HashMap<Vec<u64>, String>,
}

impl Spectra {
    /// The XML of a spectrum parameter `name`: a `value` for a constant, else a file.
    fn element(&mut self, name: &str, stem: &str, values: &[f64]) -> String {
        if values.iter().all(|v| *v == values[0]) {
            return format!(r#"<spectrum name="{name}" value="{}"/>"#, num(values[0]));
        }
        let key: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
        let rel = match self.seen.get(&key) {
            Some(rel) => rel.clone(),
            None => {
                let rel = format!("spectra/{stem}.spd");
                let mut text = String::from("# wavelength (nm) value; written by metamer export\n");
                for (i, v) in values.iter().enumerate() {
                    let _ = writeln!(text, "{} {}", num(grid_nm(i)), num(*v));
                }
                self.files.push(File {
                    rel: PathBuf::from(&rel),
                    text,
                });
                self.seen.insert(key, rel.clone());
                rel
            }
        };
        format!(r#"<spectrum name="{name}" filename="{rel}"/>"#)
    }
}

/// `to_world` of Mitsuba's rectangle for a parallelogram, row-major.
fn rect_matrix(corner: [f64; 3], u: [f64; 3], v: [f64; 3]) -> String {
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let o: Vec<f64> = (0..3).map(|k| corner[k] + 0.5 * (u[k] + v[k])).collect();
    let mut m = Vec::with_capacity(16);
    for k in 0..3 {
        m.extend([u[k] / 2.0, v[k] / 2.0, n[k] / len, o[k]]);
    }
    m.extend([0.0, 0.0, 0.0, 1.0]);
    m.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ")
}

fn triple(v: [f64; 3]) -> String {
    format!("{}, {}, {}", num(v[0]), num(v[1]), num(v[2]))
}

/// A name safe inside an XML attribute and a file name.
fn slug(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// The scene file and its spectra.
pub(super) fn files(
    scene: &Scene,
    camera: &Camera,
    approximation: &Approximation,
    spp: u32,
) -> Vec<File> {
    let mut spectra = Spectra {
        files: Vec::new(),
        seen: HashMap::new(),
    };
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="utf-8"?>"#);
    let _ = writeln!(
        x,
        "<!-- {}: written by metamer export for Mitsuba 3 (a spectral variant, e.g. \
         scalar_spectral). The image is XYZ in cd/m2, not mirrored; see README.md. -->",
        xml_comment(&scene.name)
    );
    let _ = writeln!(x, r#"<scene version="3.0.0">"#);
    for (k, v) in [
        ("spp", spp.to_string()),
        ("width", camera.width.to_string()),
        ("height", camera.height.to_string()),
        ("max_depth", "-1".to_string()),
    ] {
        let _ = writeln!(x, r#"    <default name="{k}" value="{v}"/>"#);
    }
    x.push_str(
        r#"    <integrator type="path">
        <integer name="max_depth" value="$max_depth"/>
    </integrator>
"#,
    );
    sensor(&mut x, scene, camera, &mut spectra);
    shapes(&mut x, scene, approximation, &mut spectra);
    let _ = writeln!(x, "</scene>");
    let mut out = vec![File {
        rel: PathBuf::from(SCENE_FILE),
        text: x,
    }];
    out.extend(spectra.files);
    out
}

/// The camera: a perspective sensor whose film records X, Y and Z in cd/m² (the CIE 1931
/// functions times K_m as its response functions).
fn sensor(x: &mut String, scene: &Scene, camera: &Camera, spectra: &mut Spectra) {
    let target = (camera.position + camera.forward).to_array();
    let _ = writeln!(x, r#"    <sensor type="perspective">"#);
    let _ = writeln!(
        x,
        r#"        <float name="fov" value="{}"/>"#,
        num(camera.vfov_deg)
    );
    let _ = writeln!(x, r#"        <string name="fov_axis" value="y"/>"#);
    let _ = writeln!(x, r#"        <float name="near_clip" value="0.001"/>"#);
    let _ = writeln!(x, r#"        <transform name="to_world">"#);
    let _ = writeln!(
        x,
        r#"            <lookat origin="{}" target="{}" up="{}"/>"#,
        triple(camera.position.to_array()),
        triple(target),
        triple(camera.up.to_array())
    );
    let _ = writeln!(x, r#"        </transform>"#);
    let _ = writeln!(x, r#"        <sampler type="independent">"#);
    let _ = writeln!(
        x,
        r#"            <integer name="sample_count" value="$spp"/>"#
    );
    let _ = writeln!(x, r#"        </sampler>"#);
    let _ = writeln!(x, r#"        <film type="specfilm">"#);
    let _ = writeln!(x, r#"            <integer name="width" value="$width"/>"#);
    let _ = writeln!(x, r#"            <integer name="height" value="$height"/>"#);
    let _ = writeln!(
        x,
        r#"            <string name="component_format" value="float32"/>"#
    );
    let _ = writeln!(x, r#"            <rfilter type="box"/>"#);
    for (k, ch) in ["X", "Y", "Z"].iter().enumerate() {
        // specfilm samples wavelengths by the response functions, so it refuses negative
        // entries; the 1 nm table's z̄ has a few of order 1e-18 from interpolation.
        let srf: Vec<f64> = scene.cmf[k]
            .iter()
            .map(|c| c.max(0.0) * metamer_color::K_M)
            .collect();
        let stem = format!("cie1931_{}bar_times_683", ch.to_lowercase());
        let _ = writeln!(x, "            {}", spectra.element(ch, &stem, &srf));
    }
    let _ = writeln!(x, r#"        </film>"#);
    let _ = writeln!(x, r#"    </sensor>"#);
}

/// The box's surfaces and the emitters' tiles, each a rectangle with its spectra.
fn shapes(x: &mut String, scene: &Scene, approximation: &Approximation, spectra: &mut Spectra) {
    for (i, s) in scene.surfaces.iter().enumerate() {
        let id = format!("surface_{i:03}_{}", slug(&s.name));
        let _ = writeln!(x, r#"    <shape type="rectangle" id="{id}">"#);
        let _ = writeln!(
            x,
            r#"        <transform name="to_world"><matrix value="{}"/></transform>"#,
            rect_matrix(
                s.rect.corner.to_array(),
                s.rect.edge_u.to_array(),
                s.rect.edge_v.to_array()
            )
        );
        let _ = writeln!(x, r#"        <bsdf type="diffuse">"#);
        let _ = writeln!(
            x,
            "            {}",
            spectra.element("reflectance", &format!("reflectance_{id}"), &s.reflectance)
        );
        let _ = writeln!(x, r#"        </bsdf>"#);
        let _ = writeln!(x, r#"    </shape>"#);
    }
    for t in tiles(scene, approximation) {
        let id = format!("emitter_{}_tile_r{}_c{}", t.emitter, t.row, t.col);
        let _ = writeln!(x, r#"    <shape type="rectangle" id="{id}">"#);
        let _ = writeln!(
            x,
            r#"        <transform name="to_world"><matrix value="{}"/></transform>"#,
            rect_matrix(t.corner, t.edge_u, t.edge_v)
        );
        let _ = writeln!(x, r#"        <emitter type="area">"#);
        let _ = writeln!(
            x,
            "            {}",
            spectra.element("radiance", &format!("radiance_{id}"), &t.radiance)
        );
        let _ = writeln!(x, r#"        </emitter>"#);
        let _ = writeln!(x, r#"        <bsdf type="diffuse">"#);
        let _ = writeln!(
            x,
            "            {}",
            spectra.element(
                "reflectance",
                &format!("reflectance_emitter_{}", t.emitter),
                t.reflectance
            )
        );
        let _ = writeln!(x, r#"        </bsdf>"#);
        let _ = writeln!(x, r#"    </shape>"#);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rectangle_matrix_maps_the_local_square_onto_the_parallelogram() {
        // Local (-1,-1) → corner, (1,1) → corner + u + v, +z → unit(u × v).
        let m: Vec<f64> = rect_matrix([1.0, 2.0, 3.0], [0.0, 0.0, 2.0], [0.0, 4.0, 0.0])
            .split(' ')
            .map(|s| s.parse().unwrap())
            .collect();
        let apply = |p: [f64; 4]| -> Vec<f64> {
            (0..3)
                .map(|r| (0..4).map(|c| m[r * 4 + c] * p[c]).sum())
                .collect()
        };
        assert_eq!(apply([-1.0, -1.0, 0.0, 1.0]), vec![1.0, 2.0, 3.0]);
        assert_eq!(apply([1.0, 1.0, 0.0, 1.0]), vec![1.0, 6.0, 5.0]);
        // (0,0,2) × (0,4,0) = (-8, 0, 0).
        assert_eq!(apply([0.0, 0.0, 1.0, 0.0]), vec![-1.0, 0.0, 0.0]);
    }
}
