//! One validation as one call: `metamer validate` and the experiment's validation stage fill
//! in one [`Request`] and call [`validate`], which reads the readings files, chooses
//! CIELAB's white, compares box against display, box against simulation and simulation
//! against display with their uncertainty, and writes the report.
//!
//! Where the command and the stage behave differently, the difference is a field of the
//! request, so each caller says which behaviour it wants: [`Request::coverage`] (compare
//! the patches the sides share, or refuse sides that read different patches),
//! [`Request::white`] (a file's own white or a given one, checked against the readings,
//! or a measured white taken as it is), [`Request::check_readings`] (refuse files that
//! say they are not luminances, note sides far apart in scale), [`Request::context`]
//! (what the report says beside the comparisons) and [`Request::point_files`] (the
//! stage's per-comparison CSV, charts and `comparisons.json`).

use std::path::{Path, PathBuf};

use crate::color::Xyz;
use crate::output::OutputPolicy;

use super::assess::{assess, AssessOptions};
use super::comparisons::{write_point_files, ValidationResult, FILE, RESULT_VERSION};
use super::error::ValidationError;
use super::export::write_report_files;
use super::plausible;
use super::readings::{read_readings, Format, ReadingSet};
use super::report::{InputFile, InstrumentUsed, RenderConfidenceSection, ReportInput, Sections};

/// The readings files of the three sides.
#[derive(Clone, Copy, Debug)]
pub struct ReadingFiles<'a> {
    /// The box's readings: the reference of box vs display and box vs simulation.
    pub box_readings: &'a Path,
    /// The display's readings of the rendering.
    pub display: &'a Path,
    /// The simulation's readings; without them only box vs display is compared.
    pub simulation: Option<&'a Path>,
}

/// Which patches two sides must cover.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coverage {
    /// Compare the patches both sides have (`validate`: a user may bring readings of part
    /// of the chart).
    Shared,
    /// Refuse sides that do not hold the same patches (the experiment's stage: a stage that
    /// lost readings must not pass as valid).
    Same,
}

/// Where CIELAB's reference white comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum White {
    /// The display's reading labelled `white`, else its brightest reading; checked to be
    /// in the readings' units.
    Display,
    /// The box's, likewise.
    Box,
    /// A white the user gives in the readings' unit: checked to be a white and to be in
    /// the readings' units ([`ValidationError::GivenWhite`] otherwise).
    Given(Xyz),
    /// A white measured with the readings (the experiment's display profile), taken as it
    /// is; `source` says what it is for the report.
    Measured { xyz: Xyz, source: String },
}

/// What the report says beside the comparisons.
#[derive(Clone, Debug)]
pub enum Context {
    /// The readings files alone (`validate`): each file as given with its format, patches
    /// and SHA-256, the instruments it names, its notes after a note on box and display
    /// readings far apart in scale (with [`Request::check_readings`]), and the render's
    /// per-patch statement when the simulation is `metamer render spots --json` output.
    Files,
    /// The sections the caller gathered (the experiment's, from its earlier stages'
    /// files). Their first three inputs are the readings files, box, simulation and
    /// display, whose patch counts and formats are filled in from what was read. The render's
    /// uncertainty enters the simulation's readings where they carry none of their own,
    /// and each side's interval is described in words.
    Stages(Box<Sections>),
}

/// One validation.
#[derive(Clone, Debug)]
pub struct Request<'a> {
    pub readings: ReadingFiles<'a>,
    pub white: White,
    /// How uncertainty reaches ΔE, and a display model's term; the term is added to the
    /// display's side only (box vs simulation never went through the display).
    pub options: AssessOptions,
    /// Patches the display cannot show (1–24), besides those the readings mark: marked in
    /// the comparisons with the display on one side.
    pub out_of_gamut: Vec<usize>,
    pub coverage: Coverage,
    /// Refuse a readings file that says its readings are not luminances (a journal of
    /// reflective entries) and note box and display readings far apart in scale (a user's
    /// files); the experiment's stages wrote their readings themselves, as light.
    pub check_readings: bool,
    pub context: Context,
    /// Also write each comparison's point estimates (`display_vs_box.csv` and `.svg`, …)
    /// and [`FILE`] (needs the simulation's readings): the experiment stage's files.
    pub point_files: bool,
    /// The report's title.
    pub title: String,
    /// The directory of the report (created if missing).
    pub out: &'a Path,
    /// Replace files already there; the readings files are never written over.
    pub force: bool,
}

