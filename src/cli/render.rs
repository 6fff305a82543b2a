//! `metamer render`: spot readings, images and convergence charts of a scene.

use std::path::PathBuf;

use clap::Subcommand;

use super::{parse_triple, CliError, CliResult};
use metamer::numeric_csv::NumericCsv;
use metamer::output::{OutputError, OutputPolicy};
use metamer::render::convergence;
use metamer::render::geometry::{Vec3, VecOps};
use metamer::render::image::{render_image, ImageOptions};
use metamer::render::image_io::{write_srgb_preview, write_xyz_image};
use metamer::render::probes::{illuminance as probe_illuminance_any, ProbeMethod, ProbeOptions};
use metamer::render::radiosity::image::{render_image_radiosity, RadiosityImageOptions};
use metamer::render::radiosity::probes::{Illuminance, Probe, ProbeProgress};
use metamer::render::radiosity::{self, render_spots_radiosity, RadiosityOptions};
use metamer::render::{reference_white, render_spots_with_progress, Scene, SpotOptions, Strategy};

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Cmd,
}

/// How the spot readings are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    Radiosity,
    Path,
    Auto,
}

#[derive(Subcommand)]
enum Cmd {
    /// The 24 simulated 1° meter readings, refined to a ΔE*ab confidence target.
    Spots {
        /// The scene file (default: the validation box built into the program).
        scene: Option<PathBuf>,
        /// Stop when every patch's 95 % half-width of ΔE*ab is below this.
        #[arg(long, default_value_t = 0.1)]
        target_de: f64,
        /// Reference white X,Y,Z (default: a perfect white diffuser in place of patch 19).
        #[arg(long, value_parser = parse_triple)]
        white: Option<[f64; 3]>,
        /// Wall-clock limit (s): the readings so far are reported, marked not converged.
        #[arg(long, default_value_t = 600.0)]
        max_seconds: f64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// radiosity: the deterministic solver (convex scenes of Lambertian rectangles);
        /// path: the path tracer; auto: radiosity when the scene qualifies.
        #[arg(long, value_enum, default_value_t = Method::Auto)]
        method: Method,
        #[arg(long)]
        json: bool,
    },
    /// The camera's XYZ image (absolute cd/m², float) as .exr or .pfm.
    Image {
        /// The scene file (default: the built-in validation box).
        scene: Option<PathBuf>,
        /// Samples per pixel (radiosity: a √spp × √spp grid of rays, spp rounded down to a
        /// square).
        #[arg(long)]
        spp: u64,
        /// path: the path tracer; radiosity: the deterministic solver's reflected radiance
        /// at every ray's first hit (convex scenes of Lambertian rectangles).
        #[arg(long, value_enum, default_value_t = Method::Path)]
        method: Method,
        /// Radiosity: the finest mesh level (the indirect light is extrapolated from it and
        /// the level before, as the spot readings are).
        #[arg(long, default_value_t = 3)]
        level: usize,
        /// Output size (default: the scene's, 1014×1014); the field of view is kept.
        #[arg(long)]
        width: Option<usize>,
        #[arg(long)]
        height: Option<usize>,
        #[arg(short, long)]
        output: PathBuf,
        /// sRGB PNG preview, exposed so the perfect white diffuser is at 1.
        #[arg(long)]
        preview: Option<PathBuf>,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Replace the image and preview if they exist.
        #[arg(long)]
        force: bool,
    },
    /// Illuminance (lux: direct, indirect, total) at points given as CSV rows
    /// x,y,z,nx,ny,nz (header line), the normal being the measuring surface's.
    Probes {
        scene: PathBuf,
        #[arg(long)]
        points: PathBuf,
        #[arg(long, value_enum, default_value_t = Method::Auto)]
        method: Method,
        /// Radiosity: refine until every bound is below this fraction of the total.
        #[arg(long, default_value_t = 0.001)]
        rel_tolerance: f64,
        /// Path tracing: paths per point.
        #[arg(long, default_value_t = 65536)]
        samples: u64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Wall-clock limit (s): what finished by then is reported, marked not converged.
        #[arg(long, default_value_t = 600.0)]
        max_seconds: f64,
        #[arg(long)]
        json: bool,
    },
    /// CSV and SVG of ΔE*ab error against seconds for each sampling strategy.
    Convergence {
        /// The scene file (default: the built-in validation box).
        scene: Option<PathBuf>,
        #[arg(short, long)]
        output: PathBuf,
        /// Confidence target of the reference run.
        #[arg(long, default_value_t = 0.05)]
        reference_de: f64,
        /// Time budget per strategy.
        #[arg(long, default_value_t = 20.0)]
        seconds: f64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Replace convergence.csv and convergence.svg if they exist.
        #[arg(long)]
        force: bool,
    },
}

