//! The scene as one pbrt-v4 file (`scene.pbrt`). Facts from pbrt-v4's sources (github
//! mmp/pbrt-v4):
//!
//! - Inline `"spectrum"` parameters are (λ, value) pairs read into a
//!   `PiecewiseLinearSpectrum` as given (`src/pbrt/paramdict.cpp`,
//!   `extractSpectrumArray`), which is zero outside its first and last wavelength
//!   (`PiecewiseLinearSpectrum::operator()`, `src/pbrt/util/spectrum.cpp`).
//! - `DiffuseAreaLight::Create` (`src/pbrt/lights.cpp`) divides the light's `scale` by
//!   `SpectrumToPhotometric(L)` = Σ ȳ(λ)·L(λ) over 360–830 nm at 1 nm
//!   (`src/pbrt/util/spectrum.cpp`): the absolute level of `L` is thrown away and the
//!   light's ∫ȳL becomes `scale`. Each tile therefore carries its own luminance in cd/m²
//!   as `scale`; its emitted radiance is then 683·L, and a pixel's Y, which the `cie1931`
//!   sensor computes as the unnormalised ∫ȳ·L (`PixelSensor::ToSensorRGB`,
//!   `src/pbrt/film.h`; imaging ratio = exposure time · ISO / 100 = 1 · 100 / 100,
//!   `PixelSensor::Create` in `src/pbrt/film.cpp`), is in cd/m².
//! - The `rgb` film converts the sensor's XYZ to the film's colour space
//!   (`outputRGBFromSensorRGB = colorSpace->RGBFromXYZ * sensor->XYZFromSensorRGB`,
//!   `src/pbrt/film.cpp`); pbrt-v4 has no XYZ colour space, so the file holds RGB. The
//!   export asks for ACES2065-1, whose primaries enclose every real colour (no negative
//!   component to clip) and which pbrt writes into the EXR's `chromaticities` attribute
//!   (it omits the attribute only for sRGB, `src/pbrt/util/image.cpp`): XYZ is that
//!   attribute's RGB→XYZ matrix times the pixel. 32-bit floats (`savefp16` false).
//! - `LookAt` builds a camera whose x axis is up × view (`src/pbrt/util/transform.cpp`)
//!   and raster x grows with camera x (`src/pbrt/cameras.h`): in a right-handed scene that
//!   is a mirrored image. `Scale -1 1 1` before `LookAt` turns camera x into the scene's
//!   right (view × up), so the image comes out as metamer's. The perspective camera's
//!   `fov` is the shorter image axis's (`PerspectiveCamera::Create`, `src/pbrt/cameras.cpp`).
//! - The `path` integrator stops at `maxdepth` bounces (default 5); the box needs more.
//! - pbrt's `diffuse` material reflects on both sides and clamps its reflectance to
//!   [0, 1]; metamer's surfaces are black from behind. Inside the closed box no ray meets
//!   a back face, so the image is the same.

use std::fmt::Write;
use std::path::PathBuf;

use super::approximation::Approximation;
use super::common::{grid_nm, luminance, num, one_line, tiles, File};
use crate::render::scene::{Camera, Scene};

/// The scene file's name in the export.
pub const SCENE_FILE: &str = "scene.pbrt";
/// The image file the scene names.
pub const IMAGE_FILE: &str = "image.exr";
/// The film's colour space.
pub const COLOR_SPACE: &str = "aces2065-1";
/// Bounces the path integrator follows (Russian roulette ends most paths long before).
pub const MAX_DEPTH: u32 = 1000;

/// `"spectrum NAME" [ λ v λ v … ]` on the scene's grid.
fn spectrum(name: &str, values: &[f64]) -> String {
    let mut s = format!("\"spectrum {name}\" [");
    for (i, v) in values.iter().enumerate() {
        if i % 6 == 0 {
            s.push_str("\n       ");
        }
        let _ = write!(s, " {} {}", num(grid_nm(i)), num(*v));
    }
    s.push_str(" ]");
    s
}

fn point(v: [f64; 3]) -> String {
    format!("{} {} {}", num(v[0]), num(v[1]), num(v[2]))
}

/// A parallelogram as a two-triangle mesh with its normal given, so pbrt's front side is
/// the scene's (a mesh with `N` faces its geometric normal towards it, `src/pbrt/shapes.h`).
fn quad(corner: [f64; 3], u: [f64; 3], v: [f64; 3]) -> String {
    let at = |a: f64, b: f64| -> [f64; 3] {
        [
            corner[0] + a * u[0] + b * v[0],
            corner[1] + a * u[1] + b * v[1],
            corner[2] + a * u[2] + b * v[2],
        ]
    };
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let n = [n[0] / len, n[1] / len, n[2] / len];
    format!(
        "    Shape \"trianglemesh\"\n        \"point3 P\" [ {} {} {} {} ]\n        \
         \"integer indices\" [ 0 1 2 0 2 3 ]\n        \"normal N\" [ {} {} {} {} ]\n",
        point(at(0.0, 0.0)),
        point(at(1.0, 0.0)),
        point(at(1.0, 1.0)),
        point(at(0.0, 1.0)),
        point(n),
        point(n),
        point(n),
        point(n)
    )
}

