//! `metamer render`: spot readings, images and convergence charts of a scene.

use std::path::PathBuf;

use clap::Subcommand;

use super::{parse_triple, CliError, CliResult};
use metamer::color::Xyz;
use metamer::render::job::convergence::ConvergenceRequest;
use metamer::render::job::image::ImageRequest;
use metamer::render::job::probes::{ProbesReport, ProbesRequest};
use metamer::render::job::spots::{Readings, SpotsRequest};
use metamer::render::job::spots_from_image::SpotsFromImageRequest;
use metamer::render::job::{self, RenderError, RenderEvent};
use metamer::render::method::{self, Solver};
use metamer::render::probes::{ProbeError, ProbeOptions};
use metamer::render::radiosity::probes::ProbeProgress;
use metamer::render::spot::Uncertainty;
use metamer::render::Scene;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Cmd,
}

/// The `--method` value: how the spot readings are computed, as the command spells it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    Radiosity,
    Path,
    Auto,
}

impl From<MethodArg> for method::Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Radiosity => method::Method::Radiosity,
            MethodArg::Path => method::Method::PathTracer,
            MethodArg::Auto => method::Method::Auto,
        }
    }
}

#[derive(Subcommand)]
enum Cmd {
    /// The 24 simulated 1° meter readings, refined to a ΔE*ab confidence target.
    Spots(SpotsArgs),
    /// The camera's XYZ image (absolute cd/m², float) as .exr or .pfm.
    Image(ImageArgs),
    /// The 24 meter readings read back from another renderer's XYZ image of the scene's
    /// camera: each the image's mean over the meter's 1° cone (solid-angle weighted), with
    /// a 95 % half-width from the pixels' spread; `--json` is what `validate --simulation`
    /// reads.
    SpotsFromImage(SpotsFromImageArgs),
    /// Illuminance (lux: direct, indirect, total) at points given as CSV rows
    /// x,y,z,nx,ny,nz (header line), the normal being the measuring surface's.
    Probes(ProbesArgs),
    /// CSV and SVG of ΔE*ab error against seconds for each sampling strategy.
    Convergence(ConvergenceArgs),
}

