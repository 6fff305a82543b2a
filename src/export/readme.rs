//! The README written beside an export: how to render it, what the image holds, what the
//! renderer cannot express of the scene and the difference that makes.

use std::fmt::Write;

use super::approximation::{Approximation, Measured};
use super::common::Renderer;
use super::{blender, mitsuba3, pbrt};
use crate::render::scene::Camera;
use crate::render::scene::Scene;

/// A number for people: six significant digits (the files themselves hold every digit).
fn shown(x: f64) -> String {
    let r = format!("{:.5e}", x).parse::<f64>().unwrap_or(x);
    if r == 0.0 || (1e-3..1e6).contains(&r.abs()) {
        format!("{r}")
    } else {
        format!("{r:e}")
    }
}

/// One or two sentences on what the export approximates.
pub(super) fn summary(a: &Approximation) -> String {
    match &a.difference {
        Measured::NotNeeded => {
            "exact: every emitter is Lambertian, as the renderers' area lights are".into()
        }
        Measured::Done(d) => format!(
            "approximated: the emitter's angular distribution is written as Lambertian tiles \
             with each tile's radiance towards the chart centre, scaled by {:.4} to fit the \
             patches' luminance; metamer's radiosity solver puts the difference on the 24 \
             patches at ΔE*ab max {:.3}, mean {:.3} (Y ratio {:.4}–{:.4})",
            d.fit_scale, d.max_de, d.mean_de, d.luminance_ratio.0, d.luminance_ratio.1
        ),
        Measured::Skipped => "approximated: the emitter's angular distribution is written as \
             Lambertian tiles with each tile's radiance towards the chart centre; the \
             difference was not measured (asked not to)"
            .into(),
        Measured::NotPossible(why) => format!(
            "approximated: the emitter's angular distribution is written as Lambertian tiles \
             with each tile's radiance towards the chart centre; the difference could not be \
             measured: {why}"
        ),
    }
}

fn render_section(to: Renderer, camera: &Camera) -> String {
    match to {
        Renderer::Mitsuba3 => format!(
            "## Rendering\n\n\
             Mitsuba 3 in a spectral variant (the PyPI wheel `mitsuba` has `scalar_spectral`):\n\n\
             ```python\n\
             import mitsuba as mi\n\
             mi.set_variant(\"scalar_spectral\")\n\
             scene = mi.load_file(\"{file}\")            # spp=…, width=…, height=… override the defaults\n\
             image = mi.render(scene)\n\
             mi.Bitmap(image).write(\"image.pfm\")     # X, Y, Z; rows bottom to top, as metamer's PFM\n\
             ```\n\n\
             or `mitsuba -m scalar_spectral -D spp=1024 -o image.exr {file}`, which writes an \
             OpenEXR file whose channels are named X, Y and Z.\n\n\
             ## The image\n\n\
             {w}×{h} pixels, vertical field of view {fov}°, from the scene camera, row 0 at the \
             top and x along the camera's right: the orientation of `metamer render image`, not \
             mirrored (the display's mirror is the reproduction's business). The film is a \
             `specfilm` with three channels, X, Y and Z, whose response functions are the \
             scene's CIE 1931 2° colour-matching functions times K_m = 683 lm/W on 380–780 nm \
             (`spectra/cie1931_*bar_times_683.spd`): specfilm stores the unnormalised \
             ∫ L(λ)·srf(λ) dλ, so every pixel is absolute XYZ in cd/m² with metamer's own table \
             and no colour-space conversion. (`hdrfilm` with `pixel_format=\"xyz\"` would \
             divide by Mitsuba's ∫ȳ = 106.75… and use Mitsuba's own CIE table over 360–830 nm; \
             it is not used.) A box filter makes a pixel the mean over its footprint, as in \
             metamer's image.\n",
            file = mitsuba3::SCENE_FILE,
            w = camera.width,
            h = camera.height,
            fov = shown(camera.vfov_deg),
        ),
        Renderer::PbrtV4 => format!(
            "## Rendering\n\n\
             ```sh\n\
             pbrt {file}            # writes {image}; --spp N overrides the samples per pixel\n\
             ```\n\n\
             pbrt-v4 is spectral in every build; no flag is needed.\n\n\
             ## The image\n\n\
             {w}×{h} pixels, vertical field of view {fov}° (pbrt's `fov` is the shorter \
             axis's: {pfov}°), from the scene camera, row 0 at the top and x along the camera's \
             right: the orientation of `metamer render image`, not mirrored. pbrt's `LookAt` \
             alone would mirror a right-handed scene; the `Scale -1 1 1` before it undoes \
             that. The film uses pbrt's `cie1931` sensor at imaging ratio 1 (ISO 100, shutter \
             0–1), so the sensor's XYZ is absolute, Y in cd/m² (each tile's `scale` is its \
             luminance, see below). pbrt-v4's `rgb` film has no XYZ output: it writes RGB in \
             the film's colour space, here `{cs}`, whose primaries and white pbrt records in \
             the EXR's `chromaticities` attribute. XYZ is that attribute's RGB→XYZ matrix times \
             the pixel (R, G, B), which metamer applies when it reads the file: a fixed linear map, nothing clipped (ACES2065-1's primaries \
             enclose every real colour) and 32-bit floats (`savefp16` false).\n\n\
             ## Lights\n\n\
             pbrt-v4's `diffuse` area light divides its `scale` by the photometric value \
             Σ ȳ·L of its spectrum (`DiffuseAreaLight::Create`, `src/pbrt/lights.cpp`), so the \
             level of `\"spectrum L\"` is thrown away. Each tile's `L` is its absolute spectral \
             radiance (W·sr⁻¹·m⁻²·nm⁻¹) and its `scale` its luminance along the normal, \
             683·Σ ȳ·L·1 nm in cd/m²: pbrt then emits 683·L, its convention for a light of that \
             many nits, and the image's Y is in cd/m².\n",
            file = pbrt::SCENE_FILE,
            image = pbrt::IMAGE_FILE,
            w = camera.width,
            h = camera.height,
            fov = shown(camera.vfov_deg),
            pfov = shown(pbrt::fov_deg(camera)),
            cs = pbrt::COLOR_SPACE,
        ),
        Renderer::Blender => blender::render_section(camera),
    }
}

