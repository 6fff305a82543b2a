//! EULUMDAT (.ldt) photometric files, the European format.
//!
//! The layout (sources in `src/light/README.md`) is one field per line: company, type
//! indicator Ityp, symmetry indicator Isym, number of C-planes Mc and their spacing Dc,
//! number of γ angles Ng and their spacing Dg, report number, luminaire name and number,
//! file name, date/user, the luminaire's length, width and height and the luminous area's
//! length, width and heights at C0/C90/C180/C270 (mm), downward flux fraction and light
//! output ratio (%), the intensity conversion factor, the tilt, the number n of lamp sets
//! and, for each field in turn, n lines of lamp counts, lamp types, lamp fluxes (lm),
//! colour temperatures, colour rendering and wattages; then ten direct ratios, the Mc
//! C angles, the Ng γ angles and the intensities in cd per 1000 lm of lamp flux, one C-plane
//! after another. Isym says which planes are stored: 0 all Mc, 1 one (rotational
//! symmetry), 2 C0…C180 (mirror about C0–C180), 3 C90…C270 (mirror about C90–C270), 4
//! C0…C90 (both mirrors). Decimal commas are read as points.
//!
//! Written files store every plane (Isym 0, or 1 for a rotationally symmetric table), one
//! lamp set of 1 lamp whose flux is the panel's flux, so the cd/klm values times that flux
//! are the absolute candela, and a light output ratio of 100 %. The ten direct ratios
//! (utilisation factors for standard rooms) are not computed and written as 0. The
//! luminous area's length is along C90–C270 (the panel's `height_m`), its width along
//! C0–C180 (`width_m`); the reader uses only their product, the area.

use std::path::Path;

use metamer_color::text::{echo, strip_bom};

use super::cgamma::CGammaTable;
use super::fit::Extrapolation;
use super::numbers::{tokens, Numbers};
use super::photometry::{
    candela_grid, decode_text, finish, flux_lm, format_sig, mirror_planes, Opening, Panel,
    Photometry, PhotometryError,
};

/// Text for the descriptive lines of a written file.
#[derive(Clone, Debug)]
pub struct LdtInfo {
    pub luminaire: String,
    /// Line 11, the file's own name.
    pub file_name: String,
    /// Line 12, date and user.
    pub date_user: String,
    /// Where the table is extrapolated past the readings: said in line 8, the measurement
    /// report, the one line about how the data were obtained.
    pub extrapolation: Option<Extrapolation>,
}

/// The EULUMDAT text of `table` for `panel`.
pub fn to_string(table: &CGammaTable, panel: &Panel, info: &LdtInfo) -> String {
    let flux = flux_lm(table, panel);
    let c = table.c_deg();
    let g = table.gamma_deg();
    let symmetric = c.len() == 1;
    let dc = if symmetric { 0.0 } else { c[1] - c[0] };
    let dg = if g
        .windows(2)
        .all(|w| (w[1] - w[0] - (g[1] - g[0])).abs() < 1e-9)
    {
        g[1] - g[0]
    } else {
        0.0
    };
    let mm = |m: f64| format_sig(m * 1000.0, 6);
    // EULUMDAT's text lines hold at most 78 characters.
    let text = |s: &str| {
        s.replace(['\r', '\n'], " ")
            .chars()
            .take(78)
            .collect::<String>()
    };
    let mut lines: Vec<String> = vec![
        "metamer".into(),
        if symmetric { "1" } else { "3" }.into(),
        if symmetric { "1" } else { "0" }.into(),
        c.len().to_string(),
        format_sig(dc, 8),
        g.len().to_string(),
        format_sig(dg, 8),
        text(&report_line(info.extrapolation.as_ref())),
        text(&info.luminaire),
        "-".into(),
        text(&info.file_name),
        text(&info.date_user),
        mm(panel.height_m),
        mm(panel.width_m),
        "0".into(),
        mm(panel.height_m),
        mm(panel.width_m),
        "0".into(),
        "0".into(),
        "0".into(),
        "0".into(),
        "100".into(),
        "100".into(),
        "1".into(),
        "0".into(),
        "1".into(),
        "1".into(),
        "flat panel".into(),
        format_sig(flux, 8),
        "-".into(),
        "-".into(),
        "0".into(),
    ];
    lines.extend(std::iter::repeat_n("0".to_string(), 10));
    lines.extend(c.iter().map(|x| format_sig(*x, 8)));
    lines.extend(g.iter().map(|x| format_sig(*x, 8)));
    for row in candela_grid(table, panel) {
        lines.extend(row.iter().map(|v| format_sig(v * 1000.0 / flux, 7)));
    }
    let mut out = lines.join("\r\n");
    out.push_str("\r\n");
    out
}

