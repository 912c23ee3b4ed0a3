//! The eye pass: a pinhole camera, pixels rendered in parallel through the [`integrator`], and
//! the orchestration of a whole render ([`pipeline`]: scene → Embree → photon maps → estimate →
//! image) with its up-front memory check ([`memory_budget`]). Owns pixels and sample
//! placement; must not parse scenes or store photons.

pub mod integrator;
pub mod memory_budget;
pub mod pipeline;

use crate::estimate::Scratch;
use crate::image_io::Image;
use crate::sampling::{Rng, Stream};
use crate::scene::Camera;
use glam::Vec3;
use indicatif::ProgressBar;
use integrator::Integrator;
use rayon::prelude::*;

/// Primary rays of a pinhole camera.
#[derive(Clone, Copy, Debug)]
pub struct PinholeCamera {
    origin: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half: f32,
    width: u32,
    height: u32,
}

impl PinholeCamera {
    pub fn new(c: &Camera) -> Self {
        let forward = (c.look_at - c.position).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        Self {
            origin: c.position,
            forward,
            right,
            up,
            tan_half: (c.fov_y_degrees.to_radians() * 0.5).tan(),
            width: c.width,
            height: c.height,
        }
    }

    /// The unit direction through image position (`x`, `y`) in pixels, (0, 0) the top-left corner.
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let aspect = self.width as f32 / self.height as f32;
        let u = (2.0 * x / self.width as f32 - 1.0) * self.tan_half * aspect;
        let v = (1.0 - 2.0 * y / self.height as f32) * self.tan_half;
        (self.forward + u * self.right + v * self.up).normalize()
    }

    pub fn origin(&self) -> Vec3 {
        self.origin
    }
}

/// Renders every pixel: `spp` samples each (one sample goes through the pixel centre; more are
/// jittered), drawn from the pixel's own generator so the image is the same on any thread count.
/// Pixels not yet started when an interruption is requested ([`crate::interrupt`]) are left
/// black; the caller must check for it and discard the image.
pub fn render_image(
    camera: &PinholeCamera,
    integrator: &Integrator,
    spp: u32,
    seed: u64,
    progress: &ProgressBar,
) -> Image {
    let w = camera.width as usize;
    shade_pixels(camera, progress, |scratch, x, y| {
        // Per pixel, not per row: a row through glass can take seconds.
        if crate::interrupt::requested() {
            return Vec3::ZERO;
        }
        let mut rng = Rng::for_index(seed, Stream::Pixels, (y * w + x) as u64);
        let mut sum = Vec3::ZERO;
        for s in 0..spp {
            let (jx, jy) = if s == 0 { (0.5, 0.5) } else { rng.next_2d() };
            let d = camera.direction(x as f32 + jx, y as f32 + jy);
            sum += integrator.radiance(camera.origin(), d, 0, &mut rng, scratch);
        }
        sum / spp.max(1) as f32
    })
}

/// Every pixel of the camera's image, rows in parallel, each thread with its own scratch.
fn shade_pixels(
    camera: &PinholeCamera,
    progress: &ProgressBar,
    shade: impl Fn(&mut Scratch, usize, usize) -> Vec3 + Sync,
) -> Image {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut pixels = vec![Vec3::ZERO; w * h];
    // One row per job, so rows of very different cost (a caustic against empty floor) are
    // shared out evenly instead of in rayon's adaptive blocks.
    pixels
        .par_chunks_mut(w)
        .with_max_len(1)
        .enumerate()
        .for_each_init(Scratch::default, |scratch, (y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                *px = shade(scratch, x, y);
            }
            progress.inc(1);
        });
    Image {
        width: w,
        height: h,
        pixels,
    }
}

/// The diffusion kernel's shape where each primary ray first meets a diffuse surface (the
/// paper's Figure 2b as a picture): hue = edge direction `X1` (angle in the surface's tangent
/// frame, modulo 180°), brightness = 1 − λ2. Black where the kernel is round or nothing
/// diffuse is hit. The map must have had the estimate's gradient pass.
pub fn render_kernel_field(
    camera: &PinholeCamera,
    world: &crate::world::World,
    map: &crate::photon::PhotonMap,
    estimate: &crate::estimate::DiffusionEstimate,
) -> Image {
    use crate::world::Surface;
    shade_pixels(camera, &ProgressBar::hidden(), |scratch, x, y| {
        let d = camera.direction(x as f32 + 0.5, y as f32 + 0.5);
        let Some(hit) = world.intersect(camera.origin(), d, 0.0, f32::INFINITY) else {
            return Vec3::ZERO;
        };
        let Surface::Material(m) = hit.surface else {
            return Vec3::ZERO;
        };
        if !matches!(world.material(m), crate::scene::Material::Diffuse { .. }) {
            return Vec3::ZERO;
        }
        let n = if d.dot(hit.geometric_normal) < 0.0 {
            hit.shading_normal
        } else {
            -hit.shading_normal
        };
        let query = crate::estimate::Query {
            position: hit.position,
            normal: n,
        };
        let shape = estimate.kernel_at(map, &query, scratch);
        let (t, b) = crate::sampling::basis(n);
        crate::density::kernel_field::colour(shape.x1.dot(b).atan2(shape.x1.dot(t)), shape.lambda2)
    })
}
