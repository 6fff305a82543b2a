//! Per-patch readings passed between stages as a small CSV that `metamer validate` and a
//! spreadsheet read too: `patch,X,Y,Z,sd_X,sd_Y,sd_Z,n` — the mean of `n` readings and the
//! sample standard deviation of one reading (0 with a single reading or for a render,
//! whose uncertainty is its own column where the stage has one).

use std::path::{Path, PathBuf};

use metamer_drivers::Reading;

use super::cache::{write_atomic, CacheError};

/// The readings of one ColorChecker patch.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PatchStat {
    pub patch: usize,
    /// Mean XYZ, cd/m².
    pub xyz: [f64; 3],
    /// Standard deviation of a single reading.
    pub sd: [f64; 3],
    pub n: usize,
}

impl PatchStat {
    /// Mean and sample standard deviation of `readings` of `patch` (at least one).
    pub fn of(patch: usize, readings: &[[f64; 3]]) -> PatchStat {
        let n = readings.len().max(1);
        let mut mean = [0.0; 3];
        for r in readings {
            (0..3).for_each(|k| mean[k] += r[k] / n as f64);
        }
        let mut sd = [0.0; 3];
        if readings.len() > 1 {
            for r in readings {
                (0..3).for_each(|k| sd[k] += (r[k] - mean[k]).powi(2));
            }
            sd = sd.map(|s| (s / (readings.len() - 1) as f64).sqrt());
        }
        PatchStat {
            patch,
            xyz: mean,
            sd,
            n: readings.len(),
        }
    }

    /// Groups instrument readings by patch number.
    pub fn group(readings: &[(usize, &Reading)]) -> Vec<PatchStat> {
        let mut patches: Vec<usize> = readings.iter().map(|(p, _)| *p).collect();
        patches.sort_unstable();
        patches.dedup();
        patches
            .into_iter()
            .map(|p| {
                let xs: Vec<[f64; 3]> = readings
                    .iter()
                    .filter(|(q, _)| *q == p)
                    .map(|(_, r)| r.xyz)
                    .collect();
                PatchStat::of(p, &xs)
            })
            .collect()
    }
}

/// A readings file is not what a stage wrote.
#[derive(Debug, thiserror::Error)]
pub enum ReadingsError {
    #[error("reading {}: {source}", file.display())]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{}, line {line}: {message}", file.display())]
    Parse {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error(transparent)]
    Write(#[from] CacheError),
}

const HEADER: &str = "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n";

pub fn write_readings(path: &Path, stats: &[PatchStat]) -> Result<(), ReadingsError> {
    let mut s = format!("{HEADER}\n");
    for p in stats {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{}\n",
            p.patch, p.xyz[0], p.xyz[1], p.xyz[2], p.sd[0], p.sd[1], p.sd[2], p.n
        ));
    }
    write_atomic(path, s.as_bytes())?;
    Ok(())
}

pub fn read_readings(path: &Path) -> Result<Vec<PatchStat>, ReadingsError> {
    let text = metamer_color::text::read_text(path).map_err(|source| ReadingsError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    // A spreadsheet that saved the file as "UTF-8 with BOM" puts it before the header.
    let text = metamer_color::text::strip_bom(&text);
    let bad = |line: usize, message: String| ReadingsError::Parse {
        file: path.to_path_buf(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == HEADER => {}
        _ => return Err(bad(1, format!("the header must be `{HEADER}`"))),
    }
    let mut out = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 8 {
            return Err(bad(i + 1, format!("expected 8 fields, found {}", f.len())));
        }
        let num = |k: usize| -> Result<f64, ReadingsError> {
            f[k].parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(i + 1, format!("field {} is not a finite number", k + 1)))
        };
        let patch = f[0]
            .parse::<usize>()
            .map_err(|_| bad(i + 1, "the patch is not a whole number".into()))?;
        let n = f[7]
            .parse::<usize>()
            .map_err(|_| bad(i + 1, "n is not a whole number".into()))?;
        let xyz = [num(1)?, num(2)?, num(3)?];
        // A reading no instrument can take (X = −1e308) would become an infinite CIELAB
        // and a chart without end downstream: refused here, where it enters.
        metamer_color::check_xyz(xyz).map_err(|e| bad(i + 1, format!("not a measurement: {e}")))?;
        let sd = [num(4)?, num(5)?, num(6)?];
        if !metamer_color::plausible_spread(sd) {
            return Err(bad(
                i + 1,
                format!(
                    "a standard deviation of {sd:?}: must be ≥ 0 and at most {:e}",
                    metamer_color::MAX_CD_M2
                ),
            ));
        }
        out.push(PatchStat { patch, xyz, sd, n });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_sample_sd() {
        // X: 1, 2, 3 → mean 2, s = 1; Y constant → 0.
        let s = PatchStat::of(7, &[[1.0, 5.0, 0.0], [2.0, 5.0, 0.0], [3.0, 5.0, 3.0]]);
        assert_eq!(s.xyz, [2.0, 5.0, 1.0]);
        assert!((s.sd[0] - 1.0).abs() < 1e-12);
        assert_eq!(s.sd[1], 0.0);
        assert!((s.sd[2] - 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(s.n, 3);
    }

    #[test]
    fn round_trip_and_errors() {
        let dir = std::env::temp_dir().join(format!("metamer-readings-{}", std::process::id()));
        let p = dir.join("r.csv");
        let stats = vec![
            PatchStat::of(1, &[[0.1, 0.2, 0.3]]),
            PatchStat::of(2, &[[1.0, 2.0, 3.0], [1.5, 2.5, 3.5]]),
        ];
        write_readings(&p, &stats).unwrap();
        assert_eq!(read_readings(&p).unwrap(), stats);
        std::fs::write(&p, format!("{HEADER}\n1,0,1,NaN,0,0,0,1\n")).unwrap();
        let e = read_readings(&p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("field 4"), "{e}");
        // Saved with a byte-order mark: the same readings.
        write_readings(&p, &stats).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        std::fs::write(&p, format!("\u{feff}{text}")).unwrap();
        assert_eq!(read_readings(&p).unwrap(), stats);
        // Finite but impossible: refused with the line.
        for row in [
            "1,-1e308,1,1,0,0,0,1",
            "1,1,1e300,1,0,0,0,1",
            "1,1,1,1,0,-1,0,2",
        ] {
            std::fs::write(&p, format!("{HEADER}\n{row}\n")).unwrap();
            let e = read_readings(&p).unwrap_err().to_string();
            assert!(e.contains("line 2"), "{row}: {e}");
        }
    }
}