/// Line 8, the measurement report: a fit, and where it is extrapolated (at most 78
/// characters whatever the model's name: the longest is 10).
fn report_line(e: Option<&Extrapolation>) -> String {
    match e {
        None => "fitted light distribution".into(),
        Some(e) => format!(
            "fit of readings to gamma {} deg; above, extrapolated by the {} model",
            e.beyond_deg, e.model
        ),
    }
}

/// Reads an EULUMDAT file: the distribution as a C-γ table and its photometry.
pub fn read(path: &Path) -> Result<(CGammaTable, Photometry), PhotometryError> {
    let bytes = metamer_color::text::read_bytes(path).map_err(|source| PhotometryError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    // Files from Windows tools are often in its code page: see `decode_text`.
    let (text, encoding) = decode_text(&bytes);
    let (table, mut photometry) = parse(&text, path)?;
    photometry.text_encoding = encoding.map(String::from);
    Ok((table, photometry))
}

/// [`read`] on text; `source` names the file in errors.
pub fn parse(text: &str, source: &Path) -> Result<(CGammaTable, Photometry), PhotometryError> {
    let lines: Vec<&str> = strip_bom(text).lines().collect();
    let header = Header::read(&HeaderLines {
        lines: &lines,
        source,
    })?;
    let data_start = 27 + 6 * header.sets;
    let rest = lines.get(data_start - 1..).unwrap_or(&[]).join("\n");
    let toks = tokens_decimal_comma(&rest, data_start);
    let mut values = Numbers::new(toks, source, lines.len().max(1));
    for _ in 0..10 {
        values.next("the direct ratios")?;
    }
    let c_angles = c_angles(&mut values, header.mc)?;
    let (_, gammas) = values.take(header.ng, "the γ angles")?;
    let stored = StoredPlanes::of(&values, &header, &c_angles)?;
    let planes = intensities(&mut values, &header, &stored, &c_angles)?;
    let (table, mut photometry) = finish(
        "EULUMDAT".into(),
        stored.symmetry.into(),
        stored.count,
        header.opening(),
        planes,
        &gammas,
    )
    .map_err(|message| PhotometryError::Content {
        file: source.to_path_buf(),
        message,
    })?;
    photometry.labels = labels(&lines);
    Ok((table, photometry))
}

/// The header's lines, one field each, read by line number (1-based, as the format counts).
struct HeaderLines<'a> {
    lines: &'a [&'a str],
    source: &'a Path,
}

impl HeaderLines<'_> {
    fn error(&self, line: usize, message: String) -> PhotometryError {
        PhotometryError::Format {
            file: self.source.to_path_buf(),
            line,
            message,
        }
    }

    fn line(&self, k: usize) -> Result<&str, PhotometryError> {
        let n = self.lines.len();
        self.lines.get(k - 1).copied().ok_or_else(|| {
            self.error(
                n.max(1),
                format!("the file ends at line {n}, before line {k} of the header"),
            )
        })
    }

    fn number(&self, k: usize, what: &str) -> Result<f64, PhotometryError> {
        let raw = self.line(k)?.trim();
        raw.replace(',', ".")
            .parse::<f64>()
            .map_err(|_| self.error(k, format!("{what}: '{}' is not a number", echo(raw))))
    }

    fn count(&self, k: usize, what: &str) -> Result<usize, PhotometryError> {
        let v = self.number(k, what)?;
        if v >= 0.0 && v.fract() == 0.0 {
            Ok(v as usize)
        } else {
            Err(self.error(k, format!("{what} {v} is not a count")))
        }
    }
}

/// The header fields the distribution needs.
struct Header {
    /// The symmetry indicator Isym.
    isym: usize,
    /// The number of C-planes Mc.
    mc: usize,
    /// The number of γ angles Ng.
    ng: usize,
    length_mm: f64,
    width_mm: f64,
    /// The intensity conversion factor.
    conversion: f64,
    /// The number of lamp sets.
    sets: usize,
    /// The lamp sets' flux, lm.
    total_flux: f64,
}

