//! What the export's writers share: the renderers, one written file, the emitter's tiles
//! as both renderers write them, and how numbers and wavelengths are printed.

use std::path::PathBuf;

use super::approximation::Approximation;
use crate::render::scene::Scene;

/// The renderers a scene can be exported to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Renderer {
    /// Mitsuba 3, a spectral variant (`scalar_spectral`).
    Mitsuba3,
    /// pbrt-v4 (spectral by construction).
    PbrtV4,
    /// Blender 4.2's Cycles through `bpy` (an RGB renderer).
    Blender,
}

impl Renderer {
    /// The name `--to` takes.
    pub fn name(self) -> &'static str {
        match self {
            Renderer::Mitsuba3 => "mitsuba3",
            Renderer::PbrtV4 => "pbrt-v4",
            Renderer::Blender => "blender",
        }
    }
}

/// One file of an export: its path inside the output directory and its text.
pub(crate) struct File {
    pub rel: PathBuf,
    pub text: String,
}

/// A number with every digit it has: Rust's shortest representation that reads back to
/// the same f64.
pub(crate) fn num(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 {
        format!("{x:.1}")
    } else {
        format!("{x:e}")
    }
}

/// A name as the text of a one-line comment: every control character (the line ends `\n`
/// and `\r` among them), Unicode's line and paragraph separators, the noncharacters
/// U+FFFE and U+FFFF and the backslash are written as Rust escapes (`\r`, `\u{2028}`,
/// `\\`), so a name can neither end the comment's line nor show as something it is not,
/// and the escape is read back unambiguously.
pub(crate) fn one_line(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if c.is_control()
            || c == '\\'
            || matches!(c, '\u{2028}' | '\u{2029}' | '\u{fffe}' | '\u{ffff}')
        {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// A name as text inside an XML comment (`<!-- … -->`): on one line ([`one_line`]), which
/// also leaves only characters XML 1.0 allows (its `Char` production excludes the C0
/// controls but tab and the line ends, and U+FFFE, U+FFFF), and with a space between any
/// two hyphens and after a last one, since a comment may not hold `--` nor end with `-`
/// (XML 1.0 §2.5): `-->` in a name cannot close the comment.
pub(crate) fn xml_comment(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in one_line(s).chars() {
        if c == '-' && out.ends_with('-') {
            out.push(' ');
        }
        out.push(c);
    }
    if out.ends_with('-') {
        out.push(' ');
    }
    out
}

/// The wavelength of bin `i` of the scene's 1 nm grid.
pub(crate) fn grid_nm(i: usize) -> f64 {
    (metamer_color::START_NM as usize + i) as f64
}

/// One emitter tile as both renderers write it: a rectangle radiating `radiance` (absolute,
/// W·sr⁻¹·m⁻²·nm⁻¹ on the 1 nm grid, the written gain included) from its front.
pub(crate) struct Tile<'a> {
    pub emitter: usize,
    pub row: usize,
    pub col: usize,
    pub corner: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    pub radiance: Vec<f64>,
    /// The emitter's own reflectance (what its tiles reflect of the box's light).
    pub reflectance: &'a [f64],
}

/// Every emitter's tiles, emitter by emitter, row by row.
pub(crate) fn tiles<'a>(scene: &'a Scene, approximation: &Approximation) -> Vec<Tile<'a>> {
    let mut out = Vec::new();
    for (i, e) in scene.emitters.iter().enumerate() {
        let (u, v) = (e.rect.edge_u / e.cols as f64, e.rect.edge_v / e.rows as f64);
        for row in 0..e.rows {
            for col in 0..e.cols {
                let t = row * e.cols + col;
                let gain = approximation.gains[i][t];
                out.push(Tile {
                    emitter: i,
                    row,
                    col,
                    corner: (e.rect.corner + u * col as f64 + v * row as f64).to_array(),
                    edge_u: u.to_array(),
                    edge_v: v.to_array(),
                    radiance: e.tile_spectrum(t).iter().map(|s| s * gain).collect(),
                    reflectance: &e.reflectance,
                });
            }
        }
    }
    out
}

/// The luminance (cd/m²) of a spectral radiance on the grid: 683 · Σ L · ȳ · 1 nm, the
/// scene's own definition (paper Eq. 8).
pub(crate) fn luminance(scene: &Scene, radiance: &[f64]) -> f64 {
    metamer_color::K_M
        * radiance
            .iter()
            .zip(&scene.cmf[1])
            .map(|(l, y)| l * y)
            .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_cannot_end_a_comment_line_or_an_xml_comment() {
        assert_eq!(one_line("a\rWorldEnd\nb\\r"), "a\\rWorldEnd\\nb\\\\r");
        assert_eq!(one_line("x\u{2028}y\u{1b}"), "x\\u{2028}y\\u{1b}");
        assert_eq!(one_line("<&\"é>"), "<&\"é>");
        assert_eq!(xml_comment("a-->b"), "a- ->b");
        assert_eq!(xml_comment("---"), "- - - ");
        assert_eq!(xml_comment("-a-"), "-a- ");
        assert!(!xml_comment("x\r\n--\u{ffff}-").contains("--"));
    }
}
