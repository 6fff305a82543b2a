//! Illuminance at points listed in a CSV file: `metamer render probes` in one call.
//!
//! ```no_run
//! use metamer::render::job::probes::{run, ProbesRequest};
//! use metamer::render::probes::ProbeOptions;
//!
//! let request = ProbesRequest {
//!     scene: "room.json".into(),
//!     points: "points.csv".into(),
//!     options: ProbeOptions::default(),
//! };
//! let report = run(&request, &|_| {})?;
//! println!("{}", report.to_json()?);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;

use super::{load_scene, RenderError, RenderEvent};
use crate::numeric_csv::NumericCsv;
use crate::render::geometry::{Vec3, VecOps};
use crate::render::probes::{illuminance, ProbeOptions, ProbeResult};
use crate::render::radiosity::probes::{Illuminance, Probe};

/// What to compute.
#[derive(Clone, Debug)]
pub struct ProbesRequest {
    pub scene: PathBuf,
    /// CSV rows x,y,z,nx,ny,nz (header line), the normal being the measuring surface's.
    pub points: PathBuf,
    pub options: ProbeOptions,
}

/// The points and their illuminance.
#[derive(Clone, Debug)]
pub struct ProbesReport {
    /// The points as read, normals made unit length.
    pub probes: Vec<Probe>,
    pub result: ProbeResult,
    /// The tolerance asked for, which a not-converged radiosity run is measured against.
    pub rel_tolerance: f64,
}

impl ProbesReport {
    /// The largest bound as a fraction of its total: how far from converged a run is.
    pub fn worst_relative_bound(&self) -> f64 {
        self.result
            .probes
            .iter()
            .map(|e| e.bound_lux / e.total_lux.abs())
            .fold(0.0, f64::max)
    }

    /// One JSON object: the result, each probe with its point and normal.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        #[derive(serde::Serialize)]
        struct Row<'a> {
            point: [f64; 3],
            normal: [f64; 3],
            #[serde(flatten)]
            lux: &'a Illuminance,
        }
        let rows: Vec<Row> = self
            .probes
            .iter()
            .zip(&self.result.probes)
            .map(|(p, lux)| Row {
                point: p.position.to_array(),
                normal: p.normal.to_array(),
                lux,
            })
            .collect();
        let mut v = serde_json::to_value(&self.result)?;
        v["probes"] = serde_json::to_value(rows)?;
        Ok(v.to_string())
    }
}

/// Loads the scene and the points, then computes every point's illuminance by the
/// method the options ask for (`auto` resolved by [`illuminance`], its reason kept in the
/// result). Failures of the computation are named by the points file.
pub fn run(
    request: &ProbesRequest,
    events: &(dyn Fn(RenderEvent) + Sync),
) -> Result<ProbesReport, RenderError> {
    let scene = load_scene(Some(&request.scene), events)?;
    let points = &request.points;
    let csv = NumericCsv::read(points, &["x", "y", "z", "nx", "ny", "nz"])?;
    let mut probes = Vec::with_capacity(csv.rows.len());
    for (line, v) in &csv.rows {
        let normal = Vec3::from_array([v[3], v[4], v[5]]);
        if normal.length() == 0.0 {
            return Err(RenderError::ZeroNormal {
                file: points.clone(),
                line: *line,
            });
        }
        probes.push(Probe {
            position: Vec3::from_array([v[0], v[1], v[2]]),
            normal: normal.normalized(),
        });
    }
    let result = illuminance(&scene, &probes, &request.options, &|p| {
        events(RenderEvent::Probe(p))
    })
    .map_err(|error| RenderError::Probes {
        file: points.clone(),
        error,
    })?;
    Ok(ProbesReport {
        probes,
        result,
        rel_tolerance: request.options.rel_tolerance,
    })
}