/// What a validation found and wrote.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The report's data (as `validation.json`).
    pub report: ReportInput,
    /// CIELAB's reference white.
    pub white: Xyz,
    /// [`FILE`]'s content, where [`Request::point_files`] asked for it.
    pub result: Option<ValidationResult>,
    /// The files written, in the order written.
    pub files: Vec<PathBuf>,
}

/// The three sides as read.
struct Sides {
    box_readings: ReadingSet,
    display: ReadingSet,
    simulation: Option<ReadingSet>,
}

/// Reads the three sides' files and, with `check`, refuses one whose file says its
/// readings are not luminances.
pub fn read_sides(files: &ReadingFiles<'_>, check: bool) -> Result<(), ValidationError> {
    read(files, check).map(|_| ())
}

fn read(files: &ReadingFiles<'_>, check: bool) -> Result<Sides, ValidationError> {
    let sides = Sides {
        box_readings: read_readings(files.box_readings)?,
        display: read_readings(files.display)?,
        simulation: files.simulation.map(read_readings).transpose()?,
    };
    if check {
        for set in sides.all() {
            plausible::check_luminance(set)?;
        }
    }
    Ok(sides)
}

impl Sides {
    fn all(&self) -> Vec<&ReadingSet> {
        [&self.box_readings, &self.display]
            .into_iter()
            .chain(&self.simulation)
            .collect()
    }
}

/// Validates as `request` says and writes the report; see [`Request`] for what each field
/// changes.
///
/// # Examples
///
/// ```
/// use std::path::Path;
/// use metamer::validation::job::{validate, Context, Coverage, ReadingFiles, Request, White};
///
/// let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/validate");
/// let out = std::env::temp_dir().join(format!("metamer-doc-validate-{}", std::process::id()));
/// let outcome = validate(&Request {
///     readings: ReadingFiles {
///         box_readings: &data.join("box.csv"),
///         display: &data.join("display.csv"),
///         simulation: None,
///     },
///     white: White::Display,
///     options: Default::default(),
///     out_of_gamut: Vec::new(),
///     coverage: Coverage::Shared,
///     check_readings: true,
///     context: Context::Files,
///     point_files: false,
///     title: "box against display".into(),
///     out: &out,
///     force: true,
/// })?;
/// let a = outcome.report.display_vs_box.as_ref().unwrap();
/// assert_eq!(a.patches.len(), 24);
/// assert_eq!(outcome.files.len(), 3); // validation.json, validation.csv, report.html
/// # std::fs::remove_dir_all(&out).ok();
/// # Ok::<(), metamer::validation::ValidationError>(())
/// ```
pub fn validate(request: &Request<'_>) -> Result<Outcome, ValidationError> {
    let (report, white) = assess_all(request)?;
    let mut policy = OutputPolicy::new(request.force);
    policy.inputs(
        [request.readings.box_readings, request.readings.display]
            .into_iter()
            .chain(request.readings.simulation),
    );
    let mut files = Vec::new();
    let mut result = None;
    if let (true, Some(display_vs_box), Some(simulation_vs_box), Some(display_vs_simulation)) = (
        request.point_files,
        &report.display_vs_box,
        &report.simulation_vs_box,
        &report.display_vs_simulation,
    ) {
        policy.dir(request.out)?;
        for (stem, assessment) in [
            ("display_vs_box", display_vs_box),
            ("simulation_vs_box", simulation_vs_box),
            ("display_vs_simulation", display_vs_simulation),
        ] {
            let names = write_point_files(request.out, stem, assessment, &policy)?;
            files.extend(names.iter().map(|n| request.out.join(n)));
        }
        let r = ValidationResult {
            version: RESULT_VERSION,
            white,
            out_of_gamut_patches: request.out_of_gamut.clone(),
            display_vs_box: display_vs_box.clone(),
            simulation_vs_box: simulation_vs_box.clone(),
            display_vs_simulation: display_vs_simulation.clone(),
        };
        let text = serde_json::to_string_pretty(&r).map_err(ValidationError::Json)?;
        policy.write(&request.out.join(FILE), text.as_bytes())?;
        files.push(request.out.join(FILE));
        result = Some(r);
    }
    files.extend(write_report_files(request.out, &report, &policy)?);
    Ok(Outcome {
        report,
        white,
        result,
        files,
    })
}

