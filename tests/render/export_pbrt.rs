//! `metamer export --to pbrt-v4` read by a tokenizer and parser of pbrt-v4's scene grammar
//! written here from the facts of pbrt-v4's sources (github mmp/pbrt-v4), since pbrt-v4
//! cannot be built in CI (no network but package registries, and no package of it):
//!
//! - tokens (`src/pbrt/parser.cpp`, `Tokenizer::Next`): whitespace separates; `#` starts a
//!   comment up to the next `\n` or `\r`; `"…"` is a string with `\b \f \n \r \t \\ \' \"`
//!   escapes; `[` and `]` are tokens of their own; anything else runs to whitespace, a
//!   quote or a bracket;
//! - directives (`parse` in the same file) and their fixed arguments (`LookAt` 9 numbers,
//!   `Scale` 3, `ColorSpace` a name, the plugin directives a quoted type) followed by
//!   parameters: a quoted `"type name"` and one value or a `[ … ]` list; the types pbrt-v4
//!   knows are those of `ParameterTypeTraits` (`src/pbrt/paramdict.cpp`) plus `spectrum`,
//!   `rgb`, `blackbody` and `texture`; integers are digits only (`parseInt`);
//! - each plugin's parameter names, as its `Create` function looks them up (files named in
//!   [`allowed`]); pbrt-v4 stops on a parameter nobody looked up.
//!
//! The values are then checked against numbers computed here from the scene file and its
//! CSV tables, and the camera against pbrt-v4's `LookAt` and projection arithmetic.

use std::collections::HashMap;

use metamer::export::{self, ExportRequest, Renderer};
use metamer::render::image::Frame;
use metamer::render::Scene;

use crate::support::{fresh_dir, root, scenes_dir};

#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Token {
    Str(String),
    Open,
    Close,
    Word(String),
}

pub(crate) fn tokenize(text: &str) -> Vec<Token> {
    let mut out = Vec::new();
    let mut chars = text.chars().peekable();
    while let Some(&c) = chars.peek() {
        if c.is_whitespace() {
            chars.next();
        } else if c == '#' {
            // pbrt-v4 ends a comment at either line end (`Tokenizer::Next`).
            while chars.next().is_some_and(|c| c != '\n' && c != '\r') {}
        } else if c == '[' || c == ']' {
            chars.next();
            out.push(if c == '[' { Token::Open } else { Token::Close });
        } else if c == '"' {
            chars.next();
            let mut s = String::new();
            loop {
                match chars.next().expect("unterminated string") {
                    '"' => break,
                    '\n' => panic!("new line in a string"),
                    '\\' => s.push(match chars.next().expect("escape at the end") {
                        'b' => '\u{8}',
                        'f' => '\u{c}',
                        'n' => '\n',
                        'r' => '\r',
                        't' => '\t',
                        e @ ('\\' | '\'' | '"') => e,
                        e => panic!("unknown escape \\{e}"),
                    }),
                    c => s.push(c),
                }
            }
            out.push(Token::Str(s));
        } else {
            let mut s = String::new();
            while let Some(&c) = chars.peek() {
                if c.is_whitespace() || c == '"' || c == '[' || c == ']' || c == '#' {
                    break;
                }
                s.push(c);
                chars.next();
            }
            out.push(Token::Word(s));
        }
    }
    out
}

#[derive(Clone, Debug)]
struct Param {
    ty: String,
    name: String,
    values: Vec<Token>,
}

impl Param {
    fn floats(&self) -> Vec<f64> {
        self.values
            .iter()
            .map(|t| match t {
                Token::Word(w) => w.parse().unwrap_or_else(|_| panic!("{w} is not a number")),
                other => panic!("{other:?} is not a number"),
            })
            .collect()
    }
}

#[derive(Clone, Debug)]
struct Directive {
    name: String,
    /// The numbers of a transform directive, or the quoted type/name of the others.
    args: Vec<Token>,
    params: Vec<Param>,
}