pub fn run(args: Args) -> CliResult {
    match args.command {
        Cmd::Spots {
            scene,
            target_de,
            white,
            max_seconds,
            seed,
            method,
            json,
        } => {
            if target_de.is_nan() || target_de <= 0.0 {
                return Err(CliError::Usage("--target-de must be > 0".into()));
            }
            if max_seconds.is_nan() || max_seconds <= 0.0 {
                return Err(CliError::Usage("--max-seconds must be > 0".into()));
            }
            if let Some(w) = white {
                if !(w.iter().all(|x| x.is_finite()) && w[1] > 0.0) {
                    return Err(CliError::Usage("--white must be finite with Y > 0".into()));
                }
            }
            let scene = load(scene.as_deref())?;
            let use_radiosity = uses_radiosity(method, &scene)?;
            if use_radiosity {
                return spots_radiosity(&scene, target_de, white, max_seconds, json);
            }
            let opts = SpotOptions {
                target_de,
                white,
                max_seconds,
                seed,
                ..SpotOptions::default()
            };
            // Progress on stderr (hidden when it is not a terminal, e.g. in scripts).
            let bar = indicatif::ProgressBar::new(24);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} patches at target, {elapsed} elapsed {msg}",
                )
                .map_err(|e| CliError::Failed(e.to_string().into()))?,
            );
            bar.set_message("(reference white)");
            let r = render_spots_with_progress(&scene, &opts, &|p| {
                bar.set_position(p.converged as u64);
                bar.set_message(format!("worst ΔE95 {:.3}", p.worst_de));
            })?;
            bar.finish_and_clear();
            if json {
                println!(
                    "{}",
                    serde_json::to_string(&Tagged {
                        method: "path",
                        provenance: scene.provenance.as_ref(),
                        result: &r
                    })?
                );
            } else {
                print_provenance(&scene);
                println!(
                    "white X Y Z = {:.4} {:.4} {:.4} cd/m²   {:.1} s{}",
                    r.white[0],
                    r.white[1],
                    r.white[2],
                    r.seconds,
                    if r.converged {
                        ""
                    } else {
                        "  (time limit: not converged)"
                    }
                );
                println!(
                    "{:>5} {:>10} {:>10} {:>10} {:>8} {:>8} {:>8} {:>8} {:>10}",
                    "patch", "X", "Y", "Z", "L*", "a*", "b*", "ΔE95", "samples"
                );
                for p in &r.patches {
                    println!(
                        "{:>5} {:>10.4} {:>10.4} {:>10.4} {:>8.3} {:>8.3} {:>8.3} {:>8.4} {:>10}",
                        p.patch,
                        p.xyz[0],
                        p.xyz[1],
                        p.xyz[2],
                        p.lab[0],
                        p.lab[1],
                        p.lab[2],
                        p.de_ci95,
                        p.samples
                    );
                }
            }
            Ok(())
        }
        Cmd::Image {
            scene,
            spp,
            method,
            level,
            width,
            height,
            output,
            preview,
            seed,
            force,
        } => {
            if spp == 0 {
                return Err(CliError::Usage("--spp must be ≥ 1".into()));
            }
            let mut out = OutputPolicy::new(force);
            if let Some(s) = &scene {
                out.input(s);
            }
            // Before the render: a refused output costs nothing yet.
            out.check(&output)?;
            if let Some(p) = &preview {
                let mut besides_image = out.clone();
                besides_image.input(&output);
                if let Err(OutputError::IsInput { .. }) = besides_image.check(p) {
                    return Err(CliError::Usage(format!(
                        "--preview {} is the same file as --output {}",
                        p.display(),
                        output.display()
                    )));
                }
                out.check(p)?;
            }
            let name = scene
                .as_ref()
                .map_or("the built-in scene".into(), |p| p.display().to_string());
            let scene = load(scene.as_deref())?;
            let camera = scene.camera.ok_or_else(|| {
                CliError::Failed(format!("{name}: the scene has no camera").into())
            })?;
            let width = width.unwrap_or(camera.width);
            let height = height.unwrap_or(camera.height);
            if width == 0 || height == 0 {
                return Err(CliError::Usage("--width and --height must be ≥ 1".into()));
            }
            let bar = indicatif::ProgressBar::new(height as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:40} {pos}/{len} rows, {elapsed} elapsed, ETA {eta}",
                )
                .map_err(|e| CliError::Failed(e.to_string().into()))?,
            );
            let opts = ImageOptions {
                width,
                height,
                spp,
                seed,
                strategy: Strategy::default(),
                window: None,
            };
            let t = std::time::Instant::now();
            let radiosity = match method {
                Method::Radiosity => true,
                Method::Path => false,
                Method::Auto => radiosity::qualifies(&scene).is_ok(),
            };
            let img = if radiosity {
                let iopts = RadiosityImageOptions {
                    width,
                    height,
                    level,
                    subpixels: (spp as f64).sqrt().floor().max(1.0) as usize,
                    ..RadiosityImageOptions::default()
                };
                render_image_radiosity(&scene, &RadiosityOptions::default(), &iopts)?
            } else {
                render_image(&scene, &opts, &|n| bar.inc(n as u64))?
            };
            bar.finish_and_clear();
            let secs = t.elapsed().as_secs_f64();
            write_xyz_image(&output, &img, &out)?;
            eprintln!(
                "{width}×{height} at {spp} spp by {} in {secs:.1} s ({:.0} samples/s), wrote {}",
                if radiosity {
                    "radiosity"
                } else {
                    "the path tracer"
                },
                (width * height) as f64 * spp as f64 / secs,
                output.display()
            );
            if let Some(p) = preview {
                // Expose for the perfect diffuser under the scene's light, read by the meter.
                let white = reference_white(
                    &scene,
                    &SpotOptions {
                        target_de: 0.5,
                        ..SpotOptions::default()
                    },
                )?;
                write_srgb_preview(&p, &img, white[1], &out)?;
                eprintln!("preview {}", p.display());
            }
            Ok(())
        }
        Cmd::Probes {
            scene,
            points,
            method,
            rel_tolerance,
            samples,
            seed,
            max_seconds,
            json,
        } => {
            let opts = ProbeOptions {
                method: match method {
                    Method::Auto => ProbeMethod::Auto,
                    Method::Radiosity => ProbeMethod::Radiosity,
                    Method::Path => ProbeMethod::Path,
                },
                rel_tolerance,
                samples,
                seed,
                max_seconds,
            };
            probes(&scene, &points, opts, json)
        }
        Cmd::Convergence {
            scene,
            output,
            reference_de,
            seconds,
            seed,
            force,
        } => {
            convergence::check_seconds(seconds)
                .map_err(|e| CliError::Usage(format!("--seconds: {e}")))?;
            let mut out = OutputPolicy::new(force);
            if let Some(s) = &scene {
                out.input(s);
            }
            out.dir(&output)?;
            for f in ["convergence.csv", "convergence.svg"] {
                out.check(&output.join(f))?;
            }
            let scene = load(scene.as_deref())?;
            let (points, _) =
                convergence::run(&scene, reference_de, seconds, seed, &|m| eprintln!("{m}"))?;
            convergence::write(&output, &points, &out)?;
            eprintln!(
                "wrote {}/convergence.csv and convergence.svg",
                output.display()
            );
            Ok(())
        }
    }
}

