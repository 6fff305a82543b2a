//! Gathering the report's input from what the earlier stages wrote, as the one type the
//! validation takes from the experiment ([`Sections`]; the validation draws it, with the
//! comparisons, in `validation::report`): the display model
//! (`display/summary.json`), the light distribution fit (`box/light.json`, `light.svg`,
//! the scene's provenance), the renders' confidence (`simulation/simulation.json`), the
//! instruments and every calibration (the box, display and display-spots journals), and
//! the inputs with their SHA-256. A file that is missing or unreadable leaves its section
//! out with a note saying which file and why; it never fails the report.

mod cost;
mod display;
mod files;
mod instruments;
mod light;
mod render;

use std::path::{Path, PathBuf};

use crate::digest::sha256_file;
use crate::validation::report::{ComparedCost, InputFile};
pub use crate::validation::report::{RenderUncertainty, Sections};

/// Where the stages' files are.
#[derive(Clone, Debug)]
pub struct Layout {
    /// The experiment's directory.
    pub root: PathBuf,
    /// The box's directory: its spot readings' and, when measured here, its scene's.
    pub box_dir: PathBuf,
    pub simulation_dir: PathBuf,
    pub display_dir: PathBuf,
    pub reproduction_dir: PathBuf,
    pub display_spots_dir: PathBuf,
}

impl Layout {
    /// The experiment's layout under `root`, the box's files beside `box_spots` (the
    /// experiment's `box/`, or the directory of readings given with `--box-spots`).
    pub fn of(root: &Path, box_spots: &Path) -> Layout {
        let stage = |s: super::Stage| root.join(s.name());
        Layout {
            root: root.to_path_buf(),
            box_dir: box_spots
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_else(|| stage(super::Stage::Box)),
            simulation_dir: stage(super::Stage::Simulation),
            display_dir: stage(super::Stage::Display),
            reproduction_dir: stage(super::Stage::Reproduction),
            display_spots_dir: stage(super::Stage::DisplaySpots),
        }
    }

    /// The measuring stages' directories.
    pub fn dirs(&self) -> cost::RunDirs<'_> {
        cost::RunDirs {
            box_dir: &self.box_dir,
            display_dir: &self.display_dir,
            display_spots_dir: &self.display_spots_dir,
        }
    }
}

/// The files of the run saved in `dir` that [`compare_with`] reads, by a name for each.
pub fn compared_files(dir: &Path) -> Vec<(String, PathBuf)> {
    let layout = Layout::of(dir, &dir.join(super::Stage::Box.name()).join("spots.csv"));
    cost::compared_files(layout.dirs())
}

/// Adds the run saved in `dir` (an experiment's or `lab`'s folder, measured with another
/// plan on the same rig) to `sections`: its stages' costs and its curves, named by the
/// folder's name. A folder without these files adds notes only.
pub fn compare_with(sections: &mut Sections, dir: &Path) {
    let run = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| dir.display().to_string());
    let layout = Layout::of(dir, &dir.join(super::Stage::Box.name()).join("spots.csv"));
    let stages = cost::measuring_cost(layout.dirs());
    if stages.is_empty() {
        sections.notes.push(format!(
            "the compared run {} keeps no measuring cost",
            dir.display()
        ));
    }
    let (curves, notes) = cost::curves(layout.dirs(), &run);
    sections.compared_cost = Some(ComparedCost { run, stages });
    sections.cost_curves.extend(curves);
    sections.notes.extend(notes);
}

/// Gathers every section from the files under `layout`.
pub fn gather(layout: &Layout, readings: &[(&str, &Path, usize)]) -> Sections {
    let mut s = Sections::default();
    match display::section(&layout.display_dir) {
        Ok(d) => s.display_model = Some(d),
        Err(note) => s.notes.push(note),
    }
    match light::section(&layout.box_dir) {
        Ok((l, notes)) => {
            s.light_fit = Some(l);
            s.notes.extend(notes);
        }
        Err(note) => s.notes.push(note),
    }
    match render::section(&layout.simulation_dir) {
        Ok((r, u)) => {
            s.render_confidence = Some(r);
            s.render_uncertainty = Some(u);
        }
        Err(note) => s.notes.push(note),
    }
    let (instruments, notes) = instruments::used(&[
        ("box", &layout.box_dir),
        ("display", &layout.display_dir),
        ("display spots", &layout.display_spots_dir),
    ]);
    s.instruments = instruments;
    s.notes.extend(notes);
    s.inputs = inputs(layout, readings);
    s.measuring_cost = cost::measuring_cost(layout.dirs());
    let (curves, notes) = cost::curves(layout.dirs(), crate::validation::cost_curve::THIS_RUN);
    s.cost_curves = curves;
    s.notes.extend(notes);
    s
}