/// Fixed arguments of the directives pbrt-v4 knows (`src/pbrt/parser.cpp`), as a count of
/// numbers (`Some(n)`), a quoted string (`None`), or nothing.
fn fixed_args(name: &str) -> Option<Option<usize>> {
    Some(match name {
        "LookAt" => Some(9),
        "Scale" | "Translate" => Some(3),
        "Rotate" => Some(4),
        "WorldBegin" | "AttributeBegin" | "AttributeEnd" | "Identity" | "ReverseOrientation"
        | "ObjectEnd" => Some(0),
        "ColorSpace" | "Camera" | "Film" | "Sampler" | "Integrator" | "PixelFilter"
        | "Accelerator" | "Shape" | "Material" | "AreaLightSource" | "LightSource"
        | "MakeNamedMaterial" | "NamedMaterial" | "MakeNamedMedium" | "ObjectBegin"
        | "ObjectInstance" | "CoordinateSystem" | "CoordSysTransform" | "Attribute" => None,
        _ => return None,
    })
}

/// The directives that take a parameter list after their quoted argument.
fn takes_params(name: &str) -> bool {
    !matches!(
        name,
        "ColorSpace"
            | "NamedMaterial"
            | "ObjectBegin"
            | "ObjectInstance"
            | "CoordinateSystem"
            | "CoordSysTransform"
    )
}

const PARAM_TYPES: [&str; 13] = [
    "integer",
    "float",
    "point2",
    "vector2",
    "point3",
    "vector3",
    "normal",
    "string",
    "bool",
    "spectrum",
    "rgb",
    "blackbody",
    "texture",
];

fn parse(tokens: &[Token]) -> Vec<Directive> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let Token::Word(name) = &tokens[i] else {
            panic!("expected a directive, found {:?}", tokens[i]);
        };
        let fixed = fixed_args(name).unwrap_or_else(|| panic!("{name} is not a pbrt-v4 directive"));
        i += 1;
        let mut args = Vec::new();
        match fixed {
            Some(n) => {
                for _ in 0..n {
                    assert!(
                        matches!(tokens[i], Token::Word(_)),
                        "{name}: {:?}",
                        tokens[i]
                    );
                    args.push(tokens[i].clone());
                    i += 1;
                }
            }
            None => {
                assert!(
                    matches!(tokens[i], Token::Str(_)),
                    "{name}: {:?}",
                    tokens[i]
                );
                args.push(tokens[i].clone());
                i += 1;
            }
        }
        let mut params = Vec::new();
        while fixed.is_none() && takes_params(name) && i < tokens.len() {
            let Token::Str(decl) = &tokens[i] else { break };
            let words: Vec<&str> = decl.split_whitespace().collect();
            assert_eq!(words.len(), 2, "parameter declaration {decl:?}");
            assert!(PARAM_TYPES.contains(&words[0]), "unknown type in {decl:?}");
            i += 1;
            let mut values = Vec::new();
            if tokens[i] == Token::Open {
                i += 1;
                while tokens[i] != Token::Close {
                    values.push(tokens[i].clone());
                    i += 1;
                }
                i += 1;
            } else {
                values.push(tokens[i].clone());
                i += 1;
            }
            assert!(!values.is_empty(), "{decl}: no values");
            for v in &values {
                match (words[0], v) {
                    ("string", Token::Str(_)) => {}
                    ("bool", Token::Word(w)) => assert!(w == "true" || w == "false", "{decl}"),
                    ("integer", Token::Word(w)) => {
                        let digits = w.strip_prefix(['-', '+']).unwrap_or(w);
                        assert!(digits.chars().all(|c| c.is_ascii_digit()), "{decl}: {w}");
                    }
                    (_, Token::Word(w)) => {
                        w.parse::<f64>().unwrap_or_else(|_| panic!("{decl}: {w}"));
                    }
                    other => panic!("{decl}: {other:?}"),
                }
            }
            params.push(Param {
                ty: words[0].into(),
                name: words[1].into(),
                values,
            });
        }
        out.push(Directive {
            name: name.clone(),
            args,
            params,
        });
    }
    out
}

