//! Colour coordinates: CIE XYZ, xyY, CIELAB 1976 and its cylindrical LCh form (CIE 15:2018
//! §8.2.1 for CIELAB, with the exact constants ε = 216/24389, κ = 24389/27 of CIE 015's
//! technical note rather than the rounded 0.008856 / 903.3).

use serde::{Deserialize, Serialize};

/// CIE XYZ tristimulus values (absolute cd/m² for emission, relative Y = 100 for objects).
///
/// In files it is the array `[X, Y, Z]`, the form every metamer JSON file already used for
/// XYZ before this type crossed module boundaries, so a field can change from `[f64; 3]` to
/// `Xyz` without changing a byte of what is written or read. `xyz[0]`, `xyz[1]`, `xyz[2]`
/// are X, Y, Z.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "[f64; 3]", into = "[f64; 3]")]
pub struct Xyz {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// Chromaticity x, y and luminance Y.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct XyY {
    pub x: f64,
    pub y: f64,
    pub luminance: f64,
}

/// CIELAB 1976 L*, a*, b*.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lab {
    pub l: f64,
    pub a: f64,
    pub b: f64,
}

/// CIELAB in cylindrical form: lightness, chroma, hue angle in degrees [0, 360).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lch {
    pub l: f64,
    pub c: f64,
    pub h_deg: f64,
}

/// Chromaticity of CIE D65 (CIE 15:2018 Table T.3), used for black where x, y are undefined.
pub const D65_XY: (f64, f64) = (0.31272, 0.32903);

const EPSILON: f64 = 216.0 / 24389.0;
const KAPPA: f64 = 24389.0 / 27.0;

impl Xyz {
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Xyz { x, y, z }
    }

    pub fn from_array(v: [f64; 3]) -> Self {
        Xyz::new(v[0], v[1], v[2])
    }

    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    /// xyY. Black (X+Y+Z = 0) has no chromaticity; it gets D65's so that the round trip
    /// still gives black (Y = 0 makes X and Z zero whatever x, y are).
    pub fn to_xyy(self) -> XyY {
        let sum = self.x + self.y + self.z;
        if sum == 0.0 {
            return XyY {
                x: D65_XY.0,
                y: D65_XY.1,
                luminance: self.y,
            };
        }
        XyY {
            x: self.x / sum,
            y: self.y / sum,
            luminance: self.y,
        }
    }

    /// CIELAB relative to `white` (white's Y must be positive).
    pub fn to_lab(self, white: Xyz) -> Lab {
        let f = |t: f64| {
            if t > EPSILON {
                t.cbrt()
            } else {
                (KAPPA * t + 16.0) / 116.0
            }
        };
        let fx = f(self.x / white.x);
        let fy = f(self.y / white.y);
        let fz = f(self.z / white.z);
        Lab {
            l: 116.0 * fy - 16.0,
            a: 500.0 * (fx - fy),
            b: 200.0 * (fy - fz),
        }
    }

    pub fn scaled(self, k: f64) -> Xyz {
        Xyz::new(self.x * k, self.y * k, self.z * k)
    }

    /// X, Y, Z in turn, by value, as an array's `iter().copied()` gives them.
    pub fn iter(&self) -> std::array::IntoIter<f64, 3> {
        self.to_array().into_iter()
    }

    /// Each component through `f`, as an array's `map` does.
    pub fn map(self, mut f: impl FnMut(f64) -> f64) -> Xyz {
        Xyz::new(f(self.x), f(self.y), f(self.z))
    }

    /// Whether X, Y and Z are all finite numbers.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
}

impl IntoIterator for Xyz {
    type Item = f64;
    type IntoIter = std::array::IntoIter<f64, 3>;
    fn into_iter(self) -> Self::IntoIter {
        self.to_array().into_iter()
    }
}

impl IntoIterator for &Xyz {
    type Item = f64;
    type IntoIter = std::array::IntoIter<f64, 3>;
    fn into_iter(self) -> Self::IntoIter {
        self.to_array().into_iter()
    }
}

impl From<[f64; 3]> for Xyz {
    fn from(v: [f64; 3]) -> Xyz {
        Xyz::from_array(v)
    }
}

