//! The map between unit directions and the square ((cosθ+1)/2, φ/2π) the quadtrees live
//! on, with z the polar axis and φ = atan2(y, x) in [0, 2π). It is area-preserving up to
//! the constant 4π (dω = dcosθ dφ = 4π du dv), so a density q on the square is the
//! solid-angle pdf q / 4π. Mirrors `guide_dir_to_square` / `guide_square_to_dir` in
//! shaders_glsl/inc/guiding.glsl operation for operation.

use glam::Vec3;
use std::f32::consts::PI;

/// 1 / 4π: the solid-angle pdf of a uniform density on the square.
pub const INV_4PI: f32 = (0.25 / std::f64::consts::PI) as f32;

/// Largest float below 1.
pub const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

/// Square coordinates of a direction (need not be normalised exactly; non-finite
/// directions map to the origin).
pub fn dir_to_square(d: Vec3) -> [f32; 2] {
    let cos_theta = d.z.clamp(-1.0, 1.0);
    let mut phi = d.y.atan2(d.x);
    if phi.is_nan() {
        phi = 0.0;
    }
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let p = [
        ((cos_theta + 1.0) * 0.5).clamp(0.0, 1.0),
        (phi * (0.5 / PI)).clamp(0.0, 1.0),
    ];
    if p[0].is_nan() || p[1].is_nan() {
        [0.0, 0.0]
    } else {
        p
    }
}

/// The unit direction at square coordinates `p`.
pub fn square_to_dir(p: [f32; 2]) -> Vec3 {
    let cos_theta = 2.0 * p[0] - 1.0;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    // Reduced to [-π, π] first (v - roundEven(v) is exact, as in the kernel): more absolute precision near 2π.
    let phi = (2.0 * PI) * (p[1] - p[1].round_ties_even());
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_poles() {
        for i in 0..64 {
            for j in 0..64 {
                let p = [(i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0];
                let d = square_to_dir(p);
                assert!((d.length() - 1.0).abs() < 1e-6);
                let q = dir_to_square(d);
                assert!(
                    (q[0] - p[0]).abs() < 1e-5 && (q[1] - p[1]).abs() < 1e-5,
                    "{p:?} {q:?}"
                );
            }
        }
        assert_eq!(dir_to_square(Vec3::Z), [1.0, 0.0]);
        assert_eq!(dir_to_square(Vec3::new(0.0, 0.0, -1.0)), [0.0, 0.0]);
        assert_eq!(dir_to_square(Vec3::splat(f32::NAN)), [0.0, 0.0]);
        // φ wraps to [0, 2π): just below the +x axis is near v = 1.
        assert!(dir_to_square(Vec3::new(1.0, -1e-6, 0.0))[1] > 0.999);
    }
}