/// The report's data for `request` without writing anything: the readings read, the white
/// chosen and the comparisons made.
pub fn report(request: &Request<'_>) -> Result<ReportInput, ValidationError> {
    assess_all(request).map(|(report, _)| report)
}

fn assess_all(request: &Request<'_>) -> Result<(ReportInput, Xyz), ValidationError> {
    let mut sides = read(&request.readings, request.check_readings)?;
    if request.coverage == Coverage::Same {
        same_patches(&sides)?;
    }
    let (white, white_source) = choose_white(&request.white, &sides)?;
    let mut uncertainty = Vec::new();
    if let Context::Stages(sections) = &request.context {
        if let (Some(u), Some(s)) = (&sections.render_uncertainty, &mut sides.simulation) {
            // The stage's readings carry the render's uncertainty themselves; a simulation
            // stage written before they did has it in its summary only.
            if s.patches.values().all(|p| p.u_lab == 0.0) {
                u.apply(s);
            }
            uncertainty.push(("simulation".to_string(), u.description.clone()));
        }
        for (side, set) in [("box", &sides.box_readings), ("display", &sides.display)] {
            uncertainty.push((side.to_string(), repeatability(set)));
        }
    }
    let run = |r: &ReadingSet, rn: &str, t: &ReadingSet, tn: &str, display: bool| {
        let o = AssessOptions {
            model_term_de: if display {
                request.options.model_term_de
            } else {
                0.0
            },
            ..request.options
        };
        assess(rn, r, tn, t, white, &o).map(|mut a| {
            for p in &mut a.patches {
                p.out_of_gamut |= display && request.out_of_gamut.contains(&p.patch);
            }
            a
        })
    };
    let (b, d) = (&sides.box_readings, &sides.display);
    let display_vs_box = run(b, "box", d, "display", true)?;
    let (simulation_vs_box, display_vs_simulation) = match &sides.simulation {
        Some(s) => (
            Some(run(b, "box", s, "simulation", false)?),
            Some(run(s, "simulation", d, "display", true)?),
        ),
        None => (None, None),
    };
    let mut report = ReportInput {
        title: request.title.clone(),
        white_source,
        display_vs_box: Some(display_vs_box),
        simulation_vs_box,
        display_vs_simulation,
        out_of_gamut: request.out_of_gamut.clone(),
        uncertainty,
        ..ReportInput::default()
    };
    match &request.context {
        Context::Files => files_context(&mut report, &sides, request.check_readings),
        Context::Stages(sections) => stages_context(&mut report, &sides, sections),
    }
    Ok((report, white))
}

/// Under [`Coverage::Same`]: box and display, box and simulation, simulation and display
/// each read the same patches.
fn same_patches(sides: &Sides) -> Result<(), ValidationError> {
    let mut pairs = vec![(("box", &sides.box_readings), ("display", &sides.display))];
    if let Some(s) = &sides.simulation {
        pairs.push((("box", &sides.box_readings), ("simulation", s)));
        pairs.push((("simulation", s), ("display", &sides.display)));
    }
    for ((first, a), (second, b)) in pairs {
        let first_patches: Vec<usize> = a.patches.keys().copied().collect();
        let second_patches: Vec<usize> = b.patches.keys().copied().collect();
        if first_patches != second_patches {
            return Err(ValidationError::DifferentPatches {
                first,
                first_patches,
                second,
                second_patches,
            });
        }
    }
    Ok(())
}

fn choose_white(white: &White, sides: &Sides) -> Result<(Xyz, String), ValidationError> {
    let sets = sides.all();
    let (xyz, source) = match white {
        White::Display => sides.display.white_or_brightest(),
        White::Box => sides.box_readings.white_or_brightest(),
        White::Given(white) => {
            let white = *white;
            metamer_color::check_xyz(white)
                .map_err(|e| ValidationError::GivenWhite(format!("not a white: {e}")))?;
            plausible::check_given_white(white)
                .and_then(|()| plausible::check_white_against(white, &sets))
                .map_err(|e| ValidationError::GivenWhite(e.to_string()))?;
            return Ok((white, "given on the command line".to_string()));
        }
        White::Measured { xyz, source } => return Ok((*xyz, source.clone())),
    };
    plausible::check_white_against(xyz, &sets)?;
    Ok((xyz, source))
}

