//! Per-patch readings passed between stages as a small CSV that `metamer validate` and a
//! spreadsheet read too: `patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,cov_XY,cov_XZ,cov_YZ,u_lab` — the
//! mean of `n` readings in cd/m², the standard deviations and covariances of one reading
//! (their sample's for n ≥ 2; for one reading the instrument's stated repeatability, or 0
//! when it is not known), and a render's standard uncertainty per CIELAB axis (0 for a
//! measurement). Files of the earlier form `patch,X,Y,Z,sd_X,sd_Y,sd_Z,n` still read, with
//! independent axes and no render uncertainty.

use std::path::{Path, PathBuf};

use metamer_drivers::Reading;

use super::cache::{write_atomic, CacheError};
use crate::session::repeats::Repeatability;
use crate::validation::covariance::{self, Cov3};

/// The readings of one ColorChecker patch.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PatchStat {
    pub patch: usize,
    /// Mean XYZ, cd/m².
    pub xyz: [f64; 3],
    /// Covariance of X, Y, Z of a single reading.
    pub cov: Cov3,
    pub n: usize,
    /// A render's standard uncertainty per CIELAB axis; 0 for a measurement.
    pub u_lab: f64,
}

impl PatchStat {
    /// Mean and sample covariance of `readings` of `patch` (at least one; one reading's
    /// covariance is 0: nothing is known of it).
    pub fn of(patch: usize, readings: &[[f64; 3]]) -> PatchStat {
        let (xyz, cov) = covariance::sample(readings);
        PatchStat {
            patch,
            xyz,
            cov,
            n: readings.len(),
            u_lab: 0.0,
        }
    }

    /// The standard deviations of one reading.
    pub fn sd(&self) -> [f64; 3] {
        covariance::sd(&self.cov)
    }