/// The parameters pbrt-v4 looks up for each plugin the export uses, with their types.
fn allowed(directive: &str, plugin: &str) -> Vec<(&'static str, &'static str)> {
    match (directive, plugin) {
        // src/pbrt/cameras.cpp: PerspectiveCamera::Create and CameraBaseParameters.
        ("Camera", "perspective") => vec![
            ("float", "fov"),
            ("float", "lensradius"),
            ("float", "focaldistance"),
            ("float", "frameaspectratio"),
            ("float", "screenwindow"),
            ("float", "shutteropen"),
            ("float", "shutterclose"),
        ],
        // src/pbrt/samplers.cpp: IndependentSampler::Create.
        ("Sampler", "independent") => vec![("integer", "pixelsamples"), ("integer", "seed")],
        // src/pbrt/cpu/integrators.cpp: PathIntegrator::Create.
        ("Integrator", "path") => vec![
            ("integer", "maxdepth"),
            ("bool", "regularize"),
            ("string", "lightsampler"),
        ],
        // src/pbrt/filters.cpp: BoxFilter::Create.
        ("PixelFilter", "box") => vec![("float", "xradius"), ("float", "yradius")],
        // src/pbrt/film.cpp: RGBFilm::Create, PixelSensor::Create, FilmBaseParameters.
        ("Film", "rgb") => vec![
            ("integer", "xresolution"),
            ("integer", "yresolution"),
            ("string", "filename"),
            ("string", "sensor"),
            ("float", "iso"),
            ("float", "whitebalance"),
            ("bool", "savefp16"),
            ("float", "maxcomponentvalue"),
            ("integer", "pixelbounds"),
            ("float", "cropwindow"),
            ("float", "diagonal"),
        ],
        // src/pbrt/materials.cpp: DiffuseMaterial::Create (and displacement/normalmap).
        ("Material", "diffuse") => vec![
            ("spectrum", "reflectance"),
            ("rgb", "reflectance"),
            ("texture", "reflectance"),
            ("float", "displacement"),
            ("string", "normalmap"),
        ],
        // src/pbrt/lights.cpp: DiffuseAreaLight::Create.
        ("AreaLightSource", "diffuse") => vec![
            ("spectrum", "L"),
            ("rgb", "L"),
            ("blackbody", "L"),
            ("float", "scale"),
            ("bool", "twosided"),
            ("string", "filename"),
            ("float", "power"),
        ],
        // src/pbrt/shapes.cpp: Triangle::CreateMesh.
        ("Shape", "trianglemesh") => vec![
            ("integer", "indices"),
            ("point3", "P"),
            ("point2", "uv"),
            ("vector3", "S"),
            ("normal", "N"),
            ("integer", "faceIndices"),
        ],
        (d, p) => panic!("{d} \"{p}\" is not a plugin this test knows"),
    }
}

fn arg(d: &Directive) -> &str {
    match &d.args[0] {
        Token::Str(s) => s,
        other => panic!("{other:?}"),
    }
}

/// (λ, value) pairs of a `spectrum` parameter.
fn pairs(p: &Param) -> Vec<(f64, f64)> {
    assert_eq!(p.ty, "spectrum");
    p.floats().chunks_exact(2).map(|c| (c[0], c[1])).collect()
}