/// [`Context::Files`]: each file as given, what it names and notes.
fn files_context(report: &mut ReportInput, sides: &Sides, check: bool) {
    if check {
        report
            .notes
            .extend(plausible::scale_note(&sides.box_readings, &sides.display));
    }
    for (role, set) in [
        ("box", Some(&sides.box_readings)),
        ("display", Some(&sides.display)),
        ("simulation", sides.simulation.as_ref()),
    ] {
        let Some(set) = set else { continue };
        report.inputs.push(InputFile {
            role: role.into(),
            path: set.file.display().to_string(),
            format: set.format.name().into(),
            patches: set.patches.len(),
            sha256: crate::digest::sha256_file(&set.file).ok(),
        });
        for name in &set.instruments {
            report.instruments.push(InstrumentUsed {
                role: role.into(),
                model: name.clone(),
                ..InstrumentUsed::default()
            });
        }
        for note in &set.notes {
            report.notes.push(format!("{}: {note}", set.file.display()));
        }
        if set.format == Format::RenderJson {
            report.render_confidence = Some(render_confidence(set));
        }
    }
}

/// [`Context::Stages`]: the gathered sections, the readings' counts and notes.
fn stages_context(report: &mut ReportInput, sides: &Sides, sections: &Sections) {
    let sets = [
        Some(&sides.box_readings),
        sides.simulation.as_ref(),
        Some(&sides.display),
    ];
    let mut inputs = sections.inputs.clone();
    for (input, set) in inputs.iter_mut().zip(sets) {
        if let Some(set) = set {
            input.patches = set.patches.len();
            // A given box's readings may be a journal or `spot --json` as well as a CSV.
            input.format = format!("readings ({})", set.format.name());
        }
    }
    let mut notes = sections.notes.clone();
    for set in sets.into_iter().flatten() {
        for n in &set.notes {
            notes.push(format!("{}: {n}", set.file.display()));
        }
    }
    report.display_model = sections.display_model.clone();
    report.light_fit = sections.light_fit.clone();
    report.render_confidence = sections.render_confidence.clone();
    report.instruments = sections.instruments.clone();
    report.measuring_cost = sections.measuring_cost.clone();
    report.cost_curves = sections.cost_curves.clone();
    report.compared_cost = sections.compared_cost.clone();
    report.inputs = inputs;
    report.notes = notes;
}

/// A render's per-patch ΔE statement as the report's render-confidence section.
fn render_confidence(set: &ReadingSet) -> RenderConfidenceSection {
    RenderConfidenceSection {
        method: format!("{} ({})", set.file.display(), set.format.name()),
        target_de: None,
        per_patch: set
            .patches
            .iter()
            .filter_map(|(k, p)| Some((*k, p.render_de95?)))
            .collect(),
        measure: "95 % ΔE*ab half-width or error bound".into(),
        ..Default::default()
    }
}

/// What a meter's readings' intervals contain: the covariance of the mean of each patch's
/// repeats, or for a patch read once the instrument's stated repeatability, or nothing.
fn repeatability(set: &ReadingSet) -> String {
    let ns: Vec<usize> = set.patches.values().map(|p| p.n).collect();
    let (lo, hi) = (
        ns.iter().copied().min().unwrap_or(0),
        ns.iter().copied().max().unwrap_or(0),
    );
    let k = if lo == hi {
        format!("{lo}")
    } else {
        format!("{lo}–{hi}")
    };
    let known = set.patches.values().all(|p| !p.u_factors.is_empty());
    if hi <= 1 && known {
        "single readings: the meter's stated repeatability (CS-100A: 0.1 % in Y, 0.0005 in x and y, 1σ) carried to X, Y, Z".into()
    } else if hi <= 1 {
        "single readings: the meter's repeatability is unknown and not in the interval".into()
    } else {
        format!(
            "the meter's repeatability: the full covariance in X, Y, Z of the mean of {k} repeats per patch, widened for the few repeats it is estimated from (Student's t with k − 1 degrees of freedom)"
        )
    }
}