impl Header {
    fn read(h: &HeaderLines) -> Result<Header, PhotometryError> {
        let isym = h.count(3, "the symmetry indicator Isym")?;
        let mc = h.count(4, "the number of C-planes Mc")?;
        let ng = h.count(6, "the number of γ angles Ng")?;
        if ng < 2 {
            return Err(h.error(
                6,
                format!("Ng = {ng}: a distribution needs at least 2 γ angles"),
            ));
        }
        let length_mm = h.number(16, "the luminous area's length")?;
        let width_mm = h.number(17, "the luminous area's width")?;
        let conversion = h.number(24, "the intensity conversion factor")?;
        let sets = h.count(26, "the number of lamp sets")?;
        let total_flux = lamp_flux(h, sets)?;
        Ok(Header {
            isym,
            mc,
            ng,
            length_mm,
            width_mm,
            conversion,
            sets,
            total_flux,
        })
    }

    /// The luminous area in metres.
    fn opening(&self) -> Opening {
        let (l, w) = (self.length_mm / 1000.0, self.width_mm / 1000.0);
        // A width of 0 marks a round luminous area whose length is its diameter.
        let area = if w == 0.0 {
            std::f64::consts::PI / 4.0 * l * l
        } else {
            l * w
        };
        Opening {
            width_m: if w == 0.0 { l } else { w },
            height_m: l,
            area_m2: area.abs(),
        }
    }
}

/// The total flux of the `sets` lamp sets, lm.
fn lamp_flux(h: &HeaderLines, sets: usize) -> Result<f64, PhotometryError> {
    if sets == 0 {
        return Err(h.error(
            26,
            "no lamp sets: the cd/klm values cannot be scaled to candela".into(),
        ));
    }
    // Six lines per lamp set follow: a count the file cannot hold is a corrupt header (and
    // must not overflow the line arithmetic below).
    if sets > h.lines.len() {
        return Err(h.error(
            26,
            format!(
                "{sets} lamp sets need {} more lines, but the file has {} lines",
                sets.saturating_mul(6),
                h.lines.len()
            ),
        ));
    }
    // Lines 27 … 26 + 6n: lamp counts, types, fluxes, colours, colour rendering, wattages.
    let mut total_flux = 0.0;
    for k in 0..sets {
        let line = 27 + 2 * sets + k;
        total_flux += h.number(line, "a lamp set's luminous flux")?.abs();
    }
    if total_flux.is_nan() || total_flux <= 0.0 {
        return Err(h.error(27 + 2 * sets, "the lamps' luminous flux is 0".into()));
    }
    Ok(total_flux)
}

/// The `mc` C angles, which must increase.
fn c_angles(values: &mut Numbers, mc: usize) -> Result<Vec<f64>, PhotometryError> {
    let c_at: Vec<(usize, f64)> = (0..mc)
        .map(|_| values.next("the C angles"))
        .collect::<Result<_, _>>()?;
    // A plane listed twice (or out of order) would be dropped or mirrored over another
    // one's data without a word.
    if let Some(w) = c_at
        .windows(2)
        .find(|w| w[1].1.partial_cmp(&w[0].1) != Some(std::cmp::Ordering::Greater))
    {
        return Err(values.error(
            w[1].0,
            format!(
                "the C angles must increase: C{}° then C{}° (a plane listed twice, or out of \
                 order)",
                w[0].1, w[1].1
            ),
        ));
    }
    Ok(c_at.iter().map(|c| c.1).collect())
}

/// Which C-planes Isym says the file stores, and how they mirror into the full circle.
struct StoredPlanes {
    /// Index of the first stored plane among the C angles.
    first: usize,
    count: usize,
    symmetry: &'static str,
    mirrors: Vec<fn(f64) -> f64>,
}

impl StoredPlanes {
    fn of(values: &Numbers, header: &Header, c_angles: &[f64]) -> Result<Self, PhotometryError> {
        let (isym, mc) = (header.isym, header.mc);
        type Mirror = fn(f64) -> f64;
        let (first, count, symmetry, mirrors): (usize, usize, &str, Vec<Mirror>) = match isym {
            0 => (0, mc, "none", vec![]),
            1 => (0, 1, "rotationally symmetric", vec![]),
            2 => (
                0,
                mc / 2 + 1,
                "symmetric about the C0–C180 plane",
                vec![|c| 360.0 - c],
            ),
            3 => {
                let start = c_angles.iter().position(|&c| c >= 90.0).unwrap_or(0);
                (
                    start,
                    mc / 2 + 1,
                    "symmetric about the C90–C270 plane",
                    vec![|c| 180.0 - c],
                )
            }
            4 => (
                0,
                mc / 4 + 1,
                "symmetric about C0–C180 and C90–C270",
                vec![|c| 180.0 - c, |c| 180.0 + c, |c| 360.0 - c],
            ),
            _ => {
                return Err(values.error(
                    3,
                    format!("symmetry indicator Isym = {isym}: expected 0 to 4"),
                ));
            }
        };
        if isym != 1 && first + count > mc {
            return Err(values.error(
                4,
                format!("Mc = {mc} C-planes cannot hold the {count} planes Isym = {isym} stores"),
            ));
        }
        Ok(StoredPlanes {
            first,
            count,
            symmetry,
            mirrors,
        })
    }
}

