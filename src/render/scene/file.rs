//! The scene file as written: the serde types that both read and write it.
//!
//! Reading goes through [`super::reader`], which walks the JSON value field by field so
//! every error names the JSON path of the bad field; writing is serde's derived form of the
//! same types, so a file written here reads back to the same scene.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::color::Outside;
use crate::light::CGammaTable;

/// A spectrum in the scene file.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum SpectrumRef {
    /// The same value at every wavelength.
    Constant(f64),
    /// A column of a spectral CSV file (path relative to the scene file).
    File {
        file: String,
        /// 1-based value column (default 1).
        #[serde(skip_serializing_if = "Option::is_none")]
        column: Option<usize>,
        #[serde(skip_serializing_if = "Option::is_none")]
        outside: Option<Outside>,
    },
    /// Samples given in the file.
    Inline {
        nm: Vec<f64>,
        values: Vec<f64>,
        #[serde(skip_serializing_if = "Option::is_none")]
        outside: Option<Outside>,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceFile {
    pub name: String,
    pub corner: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    pub reflectance: SpectrumRef,
    /// ColorChecker patch number (1–24) if this surface is a patch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub patch: Option<usize>,
}

/// The emitter's directional factor f relative to its luminance along the normal.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum DistributionFile {
    #[default]
    Lambertian,
    /// f(θ) = cosᵐθ (f = 1 on the normal).
    CosPower { exponent: f64 },
    /// A measured table f(C, γ), C from the emitter's edge_u towards edge_v.
    CGamma { table: CGammaTable },
    /// The distribution of an IES LM-63 file (path relative to the scene file); its
    /// candela values give the shape only, the luminance comes from the emitter.
    Ies { file: String },
    /// The same from a EULUMDAT (.ldt) file.
    Ldt { file: String },
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TileFile {
    pub row: usize,
    pub col: usize,
    /// Multiplies the tile's radiance (default 1).
    pub gain: f64,
    /// Absolute spectral radiance along the normal, W·sr⁻¹·m⁻²·nm⁻¹ (then every tile of
    /// the emitter has one, and the emitter has neither `spectrum` nor `luminance_cd_m2`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spectrum: Option<SpectrumRef>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EmitterFile {
    /// Corner of tile (0, 0); `edge_u` runs along the columns, `edge_v` along the rows.
    pub corner: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    /// Tile grid (default 1 × 1: an untiled panel).
    pub rows: usize,
    pub cols: usize,
    /// Tile gains (and spectra); omitted, every tile has gain 1.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tiles: Vec<TileFile>,
    /// Relative spectral radiance shared by every tile (default: equal energy); absent when
    /// the tiles carry absolute spectra.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spectrum: Option<SpectrumRef>,
    /// Luminance along the normal of the untiled source (gain 1); absent when the tiles
    /// carry absolute spectra.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub luminance_cd_m2: Option<f64>,
    pub distribution: DistributionFile,
    /// Reflectance of the emitting surface (default 0: the light absorbs what reaches it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reflectance: Option<SpectrumRef>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CameraFile {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    pub vfov_deg: f64,
    pub width: usize,
    pub height: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeterFile {
    pub acceptance_deg: f64,
}

/// The scene file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneFile {
    pub name: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Where the numbers came from (journal hash, date, instruments, fit residuals): any
    /// JSON object, carried through untouched.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub provenance: Option<serde_json::Map<String, serde_json::Value>>,
    pub surfaces: Vec<SurfaceFile>,
    pub emitters: Vec<EmitterFile>,
    /// A room lit for illuminance probes needs neither camera nor meter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraFile>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub meter: Option<MeterFile>,
}

/// Why a scene file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("cannot write scene {file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write scene {file}: {source}")]
    Json {
        file: PathBuf,
        source: serde_json::Error,
    },
}

impl SceneFile {
    /// Every file the scene names (spectral tables, photometric files), as written in it:
    /// relative to the scene file's directory. A program that writes beside a scene
    /// registers them as its inputs, so nothing it writes replaces what the scene reads.
    pub fn named_files(&self) -> Vec<&str> {
        fn spectrum(s: &SpectrumRef) -> Option<&str> {
            match s {
                SpectrumRef::File { file, .. } => Some(file.as_str()),
                _ => None,
            }
        }
        let mut out: Vec<&str> = Vec::new();
        out.extend(
            self.surfaces
                .iter()
                .filter_map(|s| spectrum(&s.reflectance)),
        );
        for e in &self.emitters {
            out.extend(
                e.tiles
                    .iter()
                    .filter_map(|t| t.spectrum.as_ref().and_then(spectrum)),
            );
            out.extend(e.spectrum.as_ref().and_then(spectrum));
            out.extend(e.reflectance.as_ref().and_then(spectrum));
            if let DistributionFile::Ies { file } | DistributionFile::Ldt { file } = &e.distribution
            {
                out.push(file);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Pretty JSON of the file.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// Writes the file: to a temporary file in the same directory, then renamed over
    /// `path`, so a reader never sees half a scene. File references are written as they
    /// are, relative to the directory of `path`.
    pub fn write(&self, path: &Path) -> Result<(), WriteError> {
        let text = self.to_json().map_err(|source| WriteError::Json {
            file: path.to_path_buf(),
            source,
        })?;
        let io = |source| WriteError::Io {
            file: path.to_path_buf(),
            source,
        };
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = path
            .file_name()
            .ok_or_else(|| io(std::io::Error::other("not a file name")))?;
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{}.tmp", std::process::id()));
        let tmp = dir.join(tmp_name);
        let result = (|| {
            use std::io::Write;
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(text.as_bytes())?;
            f.write_all(b"\n")?;
            f.sync_all()?;
            std::fs::rename(&tmp, path)
        })();
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result.map_err(io)
    }
}
