//! Vectors, one-sided rectangles and ray intersection: everything in the validation box is
//! a rectangle, so a linear scan over a few dozen of them is all the acceleration it needs.

/// A 3-vector in metres (positions) or a direction: glam's `DVec3`.
pub type Vec3 = glam::DVec3;

/// The renderer's vector vocabulary on `DVec3`, so the tracer's arithmetic reads as it
/// always has; new code may as well use glam's operators.
pub trait VecOps {
    fn plus(self, o: Vec3) -> Vec3;
    fn minus(self, o: Vec3) -> Vec3;
    fn times(self, k: f64) -> Vec3;
    fn normalized(self) -> Vec3;
    /// Two unit vectors completing `self` (unit) to an orthonormal basis (Duff et al.
    /// 2017, "Building an Orthonormal Basis, Revisited", which is what glam implements).
    fn basis(self) -> (Vec3, Vec3);
}

impl VecOps for Vec3 {
    #[inline]
    fn plus(self, o: Vec3) -> Vec3 {
        self + o
    }
    #[inline]
    fn minus(self, o: Vec3) -> Vec3 {
        self - o
    }
    #[inline]
    fn times(self, k: f64) -> Vec3 {
        self * k
    }
    #[inline]
    fn normalized(self) -> Vec3 {
        self * (1.0 / self.length())
    }
    #[inline]
    fn basis(self) -> (Vec3, Vec3) {
        self.any_orthonormal_pair()
    }
}

/// A parallelogram `corner + a·edge_u + b·edge_v`, a, b ∈ [0, 1], whose front side faces
/// `edge_u × edge_v`. Only the front reflects or emits; the back is black and opaque.
#[derive(Clone, Copy, Debug)]
pub struct Rect {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    pub normal: Vec3,
    pub area_m2: f64,
    inv_uu: f64,
    inv_vv: f64,
}

/// Where a ray met a rectangle.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f64,
    /// Local coordinates in [0, 1]².
    pub a: f64,
    pub b: f64,
    /// The ray arrived on the front side.
    pub front: bool,
}

impl Rect {
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> Rect {
        let c = edge_u.cross(edge_v);
        Rect {
            corner,
            edge_u,
            edge_v,
            normal: c.normalized(),
            area_m2: c.length(),
            inv_uu: 1.0 / edge_u.dot(edge_u),
            inv_vv: 1.0 / edge_v.dot(edge_v),
        }
    }

    /// Intersection for t in (t_min, t_max). Edges are assumed orthogonal (rectangles).
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f64, t_max: f64) -> Option<Hit> {
        let denom = dir.dot(self.normal);
        if denom.abs() < 1e-14 {
            return None;
        }
        let t = self.corner.minus(origin).dot(self.normal) / denom;
        if t <= t_min || t >= t_max {
            return None;
        }
        let p = origin.plus(dir.times(t)).minus(self.corner);
        let a = p.dot(self.edge_u) * self.inv_uu;
        let b = p.dot(self.edge_v) * self.inv_vv;
        if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) {
            return None;
        }
        Some(Hit {
            t,
            a,
            b,
            front: denom < 0.0,
        })
    }

    pub fn point(&self, a: f64, b: f64) -> Vec3 {
        self.corner
            .plus(self.edge_u.times(a))
            .plus(self.edge_v.times(b))
    }

    pub fn centre(&self) -> Vec3 {
        self.point(0.5, 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_front_and_back() {
        // Unit square in z = 1 facing −z (u = y, v = x gives y × x = −z).
        let r = Rect::new(
            Vec3::from_array([0.0, 0.0, 1.0]),
            Vec3::from_array([0.0, 1.0, 0.0]),
            Vec3::from_array([1.0, 0.0, 0.0]),
        );
        assert_eq!(r.normal.to_array(), [0.0, 0.0, -1.0]);
        let h = r
            .intersect(
                Vec3::from_array([0.25, 0.5, 0.0]),
                Vec3::from_array([0.0, 0.0, 1.0]),
                0.0,
                9.0,
            )
            .unwrap();
        assert!((h.t - 1.0).abs() < 1e-12 && h.front);
        assert!((h.a - 0.5).abs() < 1e-12 && (h.b - 0.25).abs() < 1e-12);
        let back = r
            .intersect(
                Vec3::from_array([0.5, 0.5, 2.0]),
                Vec3::from_array([0.0, 0.0, -1.0]),
                0.0,
                9.0,
            )
            .unwrap();
        assert!(!back.front);
        assert!(r
            .intersect(
                Vec3::from_array([1.5, 0.5, 0.0]),
                Vec3::from_array([0.0, 0.0, 1.0]),
                0.0,
                9.0
            )
            .is_none());
    }

    #[test]
    fn basis_is_orthonormal() {
        let n = Vec3::from_array([0.3, -0.5, 0.8]).normalized();
        let (s, t) = n.basis();
        for (x, y) in [(s, t), (s, n), (t, n)] {
            assert!(x.dot(y).abs() < 1e-12);
        }
        assert!((s.length() - 1.0).abs() < 1e-12 && (t.length() - 1.0).abs() < 1e-12);
    }
}
