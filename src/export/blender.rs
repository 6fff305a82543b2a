//! The scene as a Python script for Blender's `bpy` (`scene.py`), rendered by Cycles on
//! the CPU into a scene-linear OpenEXR file.
//!
//! - Every rectangle is a one-face mesh with its vertices in the order corner, +u, +u+v,
//!   +v, so Blender's face normal (right-handed in the vertex order) is the scene's
//!   `edge_u × edge_v`. Cycles' BSDFs are two-sided and its emission leaves both sides;
//!   metamer's surfaces and tiles are one-sided, so each material mixes, by the
//!   Geometry node's `Backfacing`, its front shader with a black Diffuse BSDF.
//! - Surfaces are Diffuse BSDFs (Lambertian) of the colour [`super::rgb`] states; each
//!   emitter tile adds an Emission shader whose colour is its RGB over its luminance and
//!   whose strength is its luminance in cd/m². Cycles gives a surface of emission colour
//!   c and strength s the pixel value c·s seen directly (measured: colour (0.5, 2, 3),
//!   strength 7 → pixel (3.5, 14, 21)), so a pixel is linear Rec.709 RGB with Y in cd/m².
//! - The camera looks down its local −z with +y up: its world matrix has the scene
//!   camera's right, up and −forward as columns, and its field of view is fitted to the
//!   vertical (`sensor_fit` VERTICAL, `angle_y`).
//! - Cycles renders with every clamp off, no denoiser, no adaptive sampling, a 1-pixel box
//!   filter, 1024 bounces, a black world and a fixed seed; the EXR is 32-bit float RGB in
//!   the scene's linear space, Linear Rec.709 (Blender 4.2 writes no `chromaticities`
//!   attribute, so a reader takes BT.709's with D65, which is right).

use std::fmt::Write;
use std::path::PathBuf;

use super::approximation::Approximation;
use super::common::{num, one_line, tiles, File};
use super::rgb;
use crate::render::scene::{Camera, Scene};

/// The script's name in the export.
pub const SCENE_FILE: &str = "scene.py";
/// The image the script writes by default, beside it.
pub const IMAGE_FILE: &str = "image.exr";
/// Cycles' bounce limit: far beyond what the box's light survives.
pub const MAX_BOUNCES: u32 = 1024;

fn triple(v: [f64; 3]) -> String {
    format!("({}, {}, {})", num(v[0]), num(v[1]), num(v[2]))
}

/// The colour each surface and tile is entered as, with the patches the clamp changed.
pub struct Colours {
    pub surfaces: Vec<[f64; 3]>,
    pub emitter_reflectances: Vec<[f64; 3]>,
    pub clamped: Vec<String>,
}

pub fn colours(scene: &Scene, approximation: &Approximation) -> Colours {
    let light = rgb::light(scene, approximation);
    let mut clamped = Vec::new();
    let mut entry = |name: &str, r: &[f64]| {
        let (c, was) = rgb::reflectance_rgb(scene, r, &light);
        if was {
            clamped.push(name.to_string());
        }
        c
    };
    let surfaces = scene
        .surfaces
        .iter()
        .map(|s| entry(&s.name, &s.reflectance))
        .collect();
    let emitter_reflectances = scene
        .emitters
        .iter()
        .enumerate()
        .map(|(i, e)| entry(&format!("emitter {i}"), &e.reflectance))
        .collect();
    Colours {
        surfaces,
        emitter_reflectances,
        clamped,
    }
}

const PRELUDE: &str = r#"import argparse
import math
import sys

import bpy
from mathutils import Matrix

parser = argparse.ArgumentParser(description="Render the exported box with Cycles on the CPU.")
parser.add_argument("--samples", type=int, default=SPP)
parser.add_argument("--width", type=int, default=WIDTH)
parser.add_argument("--height", type=int, default=HEIGHT)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--threads", type=int, default=0, help="0: every core")
parser.add_argument("-o", "--output", default=IMAGE)
args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
cycles = scene.cycles
cycles.device = "CPU"
cycles.samples = args.samples
cycles.seed = args.seed
cycles.use_animated_seed = False
cycles.use_adaptive_sampling = False
cycles.use_denoising = False
cycles.sample_clamp_direct = 0.0
cycles.sample_clamp_indirect = 0.0
cycles.light_sampling_threshold = 0.0
cycles.pixel_filter_type = "BOX"
cycles.filter_width = 1.0
for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
          "volume_bounces", "transparent_max_bounces"):
    setattr(cycles, k, BOUNCES)
scene.render.threads_mode = "FIXED" if args.threads > 0 else "AUTO"
if args.threads > 0:
    scene.render.threads = args.threads
scene.render.resolution_x = args.width
scene.render.resolution_y = args.height
scene.render.resolution_percentage = 100
scene.render.film_transparent = False
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.view_settings.gamma = 1.0
settings = scene.render.image_settings
settings.file_format = "OPEN_EXR"
settings.color_mode = "RGB"
settings.color_depth = "32"
settings.exr_codec = "ZIP"
world = bpy.data.worlds.new("black")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
scene.world = world


