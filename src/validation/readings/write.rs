//! Readings taken here, and the file they are written to: the experiment's stages build each
//! patch's [`PatchReading`] from what they measured or rendered and write them as
//! `patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,cov_XY,cov_XZ,cov_YZ,u_lab` — the mean of `n` readings in
//! cd/m², the standard deviations and covariances of one reading (their sample's for
//! n ≥ 2; for one reading the instrument's stated repeatability, or 0 when it is not
//! known), and a render's standard uncertainty per CIELAB axis (0 for a measurement).
//!
//! A patch is built as the CSV reader would read its row back ([`combine`] of that one
//! row), so what a stage holds is what `validate` and the next run read from its file.

use metamer_drivers::Reading;

use super::rows::combine;
use super::*;
use crate::output::OutputPolicy;
use crate::validation::repeatability;

/// The header the stages write.
pub const HEADER: &str = "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,cov_XY,cov_XZ,cov_YZ,u_lab";

impl PatchReading {
    /// The mean `xyz` of `n` readings (at least one) with one reading's covariance `cov`
    /// and a render's CIELAB standard uncertainty `u_lab` (0 for a measurement): a row of
    /// the stages' readings file.
    pub fn stated(xyz: Xyz, cov: Cov3, n: usize, u_lab: f64) -> PatchReading {
        let row = Row {
            sd: Some(covariance::sd(&cov)),
            cov: covariance::off_diagonal(&cov),
            n: n.max(1),
            u_lab: Some(u_lab),
            ..Row::reading(0, PatchId::Number(0), xyz.into())
        };
        PatchReading {
            // Kept as given, not as its standard deviations squared, and the count as
            // given: the file is written from them.
            reading_cov: Some(cov),
            n,
            ..combine(&[&row])
        }
    }

    /// The mean `xyz` of `n` readings with one reading's covariance `cov` pooled across the
    /// patches one instrument read in one mode, with its `dof` degrees of freedom
    /// ([`crate::validation::sequential::pool`]); `most` where a rule stopped the patch's
    /// repeats on what they said ([`PatchReading::most`]).
    pub fn pooled(xyz: Xyz, cov: Cov3, n: usize, dof: usize, most: Option<usize>) -> PatchReading {
        PatchReading {
            dof: Some(dof),
            most,
            ..PatchReading::stated(xyz, cov, n, 0.0)
        }
    }

    /// Whether the row of this patch needs the `dof` or `most` column: its degrees of
    /// freedom are not those the reader takes without it.
    fn needs_rule_columns(&self) -> bool {
        let implied = (self.n > 1).then(|| self.n - 1);
        self.most.is_some() || (self.dof != implied && self.source == UncertaintySource::Given)
    }

    /// The mean and sample covariance of `readings` (at least one; one reading's
    /// covariance is 0: nothing is known of it).
    pub fn of(readings: &[Xyz]) -> PatchReading {
        let (xyz, cov) = covariance::sample(readings);
        PatchReading::stated(xyz, cov, readings.len(), 0.0)
    }

    /// One rendered reading, without scatter, with the render's CIELAB standard
    /// uncertainty `u_lab`.
    pub fn rendered(xyz: Xyz, u_lab: f64) -> PatchReading {
        let (xyz, cov) = covariance::sample(&[xyz]);
        PatchReading::stated(xyz, cov, 1, u_lab)
    }

    /// Instrument readings grouped by patch number, in the patches' order; a patch read
    /// once gets its instrument's stated repeatability where it has one.
    pub fn group(readings: &[(usize, &Reading)]) -> Vec<(usize, PatchReading)> {
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
                let xs: Vec<Xyz> = of_patch.iter().map(|r| r.xyz).collect();
                let (xyz, mut cov) = covariance::sample(&xs);
                if let [one] = of_patch.as_slice() {
                    if let Some(c) = repeatability::emissive_of(&one.instrument)
                        .and_then(|r| repeatability::covariance(&r, one.xyz))
                    {
                        cov = c;
                    }
                }
                (p, PatchReading::stated(xyz, cov, xs.len(), 0.0))
            })
            .collect()
    }

    /// The covariance of one reading: as stated, else the mean's times the readings
    /// averaged.
    pub fn reading_covariance(&self) -> Cov3 {
        self.reading_cov.unwrap_or_else(|| {
            covariance::scaled(&covariance::of_factors(&self.u_factors), self.n as f64)
        })
    }

    /// The standard deviations of one reading.
    pub fn reading_sd(&self) -> [f64; 3] {
        covariance::sd(&self.reading_covariance())
    }
}