/// The stored planes' intensities in candela, mirrored into the full circle.
fn intensities(
    values: &mut Numbers,
    header: &Header,
    stored: &StoredPlanes,
    c_angles: &[f64],
) -> Result<Vec<(f64, Vec<f64>)>, PhotometryError> {
    let rotational = header.isym == 1;
    let scale = header.conversion * header.total_flux / 1000.0;
    let mut planes = Vec::with_capacity(stored.count);
    for k in 0..stored.count {
        let c = if rotational {
            0.0
        } else {
            c_angles[stored.first + k]
        };
        let what = format!("the intensities of C-plane {c}°");
        let row: Vec<f64> = (0..header.ng)
            .map(|_| values.value(&what).map(|v| v * scale))
            .collect::<Result<_, _>>()?;
        planes.push((c, row));
    }
    Ok(if rotational {
        planes
    } else {
        mirror_planes(planes, &stored.mirrors)
    })
}

/// The header's descriptive lines that are not blank.
fn labels(lines: &[&str]) -> Vec<(String, String)> {
    [
        (1, "company"),
        (8, "report"),
        (9, "luminaire"),
        (10, "number"),
        (11, "file name"),
        (12, "date/user"),
    ]
    .iter()
    .filter_map(|&(k, name)| {
        let t = lines.get(k - 1)?.trim();
        (!t.is_empty()).then(|| (name.to_string(), echo(t)))
    })
    .collect()
}

/// Tokens of the numeric block with decimal commas read as points (EULUMDAT separates
/// values by line breaks or blanks, never by commas).
fn tokens_decimal_comma(text: &str, first_line: usize) -> Vec<(usize, String)> {
    let t = text.replace(',', ".");
    tokens(&t, first_line)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A C0–C180-symmetric file by hand: Mc = 4 (Dc 90), Ng = 3 (0, 45, 90), one lamp set
    /// of 2000 lm, 1 lamp; intensities 500/353.55339/0 cd/klm in C0, 400/… in C90,
    /// 300/… in C180, i.e. I₀ = 1000 cd in every plane (different fall-offs).
    fn file(isym: u8) -> String {
        let mut l: Vec<String> = vec![
            "company", "3", "", "4", "90", "3", "45", "r", "n", "no", "f", "d", "600", "300", "0",
            "600", "300", "0", "0", "0", "0", "100", "100", "1,0", "0", "1", "1", "led", "2000",
            "-", "-", "10",
        ]
        .into_iter()
        .map(String::from)
        .collect();
        l[2] = isym.to_string();
        l.push("0 0 0 0 0 0 0 0 0 0".into());
        l.push("0 90 180 270".into());
        l.push("0 45 90".into());
        l.push("500 353,55339 0 500 282,84271".into());
        l.push("0 500 212,13203 0".into());
        l.join("\n")
    }

    #[test]
    fn expands_plane_symmetry_and_reads_decimal_commas() {
        let (t, p) = parse(&file(2), Path::new("a.ldt")).unwrap();
        assert_eq!(t.c_deg(), &[0.0, 90.0, 180.0, 270.0]);
        assert!((p.normal_intensity_cd - 1000.0).abs() < 1e-9);
        // f(45°) = I / (I₀ cos 45°): 1.0, 0.8, 0.6 in C0, C90, C180, and C270 mirrors C90.
        for (c, want) in [(0.0, 1.0), (90.0, 0.8), (180.0, 0.6), (270.0, 0.8)] {
            assert!(
                (t.at(c, 45.0) - want).abs() < 1e-7,
                "C{c}: {}",
                t.at(c, 45.0)
            );
        }
        assert!((p.area_m2 - 0.18).abs() < 1e-12);
        assert_eq!(p.stored_planes, 3);
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let e = parse(&file(7), Path::new("b.ldt")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "b.ldt:3: symmetry indicator Isym = 7: expected 0 to 4"
        );
        let e = parse("x\n1\n0\n", Path::new("c.ldt")).unwrap_err();
        assert!(e.to_string().starts_with("c.ldt:3: the file ends"), "{e}");
    }
}