fn spectra_section(to: Renderer, scene: &Scene, a: &Approximation) -> String {
    match to {
        Renderer::Blender => blender::colour_section(scene, a),
        Renderer::Mitsuba3 => "## Spectra\n\n\
             Every spectrum is the scene's, on its 1 nm grid 380–780 nm, as an irregular \
             spectrum (`.spd`; a constant is a uniform `value`). Mitsuba interpolates linearly \
             and gives 0 outside the table (`include/mitsuba/core/distr_1d.h`), while sampling \
             wavelengths over 360–830 nm. Outside 380–780 nm the emitters therefore emit \
             nothing and the film's response is 0, so no reflectance outside the table can \
             reach a pixel: XYZ on 380–780 nm is what metamer integrates (it sums 1 nm bins; \
             Mitsuba integrates the linear interpolant, a difference far below the noise for \
             these smooth tables).\n"
            .into(),
        Renderer::PbrtV4 => "## Spectra\n\n\
             Every spectrum is the scene's, on its 1 nm grid 380–780 nm, as an inline \
             `\"spectrum\"` of (λ, value) pairs: a `PiecewiseLinearSpectrum`, 0 outside \
             380–780 nm (`src/pbrt/util/spectrum.cpp`). pbrt samples wavelengths over 360–830 \
             nm; outside the table the lights emit nothing, so XYZ comes from 380–780 nm, as \
             metamer's does. pbrt's `diffuse` material clamps a reflectance to [0, 1]; a \
             measured reflectance the scene accepts up to 1.05 is clamped.\n"
            .into(),
    }
}

