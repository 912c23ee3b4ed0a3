//! Pilot rays, once per render before any pass: one through every pixel's centre and one
//! through every pixel corner (neighbours share corners: about two rays a pixel), each
//! followed along every branch of its mirror and glass chains, as camera paths are. What they
//! find plans each pixel for the whole render ([`PixelPlan`]):
//!
//! - **Emission apart** (`--emission-samples`): a chain's last ray meets a light, leaves the
//!   scene under an image environment, or passes within the pixel's spread of a light, so a
//!   light image smaller than the pilots' spacing may lie inside the pixel
//!   ([`super::emission`]). A constant environment flags nothing: every ray that leaves sees
//!   the same radiance, so camera samples count it exactly.
//! - **Edge** (`--edge-samples`): the pilots disagree on what the pixel shows — other objects
//!   along their chains, another chain shape, normals more than 30° apart, or a light's
//!   probe point visible from one pilot's diffuse hit and hidden from another's (a shadow's
//!   edge). A
//!   pixel's value there is the mean of a step across it, which camera samples resolve slowly;
//!   such pixels take more camera samples a pass, where they cost little beside the image.
//!
//! Decided from the geometry alone, so that every pass, thread count and shard agrees. Owns
//! that plan; must not shade or estimate.

mod pilot;
mod survey;

use super::camera::RayCamera;
use super::light_images::{self, LightImage};
use crate::world::World;
use glam::Vec2;
use pilot::{Pilot, holds_edge, sees_emission};
use rayon::prelude::*;
use survey::Survey;

/// Per pixel of an image, how its samples are spent in every pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PixelPlan {
    /// Bit [`EMISSION`] and bit [`EDGE`] per pixel, row-major.
    flags: Vec<u8>,
    /// Emission samples per pass in the pixels that take them (0: none does).
    emission_samples: u32,
    /// Camera samples per pass in edge pixels (0: edges take the render's `spp` too).
    edge_samples: u32,
    /// The light images of emission pixels, by pixel in ascending order (`image_pixels[i]`
    /// holds `images[i]`).
    image_pixels: Vec<u32>,
    images: Vec<LightImage>,
}

const EMISSION: u8 = 1;
const EDGE: u8 = 2;

impl PixelPlan {
    /// The plan for `camera`'s pixels: pilots follow mirrors and glass for `max_depth`
    /// bounces, as camera paths do; with `light_images` they seek the light images of the
    /// pixels that sample their emission apart. With both counts 0 no pilot is traced. `None`
    /// if an interruption was requested meanwhile.
    pub fn survey(
        camera: &RayCamera,
        world: &World,
        max_depth: u32,
        emission_samples: u32,
        edge_samples: u32,
        light_images: bool,
    ) -> Option<Self> {
        let (w, h) = (camera.width(), camera.height());
        let mut plan = Self {
            flags: vec![0; w * h],
            emission_samples,
            edge_samples,
            image_pixels: Vec::new(),
            images: Vec::new(),
        };
        if emission_samples == 0 && edge_samples == 0 {
            return Some(plan);
        }
        let survey = Survey::new(world, max_depth);
        // Through the lens's centre: a pilot stands for the pixel's whole aperture.
        let pilot = |x: usize, y: usize, inset: f32| {
            let (fx, fy) = camera.film_pixel(x, y);
            let ray = camera.chief_ray(fx as f32 + inset, fy as f32 + inset);
            survey.pilot(ray.origin, ray.direction)
        };
        // Row by row, so that an interruption is noticed within one row.
        let rows = |count: usize, width: usize, at: &(dyn Fn(usize, usize) -> Pilot + Sync)| {
            (0..count)
                .into_par_iter()
                .map(|y| {
                    if crate::interrupt::requested() {
                        return Vec::new();
                    }
                    (0..width).map(|x| at(x, y)).collect::<Vec<Pilot>>()
                })
                .collect::<Vec<_>>()
        };
        let corners = rows(h + 1, w + 1, &|x, y| pilot(x, y, 0.0));
        let centres = rows(h, w, &|x, y| pilot(x, y, 0.5));
        if crate::interrupt::requested() {
            return None;
        }
        for (pixel, flags) in plan.flags.iter_mut().enumerate() {
            let (x, y) = (pixel % w, pixel / w);
            let pilots = [
                &centres[y][x],
                &corners[y][x],
                &corners[y][x + 1],
                &corners[y + 1][x],
                &corners[y + 1][x + 1],
            ];
            if emission_samples > 0 && sees_emission(&pilots) {
                *flags |= EMISSION;
            }
            if edge_samples > 0 && holds_edge(&pilots) {
                *flags |= EDGE;
            }
        }
        // Aimed samples need a share of at least one.
        if light_images && emission_samples >= 2 {
            let flagged: Vec<usize> = (0..w * h).filter(|&p| plan.emission_apart(p)).collect();
            let found: Vec<Vec<LightImage>> = flagged
                .par_iter()
                .map(|&pixel| {
                    let (x, y) = (pixel % w, pixel / w);
                    let (fx, fy) = camera.film_pixel(x, y);
                    let corner = Vec2::new(fx as f32, fy as f32);
                    let pilots = [
                        (&centres[y][x], Vec2::splat(0.5)),
                        (&corners[y][x], Vec2::ZERO),
                        (&corners[y][x + 1], Vec2::X),
                        (&corners[y + 1][x], Vec2::Y),
                        (&corners[y + 1][x + 1], Vec2::ONE),
                    ];
                    let seeds = survey.seeds(&pilots, corner);
                    light_images::find(world, camera, corner, &seeds)
                })
                .collect();
            for (&pixel, images) in flagged.iter().zip(found) {
                for image in images {
                    plan.image_pixels.push(pixel as u32);
                    plan.images.push(image);
                }
            }
        }
        Some(plan)
    }

    /// The light images found in `pixel` (row-major), where its emission samples aim.
    pub fn light_images(&self, pixel: usize) -> &[LightImage] {
        let start = self.image_pixels.partition_point(|&p| (p as usize) < pixel);
        let end = self
            .image_pixels
            .partition_point(|&p| (p as usize) <= pixel);
        &self.images[start..end]
    }

    /// Pixels whose emission samples aim at a light image.
    pub fn aimed_pixels(&self) -> usize {
        let mut pixels = self.image_pixels.clone();
        pixels.dedup();
        pixels.len()
    }

    /// Whether `pixel` (row-major) samples the light along its mirror and glass chains apart.
    #[inline]
    pub fn emission_apart(&self, pixel: usize) -> bool {
        self.flags[pixel] & EMISSION != 0
    }

    pub fn emission_samples(&self) -> u32 {
        self.emission_samples
    }

    /// Camera samples `pixel` takes in a pass of `spp` samples a pixel.
    #[inline]
    pub fn camera_samples(&self, pixel: usize, spp: u32) -> u32 {
        if self.flags[pixel] & EDGE != 0 {
            self.edge_samples.max(spp)
        } else {
            spp
        }
    }

    /// Pixels that sample their emitted light apart.
    pub fn emission_pixels(&self) -> usize {
        self.flags.iter().filter(|&&f| f & EMISSION != 0).count()
    }

    /// Pixels that take the edge samples.
    pub fn edge_pixels(&self) -> usize {
        self.flags.iter().filter(|&&f| f & EDGE != 0).count()
    }
}

#[cfg(test)]
mod tests;
