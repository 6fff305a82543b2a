//! From relative luminance to candela and lumen: a flat panel of area A and normal
//! luminance L₀ sends I(C, γ) = L₀·A·f(C, γ)·cos γ into the direction (C, γ), and its
//! luminous flux is Φ = ∫ I dΩ over the hemisphere in front of it.

use std::f64::consts::PI;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::cgamma::CGammaTable;

/// A flat rectangular emitter: `width_m` along its `edge_u` (the C0–C180 axis),
/// `height_m` along `edge_v` (the C90–C270 axis), luminance along the normal in cd/m².
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Panel {
    pub width_m: f64,
    pub height_m: f64,
    pub normal_luminance_cd_m2: f64,
}

/// Largest panel side, metres.
pub const MAX_PANEL_M: f64 = 1000.0;

/// Why a panel, or a photometric file, cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum PhotometryError {
    #[error("panel {what} must be a positive number of at most {max:e} {unit}, got {value:?}")]
    BadPanel {
        what: &'static str,
        value: f64,
        max: f64,
        unit: &'static str,
    },
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}:{line}: {message}")]
    Format {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{file}: {message}")]
    Content { file: PathBuf, message: String },
}

impl Panel {
    /// A panel with every dimension and the luminance checked positive and finite.
    pub fn new(
        width_m: f64,
        height_m: f64,
        normal_luminance_cd_m2: f64,
    ) -> Result<Panel, PhotometryError> {
        // A kilometre-wide panel or one brighter than the sun's disc is a typo; past them
        // the photometry overflows into tables of 300-digit candela.
        for (what, value, max, unit) in [
            ("width", width_m, MAX_PANEL_M, "m"),
            ("height", height_m, MAX_PANEL_M, "m"),
            (
                "normal luminance",
                normal_luminance_cd_m2,
                metamer_color::MAX_CD_M2,
                "cd/m²",
            ),
        ] {
            if !(value > 0.0 && value <= max) {
                return Err(PhotometryError::BadPanel {
                    what,
                    value,
                    max,
                    unit,
                });
            }
        }
        Ok(Panel {
            width_m,
            height_m,
            normal_luminance_cd_m2,
        })
    }

    pub fn area_m2(&self) -> f64 {
        self.width_m * self.height_m
    }

    /// Luminous intensity along the normal, cd.
    pub fn normal_intensity_cd(&self) -> f64 {
        self.normal_luminance_cd_m2 * self.area_m2()
    }

    /// I(C, γ) in cd.
    pub fn intensity_cd(&self, table: &CGammaTable, c_deg: f64, gamma_deg: f64) -> f64 {
        self.normal_intensity_cd()
            * table.at(c_deg, gamma_deg)
            * gamma_deg.to_radians().cos().max(0.0)
    }
}

/// Φ = ∫ I dΩ in lm for `panel` emitting with the distribution `table`.
pub fn flux_lm(table: &CGammaTable, panel: &Panel) -> f64 {
    panel.normal_intensity_cd() * projected_solid_angle(table)
}

/// The part of [`flux_lm`] emitted at γ above `gamma_deg` (lm), with the same exact
/// quadrature: what an extrapolation past the last reading contributes.
pub fn flux_beyond_lm(table: &CGammaTable, panel: &Panel, gamma_deg: f64) -> f64 {
    panel.normal_intensity_cd() * projected_solid_angle_from(table, gamma_deg)
}

/// ∫ f(C, γ)·cos γ dΩ over the hemisphere, in sr (π for a Lambertian table).
///
/// The quadrature is exact for the table as it is evaluated: f is linear in γ between the
/// table's angles, so each γ interval is integrated against cos γ·sin γ in closed form, and
/// linear in C between planes (periodically), so the planes get trapezoid weights.
pub fn projected_solid_angle(table: &CGammaTable) -> f64 {
    projected_solid_angle_from(table, 0.0)
}

/// [`projected_solid_angle`] over γ ≥ `from_deg` only.
fn projected_solid_angle_from(table: &CGammaTable, from_deg: f64) -> f64 {
    let planes = table.c_deg();
    let weights: Vec<f64> = if planes.len() == 1 {
        vec![2.0 * PI]
    } else {
        let n = planes.len();
        (0..n)
            .map(|i| {
                let prev = (planes[i] - planes[(i + n - 1) % n]).rem_euclid(360.0);
                let next = (planes[(i + 1) % n] - planes[i]).rem_euclid(360.0);
                (prev + next).to_radians() / 2.0
            })
            .collect()
    };
    let g: Vec<f64> = table.gamma_deg().iter().map(|x| x.to_radians()).collect();
    weights
        .iter()
        .zip(table.values())
        .map(|(w, row)| w * profile_integral(&g, row, from_deg.to_radians()))
        .sum()
}