/// The pbrt-v4 `fov`: the shorter image axis's field of view for the scene's vertical one.
pub fn fov_deg(camera: &Camera) -> f64 {
    if camera.width >= camera.height {
        camera.vfov_deg
    } else {
        let half = (camera.vfov_deg.to_radians() / 2.0).tan();
        2.0 * (half * camera.width as f64 / camera.height as f64)
            .atan()
            .to_degrees()
    }
}

/// The scene file.
pub(super) fn files(
    scene: &Scene,
    camera: &Camera,
    approximation: &Approximation,
    spp: u32,
) -> Vec<File> {
    let mut x = String::new();
    let _ = writeln!(
        x,
        "# {}: written by metamer export for pbrt-v4. The image is RGB in ACES2065-1 \
         whose XYZ is in cd/m2, not mirrored; see README.md.",
        one_line(&scene.name)
    );
    let _ = writeln!(
        x,
        "# The image as metamer writes it: mirror camera x (see README.md)."
    );
    let _ = writeln!(x, "Scale -1 1 1");
    let target = (camera.position + camera.forward).to_array();
    let _ = writeln!(
        x,
        "LookAt {}\n       {}\n       {}",
        point(camera.position.to_array()),
        point(target),
        point(camera.up.to_array())
    );
    let _ = writeln!(
        x,
        "Camera \"perspective\" \"float fov\" [ {} ]",
        num(fov_deg(camera))
    );
    let _ = writeln!(
        x,
        "Sampler \"independent\" \"integer pixelsamples\" [ {spp} ]"
    );
    let _ = writeln!(
        x,
        "Integrator \"path\" \"integer maxdepth\" [ {MAX_DEPTH} ]"
    );
    let _ = writeln!(
        x,
        "PixelFilter \"box\" \"float xradius\" [ 0.5 ] \"float yradius\" [ 0.5 ]"
    );
    let _ = writeln!(x, "ColorSpace \"{COLOR_SPACE}\"");
    let _ = writeln!(
        x,
        "Film \"rgb\"\n    \"integer xresolution\" [ {} ]\n    \"integer yresolution\" [ {} ]\n    \
         \"string filename\" [ \"{IMAGE_FILE}\" ]\n    \"string sensor\" [ \"cie1931\" ]\n    \
         \"float iso\" [ 100 ]\n    \"bool savefp16\" [ false ]",
        camera.width, camera.height
    );
    let _ = writeln!(x, "\nWorldBegin\n");
    for s in &scene.surfaces {
        let _ = writeln!(x, "# surface {}", one_line(&s.name));
        let _ = writeln!(x, "AttributeBegin");
        let _ = writeln!(
            x,
            "    Material \"diffuse\" {}",
            spectrum("reflectance", &s.reflectance)
        );
        x.push_str(&quad(
            s.rect.corner.to_array(),
            s.rect.edge_u.to_array(),
            s.rect.edge_v.to_array(),
        ));
        let _ = writeln!(x, "AttributeEnd\n");
    }
    for t in tiles(scene, approximation) {
        let _ = writeln!(
            x,
            "# emitter {} tile row {} col {}: luminance along the normal {} cd/m2",
            t.emitter,
            t.row,
            t.col,
            num(luminance(scene, &t.radiance))
        );
        let _ = writeln!(x, "AttributeBegin");
        let lum = luminance(scene, &t.radiance);
        // A dark tile has no light: pbrt would divide its scale by its zero luminance.
        if lum > 0.0 {
            let _ = writeln!(
                x,
                "    AreaLightSource \"diffuse\" {}\n        \"float scale\" [ {} ]",
                spectrum("L", &t.radiance),
                num(lum)
            );
        }
        let _ = writeln!(
            x,
            "    Material \"diffuse\" {}",
            spectrum("reflectance", t.reflectance)
        );
        x.push_str(&quad(t.corner, t.edge_u, t.edge_v));
        let _ = writeln!(x, "AttributeEnd\n");
    }
    vec![File {
        rel: PathBuf::from(SCENE_FILE),
        text: x,
    }]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tall_image_gives_pbrt_the_horizontal_field() {
        let mut c = Scene::builtin("validation-box").unwrap().camera.unwrap();
        c.vfov_deg = 90.0;
        (c.width, c.height) = (100, 200);
        // tan(45°)·100/200 = ½: 2·atan(½) = 53.130102…°.
        assert!((fov_deg(&c) - 53.13010235415598).abs() < 1e-12);
        (c.width, c.height) = (300, 200);
        assert_eq!(fov_deg(&c), 90.0);
    }
}
