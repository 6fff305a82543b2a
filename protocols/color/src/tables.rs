//! Data tables compiled into the binary from `data/`, so no file is needed at run time.
//! Each CSV keeps its provenance comment (CIE tables via colour-science 0.4.7; the
//! ColorChecker sets as named in their files; the paper-white reflectance is defined by
//! this project's validation-box contract).

use std::sync::OnceLock;

use crate::{ColorError, Outside, SpectralTable, Spectrum};

/// The CIE standard colorimetric observers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum ObserverKind {
    /// CIE 1931 2° (the CS-100A's and the paper's observer).
    Cie1931,
    /// CIE 1964 10°.
    Cie1964,
}

impl std::str::FromStr for ObserverKind {
    type Err = ColorError;
    fn from_str(s: &str) -> Result<Self, ColorError> {
        match s.trim().to_ascii_lowercase().as_str() {
            "1931" | "2" | "cie1931" => Ok(ObserverKind::Cie1931),
            "1964" | "10" | "cie1964" => Ok(ObserverKind::Cie1964),
            _ => Err(ColorError::UnknownName {
                kind: "observer",
                name: s.into(),
                known: "1931, 1964",
            }),
        }
    }
}

/// Colour-matching functions x̄, ȳ, z̄, sampled every 1 nm from `start_nm`.
#[derive(Clone, Debug)]
pub struct Observer {
    pub kind: ObserverKind,
    pub start_nm: f64,
    pub xbar: Vec<f64>,
    pub ybar: Vec<f64>,
    pub zbar: Vec<f64>,
}

impl Observer {
    /// (x̄, ȳ, z̄) at an integer wavelength; zero outside the table.
    pub fn at_nm(&self, nm: i32) -> [f64; 3] {
        let i = nm as f64 - self.start_nm;
        if i < 0.0 || i as usize >= self.ybar.len() {
            return [0.0; 3];
        }
        let i = i as usize;
        [self.xbar[i], self.ybar[i], self.zbar[i]]
    }

    /// (x̄, ȳ, z̄) at any wavelength, linearly interpolated.
    pub fn at(&self, nm: f64) -> [f64; 3] {
        let f = nm.floor();
        let t = nm - f;
        let a = self.at_nm(f as i32);
        if t == 0.0 {
            return a;
        }
        let b = self.at_nm(f as i32 + 1);
        [
            a[0] + t * (b[0] - a[0]),
            a[1] + t * (b[1] - a[1]),
            a[2] + t * (b[2] - a[2]),
        ]
    }
}

fn parse_embedded(name: &str, text: &str) -> SpectralTable {
    SpectralTable::parse(text, name).unwrap_or_else(|e| panic!("embedded table is valid: {e}"))
}

fn build_observer(kind: ObserverKind, name: &str, text: &str) -> Observer {
    let t = parse_embedded(name, text);
    Observer {
        kind,
        start_nm: t.wavelengths_nm[0],
        xbar: t.data[0].clone(),
        ybar: t.data[1].clone(),
        zbar: t.data[2].clone(),
    }
}

/// The observer's colour-matching functions (parsed once).
pub fn observer(kind: ObserverKind) -> &'static Observer {
    static CIE1931: OnceLock<Observer> = OnceLock::new();
    static CIE1964: OnceLock<Observer> = OnceLock::new();
    match kind {
        ObserverKind::Cie1931 => CIE1931.get_or_init(|| {
            build_observer(
                kind,
                "data/cie1931_2deg_cmf_1nm.csv",
                include_str!("../../../data/cie1931_2deg_cmf_1nm.csv"),
            )
        }),
        ObserverKind::Cie1964 => CIE1964.get_or_init(|| {
            build_observer(
                kind,
                "data/cie1964_10deg_cmf_1nm.csv",
                include_str!("../../../data/cie1964_10deg_cmf_1nm.csv"),
            )
        }),
    }
}

/// The illuminants shipped with metamer (relative spectral power distributions).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Illuminant {
    A,
    D50,
    D65,
    Fl11,
    LedRgb1,
    LedB3,
}

impl Illuminant {
    pub const ALL: [Illuminant; 6] = [
        Illuminant::A,
        Illuminant::D50,
        Illuminant::D65,
        Illuminant::Fl11,
        Illuminant::LedRgb1,
        Illuminant::LedB3,
    ];