impl From<Xyz> for [f64; 3] {
    fn from(v: Xyz) -> [f64; 3] {
        v.to_array()
    }
}

impl std::ops::Index<usize> for Xyz {
    type Output = f64;
    /// X, Y, Z for 0, 1, 2; panics past 2 as an array does.
    fn index(&self, i: usize) -> &f64 {
        match i {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("XYZ has three components, index {i} asked"),
        }
    }
}

impl std::ops::IndexMut<usize> for Xyz {
    fn index_mut(&mut self, i: usize) -> &mut f64 {
        match i {
            0 => &mut self.x,
            1 => &mut self.y,
            2 => &mut self.z,
            _ => panic!("XYZ has three components, index {i} asked"),
        }
    }
}

impl std::ops::Add for Xyz {
    type Output = Xyz;
    fn add(self, o: Xyz) -> Xyz {
        Xyz::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl std::ops::Sub for Xyz {
    type Output = Xyz;
    fn sub(self, o: Xyz) -> Xyz {
        Xyz::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl XyY {
    /// XYZ from xyY (X = xY/y, Z = (1−x−y)Y/y), the one conversion the colour core and the
    /// instruments share. No light (Y = 0) is black whatever x, y say. Light without a
    /// usable chromaticity (y ≤ 0 or not a number, as a colorimeter reports when it could
    /// not measure one) keeps its Y, and X and Z are NaN: unknown, not zero.
    pub fn to_xyz(self) -> Xyz {
        if self.luminance == 0.0 {
            return Xyz::default();
        }
        if self.y.is_nan() || self.y <= 0.0 {
            return Xyz::new(f64::NAN, self.luminance, f64::NAN);
        }
        let k = self.luminance / self.y;
        Xyz::new(self.x * k, self.luminance, (1.0 - self.x - self.y) * k)
    }

    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.luminance]
    }
}

impl Lab {
    pub const fn new(l: f64, a: f64, b: f64) -> Self {
        Lab { l, a, b }
    }

    pub fn to_array(self) -> [f64; 3] {
        [self.l, self.a, self.b]
    }

    /// XYZ relative to `white` (the inverse of [`Xyz::to_lab`]).
    pub fn to_xyz(self, white: Xyz) -> Xyz {
        let fy = (self.l + 16.0) / 116.0;
        let fx = fy + self.a / 500.0;
        let fz = fy - self.b / 200.0;
        let finv = |f: f64| {
            let f3 = f * f * f;
            if f3 > EPSILON {
                f3
            } else {
                (116.0 * f - 16.0) / KAPPA
            }
        };
        let yr = if self.l > KAPPA * EPSILON {
            fy * fy * fy
        } else {
            self.l / KAPPA
        };
        Xyz::new(finv(fx) * white.x, yr * white.y, finv(fz) * white.z)
    }

    pub fn to_lch(self) -> Lch {
        let h = self.b.atan2(self.a).to_degrees();
        Lch {
            l: self.l,
            c: self.a.hypot(self.b),
            h_deg: if h < 0.0 { h + 360.0 } else { h },
        }
    }
}

impl Lch {
    pub fn to_lab(self) -> Lab {
        let h = self.h_deg.to_radians();
        Lab::new(self.l, self.c * h.cos(), self.c * h.sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const D65: Xyz = Xyz::new(95.047, 100.0, 108.883);

    #[test]
    fn xyz_is_the_array_x_y_z_in_files_and_by_index() {
        let v = Xyz::new(41.24, 21.26, 1.93);
        assert_eq!(serde_json::to_string(&v).unwrap(), "[41.24,21.26,1.93]");
        let back: Xyz = serde_json::from_str("[41.24,21.26,1.93]").unwrap();
        assert_eq!(back, v);
        // The object form was never written to a file and is not read.
        assert!(serde_json::from_str::<Xyz>(r#"{"x":1,"y":2,"z":3}"#).is_err());
        assert!(serde_json::from_str::<Xyz>("[1,2]").is_err());
        assert_eq!((v[0], v[1], v[2]), (41.24, 21.26, 1.93));
        let mut m = v;
        m[1] = 5.0;
        assert_eq!(m.y, 5.0);
        assert_eq!(<[f64; 3]>::from(v), [41.24, 21.26, 1.93]);
        assert_eq!(Xyz::from([1.0, 2.0, 3.0]), Xyz::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn white_is_l100_and_known_values() {
        let lab = D65.to_lab(D65);
        assert!((lab.l - 100.0).abs() < 1e-12 && lab.a.abs() < 1e-12 && lab.b.abs() < 1e-12);
        // Y = 18.4186 % gives L* = 50 exactly: ((50+16)/116)^3 = 0.184186.
        let mid = Xyz::new(0.184186 * D65.x, 0.184186 * D65.y, 0.184186 * D65.z).to_lab(D65);
        assert!((mid.l - 50.0).abs() < 1e-4, "{mid:?}");
        // Below ε the linear branch: Y/Yn = 0.001 → L* = κ·0.001 = 0.9033.
        let dark = Xyz::new(0.1 * 0.95047, 0.1, 0.1 * 1.08883).to_lab(D65);
        assert!((dark.l - 24389.0 / 27.0 * 0.001).abs() < 1e-9);
    }

    #[test]
    fn xyy_of_equal_energy_and_black() {
        let e = Xyz::new(1.0, 1.0, 1.0).to_xyy();
        assert!((e.x - 1.0 / 3.0).abs() < 1e-15 && (e.y - 1.0 / 3.0).abs() < 1e-15);
        let black = Xyz::default().to_xyy();
        assert_eq!(black.luminance, 0.0);
        assert_eq!(black.to_xyz(), Xyz::default());
    }

    #[test]
    fn xyy_to_xyz_by_hand_and_without_chromaticity() {
        // x = 0.3, y = 0.6, Y = 30: X = 0.3·30/0.6 = 15, Z = 0.1·30/0.6 = 5.
        let c = XyY {
            x: 0.3,
            y: 0.6,
            luminance: 30.0,
        }
        .to_xyz();
        assert!((c.x - 15.0).abs() < 1e-12 && c.y == 30.0 && (c.z - 5.0).abs() < 1e-12);
        for y in [0.0, -0.1, f64::NAN] {
            let u = XyY {
                x: 0.3,
                y,
                luminance: 52.31,
            }
            .to_xyz();
            assert!(u.x.is_nan() && u.y == 52.31 && u.z.is_nan(), "{y}: {u:?}");
            let dark = XyY {
                x: f64::NAN,
                y,
                luminance: 0.0,
            }
            .to_xyz();
            assert_eq!(dark, Xyz::default());
        }
    }

    fn xyz_strategy() -> impl Strategy<Value = Xyz> {
        (0.0..200.0f64, 0.001..200.0f64, 0.0..200.0f64).prop_map(|(x, y, z)| Xyz::new(x, y, z))
    }

    proptest! {
        #[test]
        fn lab_round_trip(c in xyz_strategy()) {
            let back = c.to_lab(D65).to_xyz(D65);
            prop_assert!((back.x - c.x).abs() < 1e-9 * (1.0 + c.x));
            prop_assert!((back.y - c.y).abs() < 1e-9 * (1.0 + c.y));
            prop_assert!((back.z - c.z).abs() < 1e-9 * (1.0 + c.z));
        }

        #[test]
        fn xyy_round_trip(c in xyz_strategy()) {
            let back = c.to_xyy().to_xyz();
            prop_assert!((back.x - c.x).abs() < 1e-9 * (1.0 + c.x));
            prop_assert!((back.y - c.y).abs() < 1e-12 * (1.0 + c.y));
            prop_assert!((back.z - c.z).abs() < 1e-9 * (1.0 + c.z));
        }

        #[test]
        fn lch_round_trip(l in 0.0..100.0f64, a in -128.0..128.0f64, b in -128.0..128.0f64) {
            let back = Lab::new(l, a, b).to_lch().to_lab();
            prop_assert!((back.a - a).abs() < 1e-9 && (back.b - b).abs() < 1e-9);
        }
    }
}