/// The files the report rests on, each with its SHA-256: the three readings files first
/// (`readings`: role, path, patches), then the scene, the light fit, the display's model
/// and summary, the reproduction, the render summary and every session journal.
fn inputs(layout: &Layout, readings: &[(&str, &Path, usize)]) -> Vec<InputFile> {
    let mut files: Vec<InputFile> = readings
        .iter()
        .map(|(role, path, patches)| input(role, path, "readings", *patches))
        .collect();
    let others = [
        ("box", layout.box_dir.join("scene.json"), "measured scene"),
        (
            "box",
            layout.box_dir.join("light.json"),
            "light distribution fit",
        ),
        (
            "simulation",
            layout.simulation_dir.join(super::simulation::SUMMARY_FILE),
            "render summary",
        ),
        (
            "display",
            layout.display_dir.join(super::display::PROFILE_FILE),
            "display profile",
        ),
        (
            "display",
            layout.display_dir.join(super::display::SUMMARY_FILE),
            "characterization summary",
        ),
        (
            "reproduction",
            layout.reproduction_dir.join(super::reproduction::FILE),
            "drive values and gamut flags",
        ),
    ];
    for (role, path, format) in others {
        if path.is_file() {
            files.push(input(role, &path, format, 0));
        }
    }
    for (role, dir) in [
        ("box", &layout.box_dir),
        ("display", &layout.display_dir),
        ("display spots", &layout.display_spots_dir),
    ] {
        for journal in instruments::journals(dir) {
            files.push(input(role, &journal, "session journal", 0));
        }
    }
    // Inside the experiment a path is shown from its directory, so the report reads the
    // same wherever the directory is moved.
    for f in &mut files {
        if let Ok(rel) = Path::new(&f.path).strip_prefix(&layout.root) {
            f.path = rel.display().to_string();
        }
    }
    files
}

fn input(role: &str, path: &Path, format: &str, patches: usize) -> InputFile {
    InputFile {
        role: role.into(),
        path: path.display().to_string(),
        format: format.into(),
        patches,
        sha256: sha256_file(path).ok(),
    }
}

#[cfg(test)]
mod tests {
    use super::files::testdir;
    use super::*;

    #[test]
    fn missing_files_leave_their_sections_out_with_notes() {
        let root = testdir::fresh("missing");
        let spots = root.join("box/spots.csv");
        let layout = Layout::of(&root, &spots);
        let s = gather(&layout, &[]);
        assert!(s.display_model.is_none() && s.light_fit.is_none());
        assert!(s.render_confidence.is_none() && s.instruments.is_empty());
        assert!(
            s.notes
                .iter()
                .any(|n| n.starts_with("no display model section: ")
                    && n.ends_with("display/summary.json does not exist")),
            "{:?}",
            s.notes
        );
        assert!(
            s.notes
                .iter()
                .any(|n| n.contains("box/light.json does not exist")),
            "{:?}",
            s.notes
        );
        std::fs::remove_dir_all(&root).ok();
    }

    #[test]
    fn inputs_carry_the_sha256_of_their_bytes() {
        let root = testdir::fresh("inputs");
        std::fs::create_dir_all(root.join("box")).unwrap();
        // SHA-256("abc"), FIPS 180-2 appendix B.1.
        testdir::write(&root.join("box"), "spots.csv", "abc");
        let spots = root.join("box/spots.csv");
        let layout = Layout::of(&root, &spots);
        let files = inputs(&layout, &[("box", &spots, 24)]);
        assert_eq!(files.len(), 1);
        assert_eq!(
            files[0].sha256.as_deref(),
            Some("ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad")
        );
        assert_eq!(files[0].patches, 24);
        assert_eq!(files[0].path, "box/spots.csv");
        std::fs::remove_dir_all(&root).ok();
    }
}