/// ∫ f(γ)·cos γ·sin γ dγ over γ ≥ `from` (radians) for f linear between (g[k], row[k]).
fn profile_integral(g: &[f64], row: &[f64], from: f64) -> f64 {
    // With w = sin 2γ / 2: ∫w = −cos 2γ / 4 and ∫γ·w = −γ·cos 2γ / 4 + sin 2γ / 8.
    let w0 = |x: f64| -(2.0 * x).cos() / 4.0;
    let w1 = |x: f64| -x * (2.0 * x).cos() / 4.0 + (2.0 * x).sin() / 8.0;
    let mut total = 0.0;
    for k in 1..g.len() {
        let (a, b) = (g[k - 1], g[k]);
        if b <= from {
            continue;
        }
        let (fa, fb) = (row[k - 1], row[k]);
        let slope = (fb - fa) / (b - a);
        // f = fa + slope·(γ − a), integrated from where the range starts.
        let start = a.max(from);
        total += (fa - slope * a) * (w0(b) - w0(start)) + slope * (w1(b) - w1(start));
    }
    total
}

/// What a photometric file says besides its distribution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Photometry {
    /// "IES LM-63-2019" (or the version the file names) or "EULUMDAT".
    pub format: String,
    /// Luminous opening along the C0–C180 and C90–C270 axes, m (0 when the file gives none).
    pub width_m: f64,
    pub height_m: f64,
    /// The opening's area, m² (a circle or ellipse where the file says so; 0 when none).
    pub area_m2: f64,
    /// Intensity along the normal, cd (the mean over the file's C-planes).
    pub normal_intensity_cd: f64,
    pub min_intensity_cd: f64,
    pub max_intensity_cd: f64,
    /// Φ = ∫ I dΩ over the front hemisphere, lm.
    pub flux_lm: f64,
    /// The C-planes the file stores and how it said they extend to 360°.
    pub stored_planes: usize,
    pub symmetry: String,
    /// Intensity the file has behind the panel (γ > 90°), cd; a flat emitter has none and
    /// it is left out of the distribution.
    pub max_backward_cd: f64,
    /// The file's descriptive lines (IES keywords such as `MANUFAC`, EULUMDAT's company,
    /// luminaire name, …), in the file's order.
    #[serde(default)]
    pub labels: Vec<(String, String)>,
    /// The encoding the text was read in when it was not UTF-8 ("Windows-1252").
    #[serde(default)]
    pub text_encoding: Option<String>,
}

impl Photometry {
    /// L₀ = I₀ / A, when the file gives the opening's size.
    pub fn normal_luminance_cd_m2(&self) -> Option<f64> {
        (self.area_m2 > 0.0).then(|| self.normal_intensity_cd / self.area_m2)
    }
}

/// A photometric file's bytes as text, and the name of the encoding when it was not UTF-8.
///
/// LM-63 asks for ASCII and EULUMDAT names none, but files from lighting tools carry
/// manufacturer and luminaire names in the Windows code page ("Müller", a no-break space
/// 0xA0). Numbers are ASCII in every one of these encodings, so only the labels depend on
/// the choice. Bytes that are not UTF-8 are read as Windows-1252: Latin-1 (each byte its
/// own code point) except 0x80–0x9F, which hold the printable characters of the mapping
/// table `cp1252.txt` published by Unicode (and WHATWG's `index-windows-1252`); its five
/// unassigned bytes keep their Latin-1 code points, as WHATWG's decoder does.
pub fn decode_text(bytes: &[u8]) -> (String, Option<&'static str>) {
    if let Ok(text) = std::str::from_utf8(bytes) {
        return (text.to_string(), None);
    }
    const HIGH: [u16; 32] = [
        0x20AC, 0x0081, 0x201A, 0x0192, 0x201E, 0x2026, 0x2020, 0x2021, 0x02C6, 0x2030, 0x0160,
        0x2039, 0x0152, 0x008D, 0x017D, 0x008F, 0x0090, 0x2018, 0x2019, 0x201C, 0x201D, 0x2022,
        0x2013, 0x2014, 0x02DC, 0x2122, 0x0161, 0x203A, 0x0153, 0x009D, 0x017E, 0x0178,
    ];
    let text = bytes
        .iter()
        .map(|&b| match b {
            0x80..=0x9F => char::from_u32(u32::from(HIGH[usize::from(b - 0x80)]))
                .unwrap_or(char::REPLACEMENT_CHARACTER),
            _ => char::from(b),
        })
        .collect();
    (text, Some("Windows-1252"))
}

