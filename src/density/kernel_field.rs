//! The kernel-field debug image of the density command (like the paper's Figure 2b): at each
//! pixel the diffusion estimate's kernel shape, hue = the edge direction `X1` (an axis, so its
//! angle is taken modulo 180° and spread over the whole colour wheel), brightness = 1 − λ2
//! (black where the kernel is round, bright where it is squeezed across an edge). Owns the
//! grid of probes; the estimate computes the shapes and
//! [`crate::estimate::diffusion::field_colour`] their colours.

use super::grid::Grid;
use crate::estimate::diffusion::field_colour::colour;
use crate::estimate::{DiffusionEstimate, Query, Scratch};
use crate::image_io::Image;
use crate::photon::PhotonMap;
use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

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