fn emitter_section(a: &Approximation) -> String {
    let mut s = String::from("## The emitter\n\n");
    s.push_str(
        "Each tile of each emitter is an area light of the tile's absolute spectral radiance \
         gain·S(λ). The renderers' area lights (Mitsuba's `area`, pbrt-v4's `diffuse`, Cycles' \
         Emission shader on a mesh) are Lambertian: they cannot give an area light an angular distribution (pbrt-v4's \
         `goniometric` light is a point light, which is not the 25-tile emitter).\n\n",
    );
    if a.is_exact() {
        s.push_str("Every emitter of this scene is Lambertian: the export is exact.\n");
        return s;
    }
    let (lo, hi) = a.factors.unwrap_or((1.0, 1.0));
    let _ = write!(
        s,
        "This scene's emitter has a non-Lambertian distribution (a `cos_power` or C-γ \
         table). It is written as Lambertian tiles, each with the radiance the distribution \
         gives towards {} ({}, {}, {}) m: tile t's gain is g_t·f(ω_t), with f from {} to {} \
         over the tiles. The patches' direct light leaves the tiles along directions near \
         these, so it changes least; walls seen at larger angles receive too much light, \
         which reaches the patches after a bounce.\n\n",
        if a.aim_is_chart {
            "the centre of the 24 ColorChecker patches"
        } else {
            "the centre of the scene's surfaces"
        },
        shown(a.aim[0]),
        shown(a.aim[1]),
        shown(a.aim[2]),
        shown(lo),
        shown(hi)
    );
    match &a.difference {
        Measured::Done(d) => {
            let _ = writeln!(
                s,
                "Aimed at the chart alone, the tiles would send the walls more light than the \
                 scene's distribution does, and the walls pass it on to the patches: metamer's \
                 radiosity solver puts that form at ΔE*ab max {:.3}, mean {:.3} from the scene. \
                 Every tile's gain is therefore multiplied by {} (`c`), the one factor that \
                 makes the 24 patches' luminances agree with the scene's in least squares \
                 (c = Σ Y·Y′ / Σ Y′², Y′ the aimed form's; light transport is linear in the \
                 emission, so the written form's readings are c times the aimed form's). The \
                 tiles' luminance towards the chart is then c times the scene's.\n\n\
                 **Measured difference** of the written form (metamer's radiosity solver, the \
                 scene as it is against this Lambertian form, both against the exact scene's \
                 reference white, each solve refined to a bound of {:.3} ΔE*ab, {:.0} s): \
                 ΔE*ab max **{:.3}**, mean **{:.3}** over the 24 patches; Y(form)/Y(scene) from \
                 {:.4} to {:.4}. A renderer of this export cannot agree with the box better \
                 than this, and its readings should be compared with `metamer render spots` of \
                 the scene only within it.\n",
                d.aimed_de.0,
                d.aimed_de.1,
                shown(d.fit_scale),
                d.solver_bound_de,
                d.seconds,
                d.max_de,
                d.mean_de,
                d.luminance_ratio.0,
                d.luminance_ratio.1
            );
            s.push_str("| patch | ΔE*ab |\n| --- | --- |\n");
            for (p, de) in &d.per_patch {
                let _ = writeln!(s, "| {p} | {de:.3} |");
            }
        }
        Measured::Skipped => s.push_str("The difference was not measured (asked not to).\n"),
        Measured::NotPossible(why) => {
            let _ = writeln!(s, "The difference could not be measured: {why}");
        }
        Measured::NotNeeded => {}
    }
    s
}

/// The whole README.
pub(super) fn text(
    to: Renderer,
    scene: &Scene,
    scene_name: &str,
    camera: &Camera,
    a: &Approximation,
    summary: &str,
) -> String {
    let mut s = format!(
        "# {} for {}\n\n\
         Written by `metamer export --to {}`. Geometry in metres; every surface a Lambertian \
         reflector with {}; every emitter tile an area light of its absolute {}.\n\n\
         **In short:** {summary}.\n\n",
        super::common::one_line(scene_name),
        match to {
            Renderer::Mitsuba3 => "Mitsuba 3",
            Renderer::PbrtV4 => "pbrt-v4",
            Renderer::Blender => "Blender (Cycles)",
        },
        to.name(),
        if to == Renderer::Blender {
            "the scene's reflectance as an RGB colour (see Colours)"
        } else {
            "the scene's spectral reflectance"
        },
        if to == Renderer::Blender {
            "radiance as an RGB colour and strength"
        } else {
            "spectral radiance"
        },
    );
    s.push_str(&render_section(to, camera));
    s.push('\n');
    s.push_str(&spectra_section(to, scene, a));
    s.push('\n');
    s.push_str(&emitter_section(a));
    s.push_str(&format!(
        "\n## Reading the image back\n\n`metamer render spots-from-image IMAGE --scene {} --json > \
         readings.json` reads the image back as the 24 meter readings, each with its \
         uncertainty from the pixels' spread; `metamer validate --reference SPOTS \
         --test readings.json -o DIR` compares them with the box's spot readings (SPOTS: \
         the box's `spots.jsonl`, or an experiment's `box/spots.csv`), and `metamer \
         experiment -o DIR --box-scene SCENE --box-spots SPOTS --simulation-image IMAGE` \
         runs the whole chain with this renderer's image as the simulation.\n",
        scene_name
            .strip_prefix("built-in scene ")
            .unwrap_or(scene_name)
    ));
    s
}