/// Rows of a CSV table (after its comment and header lines).
fn csv(rel: &str) -> Vec<Vec<f64>> {
    std::fs::read_to_string(root().join(rel))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("nm"))
        .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
        .collect()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn unit(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

#[test]
fn the_pbrt_export_is_pbrt_v4_grammar_with_the_scenes_values() {
    let dir = fresh_dir("export-pbrt");
    let scene_file = scenes_dir().join("validation-box-led-rgb1.json");
    export::run(&ExportRequest::new(
        Some(scene_file.clone()),
        Renderer::PbrtV4,
        dir.join("pbrt"),
    ))
    .unwrap();
    let text = std::fs::read_to_string(dir.join("pbrt/scene.pbrt")).unwrap();
    let ds = parse(&tokenize(&text));

    // Every parameter is one pbrt-v4 looks up for its plugin, with its type.
    for d in &ds {
        if d.params.is_empty() && !matches!(d.name.as_str(), "Shape" | "Material") {
            continue;
        }
        let ok = allowed(&d.name, arg(d));
        for p in &d.params {
            assert!(
                ok.contains(&(p.ty.as_str(), p.name.as_str())),
                "{} \"{}\": \"{} {}\" is not a parameter pbrt-v4 looks up",
                d.name,
                arg(d),
                p.ty,
                p.name
            );
        }
    }
    let names: Vec<&str> = ds.iter().map(|d| d.name.as_str()).collect();
    let world = names.iter().position(|n| *n == "WorldBegin").unwrap();
    for n in [
        "Camera",
        "Film",
        "Sampler",
        "Integrator",
        "PixelFilter",
        "ColorSpace",
    ] {
        assert!(
            names.iter().position(|m| *m == n).unwrap() < world,
            "{n} after WorldBegin"
        );
    }
    let one = |n: &str| ds.iter().find(|d| d.name == n).unwrap();
    let param = |d: &Directive, n: &str| d.params.iter().find(|p| p.name == n).cloned().unwrap();

    // Film: the camera's size, the XYZ sensor, 32-bit floats.
    let film = one("Film");
    assert_eq!(arg(film), "rgb");
    assert_eq!(param(film, "xresolution").floats(), vec![1014.0]);
    assert_eq!(param(film, "yresolution").floats(), vec![1014.0]);
    assert_eq!(
        param(film, "sensor").values,
        vec![Token::Str("cie1931".into())]
    );
    assert_eq!(
        param(film, "savefp16").values,
        vec![Token::Word("false".into())]
    );

    // Camera: pbrt-v4's own arithmetic projects each patch centre where metamer's camera
    // does. LookAt (src/pbrt/util/transform.cpp): right = up × dir, newUp = dir × right;
    // the Scale before it flips camera x. Perspective (src/pbrt/cameras.cpp/.h) on a
    // square film: screen = camera xy / (z·tan(fov/2)), raster x = (sx + 1)/2·W,
    // raster y = (1 − sy)/2·H.
    let scale_at = names.iter().position(|n| *n == "Scale").unwrap();
    let look_at = names.iter().position(|n| *n == "LookAt").unwrap();
    assert_eq!(look_at, scale_at + 1);
    let nums = |d: &Directive| -> Vec<f64> {
        d.args
            .iter()
            .map(|t| match t {
                Token::Word(w) => w.parse().unwrap(),
                _ => panic!(),
            })
            .collect()
    };
    assert_eq!(nums(&ds[scale_at]), vec![-1.0, 1.0, 1.0]);
    let l = nums(&ds[look_at]);
    let (pos, look, up) = ([l[0], l[1], l[2]], [l[3], l[4], l[5]], [l[6], l[7], l[8]]);
    let dir_ = unit(sub(look, pos));
    let right = unit(cross(unit(up), dir_));
    let new_up = cross(dir_, right);
    let fov = param(one("Camera"), "fov").floats()[0];
    let t = (fov.to_radians() / 2.0).tan();
    let scene = Scene::load(&scene_file).unwrap();
    let cam = scene.camera.unwrap();
    assert_eq!(fov, cam.vfov_deg);
    let frame = Frame::of(&cam, 1014, 1014);
    for k in 1..=24 {
        let c = scene.surfaces[scene.patch_surface(k).unwrap()]
            .rect
            .centre()
            .to_array();
        let d = sub(c, pos);
        let (x, y, z) = (-dot(d, right), dot(d, new_up), dot(d, dir_));
        let (sx, sy) = (x / (z * t), y / (z * t));
        let pbrt = ((sx + 1.0) / 2.0 * 1014.0, (1.0 - sy) / 2.0 * 1014.0);
        let ours = frame
            .project(
                scene.surfaces[scene.patch_surface(k).unwrap()]
                    .rect
                    .centre()
                    - cam.position,
            )
            .unwrap();
        assert!(
            (pbrt.0 - ours.0).abs() < 1e-6 && (pbrt.1 - ours.1).abs() < 1e-6,
            "patch {k}: pbrt-v4 pixel {pbrt:?}, metamer's {ours:?}"
        );
    }

    // Materials: patch 7's reflectance is the ColorChecker table's column 7 at its nodes
    // (380–730 nm every 10 nm, held beyond 730 as the scene file asks).
    let cc = csv("data/colorchecker_babelcolor_average.csv");
    let patch7 = text.find("# surface patch 7\n").unwrap();
    let after: Vec<Directive> = parse(&tokenize(&text[patch7..]));
    let refl = pairs(&param(&after[1], "reflectance"));
    assert_eq!(refl.len(), 401);
    assert_eq!((refl[0].0, refl[400].0), (380.0, 780.0));
    for row in &cc {
        let got = refl.iter().find(|p| p.0 == row[0]).unwrap().1;
        assert!(
            (got - row[7]).abs() < 1e-12,
            "{} nm: {got} vs {}",
            row[0],
            row[7]
        );
    }
    assert!((refl[400].1 - cc.last().unwrap()[7]).abs() < 1e-12);

    // Lights: one per tile; L ∝ the LED-RGB1 table at its nodes, and scale = the tile's
    // luminance, the file's 100 cd/m² times the tile's gain.
    let led = csv("data/illuminant_led_rgb1.csv");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene_file).unwrap()).unwrap();
    let emitter = &file["emitters"][0];
    let lum = emitter["luminance_cd_m2"].as_f64().unwrap();
    let mut gains = HashMap::new();
    for t in emitter["tiles"].as_array().unwrap() {
        let key = (t["row"].as_u64().unwrap(), t["col"].as_u64().unwrap());
        gains.insert(key, t["gain"].as_f64().unwrap());
    }
    let lights: Vec<&Directive> = ds.iter().filter(|d| d.name == "AreaLightSource").collect();
    assert_eq!(lights.len(), 25);
    for (i, light) in lights.iter().enumerate() {
        let (row, col) = ((i / 5) as u64, (i % 5) as u64);
        let gain = gains.get(&(row, col)).copied().unwrap_or(1.0);
        let scale = param(light, "scale").floats()[0];
        assert!(
            (scale - lum * gain).abs() < 1e-9 * lum,
            "tile ({row}, {col}): scale {scale}, the file's luminance × gain {}",
            lum * gain
        );
        let l = pairs(&param(light, "L"));
        let k = l.iter().find(|p| p.0 == 550.0).unwrap().1
            / led.iter().find(|r| r[0] == 550.0).unwrap()[1];
        for row in &led {
            let got = l.iter().find(|p| p.0 == row[0]).unwrap().1;
            assert!((got - k * row[1]).abs() <= 1e-12 * k, "{} nm", row[0]);
        }
    }

    // Geometry: every mesh is a planar quad whose normal N is its winding's normal, so the
    // front faces pbrt lights and shades are the scene's.
    let shapes: Vec<&Directive> = ds.iter().filter(|d| d.name == "Shape").collect();
    assert_eq!(shapes.len(), scene.surfaces.len() + 25);
    for s in shapes {
        let p = param(s, "P").floats();
        let n = param(s, "N").floats();
        let v = |i: usize| [p[3 * i], p[3 * i + 1], p[3 * i + 2]];
        let w = unit(cross(sub(v(1), v(0)), sub(v(3), v(0))));
        for i in 0..4 {
            let ni = [n[3 * i], n[3 * i + 1], n[3 * i + 2]];
            assert!(dot(ni, w) > 1.0 - 1e-12, "{ni:?} vs {w:?}");
        }
        assert_eq!(
            param(s, "indices").floats(),
            vec![0.0, 1.0, 2.0, 0.0, 2.0, 3.0]
        );
    }
}

