//! Analytic checks of the path tracer (release mode, seconds each).

use metamer::color::{observer, ObserverKind, SpectralTable};
use metamer::render::geometry::{Vec3, VecOps};
use metamer::render::image::{render_image, ImageOptions};
use metamer::render::scene::{Scene, SceneFile};
use metamer::render::spot::{patch_aim, sample_cone, Aim};
use metamer::render::{Strategy, Tracer, Wavelengths};
use serde_json::{json, Value};

use crate::support::scenes_dir;

fn box_json() -> Value {
    let text = std::fs::read_to_string(scenes_dir().join("validation-box.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn build(v: &Value) -> Scene {
    let f: SceneFile = serde_json::from_value(v.clone()).unwrap();
    Scene::build(&f, scenes_dir()).unwrap()
}

#[test]
fn source_scale_gives_100_cd_m2() {
    // 683·Σ s·S(λ)·ȳ(λ) over 380..=780 nm, summed here from the raw tables.
    let v = box_json();
    let scene = build(&v);
    let file = v["emitters"][0]["spectrum"]["file"].as_str().unwrap();
    let led = SpectralTable::read(&scenes_dir().join(file))
        .unwrap()
        .first();
    let o = observer(ObserverKind::Cie1931);
    let sum: f64 = (380..=780)
        .map(|nm| led.value_at(nm as f64) * o.at_nm(nm)[1])
        .sum();
    let y = 683.0 * scene.emitters[0].scale * sum;
    assert!((y - 100.0).abs() < 1e-9, "{y}");
}

#[test]
fn emitter_head_on_reads_its_luminance() {
    // From inside the box, looking at the centre of tile (row 2, col 2) along −x; the
    // light has reflectance 0, so one path is exact: Y = 100 cd/m² × gain.
    let gains = std::fs::read_to_string(scenes_dir().join("../light_tile_gains_5x5.csv")).unwrap();
    let g22: f64 = gains
        .lines()
        .find(|l| l.starts_with("2,2,"))
        .unwrap()
        .split(',')
        .nth(2)
        .unwrap()
        .parse()
        .unwrap();
    for file in ["validation-box.json", "validation-box-ldc.json"] {
        let text = std::fs::read_to_string(scenes_dir().join(file)).unwrap();
        let scene = build(&serde_json::from_str(&text).unwrap());
        let tracer = Tracer::new(&scene, Strategy::default());
        let aim = Aim {
            origin: Vec3::from_array([0.3, 0.25, 0.25]),
            axis: Vec3::from_array([-1.0, 0.0, 0.0]),
            acceptance_deg: 1e-4,
        };
        let st = sample_cone(&tracer, aim, 1, 0, 0, 16);
        let y = st.mean()[1];
        assert!(
            (y - 100.0 * g22).abs() < 1e-6 * y,
            "{file}: {y} vs {}",
            100.0 * g22
        );
    }
    // Off axis the ldc variant falls as cos^m: 60° from the normal in the horizontal plane.
    let text = std::fs::read_to_string(scenes_dir().join("validation-box-ldc.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    let m = v["emitters"][0]["distribution"]["exponent"]
        .as_f64()
        .unwrap();
    let scene = build(&v);
    let tracer = Tracer::new(&scene, Strategy::default());
    let dir = Vec3::from_array([-(60f64.to_radians().cos()), 0.0, 60f64.to_radians().sin()]);
    let target = Vec3::from_array([0.0, 0.25, 0.25]);
    let aim = Aim {
        origin: target.minus(dir.times(0.2)),
        axis: dir,
        acceptance_deg: 1e-4,
    };
    let y = sample_cone(&tracer, aim, 1, 0, 0, 16).mean()[1];
    let want = 100.0 * g22 * 0.5f64.powf(m);
    assert!((y - want).abs() < 1e-6 * want, "{y} vs {want}");
}

fn emitter_quad(corner: [f64; 3], u: [f64; 3], v: [f64; 3], a: f64) -> Value {
    json!({"corner": corner, "edge_u": u, "edge_v": v, "rows": 1, "cols": 1,
        "tiles": [{"row": 0, "col": 0, "gain": 1.0}],
        "spectrum": {"nm": [380.0, 780.0], "values": [1.0, 1.0]},
        "luminance_cd_m2": 100.0, "distribution": {"kind": "lambertian"}, "reflectance": a})
}

#[test]
fn white_furnace() {
    // A closed unit cube whose six inner faces all emit Le (Y = 100 cd/m²) and reflect
    // a = 0.5: every radiance is Le/(1 − a), Y = 200 cd/m².
    let a = 0.5;
    let e = [
        emitter_quad([0., 0., 0.], [0., 0., 1.], [1., 0., 0.], a), // floor, +y
        emitter_quad([0., 1., 0.], [1., 0., 0.], [0., 0., 1.], a), // ceiling, −y
        emitter_quad([0., 0., 1.], [0., 1., 0.], [1., 0., 0.], a), // back, −z
        emitter_quad([0., 0., 0.], [1., 0., 0.], [0., 1., 0.], a), // front, +z
        emitter_quad([1., 0., 0.], [0., 0., 1.], [0., 1., 0.], a), // right, −x
        emitter_quad([0., 0., 0.], [0., 1., 0.], [0., 0., 1.], a), // left, +x
    ];
    let v = json!({"name": "furnace", "surfaces": [], "emitters": e,
        "camera": {"position": [0.5, 0.5, 0.5], "look_at": [1.0, 0.6, 0.7], "up": [0, 1, 0],
                   "vfov_deg": 10.0, "width": 8, "height": 8},
        "meter": {"acceptance_deg": 1.0}});
    let scene = build(&v);
    for strategy in [
        Strategy::default(),
        Strategy {
            wavelengths: Wavelengths::Hero(4),
            wavelength_is: true,
            nee_mis: false,
        },
    ] {
        let tracer = Tracer::new(&scene, strategy);
        let aim = Aim {
            origin: Vec3::from_array([0.3, 0.5, 0.6]),
            axis: Vec3::from_array([0.5, -0.3, 0.8]).normalized(),
            acceptance_deg: 30.0,
        };
        let st = sample_cone(&tracer, aim, 3, 0, 0, 150_000);
        let y = st.mean()[1];
        assert!(
            (y - 200.0).abs() < 0.005 * 200.0,
            "{strategy:?}: Y = {y} ± {}",
            st.stderr()[1]
        );
        // The tolerance must stand at ≥ 3 standard errors for the test to mean something.
        assert!(st.stderr()[1] < 0.33, "{:?}", st.stderr());
    }
}

/// View factor from a differential area to a parallel rectangle with one corner on its
/// normal, sides a, b at distance c (Howell, "A Catalog of Radiation Heat Transfer
/// Configuration Factors", B-3).
fn corner_factor(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}

#[test]
fn direct_irradiance_matches_form_factor() {
    // Only patch 19 reflects (ρ = 1), every other surface is black and the tiles have
    // gain 1, so the patch's luminance is 100 cd/m² × F (F: point-to-light view factor).
    let mut v = box_json();
    for s in v["surfaces"].as_array_mut().unwrap() {
        let is19 = s["patch"] == json!(19);
        s["reflectance"] = json!(if is19 { 1.0 } else { 0.0 });
    }
    for t in v["emitters"][0]["tiles"].as_array_mut().unwrap() {
        t["gain"] = json!(1.0);
    }
    let scene = build(&v);
    let mut aim = patch_aim(&scene, 19).unwrap();
    aim.acceptance_deg = 0.01;
    let st = sample_cone(
        &Tracer::new(&scene, Strategy::default()),
        aim,
        5,
        0,
        0,
        40_000,
    );
    // Foot of the normal from the patch centre (y 0.365, z 0.319) on the light plane x = 0.
    let c = 0.4985;
    let f: f64 = [(0.4 - 0.365), (0.365 - 0.1)]
        .iter()
        .flat_map(|&a| [(0.4 - 0.319), (0.319 - 0.1)].map(|b| corner_factor(a, b, c)))
        .sum();
    let y = st.mean()[1];
    assert!(
        (y - 100.0 * f).abs() < 0.01 * 100.0 * f,
        "Y = {y} ± {}, expected {}",
        st.stderr()[1],
        100.0 * f
    );
}

#[test]
fn error_falls_as_one_over_sqrt_n() {
    let scene = build(&box_json());
    let tracer = Tracer::new(&scene, Strategy::default());
    let aim = patch_aim(&scene, 1).unwrap();
    let spread = |n: u64| {
        let ys: Vec<f64> = (0..24)
            .map(|r| sample_cone(&tracer, aim, 100 + r, 1, 0, n).mean()[1])
            .collect();
        let m = ys.iter().sum::<f64>() / ys.len() as f64;
        (ys.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (ys.len() - 1) as f64).sqrt()
    };
    let ratio = spread(256) / spread(4096);
    // √16 = 4; with 24 replicas each spread is known to about ±15 %.
    assert!((2.8..5.7).contains(&ratio), "ratio {ratio}");
}

#[test]
fn spot_matches_image_over_the_cone() {
    // A 203×203 image keeps the 15.71° field, so the 1° cone spans ~13 pixels. Pixels
    // whose centres fall in the cone around patch 19 are averaged and compared with the
    // spot reading (both carry a statistical error < 0.3 %; the pixel discretisation of
    // a uniform patch adds none).
    let scene = build(&box_json());
    let (w, h) = (203usize, 203usize);
    let cam = scene.camera.expect("the box has a camera");
    let aim = patch_aim(&scene, 19).unwrap();
    let half_h = (cam.vfov_deg.to_radians() / 2.0).tan();
    let cos_max = (aim.acceptance_deg.to_radians() / 2.0).cos();
    let centre = |px: usize, py: usize| {
        let sx = (-1.0 + 2.0 * (px as f64 + 0.5) / w as f64) * half_h;
        let sy = (1.0 - 2.0 * (py as f64 + 0.5) / h as f64) * half_h;
        cam.forward
            .plus(cam.right.times(sx))
            .plus(cam.up.times(sy))
            .normalized()
    };
    let inside: Vec<(usize, usize)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| centre(x, y).dot(aim.axis) >= cos_max)
        .collect();
    assert!(inside.len() > 100, "{}", inside.len());
    let x0 = inside.iter().map(|p| p.0).min().unwrap();
    let x1 = inside.iter().map(|p| p.0).max().unwrap() + 1;
    let y0 = inside.iter().map(|p| p.1).min().unwrap();
    let y1 = inside.iter().map(|p| p.1).max().unwrap() + 1;
    let img = render_image(
        &scene,
        &ImageOptions {
            width: w,
            height: h,
            spp: 512,
            seed: 9,
            strategy: Strategy::default(),
            window: Some([x0, y0, x1, y1]),
        },
        &|_| {},
    )
    .unwrap();
    let mut acc = [0.0f64; 3];
    for &(x, y) in &inside {
        let p = img.at(x, y);
        for k in 0..3 {
            acc[k] += p[k] as f64 / inside.len() as f64;
        }
    }
    let spot = sample_cone(
        &Tracer::new(&scene, Strategy::default()),
        aim,
        2,
        0,
        0,
        100_000,
    );
    let s = spot.mean();
    for k in 0..3 {
        assert!(
            (acc[k] - s[k]).abs() < 0.01 * s[k],
            "component {k}: image {} vs spot {} ± {}",
            acc[k],
            s[k],
            spot.stderr()[k]
        );
    }
}

#[test]
fn deterministic_for_seed_and_thread_count() {
    let scene = build(&box_json());
    let tracer = Tracer::new(&scene, Strategy::default());
    let aim = patch_aim(&scene, 7).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| sample_cone(&tracer, aim, 42, 7, 0, 3000).mean())
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn bad_field_is_named_by_json_path() {
    let mut v = box_json();
    v["emitters"][0]["tiles"][3]["gain"] = json!(-1.0);
    let f: SceneFile = serde_json::from_value(v).unwrap();
    let e = Scene::build(&f, scenes_dir()).unwrap_err();
    let (path, message) = (e.path, e.message);
    assert_eq!(path, "emitters[0].tiles[3].gain");
    assert_eq!(message, "must be ≥ 0");
}

#[test]
fn spot_readings_agree_across_seeds_within_their_confidence() {
    // Two independent runs to ΔE95 0.4: each patch's difference is a draw with standard
    // deviation √(σ₁² + σ₂²) where σ = half-width / 1.96; allow two half-widths combined
    // (≈ 4 σ) so 24 patches pass by chance with probability > 99.8 %, while a biased or
    // seed-dependent estimator (or a wrong half-width) fails. A shared white keeps the
    // comparison about the patches.
    use metamer::color::delta_e76;
    use metamer::render::{render_spots, SpotOptions};
    let scene = build(&box_json());
    let white = metamer::render::reference_white(
        &scene,
        &SpotOptions {
            target_de: 0.3,
            ..SpotOptions::default()
        },
    )
    .unwrap();
    let run = |seed| {
        render_spots(
            &scene,
            &SpotOptions {
                target_de: 0.4,
                white: Some(white),
                seed,
                first_batch: 1024,
                ..SpotOptions::default()
            },
        )
        .unwrap()
    };
    let (a, b) = (run(11), run(12));
    assert!(a.converged && b.converged);
    let w = white;
    let mut worst: f64 = 0.0;
    for (pa, pb) in a.patches.iter().zip(&b.patches) {
        assert!(pa.uncertainty.de_ab() < 0.4 && pb.uncertainty.de_ab() < 0.4);
        let de = delta_e76(pa.xyz.to_lab(w), pb.xyz.to_lab(w));
        let allowed =
            2.0 * (pa.uncertainty.de_ab().powi(2) + pb.uncertainty.de_ab().powi(2)).sqrt();
        worst = worst.max(de / allowed);
        assert!(
            de < allowed,
            "patch {}: ΔE {de} between seeds, allowed {allowed}",
            pa.patch
        );
    }
    eprintln!("largest difference / allowance: {worst:.3}");
    // The half-widths must not be wildly pessimistic either: some patch differs by more
    // than a tenth of its allowance (with honest errors, all 24 below that has p ≈ 1e-20).
    assert!(
        worst > 0.1,
        "largest difference only {worst} of the allowance"
    );
}