/// Candela on a grid (C-planes × γ from 0 to 90°, full circle of C) to a relative table:
/// each plane divided by its own value along the normal and by cos γ. At γ = 90° the
/// luminance is undefined (I = 0 there), so it is extrapolated linearly from the last two
/// angles, clamped at 0.
pub(crate) fn candela_to_table(
    c_deg: Vec<f64>,
    gamma_deg: Vec<f64>,
    candela: &[Vec<f64>],
) -> Result<(CGammaTable, f64), String> {
    let mut i0_sum = 0.0;
    let mut values = Vec::with_capacity(candela.len());
    for (plane, row) in c_deg.iter().zip(candela) {
        let i0 = row[0];
        if i0.is_nan() || i0 <= 0.0 {
            return Err(format!(
                "C-plane {plane}°: intensity {i0} cd along the normal; a distribution relative to it needs it > 0"
            ));
        }
        i0_sum += i0;
        let mut f: Vec<f64> = row
            .iter()
            .zip(&gamma_deg)
            .map(|(i, g)| {
                let c = g.to_radians().cos();
                if *g >= 90.0 || c <= 0.0 {
                    f64::NAN
                } else {
                    i / (i0 * c)
                }
            })
            .collect();
        let n = f.len();
        if f[n - 1].is_nan() {
            f[n - 1] = if n >= 3 {
                let (g1, g2, g3) = (gamma_deg[n - 3], gamma_deg[n - 2], gamma_deg[n - 1]);
                let t = (g3 - g2) / (g2 - g1);
                (f[n - 2] + t * (f[n - 2] - f[n - 3])).max(0.0)
            } else {
                f[n - 2]
            };
        }
        f[0] = 1.0;
        values.push(f);
    }
    let i0 = i0_sum / c_deg.len() as f64;
    let table = CGammaTable::new(c_deg, gamma_deg, values).map_err(|e| e.to_string())?;
    Ok((table, i0))
}

/// The table's candela on its own grid, for the writers.
pub(crate) fn candela_grid(table: &CGammaTable, panel: &Panel) -> Vec<Vec<f64>> {
    table
        .c_deg()
        .iter()
        .map(|&c| {
            table
                .gamma_deg()
                .iter()
                .map(|&g| panel.intensity_cd(table, c, g))
                .collect()
        })
        .collect()
}

