//! The colour of a diffusion kernel's shape, as the kernel-field images show it (like the
//! paper's Figure 2b): hue = the edge direction `X1` (an axis, so its angle is taken modulo
//! 180° and spread over the whole colour wheel), brightness = 1 − λ2 (black where the kernel is
//! round, bright where it is squeezed across an edge). Shared by `dpm density`'s field and the
//! render film's kernel-field layer. Owns the colour mapping only.

use glam::Vec3;
use std::f32::consts::PI;

/// The colour of a kernel whose long axis has angle `angle` (radians) and whose squeeze is
/// `lambda2`.
pub fn colour(angle: f32, lambda2: f32) -> Vec3 {
    let hue = (angle.rem_euclid(PI) / PI).min(1.0);
    let value = (1.0 - lambda2).clamp(0.0, 1.0);
    hsv(hue, 1.0, value)
}

/// HSV (all in [0, 1]) to RGB.
fn hsv(hue: f32, saturation: f32, value: f32) -> Vec3 {
    let h = hue.fract() * 6.0;
    let c = value * saturation;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    Vec3::new(r, g, b) + Vec3::splat(value - c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_kernels_are_black_and_opposite_axes_share_a_colour() {
        assert_eq!(colour(0.3, 1.0), Vec3::ZERO);
        let a = colour(0.3, 0.01);
        let b = colour(0.3 + PI, 0.01);
        assert!((a - b).abs().max_element() < 1e-5);
        assert!((a.max_element() - 0.99).abs() < 1e-6);
        // Horizontal and vertical edges get different hues (red and cyan).
        let (h, v) = (colour(0.0, 0.0), colour(PI / 2.0, 0.0));
        assert!(
            (h - Vec3::X).length() < 1e-6 && (v - Vec3::new(0.0, 1.0, 1.0)).length() < 1e-5,
            "{h} {v}"
        );
    }
}