#[test]
fn the_tokenizer_reads_pbrt_v4_comments_strings_and_brackets() {
    let t = tokenize("Shape \"sphere\" # a comment \"x\"\n \"float radius\" [2.5e-1]\"s\\\"q\"");
    assert_eq!(
        t,
        vec![
            Token::Word("Shape".into()),
            Token::Str("sphere".into()),
            Token::Str("float radius".into()),
            Token::Open,
            Token::Word("2.5e-1".into()),
            Token::Close,
            Token::Str("s\"q".into()),
        ]
    );
}

#[test]
fn an_export_refuses_a_directory_that_holds_files_unless_forced() {
    let dir = fresh_dir("export-refuse");
    std::fs::write(dir.join("mine.txt"), "keep").unwrap();
    let mut request = ExportRequest::new(
        Some("validation-box-led-rgb1".into()),
        Renderer::PbrtV4,
        dir.clone(),
    );
    let err = export::run(&request).unwrap_err();
    assert!(
        matches!(&err, export::ExportError::NotEmpty { dir: d } if *d == dir),
        "{err}"
    );
    assert!(err.to_string().contains("is not empty"), "{err}");
    assert!(!dir.join("scene.pbrt").exists());
    request.force = true;
    let report = export::run(&request).unwrap();
    assert_eq!(report.files.len(), 2);
    assert_eq!(
        std::fs::read_to_string(dir.join("mine.txt")).unwrap(),
        "keep"
    );
    // A scene that is neither a file nor a built-in name is an error naming it.
    request.scene = Some(dir.join("no-such-scene.json"));
    let err = export::run(&request).unwrap_err().to_string();
    assert!(err.contains("no-such-scene.json"), "{err}");
}
