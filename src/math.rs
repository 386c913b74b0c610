//! Planar math: the scalar type, 2-D vectors and poses (parry2d's glam types), and small
//! helpers.

pub use parry2d_f64::math::{Pose, Vector as Vec2};

/// The scalar type of the whole crate.
pub type Real = f64;

/// The scalar cross product of two planar vectors, `a × b = a_x b_y − a_y b_x`.
#[inline]
pub fn cross(a: Vec2, b: Vec2) -> Real {
    a.x * b.y - a.y * b.x
}

/// The vector rotated by +90°, `(−v_y, v_x)`: `ω × r` for a planar angular velocity `ω`
/// is `ω · perp(r)`.
#[inline]
pub fn perp(v: Vec2) -> Vec2 {
    Vec2::new(-v.y, v.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perp_is_cross_with_unit_z() {
        let r = Vec2::new(0.3, -1.7);
        // ω ẑ × r = ω (−r_y, r_x)
        assert_eq!(perp(r), Vec2::new(1.7, 0.3));
        assert_eq!(cross(r, perp(r)), r.length_squared());
    }
}