def material(name, rgb, emission=None):
    """A one-sided Lambertian reflector of colour rgb, emitting (colour, strength) from its front."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nodes, links = m.node_tree.nodes, m.node_tree.links
    nodes.clear()
    front = nodes.new("ShaderNodeBsdfDiffuse")
    front.inputs["Color"].default_value = (*rgb, 1.0)
    front.inputs["Roughness"].default_value = 0.0
    if emission is not None:
        light = nodes.new("ShaderNodeEmission")
        light.inputs["Color"].default_value = (*emission[0], 1.0)
        light.inputs["Strength"].default_value = emission[1]
        both = nodes.new("ShaderNodeAddShader")
        links.new(front.outputs[0], both.inputs[0])
        links.new(light.outputs[0], both.inputs[1])
        front = both
        m.cycles.emission_sampling = "FRONT"
    back = nodes.new("ShaderNodeBsdfDiffuse")
    back.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    side = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(side.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(front.outputs[0], mix.inputs[1])
    links.new(back.outputs[0], mix.inputs[2])
    out = nodes.new("ShaderNodeOutputMaterial")
    links.new(mix.outputs[0], out.inputs["Surface"])
    return m


def rectangle(name, corner, u, v, mat):
    """A one-face mesh: corner, +u, +u+v, +v, so its normal is u x v."""
    p = [corner, [corner[k] + u[k] for k in range(3)],
         [corner[k] + u[k] + v[k] for k in range(3)], [corner[k] + v[k] for k in range(3)]]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(p, [], [(0, 1, 2, 3)])
    mesh.materials.append(mat)
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)

"#;

const POSTLUDE: &str = r#"
data = bpy.data.cameras.new("camera")
data.sensor_fit = "VERTICAL"
data.angle_y = math.radians(VFOV)
data.clip_start = 0.001
data.clip_end = 1000.0
camera = bpy.data.objects.new("camera", data)
# Blender's camera looks down its local -z with +y up.
camera.matrix_world = Matrix((
    (RIGHT[0], UP[0], -FORWARD[0], POSITION[0]),
    (RIGHT[1], UP[1], -FORWARD[1], POSITION[1]),
    (RIGHT[2], UP[2], -FORWARD[2], POSITION[2]),
    (0.0, 0.0, 0.0, 1.0),
))
scene.collection.objects.link(camera)
scene.camera = camera
scene.render.filepath = args.output
bpy.ops.render.render(write_still=True)
print("wrote", args.output)
"#;

/// The script.
pub(super) fn files(
    scene: &Scene,
    camera: &Camera,
    approximation: &Approximation,
    spp: u32,
) -> Vec<File> {
    let mut x = format!(
        "# {}: written by metamer export for Blender 4.2 (bpy) with Cycles on the CPU.\n\
         # python3 {SCENE_FILE} [--samples N] [--width W] [--height H] [--seed S] [-o IMAGE]\n\
         # writes a scene-linear OpenEXR (Linear Rec.709, D65; Y in cd/m2), not mirrored;\n\
         # see README.md for how each spectrum became a colour.\n",
        one_line(&scene.name)
    );
    x.push_str(
        &PRELUDE
            .replace("SPP", &spp.to_string())
            .replace("WIDTH", &camera.width.to_string())
            .replace("HEIGHT", &camera.height.to_string())
            .replace("IMAGE", &format!("{IMAGE_FILE:?}"))
            .replace("BOUNCES", &MAX_BOUNCES.to_string()),
    );
    let c = colours(scene, approximation);
    for (i, (s, rgb)) in scene.surfaces.iter().zip(&c.surfaces).enumerate() {
        let _ = writeln!(x, "# {}", one_line(&s.name));
        let _ = writeln!(
            x,
            "rectangle(\"surface_{i:03}\", {}, {}, {}, material(\"surface_{i:03}\", {}))",
            triple(s.rect.corner.to_array()),
            triple(s.rect.edge_u.to_array()),
            triple(s.rect.edge_v.to_array()),
            triple(*rgb)
        );
    }
    for t in tiles(scene, approximation) {
        let colour = rgb::emission_rgb(scene, &t.radiance);
        let y = rgb::xyz(scene, &t.radiance)[1];
        // Colour over luminance, strength the luminance: the pixel is their product. A
        // tile whose clamped colour has no luminance left emits nothing.
        let ycol = rgb::rgb_to_xyz()[1]
            .iter()
            .zip(colour)
            .map(|(m, c)| m * c)
            .sum::<f64>();
        let (colour, strength) = if ycol > 0.0 && y > 0.0 {
            (colour.map(|c| c / ycol), ycol)
        } else {
            ([0.0; 3], 0.0)
        };
        let name = format!("emitter_{}_tile_r{}_c{}", t.emitter, t.row, t.col);
        let _ = writeln!(
            x,
            "rectangle(\"{name}\", {}, {}, {}, material(\"{name}\", {}, ({}, {})))",
            triple(t.corner),
            triple(t.edge_u),
            triple(t.edge_v),
            triple(c.emitter_reflectances[t.emitter]),
            triple(colour),
            num(strength)
        );
    }
    let p = |v: crate::render::geometry::Vec3| triple(v.to_array());
    x.push_str(
        &POSTLUDE
            .replace("VFOV", &num(camera.vfov_deg))
            .replace("RIGHT", &p(camera.right))
            .replace("UP", &p(camera.up))
            .replace("FORWARD", &p(camera.forward))
            .replace("POSITION", &p(camera.position)),
    );
    vec![File {
        rel: PathBuf::from(SCENE_FILE),
        text: x,
    }]
}

fn shown(x: f64) -> String {
    format!("{x:.4}")
}

/// The README's rendering and image sections.
pub(super) fn render_section(camera: &Camera) -> String {
    format!(
        "## Rendering\n\n\
         Blender 4.2 LTS as a Python module (`python3 -m pip install bpy==4.2.23`, CPython \
         3.11), Cycles on the CPU, no display needed:\n\n\
         ```sh\n\
         python3 {SCENE_FILE}                       # writes {IMAGE_FILE} beside the working directory\n\
         python3 {SCENE_FILE} --samples 1024 --width 640 --height 480 --seed 3 -o box.exr\n\
         ```\n\n\
         (`blender -b -P {SCENE_FILE} -- --samples 64` runs it in a Blender install too.) \
         Cycles is set for a physically comparable image: sample clamping off (direct and \
         indirect), no denoiser, no adaptive sampling, light sampling threshold 0, a box \
         pixel filter 1 pixel wide (a pixel is the mean over its footprint, as in metamer's \
         image), {MAX_BOUNCES} bounces, a black world, view transform Standard with no look \
         (the EXR holds scene-linear values whatever the view transform; Filmic and AgX only \
         change what the screen shows), and a fixed seed.\n\n\
         ## The image\n\n\
         {w}×{h} pixels by default, vertical field of view {fov}° (`sensor_fit` VERTICAL), \
         from the scene camera, row 0 at the top and x along the camera's right: the \
         orientation of `metamer render image`, not mirrored. The file is a 32-bit float \
         OpenEXR with channels R, G, B in Blender's scene-linear working space, Linear \
         Rec.709: BT.709 primaries, D65 white. Blender 4.2 writes no `chromaticities` \
         attribute, and OpenEXR's rule for a file without one is BT.709 with D65, so a \
         reader converts it by the right matrix; metamer does (XYZ = M·RGB, Y = 0.2126 R + \
         0.7152 G + 0.0722 B). Cycles gives a surface of emission colour c and strength s \
         the pixel value c·s seen directly, and every tile's colour is written with \
         luminance 1 and its strength as its luminance in cd/m², so a pixel's Y is in \
         cd/m²: Blender's unit radiance stands for 1 cd/m² of luminance.\n",
        w = camera.width,
        h = camera.height,
        fov = camera.vfov_deg,
    )
}

/// The README's section on how each spectrum became a colour.
pub(super) fn colour_section(scene: &Scene, a: &Approximation) -> String {
    let light = rgb::light(scene, a);
    let white = rgb::rgb(scene, &light);
    let c = colours(scene, a);
    let mut s = format!(
        "## Colours\n\n\
         Cycles is an RGB renderer: every spectrum is entered as the linear Rec.709 (D65) \
         colour a careful Blender user would give it.\n\n\
         - **Emitter tiles**: RGB = M⁻¹·XYZ of the tile's absolute radiance, XYZ = 683·Σ \
         L(λ)·cmf(λ)·1 nm with the scene's CIE 1931 table, M the BT.709/D65 RGB→XYZ matrix. A \
         negative component (a radiance outside the Rec.709 gamut, as a narrow LED's is) \
         is entered as 0, as a colour picker would. The colour is written divided by its \
         luminance and the luminance (cd/m²) is the strength.\n\
         - **Reflectances** (surfaces and the emitter's own): the colour under the box's \
         light S (every tile's radiance times its area, summed), normalised by the light's \
         own colour, von Kries style: ρ_c = RGB(ρ·S)_c / RGB(S)_c, clamped to [0, 1]. Lit \
         by S alone, Cycles then gives a surface the colour the spectral scene gives it; \
         every further bounce multiplies colours where light multiplies spectra. This \
         box's light has RGB(S) ∝ ({}, {}, {}) (G = 1).\n\n",
        shown(white[0] / white[1]),
        shown(1.0),
        shown(white[2] / white[1])
    );
    if c.clamped.is_empty() {
        s.push_str("No reflectance's colour left [0, 1]: nothing was clamped.\n");
    } else {
        let _ = writeln!(
            s,
            "Clamped to [0, 1] (their colour under this light left it): {}.",
            c.clamped
                .iter()
                .map(|n| one_line(n))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s.push_str(
        "\nWhat an ideal RGB renderer of these colours must produce, and how far that is from \
         the spectral box, metamer computes with its own solver on the RGB form of the scene \
         (`metamer::export::rgb::rgb_form`; docs/renderers.md states the figures).\n",
    );
    s
}