    /// Groups instrument readings by patch number; a patch read once gets its instrument's
    /// stated repeatability where it has one.
    pub fn group(readings: &[(usize, &Reading)]) -> Vec<PatchStat> {
        let mut patches: Vec<usize> = readings.iter().map(|(p, _)| *p).collect();
        patches.sort_unstable();
        patches.dedup();
        patches
            .into_iter()
            .map(|p| {
                let of_patch: Vec<&Reading> = readings
                    .iter()
                    .filter(|(q, _)| *q == p)
                    .map(|(_, r)| *r)
                    .collect();
                let xs: Vec<[f64; 3]> = of_patch.iter().map(|r| r.xyz).collect();
                let mut s = PatchStat::of(p, &xs);
                if let [one] = of_patch.as_slice() {
                    if let Some(c) = Repeatability::emissive_of(&one.instrument)
                        .and_then(|r| r.covariance(one.xyz))
                    {
                        s.cov = c;
                    }
                }
                s
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

const HEADER: &str = "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,cov_XY,cov_XZ,cov_YZ,u_lab";
/// The form written before the covariance and the render's uncertainty were kept.
const HEADER_SD_ONLY: &str = "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n";

pub fn write_readings(path: &Path, stats: &[PatchStat]) -> Result<(), ReadingsError> {
    let mut s = format!("{HEADER}\n");
    for p in stats {
        let sd = p.sd();
        let off = covariance::off_diagonal(&p.cov);
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{}\n",
            p.patch,
            p.xyz[0],
            p.xyz[1],
            p.xyz[2],
            sd[0],
            sd[1],
            sd[2],
            p.n,
            off[0],
            off[1],
            off[2],
            p.u_lab
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
    let fields = match lines.next().map(|(_, h)| h.trim()) {
        Some(HEADER) => 12,
        Some(HEADER_SD_ONLY) => 8,
        _ => {
            return Err(bad(
                1,
                format!("the header must be `{HEADER}` (or the earlier `{HEADER_SD_ONLY}`)"),
            ))
        }
    };
    let mut out = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != fields {
            return Err(bad(
                i + 1,
                format!("expected {fields} fields, found {}", f.len()),
            ));
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
        let (off, u_lab) = if fields == 12 {
            ([num(8)?, num(9)?, num(10)?], num(11)?)
        } else {
            ([0.0; 3], 0.0)
        };
        let cov = covariance::from_parts(sd, off);
        covariance::check(&cov).map_err(|e| bad(i + 1, e))?;
        if !(0.0..=1000.0).contains(&u_lab) {
            return Err(bad(
                i + 1,
                format!("u_lab {u_lab}: must be a ΔE*ab from 0 to 1000"),
            ));
        }
        out.push(PatchStat {
            patch,
            xyz,
            cov,
            n,
            u_lab,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_sample_sd() {
        // X: 1, 2, 3 → mean 2, s = 1; Y constant → 0; Z 0, 0, 3: s = √3, cov XZ
        // ((−1)(−1) + 0 + (1)(2))/2 = 1.5.
        let s = PatchStat::of(7, &[[1.0, 5.0, 0.0], [2.0, 5.0, 0.0], [3.0, 5.0, 3.0]]);
        assert_eq!(s.xyz, [2.0, 5.0, 1.0]);
        assert!((s.sd()[0] - 1.0).abs() < 1e-12);
        assert_eq!(s.sd()[1], 0.0);
        assert!((s.sd()[2] - 3f64.sqrt()).abs() < 1e-12);
        assert!((s.cov[0][2] - 1.5).abs() < 1e-12);
        assert_eq!(s.n, 3);
    }

    /// One reading of a CS-100A carries its stated repeatability; two carry their scatter.
    #[test]
    fn a_single_reading_gets_the_instruments_repeatability() {
        let one = Reading::from_yxy(10.0, 0.45, 0.5, "cs100a");
        let two = Reading::from_yxy(10.1, 0.45, 0.5, "cs100a");
        let g = PatchStat::group(&[(16, &one), (17, &one), (17, &two)]);
        // σY: 0.1 % of 10 and the last of four digits of 10.00 (0.01, variance 0.01²/12):
        // 0.01·√(1 + 1/12) = 0.010408.
        assert!((g[0].sd()[1] - 0.010_408_33).abs() < 1e-8, "{g:?}");
        let stated = Repeatability::emissive_of("cs100a")
            .unwrap()
            .covariance(one.xyz)
            .unwrap();
        assert_eq!(g[0].cov, stated);
        assert!((g[1].sd()[1] - 0.1 / 2f64.sqrt()).abs() < 1e-12, "{g:?}");
        let unknown = Reading::from_yxy(10.0, 0.45, 0.5, "mystery");
        assert_eq!(PatchStat::group(&[(1, &unknown)])[0].cov, covariance::ZERO);
    }

    #[test]
    fn round_trip_and_errors() {
        let dir = std::env::temp_dir().join(format!("metamer-readings-{}", std::process::id()));
        let p = dir.join("r.csv");
        let stats = vec![
            PatchStat::of(1, &[[0.1, 0.2, 0.3]]),
            PatchStat::of(2, &[[1.0, 2.0, 3.0], [1.5, 2.5, 3.5]]),
        ];
        // The covariance's diagonal is written as standard deviations: back to within
        // rounding.
        let same = |a: &[PatchStat], b: &[PatchStat]| {
            a.len() == b.len()
                && a.iter().zip(b).all(|(a, b)| {
                    a.patch == b.patch
                        && a.xyz == b.xyz
                        && a.n == b.n
                        && a.cov
                            .iter()
                            .flatten()
                            .zip(b.cov.iter().flatten())
                            .all(|(x, y)| (x - y).abs() <= 1e-15 * x.abs().max(1.0))
                })
        };
        write_readings(&p, &stats).unwrap();
        assert!(same(&read_readings(&p).unwrap(), &stats));
        std::fs::write(&p, format!("{HEADER}\n1,0,1,NaN,0,0,0,1,0,0,0,0\n")).unwrap();
        let e = read_readings(&p).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("field 4"), "{e}");
        // Saved with a byte-order mark: the same readings.
        write_readings(&p, &stats).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        std::fs::write(&p, format!("\u{feff}{text}")).unwrap();
        assert!(same(&read_readings(&p).unwrap(), &stats));
        // Finite but impossible: refused with the line.
        for row in [
            "1,-1e308,1,1,0,0,0,1,0,0,0,0",
            "1,1,1e300,1,0,0,0,1,0,0,0,0",
            "1,1,1,1,0,-1,0,2,0,0,0,0",
            "1,1,1,1,1,1,1,2,3,0,0,0",
            "1,1,1,1,0,0,0,1,0,0,0,-1",
        ] {
            std::fs::write(&p, format!("{HEADER}\n{row}\n")).unwrap();
            let e = read_readings(&p).unwrap_err().to_string();
            assert!(e.contains("line 2"), "{row}: {e}");
        }
        // The earlier form without covariances reads, its axes independent.
        std::fs::write(&p, format!("{HEADER_SD_ONLY}\n3,1,2,3,0.1,0.2,0.3,5\n")).unwrap();
        let old = read_readings(&p).unwrap();
        assert_eq!(old[0].sd(), [0.1, 0.2, 0.3]);
        assert_eq!(covariance::off_diagonal(&old[0].cov), [0.0; 3]);
    }
}