    /// The CIE name as the CLI accepts it.
    pub fn name(self) -> &'static str {
        match self {
            Illuminant::A => "A",
            Illuminant::D50 => "D50",
            Illuminant::D65 => "D65",
            Illuminant::Fl11 => "FL11",
            Illuminant::LedRgb1 => "LED-RGB1",
            Illuminant::LedB3 => "LED-B3",
        }
    }

    /// The relative spectral power distribution (zero outside its table).
    pub fn spectrum(self) -> Spectrum {
        let (name, text) = match self {
            Illuminant::A => (
                "data/illuminant_a.csv",
                include_str!("../../../data/illuminant_a.csv"),
            ),
            Illuminant::D50 => (
                "data/illuminant_d50.csv",
                include_str!("../../../data/illuminant_d50.csv"),
            ),
            Illuminant::D65 => (
                "data/illuminant_d65.csv",
                include_str!("../../../data/illuminant_d65.csv"),
            ),
            Illuminant::Fl11 => (
                "data/illuminant_fl11.csv",
                include_str!("../../../data/illuminant_fl11.csv"),
            ),
            Illuminant::LedRgb1 => (
                "data/illuminant_led_rgb1.csv",
                include_str!("../../../data/illuminant_led_rgb1.csv"),
            ),
            Illuminant::LedB3 => (
                "data/illuminant_led_b3.csv",
                include_str!("../../../data/illuminant_led_b3.csv"),
            ),
        };
        parse_embedded(name, text).first()
    }
}

impl std::str::FromStr for Illuminant {
    type Err = ColorError;
    fn from_str(s: &str) -> Result<Self, ColorError> {
        let want = s.trim().to_ascii_uppercase().replace('_', "-");
        Illuminant::ALL
            .into_iter()
            .find(|i| i.name() == want)
            .ok_or_else(|| ColorError::UnknownName {
                kind: "illuminant",
                name: s.into(),
                known: "D65, D50, A, FL11, LED-RGB1, LED-B3",
            })
    }
}

/// Which measured ColorChecker Classic reflectance set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorCheckerSet {
    /// BabelColor average of 30 charts, 380–730 nm at 10 nm (the validation box uses it).
    BabelColorAverage,
    /// N. Ohta's measurement, 380–780 nm at 5 nm.
    Ohta,
}

/// Names of the 24 ColorChecker patches in the standard order.
pub const COLORCHECKER_NAMES: [&str; 24] = [
    "dark skin",
    "light skin",
    "blue sky",
    "foliage",
    "blue flower",
    "bluish green",
    "orange",
    "purplish blue",
    "moderate red",
    "purple",
    "yellow green",
    "orange yellow",
    "blue",
    "green",
    "red",
    "yellow",
    "magenta",
    "cyan",
    "white 9.5",
    "neutral 8",
    "neutral 6.5",
    "neutral 5",
    "neutral 3.5",
    "black 2",
];

/// The 24 patch reflectances, end values held outside the measured range (as the
/// validation-box contract asks for 380–780 nm).
pub fn colorchecker(set: ColorCheckerSet) -> Vec<Spectrum> {
    let (name, text) = match set {
        ColorCheckerSet::BabelColorAverage => (
            "data/colorchecker_babelcolor_average.csv",
            include_str!("../../../data/colorchecker_babelcolor_average.csv"),
        ),
        ColorCheckerSet::Ohta => (
            "data/colorchecker_ohta.csv",
            include_str!("../../../data/colorchecker_ohta.csv"),
        ),
    };
    parse_embedded(name, text).all(Outside::HoldEnds)
}

/// Reflectance of the validation box's wall paper.
pub fn paper_white() -> Spectrum {
    parse_embedded(
        "data/paper_white_reflectance.csv",
        include_str!("../../../data/paper_white_reflectance.csv"),
    )
    .first()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_tables_parse_with_expected_shape() {
        let o = observer(ObserverKind::Cie1931);
        assert_eq!(o.start_nm, 360.0);
        assert_eq!(o.ybar.len(), 471);
        // CIE 1931 ȳ(555) = 1.0 and ȳ(560) = 0.995 (CIE 15:2018 Table).
        assert_eq!(o.at_nm(555)[1], 1.0);
        assert!((o.at_nm(560)[1] - 0.995).abs() < 1e-9);
        assert_eq!(observer(ObserverKind::Cie1964).ybar.len(), 471);
        for i in Illuminant::ALL {
            assert!(i.spectrum().values().len() > 50, "{}", i.name());
        }
        // D65 is normalised to 100 at 560 nm.
        assert!((Illuminant::D65.spectrum().value_at(560.0) - 100.0).abs() < 1e-9);
        let cc = colorchecker(ColorCheckerSet::BabelColorAverage);
        assert_eq!(cc.len(), 24);
        assert_eq!(cc[0].value_at(780.0), cc[0].value_at(730.0));
        assert_eq!(colorchecker(ColorCheckerSet::Ohta).len(), 24);
        assert_eq!(paper_white().value_at(380.0), 0.62);
    }

    #[test]
    fn names_parse() {
        assert_eq!(
            "led-rgb1".parse::<Illuminant>().unwrap(),
            Illuminant::LedRgb1
        );
        assert_eq!(
            "1964".parse::<ObserverKind>().unwrap(),
            ObserverKind::Cie1964
        );
        assert!("D75".parse::<Illuminant>().is_err());
    }
}