/// C-planes a file stores, mirrored by its symmetry into the full circle: each stored
/// plane at C also stands for every `mirror(C)` the file does not store itself. Sorted,
/// within [0°, 360°), 360° folded onto 0°.
pub(crate) fn mirror_planes(
    stored: Vec<(f64, Vec<f64>)>,
    mirrors: &[fn(f64) -> f64],
) -> Vec<(f64, Vec<f64>)> {
    let norm = |c: f64| {
        let c = c.rem_euclid(360.0);
        if (c - 360.0).abs() < 1e-9 {
            0.0
        } else {
            c
        }
    };
    let mut out: Vec<(f64, Vec<f64>)> = Vec::new();
    let has = |out: &Vec<(f64, Vec<f64>)>, c: f64| out.iter().any(|(x, _)| (x - c).abs() < 1e-9);
    for (c, row) in &stored {
        let c = norm(*c);
        if !has(&out, c) {
            out.push((c, row.clone()));
        }
    }
    for (c, row) in &stored {
        for m in mirrors {
            let c2 = norm(m(*c));
            if !has(&out, c2) {
                out.push((c2, row.clone()));
            }
        }
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// The opening of a file, as the readers hand it to [`finish`].
pub(crate) struct Opening {
    pub width_m: f64,
    pub height_m: f64,
    pub area_m2: f64,
}

/// A file's full-circle candela grid to the front-hemisphere table and its summary.
/// Errors are messages; the reader adds the file.
pub(crate) fn finish(
    format: String,
    symmetry: String,
    stored_planes: usize,
    opening: Opening,
    planes: Vec<(f64, Vec<f64>)>,
    gamma_deg: &[f64],
) -> Result<(CGammaTable, Photometry), String> {
    // A file may state any number; what it says must still be a usable opening.
    for (what, v) in [
        ("width", opening.width_m),
        ("height", opening.height_m),
        ("area", opening.area_m2),
    ] {
        if !v.is_finite() {
            return Err(format!(
                "the luminous opening's {what} is {v}, not a finite size"
            ));
        }
    }
    if gamma_deg.first() != Some(&0.0) {
        return Err(format!(
            "the γ angles start at {}°: a flat emitter's distribution needs γ from 0° (its normal)",
            gamma_deg.first().copied().unwrap_or(f64::NAN)
        ));
    }
    if let Some(w) = gamma_deg.windows(2).find(|w| w[1].is_nan() || w[1] <= w[0]) {
        return Err(format!(
            "the γ angles must increase: {}° then {}°",
            w[0], w[1]
        ));
    }
    let last = gamma_deg[gamma_deg.len() - 1];
    if last < 90.0 {
        return Err(format!(
            "the γ angles end at {last}°: the front hemisphere needs them up to 90°"
        ));
    }
    let front = gamma_deg.partition_point(|&g| g < 90.0);
    let mut gammas: Vec<f64> = gamma_deg[..front].to_vec();
    gammas.push(90.0);
    let mut c_deg = Vec::with_capacity(planes.len());
    let mut candela = Vec::with_capacity(planes.len());
    let (mut lo, mut hi, mut back) = (f64::INFINITY, 0.0f64, 0.0f64);
    for (c, row) in planes {
        if let Some(v) = row.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!(
                "C-plane {c}°: intensity {v} must be finite and ≥ 0"
            ));
        }
        let mut r: Vec<f64> = row[..front].to_vec();
        let at90 = if gamma_deg[front] == 90.0 {
            row[front]
        } else {
            let (g0, g1) = (gamma_deg[front - 1], gamma_deg[front]);
            let t = (90.0 - g0) / (g1 - g0);
            (1.0 - t) * row[front - 1] + t * row[front]
        };
        r.push(at90);
        for &v in &r {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        for (g, &v) in gamma_deg.iter().zip(&row) {
            if *g > 90.0 {
                back = back.max(v);
            }
        }
        c_deg.push(c);
        candela.push(r);
    }
    let (table, i0) = candela_to_table(c_deg, gammas, &candela)?;
    let flux_lm = i0 * projected_solid_angle(&table);
    // Finite intensities can still sum past the largest number (1e308 cd in a file).
    if !(i0.is_finite() && flux_lm.is_finite()) {
        return Err(format!(
            "the intensities are too large to use: the intensity along the normal is {i0} cd, \
             the flux {flux_lm} lm"
        ));
    }
    let photometry = Photometry {
        format,
        width_m: opening.width_m,
        height_m: opening.height_m,
        area_m2: opening.area_m2,
        normal_intensity_cd: i0,
        min_intensity_cd: lo,
        max_intensity_cd: hi,
        flux_lm,
        stored_planes,
        symmetry,
        max_backward_cd: back,
        labels: Vec::new(),
        text_encoding: None,
    };
    Ok((table, photometry))
}

/// `v` with `digits` significant digits in plain decimal notation (what lighting tools
/// read), without trailing zeros.
pub(crate) fn format_sig(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    let decimals = (digits - 1 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambertian_flux_is_pi_l_a() {
        let t = CGammaTable::symmetric(vec![0.0, 30.0, 90.0], vec![1.0, 1.0, 1.0]).unwrap();
        let p = Panel::new(0.3, 0.2, 100.0).unwrap();
        let want = PI * 100.0 * 0.06;
        assert!((flux_lm(&t, &p) - want).abs() < 1e-12 * want);
    }

    #[test]
    fn linear_profile_is_integrated_exactly() {
        // f = 1 − γ/(π/2) on one interval: ∫ (1 − 2γ/π) cos γ sin γ dγ = 1/2 − 2/π · π/8 = 1/4.
        let t = CGammaTable::symmetric(vec![0.0, 90.0], vec![1.0, 0.0]).unwrap();
        assert!((projected_solid_angle(&t) - 2.0 * PI * 0.25).abs() < 1e-12);
        // Four planes, two of them Lambertian and two linear: trapezoid in C gives the mean.
        let t = CGammaTable::new(
            vec![0.0, 90.0, 180.0, 270.0],
            vec![0.0, 90.0],
            vec![
                vec![1.0, 1.0],
                vec![1.0, 0.0],
                vec![1.0, 1.0],
                vec![1.0, 0.0],
            ],
        )
        .unwrap();
        let want = 2.0 * PI * (0.5 + 0.25) / 2.0;
        assert!((projected_solid_angle(&t) - want).abs() < 1e-12);
    }

    #[test]
    fn rejects_bad_panels() {
        assert!(Panel::new(0.0, 1.0, 1.0).is_err());
        assert!(Panel::new(1.0, f64::NAN, 1.0).is_err());
        assert!(Panel::new(1.0, 1.0, -3.0).is_err());
        // Once accepted: the IES table of such a panel held 300-digit candela.
        let e = Panel::new(0.3, 0.3, 1e308).unwrap_err().to_string();
        assert_eq!(
            e,
            "panel normal luminance must be a positive number of at most 1e10 cd/m², got 1e308"
        );
        assert!(Panel::new(1e308, 0.3, 100.0).is_err());
        assert!(Panel::new(1000.0, 1000.0, 1e10).is_ok());
    }
}