/// A result with the method that produced it, for `--json`.
#[derive(serde::Serialize)]
struct Tagged<'a, T: serde::Serialize> {
    method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    provenance: Option<&'a serde_json::Map<String, serde_json::Value>>,
    #[serde(flatten)]
    result: &'a T,
}

/// The scene at `path`, or the built-in validation box; its warnings go to stderr.
fn load(path: Option<&std::path::Path>) -> Result<Scene, CliError> {
    let scene = match path {
        Some(p) => Scene::load(p)?,
        None => Scene::builtin("validation-box")?,
    };
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// The scene's provenance, one line, ahead of the readings.
fn print_provenance(scene: &Scene) {
    if let Some(p) = &scene.provenance {
        println!("provenance: {}", serde_json::Value::Object(p.clone()));
    }
}

/// Whether `method` renders `scene` by radiosity; `auto` says why when it cannot.
fn uses_radiosity(method: Method, scene: &Scene) -> Result<bool, CliError> {
    Ok(match method {
        Method::Path => false,
        Method::Radiosity => {
            radiosity::qualifies(scene)?;
            true
        }
        Method::Auto => match radiosity::qualifies(scene) {
            Ok(()) => true,
            Err(why) => {
                eprintln!("using the path tracer: {why}");
                false
            }
        },
    })
}

fn spots_radiosity(
    scene: &Scene,
    target_de: f64,
    white: Option<[f64; 3]>,
    max_seconds: f64,
    json: bool,
) -> CliResult {
    let opts = RadiosityOptions {
        target_de,
        white,
        max_seconds,
        ..RadiosityOptions::default()
    };
    let r = render_spots_radiosity(scene, &opts, &|l| {
        eprintln!(
            "level {}: {} elements, {} sweeps, {:.2} s",
            l.level, l.elements, l.sweeps, l.seconds
        )
    })?;
    if json {
        println!(
            "{}",
            serde_json::to_string(&Tagged {
                method: "radiosity",
                provenance: scene.provenance.as_ref(),
                result: &r
            })?
        );
        return Ok(());
    }
    print_provenance(scene);
    println!(
        "radiosity: white X Y Z = {:.4} {:.4} {:.4} cd/m²   {:.2} s, {} levels{}",
        r.white[0],
        r.white[1],
        r.white[2],
        r.seconds,
        r.levels.len(),
        if r.converged {
            ""
        } else {
            "  (level or time limit reached: bound above the target)"
        }
    );
    println!(
        "{:>5} {:>10} {:>10} {:>10} {:>8} {:>8} {:>8} {:>9}",
        "patch", "X", "Y", "Z", "L*", "a*", "b*", "ΔE bound"
    );
    for p in &r.patches {
        println!(
            "{:>5} {:>10.4} {:>10.4} {:>10.4} {:>8.3} {:>8.3} {:>8.3} {:>9.5}",
            p.patch, p.xyz[0], p.xyz[1], p.xyz[2], p.lab[0], p.lab[1], p.lab[2], p.de_bound
        );
    }
    Ok(())
}

fn probes(
    scene: &std::path::Path,
    points: &std::path::Path,
    opts: ProbeOptions,
    json: bool,
) -> CliResult {
    let scene = load(Some(scene))?;
    let csv = NumericCsv::read(points, &["x", "y", "z", "nx", "ny", "nz"])?;
    let mut probes = Vec::with_capacity(csv.rows.len());
    for (line, v) in &csv.rows {
        let normal = Vec3::from_array([v[3], v[4], v[5]]);
        if normal.length() == 0.0 {
            return Err(CliError::Failed(
                format!("{}:{line}: the normal is zero", points.display()).into(),
            ));
        }
        probes.push(Probe {
            position: Vec3::from_array([v[0], v[1], v[2]]),
            normal: normal.normalized(),
        });
    }
    // Progress on stderr (hidden when it is not a terminal).
    let bar = indicatif::ProgressBar::new(probes.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} {bar:30} {pos}/{len} points, {elapsed}")
            .map_err(|e| CliError::Failed(e.to_string().into()))?,
    );
    let r = probe_illuminance_any(&scene, &probes, &opts, &|p| match p {
        ProbeProgress::Solved { level, elements } => {
            bar.set_message(format!("level {level} ({elements} elements)"));
            bar.set_position(0);
        }
        ProbeProgress::Evaluated { done, .. } => bar.set_position(done as u64),
        ProbeProgress::Estimated { .. } => {}
    })
    .map_err(|e| CliError::Failed(format!("{}: {e}", points.display()).into()))?;
    bar.finish_and_clear();
    if let Some(why) = &r.method_reason {
        eprintln!("using the path tracer: {why}");
    }
    if !r.converged {
        let worst = r
            .probes
            .iter()
            .map(|e| e.bound_lux / e.total_lux.abs())
            .fold(0.0, f64::max);
        eprintln!(
            "warning: not converged: {}; the largest bound is {worst:.3e} of its total{}",
            r.stopped.as_deref().unwrap_or("stopped early"),
            if r.method == "radiosity" {
                format!(" (tolerance {:e})", opts.rel_tolerance)
            } else {
                String::new()
            }
        );
    }
    if json {
        #[derive(serde::Serialize)]
        struct Row<'a> {
            point: [f64; 3],
            normal: [f64; 3],
            #[serde(flatten)]
            lux: &'a Illuminance,
        }
        let rows: Vec<Row> = probes
            .iter()
            .zip(&r.probes)
            .map(|(p, lux)| Row {
                point: p.position.to_array(),
                normal: p.normal.to_array(),
                lux,
            })
            .collect();
        let mut v = serde_json::to_value(&r)?;
        v["probes"] = serde_json::to_value(rows)?;
        println!("{v}");
        return Ok(());
    }
    eprintln!("{}: {:.2} s", r.method, r.seconds);
    println!("x,y,z,nx,ny,nz,direct_lux,indirect_lux,total_lux,bound_lux");
    for (p, e) in probes.iter().zip(&r.probes) {
        let [x, y, z] = p.position.to_array();
        let [a, b, c] = p.normal.to_array();
        println!(
            "{x},{y},{z},{a},{b},{c},{:.6},{:.6},{:.6},{:.6}",
            e.direct_lux, e.indirect_lux, e.total_lux, e.bound_lux
        );
    }
    Ok(())
}