#[derive(clap::Args)]
struct SpotsArgs {
    /// The scene file, or a built-in box by name (validation-box, validation-box-led-rgb1;
    /// default: validation-box).
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
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    method: MethodArg,
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct SpotsFromImageArgs {
    /// The image (.exr or .pfm): absolute XYZ in cd/m², rows from the top, not mirrored.
    image: PathBuf,
    /// The scene the image is of: a file, or a built-in box by name (validation-box,
    /// validation-box-led-rgb1; default: validation-box).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Reference white X,Y,Z for the readings' CIELAB (default: a perfect white diffuser
    /// in place of patch 19, path traced).
    #[arg(long, value_parser = parse_triple)]
    white: Option<[f64; 3]>,
    /// The traced white's 95 % half-width is driven below a third of this ΔE*ab.
    #[arg(long, default_value_t = 0.1)]
    target_de: f64,
    /// Wall-clock limit (s) of tracing the white.
    #[arg(long, default_value_t = 600.0)]
    max_seconds: f64,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct ImageArgs {
    /// The scene file, or a built-in box by name (validation-box, validation-box-led-rgb1;
    /// default: validation-box).
    scene: Option<PathBuf>,
    /// Samples per pixel (radiosity: a √spp × √spp grid of rays, spp rounded down to a
    /// square).
    #[arg(long)]
    spp: u64,
    /// path: the path tracer; radiosity: the deterministic solver's reflected radiance
    /// at every ray's first hit (convex scenes of Lambertian rectangles).
    #[arg(long, value_enum, default_value_t = MethodArg::Path)]
    method: MethodArg,
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
}

#[derive(clap::Args)]
struct ProbesArgs {
    scene: PathBuf,
    #[arg(long)]
    points: PathBuf,
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    method: MethodArg,
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
}

#[derive(clap::Args)]
struct ConvergenceArgs {
    /// The scene file, or a built-in box by name (validation-box, validation-box-led-rgb1;
    /// default: validation-box).
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
}

pub fn run(args: Args) -> CliResult {
    match args.command {
        Cmd::Spots(a) => spots(a),
        Cmd::Image(a) => image(a),
        Cmd::SpotsFromImage(a) => spots_from_image(a),
        Cmd::Probes(a) => probes(a),
        Cmd::Convergence(a) => convergence(a),
    }
}

fn convergence(a: ConvergenceArgs) -> CliResult {
    let request = ConvergenceRequest {
        scene: a.scene,
        output: a.output,
        reference_de: a.reference_de,
        seconds: a.seconds,
        seed: a.seed,
        force: a.force,
    };
    job::convergence::run(&request, &|e| match e {
        RenderEvent::Log(m) => super::console::reported_at_exit(errln!("{m}")),
        other => print_event(other),
    })
    .map_err(cli_error)?;
    errln!(
        "wrote {}/convergence.csv and convergence.svg",
        request.output.display()
    )?;
    Ok(())
}

/// A usage error for a bad request (exit 2), else a failure (exit 1).
fn cli_error(e: RenderError) -> CliError {
    let usage = match e {
        RenderError::TargetDe => "--target-de must be > 0".into(),
        RenderError::MaxSeconds => "--max-seconds must be > 0".into(),
        RenderError::White => "--white must be finite with Y > 0".into(),
        RenderError::Seconds(why) => format!("--seconds: {why}"),
        RenderError::Spp => "--spp must be ≥ 1".into(),
        RenderError::Size => "--width and --height must be ≥ 1".into(),
        RenderError::PreviewIsImage { preview, image } => format!(
            "--preview {} is the same file as --output {}",
            preview.display(),
            image.display()
        ),
        e if e.is_bad_request() => e.to_string(),
        RenderError::Probes {
            file,
            error:
                ProbeError::TimeLimit {
                    seconds,
                    samples,
                    done,
                    of,
                },
        } => {
            return CliError::Failed(
                format!(
                    "{}: no result within the time limit of {seconds} s: the path tracer \
                     finished its first {samples} paths for {done} of {of} probes (give more \
                     time with --max-seconds, or fewer points)",
                    file.display()
                )
                .into(),
            )
        }
        RenderError::Radiosity(ref r) if r.is_time_limit() => {
            return CliError::Failed(format!("{e} (--max-seconds)").into())
        }
        RenderError::Probes {
            error: ProbeError::Radiosity(ref r),
            ..
        } if r.is_time_limit() => return CliError::Failed(format!("{e} (--max-seconds)").into()),
        e => return CliError::Failed(Box::new(e)),
    };
    CliError::Usage(usage)
}

/// The events every command shows the same way.
fn print_event(e: RenderEvent) {
    if let RenderEvent::SceneWarning(w) | RenderEvent::Warning(w) = e {
        super::console::reported_at_exit(errln!("warning: {w}"));
    }
}

/// A progress bar on stderr (hidden when it is not a terminal, e.g. in scripts).
fn progress_bar(len: u64, template: &str) -> Result<indicatif::ProgressBar, CliError> {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(template)
            .map_err(|e| CliError::Failed(e.to_string().into()))?,
    );
    Ok(bar)
}

fn spots(a: SpotsArgs) -> CliResult {
    let request = SpotsRequest {
        scene: a.scene,
        method: a.method.into(),
        target_de: a.target_de,
        white: a.white.map(Xyz::from),
        max_seconds: a.max_seconds,
        seed: a.seed,
    };
    let bar = progress_bar(
        24,
        "{bar:30} {pos}/{len} patches at target, {elapsed} elapsed {msg}",
    )?;
    let report = job::spots::run(&request, &|e| match e {
        RenderEvent::Method(m) => {
            if let Some(why) = m.fallback() {
                super::console::reported_at_exit(errln!("using the path tracer: {why}"));
            }
            if m.method == Solver::PathTracer {
                bar.set_message("(reference white)");
            }
        }
        RenderEvent::Level(l) => super::console::reported_at_exit(errln!(
            "level {}: {} elements, {} sweeps, {:.2} s",
            l.level,
            l.elements,
            l.sweeps,
            l.seconds
        )),
        RenderEvent::Spots(p) => {
            bar.set_position(p.converged as u64);
            bar.set_message(format!("worst ΔE95 {:.3}", p.worst_de));
        }
        other => print_event(other),
    })
    .map_err(cli_error)?;
    bar.finish_and_clear();
    if a.json {
        outln!("{}", report.to_json()?)?;
        return Ok(());
    }
    print_spots(&report.readings)?;
    print_provenance(&report.scene)
}

/// The scene's provenance in one short line after the readings (the answer comes first):
/// its plain values in full, a nested object or list by its size; `--json` carries it all.
fn print_provenance(scene: &Scene) -> CliResult {
    if let Some(p) = &scene.provenance {
        outln!(
            "provenance (in full with --json): {}",
            provenance_summary(p)
        )?;
    }
    Ok(())
}

fn provenance_summary(p: &serde_json::Map<String, serde_json::Value>) -> String {
    use serde_json::Value;
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    let shown = |v: &Value| match v {
        Value::String(s) if s.chars().count() <= 60 => s.clone(),
        Value::String(s) => format!("{}…", s.chars().take(60).collect::<String>()),
        Value::Object(o)
            if o.values().all(|v| !v.is_object() && !v.is_array()) && v.to_string().len() <= 80 =>
        {
            v.to_string()
        }
        Value::Object(o) => format!("{{{} field{}}}", o.len(), plural(o.len())),
        Value::Array(a) if a.is_empty() => "none".into(),
        Value::Array(a) => format!("[{} item{}]", a.len(), plural(a.len())),
        other => other.to_string(),
    };
    p.iter()
        .map(|(k, v)| format!("{k} {}", shown(v)))
        .collect::<Vec<_>>()
        .join(" · ")
}

/// The run's white and time, then one row per patch with its uncertainty as its solver
/// states it (the path tracer's 95 % half-width and samples, the radiosity bound).
fn print_spots(readings: &Readings) -> CliResult {
    let w = readings.white();
    match readings {
        Readings::PathTracer(r) => {
            outln!(
                "white X Y Z = {:.4} {:.4} {:.4} cd/m²   {:.1} s{}",
                w[0],
                w[1],
                w[2],
                r.seconds,
                if r.converged {
                    ""
                } else {
                    "  (time limit: not converged)"
                }
            )?;
            outln!(
                "{}",
                reading_header(&format!("{:>8} {:>10}", "ΔE95", "samples"))
            )?;
        }
        Readings::Radiosity { result: r, .. } => {
            outln!(
                "radiosity: white X Y Z = {:.4} {:.4} {:.4} cd/m²   {:.2} s, {} levels{}",
                w[0],
                w[1],
                w[2],
                r.seconds,
                r.levels.len(),
                if r.converged {
                    ""
                } else {
                    "  (level or time limit reached: bound above the target)"
                }
            )?;
            outln!("{}", reading_header(&format!("{:>9}", "ΔE bound")))?;
        }
    }
    for p in readings.patches() {
        let row = reading_row(p.patch, p.xyz, p.lab);
        match p.uncertainty {
            Uncertainty::HalfWidth95 { de, sampling } => {
                let samples = sampling.map(|s| s.samples.to_string());
                outln!("{row} {de:>8.4} {:>10}", samples.unwrap_or_default())
            }
            Uncertainty::Bound { de, .. } => outln!("{row} {de:>9.5}"),
        }?;
    }
    Ok(())
}

/// The header of a table of spot readings: the columns every such table starts with (patch,
/// X, Y, Z, L*, a*, b*) and then `extra`, the table's own, as [`reading_row`] aligns them.
fn reading_header(extra: &str) -> String {
    format!(
        "{:>5} {:>10} {:>10} {:>10} {:>8} {:>8} {:>8} {extra}",
        "patch", "X", "Y", "Z", "L*", "a*", "b*"
    )
}

/// A reading's common columns under [`reading_header`].
fn reading_row(patch: usize, xyz: Xyz, [l, a, b]: [f64; 3]) -> String {
    let Xyz { x, y, z } = xyz;
    format!("{patch:>5} {x:>10.4} {y:>10.4} {z:>10.4} {l:>8.3} {a:>8.3} {b:>8.3}")
}

fn spots_from_image(a: SpotsFromImageArgs) -> CliResult {
    let request = SpotsFromImageRequest {
        white: a.white.map(Xyz::from),
        target_de: a.target_de,
        max_seconds: a.max_seconds,
        seed: a.seed,
        ..SpotsFromImageRequest::new(a.image, a.scene)
    };
    let report = job::spots_from_image::run(&request, &print_event).map_err(cli_error)?;
    if a.json {
        outln!("{}", report.to_json()?)?;
        return Ok(());
    }
    let w = report.white;
    outln!(
        "{} ({}×{}, sha256 {}): white X Y Z = {:.4} {:.4} {:.4} cd/m²   {:.1} s",
        report.image.display(),
        report.pixels.width,
        report.pixels.height,
        report.sha256,
        w[0],
        w[1],
        w[2],
        report.seconds
    )?;
    let extra = format!("{:>8} {:>7} {:>9}", "ΔE95", "pixels", "effective");
    outln!("{}", reading_header(&extra))?;
    for (p, c) in report.patches.iter().zip(&report.cones) {
        outln!(
            "{} {:>8.4} {:>7} {:>9.1}",
            reading_row(p.patch, p.xyz, p.lab),
            p.uncertainty.de_ab(),
            c.pixels,
            c.effective
        )?;
    }
    print_provenance(&report.scene)
}

fn image(a: ImageArgs) -> CliResult {
    let request = ImageRequest {
        scene: a.scene,
        spp: a.spp,
        method: a.method.into(),
        level: a.level,
        width: a.width,
        height: a.height,
        output: a.output,
        preview: a.preview,
        seed: a.seed,
        force: a.force,
    };
    // Sized when the job knows the image's height (the scene's camera may set it).
    let bar = progress_bar(0, "{bar:40} {pos}/{len} rows, {elapsed} elapsed, ETA {eta}")?;
    job::image::run(&request, &|e| match e {
        RenderEvent::ImageSize { height, .. } => bar.set_length(height as u64),
        RenderEvent::Rows(n) => bar.inc(n as u64),
        RenderEvent::ImageWritten(r) => {
            bar.finish_and_clear();
            super::console::reported_at_exit(errln!(
                "{}×{} at {} spp by {} in {:.1} s ({:.0} samples/s), wrote {}",
                r.width,
                r.height,
                r.spp,
                match r.method {
                    Solver::Radiosity => "radiosity",
                    Solver::PathTracer => "the path tracer",
                },
                r.seconds,
                (r.width * r.height) as f64 * r.spp as f64 / r.seconds,
                r.output.display()
            ));
        }
        RenderEvent::PreviewWritten(p) => {
            super::console::reported_at_exit(errln!("preview {}", p.display()))
        }
        other => print_event(other),
    })
    .map_err(cli_error)?;
    Ok(())
}

fn probes(a: ProbesArgs) -> CliResult {
    let request = ProbesRequest {
        scene: a.scene,
        points: a.points,
        options: ProbeOptions {
            method: a.method.into(),
            rel_tolerance: a.rel_tolerance,
            samples: a.samples,
            seed: a.seed,
            max_seconds: a.max_seconds,
        },
    };
    let bar = progress_bar(0, "{msg} {bar:30} {pos}/{len} points, {elapsed}")?;
    let report = job::probes::run(&request, &|e| match e {
        RenderEvent::Probe(ProbeProgress::Solved { level, elements }) => {
            bar.set_message(format!("level {level} ({elements} elements)"));
            bar.set_position(0);
        }
        RenderEvent::Probe(ProbeProgress::Evaluated { done, of }) => {
            bar.set_length(of as u64);
            bar.set_position(done as u64);
        }
        other => print_event(other),
    })
    .map_err(cli_error)?;
    bar.finish_and_clear();
    let r = &report.result;
    if let Some(why) = &r.method_reason {
        errln!("using the path tracer: {why}")?;
    }
    if !r.converged {
        errln!(
            "warning: not converged: {}; the largest bound is {:.3e} of its total{}",
            r.stopped.as_deref().unwrap_or("stopped early"),
            report.worst_relative_bound(),
            if r.method == "radiosity" {
                format!(" (tolerance {:e})", report.rel_tolerance)
            } else {
                String::new()
            }
        )?;
    }
    if a.json {
        outln!("{}", report.to_json()?)?;
    } else {
        print_probes(&report)?;
    }
    Ok(())
}

fn print_probes(report: &ProbesReport) -> CliResult {
    let r = &report.result;
    errln!("{}: {:.2} s", r.method, r.seconds)?;
    outln!("x,y,z,nx,ny,nz,direct_lux,indirect_lux,total_lux,bound_lux")?;
    for (p, e) in report.probes.iter().zip(&r.probes) {
        let [x, y, z] = p.position.to_array();
        let [a, b, c] = p.normal.to_array();
        outln!(
            "{x},{y},{z},{a},{b},{c},{:.6},{:.6},{:.6},{:.6}",
            e.direct_lux,
            e.indirect_lux,
            e.total_lux,
            e.bound_lux
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::provenance_summary;

    #[test]
    fn the_provenance_line_shows_plain_values_and_sizes_the_rest() {
        let p: serde_json::Value = serde_json::json!({
            "date": "2026-12-07T17:11:19Z",
            "clamped_values": 0,
            "instrument_specs": {"spot": "sim:cs100a"},
            "instruments": {"spot": {"model": "cs100a"}},
            "journals": [{"file": "a"}, {"file": "b"}],
            "outliers": [],
        });
        // serde_json's map keeps its keys sorted.
        assert_eq!(
            provenance_summary(p.as_object().unwrap()),
            "clamped_values 0 · date 2026-12-07T17:11:19Z · instrument_specs \
             {\"spot\":\"sim:cs100a\"} · instruments {1 field} · journals [2 items] · \
             outliers none"
        );
    }
}
