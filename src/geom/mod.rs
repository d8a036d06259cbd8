//! Plane geometry: a small `Vec2` value type and point–segment queries;
//! polygonal domains ([`polygon`]), cracks in them ([`crack`]) and their
//! triangulation ([`triangulate`]).

pub mod crack;
pub mod exact_sum;
pub mod polygon;
pub mod segment_index;
pub mod triangulate;

use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// A 2D vector or point, `f64` components. `repr(C)`: a `[Vec2]` is laid
/// out as `[f64; 2]` pairs, so bindings can view it as an `(n, 2)` array.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Vec2 {
    /// x component (horizontal).
    pub x: f64,
    /// y component (vertical, up; gravity is usually −y).
    pub y: f64,
}

/// A `[Vec2]` as its `[x0, y0, x1, y1, …]` components (no copy).
pub fn flat(v: &[Vec2]) -> &[f64] {
    // SAFETY: `Vec2` is `repr(C)` with two `f64` fields and no padding:
    // `n` of them are `2n` `f64`s at the same address and alignment,
    // borrowed for the same lifetime.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<f64>(), 2 * v.len()) }
}

impl Vec2 {
    /// The zero vector / origin.
    pub const ZERO: Vec2 = Vec2 { x: 0.0, y: 0.0 };

    /// `(x, y)`.
    #[inline]
    pub const fn new(x: f64, y: f64) -> Self {
        Vec2 { x, y }
    }
    /// Scalar product `self · o`.
    #[inline]
    pub fn dot(self, o: Vec2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// z-component of the 3D cross product `self × o`.
    #[inline]
    pub fn cross(self, o: Vec2) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Squared Euclidean length `|self|²`.
    #[inline]
    pub fn norm2(self) -> f64 {
        self.dot(self)
    }
    /// Euclidean length `|self|`.
    #[inline]
    pub fn norm(self) -> f64 {
        self.norm2().sqrt()
    }
    /// Rotated by +90°: `(−y, x)`.
    #[inline]
    pub fn perp(self) -> Vec2 {
        Vec2::new(-self.y, self.x)
    }
    /// `[x, y]`.
    #[inline]
    pub fn to_array(self) -> [f64; 2] {
        [self.x, self.y]
    }
}

impl From<[f64; 2]> for Vec2 {
    #[inline]
    fn from(a: [f64; 2]) -> Self {
        Vec2::new(a[0], a[1])
    }
}

impl Add for Vec2 {
    type Output = Vec2;
    #[inline]
    fn add(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x + o.x, self.y + o.y)
    }
}
impl Sub for Vec2 {
    type Output = Vec2;
    #[inline]
    fn sub(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x - o.x, self.y - o.y)
    }
}
impl Neg for Vec2 {
    type Output = Vec2;
    #[inline]
    fn neg(self) -> Vec2 {
        Vec2::new(-self.x, -self.y)
    }
}
impl Mul<f64> for Vec2 {
    type Output = Vec2;
    #[inline]
    fn mul(self, s: f64) -> Vec2 {
        Vec2::new(self.x * s, self.y * s)
    }
}
impl Mul<Vec2> for f64 {
    type Output = Vec2;
    #[inline]
    fn mul(self, v: Vec2) -> Vec2 {
        v * self
    }
}
impl AddAssign for Vec2 {
    #[inline]
    fn add_assign(&mut self, o: Vec2) {
        self.x += o.x;
        self.y += o.y;
    }
}
impl SubAssign for Vec2 {
    #[inline]
    fn sub_assign(&mut self, o: Vec2) {
        self.x -= o.x;
        self.y -= o.y;
    }
}

/// Closest point of segment `[a, b]` to `p`, as the parameter `s ∈ [0, 1]`
/// along the segment and the point itself.
#[inline]
pub fn closest_on_segment(p: Vec2, a: Vec2, b: Vec2) -> (f64, Vec2) {
    let ab = b - a;
    let l2 = ab.norm2();
    let s = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (s, a + ab * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slice_of_vectors_is_its_components() {
        let v = [Vec2::new(1.0, -2.0), Vec2::new(3.5, 4.0)];
        assert_eq!(flat(&v), &[1.0, -2.0, 3.5, 4.0]);
        assert!(flat(&[]).is_empty());
    }

    #[test]
    fn closest_point_interior_and_ends() {
        let a = Vec2::new(0.0, 0.0);
        let b = Vec2::new(2.0, 0.0);
        let (s, q) = closest_on_segment(Vec2::new(0.5, 3.0), a, b);
        assert_eq!((s, q), (0.25, Vec2::new(0.5, 0.0)));
        let (s, q) = closest_on_segment(Vec2::new(-1.0, 1.0), a, b);
        assert_eq!((s, q), (0.0, a));
        let (s, q) = closest_on_segment(Vec2::new(5.0, -1.0), a, b);
        assert_eq!((s, q), (1.0, b));
    }

    #[test]
    fn cross_sign_is_counter_clockwise_positive() {
        assert_eq!(Vec2::new(1.0, 0.0).cross(Vec2::new(0.0, 1.0)), 1.0);
        assert_eq!(Vec2::new(1.0, 0.0).perp(), Vec2::new(0.0, 1.0));
    }
}
