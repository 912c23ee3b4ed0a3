//! The kernel-field debug image of the density command (like the paper's Figure 2b): at each
//! pixel the diffusion estimate's kernel shape, hue = the edge direction `X1` (an axis, so its
//! angle is taken modulo 180° and spread over the whole colour wheel), brightness = 1 − λ2
//! (black where the kernel is round, bright where it is squeezed across an edge). Owns the
//! colour mapping; it asks the estimate for the shape and must not compute shapes itself.

use super::grid::Grid;
use crate::estimate::{DiffusionEstimate, Query, Scratch};
use crate::image_io::Image;
use crate::photon::PhotonMap;
use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;
use std::f32::consts::PI;

/// The kernel field on `grid`; the map must have had the estimate's gradient pass.
pub fn render(
    grid: &Grid,
    map: &PhotonMap,
    estimate: &DiffusionEstimate,
    bar: &ProgressBar,
) -> Image {
    let mut pixels = vec![Vec3::ZERO; grid.len()];
    pixels.par_chunks_mut(grid.width).enumerate().for_each_init(
        Scratch::default,
        |scratch, (row, out)| {
            for (col, pixel) in out.iter_mut().enumerate() {
                let c = grid.centre(row, col);
                let query = Query {
                    position: Vec3::new(c.x as f32, c.y as f32, 0.0),
                    normal: Vec3::Z,
                };
                let shape = estimate.kernel_at(map, &query, scratch);
                *pixel = colour(shape.x1.y.atan2(shape.x1.x), shape.lambda2);
            }
            bar.inc(1);
        },
    );
    bar.finish_and_clear();
    Image {
        width: grid.width,
        height: grid.height,
        pixels,
    }
}

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