/// Writes `patches` (patch number and reading, in this order) to `path` in the stages'
/// form, replacing the file: a stage's directory is its own.
pub fn write_readings(path: &Path, patches: &[(usize, PatchReading)]) -> Result<(), ReadingsError> {
    let rule_columns = patches.iter().any(|(_, p)| p.needs_rule_columns());
    let mut s = if rule_columns {
        format!("{HEADER},dof,most\n")
    } else {
        format!("{HEADER}\n")
    };
    let cell = |v: Option<usize>| v.map_or(String::new(), |v| v.to_string());
    for (patch, p) in patches {
        let cov = p.reading_covariance();
        let sd = covariance::sd(&cov);
        let off = covariance::off_diagonal(&cov);
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{}\n",
            patch,
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
        if rule_columns {
            s.insert_str(s.len() - 1, &format!(",{},{}", cell(p.dof), cell(p.most)));
        }
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| ReadingsError::Write {
            file: path.to_path_buf(),
            source,
        })?;
    }
    OutputPolicy::new(true)
        .write(path, s.as_bytes())
        .map_err(|source| ReadingsError::Output {
            file: path.to_path_buf(),
            source,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_sample_sd() {
        // X: 1, 2, 3 → mean 2, s = 1; Y constant → 0; Z 0, 0, 3: s = √3, cov XZ
        // ((−1)(−1) + 0 + (1)(2))/2 = 1.5.
        let s = PatchReading::of(&[
            Xyz::new(1.0, 5.0, 0.0),
            Xyz::new(2.0, 5.0, 0.0),
            Xyz::new(3.0, 5.0, 3.0),
        ]);
        assert_eq!(s.xyz, Xyz::new(2.0, 5.0, 1.0));
        assert!((s.reading_sd()[0] - 1.0).abs() < 1e-12);
        assert_eq!(s.reading_sd()[1], 0.0);
        assert!((s.reading_sd()[2] - 3f64.sqrt()).abs() < 1e-12);
        assert!((s.reading_covariance()[0][2] - 1.5).abs() < 1e-12);
        assert_eq!(s.n, 3);
        // The mean's uncertainty is one reading's over √3, with 2 degrees of freedom.
        assert!((s.u_xyz[0] - 1.0 / 3f64.sqrt()).abs() < 1e-12);
        assert_eq!((s.dof, s.source), (Some(2), UncertaintySource::Given));
    }

    /// One reading of a CS-100A carries its stated repeatability; two carry their scatter.
    #[test]
    fn a_single_reading_gets_the_instruments_repeatability() {
        let one = Reading::from_yxy(10.0, 0.45, 0.5, "cs100a");
        let two = Reading::from_yxy(10.1, 0.45, 0.5, "cs100a");
        let g = PatchReading::group(&[(16, &one), (17, &one), (17, &two)]);
        assert_eq!((g[0].0, g[1].0), (16, 17));
        // σY: 0.1 % of 10 and the last of four digits of 10.00 (0.01, variance 0.01²/12):
        // 0.01·√(1 + 1/12) = 0.010408.
        assert!(
            (g[0].1.reading_sd()[1] - 0.010_408_33).abs() < 1e-8,
            "{g:?}"
        );
        let stated =
            repeatability::covariance(&repeatability::emissive_of("cs100a").unwrap(), one.xyz)
                .unwrap();
        assert_eq!(g[0].1.reading_covariance(), stated);
        assert!(
            (g[1].1.reading_sd()[1] - 0.1 / 2f64.sqrt()).abs() < 1e-12,
            "{g:?}"
        );
        let unknown = Reading::from_yxy(10.0, 0.45, 0.5, "mystery");
        assert_eq!(
            PatchReading::group(&[(1, &unknown)])[0]
                .1
                .reading_covariance(),
            covariance::ZERO
        );
    }

    #[test]
    fn round_trip_and_errors() {
        let dir = std::env::temp_dir().join(format!("metamer-readings-{}", std::process::id()));
        let p = dir.join("r.csv");
        let stats = vec![
            (1, PatchReading::of(&[Xyz::new(0.1, 0.2, 0.3)])),
            (
                2,
                PatchReading::of(&[Xyz::new(1.0, 2.0, 3.0), Xyz::new(1.5, 2.5, 3.5)]),
            ),
        ];
        // The covariance's diagonal is written as standard deviations: back to within
        // rounding.
        let same = |a: &ReadingSet, b: &[(usize, PatchReading)]| {
            a.patches.len() == b.len()
                && a.patches.iter().zip(b).all(|((ka, a), (kb, b))| {
                    ka == kb
                        && a.xyz == b.xyz
                        && a.n == b.n
                        && a.reading_covariance()
                            .iter()
                            .flatten()
                            .zip(b.reading_covariance().iter().flatten())
                            .all(|(x, y)| (x - y).abs() <= 1e-15 * x.abs().max(1.0))
                })
        };
        write_readings(&p, &stats).unwrap();
        assert!(same(&read_readings(&p).unwrap(), &stats));
        std::fs::write(&p, format!("{HEADER}\n1,0,1,NaN,0,0,0,1,0,0,0,0\n")).unwrap();
        let e = read_readings(&p).unwrap_err().to_string();
        assert!(e.contains("r.csv:2:") && e.contains("Z: 'NaN'"), "{e}");
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
            assert!(e.contains("r.csv:2:"), "{row}: {e}");
        }
        // The earlier form without covariances reads, its axes independent.
        std::fs::write(&p, "patch,X,Y,Z,sd_X,sd_Y,sd_Z,n\n3,1,2,3,0.1,0.2,0.3,5\n").unwrap();
        let old = read_readings(&p).unwrap();
        assert_eq!(old.patches[&3].reading_sd(), [0.1, 0.2, 0.3]);
        assert_eq!(
            covariance::off_diagonal(&old.patches[&3].reading_covariance()),
            [0.0; 3]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A render's readings: no scatter, its CIELAB uncertainty written and read back as the
    /// render's.
    #[test]
    fn a_rendered_patch_carries_its_lab_uncertainty() {
        let r = PatchReading::rendered(Xyz::new(1.0, 2.0, 3.0), 0.25);
        assert_eq!((r.u_lab, r.source), (0.25, UncertaintySource::Render));
        let dir = std::env::temp_dir().join(format!("metamer-rendered-{}", std::process::id()));
        let p = dir.join("spots.csv");
        write_readings(&p, &[(4, r.clone())]).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(text, format!("{HEADER}\n4,1,2,3,0,0,0,1,0,0,0,0.25\n"));
        let back = read_readings(&p).unwrap();
        assert_eq!(back.patches[&4].u_lab, r.u_lab);
        assert_eq!(back.patches[&4].source, r.source);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
