//! The camera as the renderer uses it: [`RayCamera`] turns a position on the film (and a point
//! on the lens) into a primary ray for each of dpm's cameras — perspective, orthographic (each
//! with an optional thin lens) and pbrt-v3's lat-long environment camera — says which film
//! pixels are rendered (the crop window) and whether a point lies in view. Where a pixel's
//! samples go is [`samples`]' ([`PassSamples`]). Owns the projection; must not trace, shade
//! or accumulate.
//!
//! Positions are full-film pixel coordinates, (0, 0) the film's top-left corner, whatever the
//! crop: a crop renders exactly the full render's pixels, since every pixel keys its samples
//! by its full-film index ([`RayCamera::pixel_key`]) and what looks at the view as a whole (the
//! caustic guide's [`RayCamera::sees`], its grid of chief rays) sees the full film.

mod samples;
#[cfg(test)]
mod tests;

pub use samples::{CameraSample, EmissionSample, PassSamples};

use crate::sampling::uniform_disc;
use crate::scene::{self, Handedness, Projection, ThinLens};
use glam::Vec3;
use std::f32::consts::PI;

/// One primary ray: `direction` is unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraRay {
    pub origin: Vec3,
    pub direction: Vec3,
}

/// How film positions become rays, with what each kind precomputes.
#[derive(Clone, Copy, Debug)]
enum Optics {
    /// `tan_half`: the tangent of half the vertical field of view.
    Perspective {
        tan_half: f32,
    },
    /// `half_height`: half the film's world-space height.
    Orthographic {
        half_height: f32,
    },
    Environment,
}

/// A scene camera made ready to shoot rays (see the module's notes on coordinates).
#[derive(Clone, Copy, Debug)]
pub struct RayCamera {
    origin: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    optics: Optics,
    lens: ThinLens,
    /// The full film, in pixels.
    film_width: u32,
    film_height: u32,
    /// The rendered pixels `[x0, x1, y0, y1]` of the full film.
    crop: [u32; 4],
}

impl RayCamera {
    pub fn new(c: &scene::Camera) -> Self {
        let forward = (c.look_at - c.position).normalize();
        let right_handed = forward.cross(c.up).normalize();
        let up = right_handed.cross(forward);
        let right = match c.handedness {
            Handedness::Right => right_handed,
            Handedness::Left => -right_handed,
        };
        let optics = match c.projection {
            Projection::Perspective { fov_y_degrees } => Optics::Perspective {
                tan_half: (fov_y_degrees.to_radians() * 0.5).tan(),
            },
            Projection::Orthographic { view_height } => Optics::Orthographic {
                half_height: 0.5 * view_height,
            },
            Projection::Environment => Optics::Environment,
        };
        Self {
            origin: c.position,
            forward,
            right,
            up,
            optics,
            lens: c.lens,
            film_width: c.width,
            film_height: c.height,
            crop: c.crop_pixels(),
        }
    }

    /// The rendered image's width in pixels (the crop's).
    pub fn width(&self) -> usize {
        (self.crop[1] - self.crop[0]) as usize
    }

    /// The rendered image's height in pixels (the crop's).
    pub fn height(&self) -> usize {
        (self.crop[3] - self.crop[2]) as usize
    }

    /// The full film's size in pixels, which the projection spans.
    pub fn film_size(&self) -> (usize, usize) {
        (self.film_width as usize, self.film_height as usize)
    }

    /// The full-film pixel of the rendered image's pixel (`x`, `y`) (also its corners: `x` up
    /// to the width).
    pub fn film_pixel(&self, x: usize, y: usize) -> (usize, usize) {
        (x + self.crop[0] as usize, y + self.crop[2] as usize)
    }

    /// The number a pixel's samples are keyed by: its row-major index in the full film, so
    /// that a crop's pixels draw what the full render's do.
    pub fn pixel_key(&self, x: usize, y: usize) -> u64 {
        let (fx, fy) = self.film_pixel(x, y);
        (fy * self.film_width as usize + fx) as u64
    }

    /// The ray through full-film position (`x`, `y`) in pixels and lens sample `lens` in
    /// [0, 1)² (unused without a lens).
    pub fn ray(&self, x: f32, y: f32, lens: (f32, f32)) -> CameraRay {
        let (w, h) = (self.film_width as f32, self.film_height as f32);
        let aspect = w / h;
        let pinhole = self.lens.radius == 0.0;
        match self.optics {
            Optics::Perspective { tan_half } => {
                let u = (2.0 * x / w - 1.0) * tan_half * aspect;
                let v = (1.0 - 2.0 * y / h) * tan_half;
                let through = self.forward + u * self.right + v * self.up;
                if pinhole {
                    return CameraRay {
                        origin: self.origin,
                        direction: through.normalize(),
                    };
                }
                // `through` is one unit deep: the focal plane meets it at focal_distance times.
                let offset = self.lens_offset(lens);
                CameraRay {
                    origin: self.origin + offset,
                    direction: (self.lens.focal_distance * through - offset).normalize(),
                }
            }
            Optics::Orthographic { half_height } => {
                let u = (2.0 * x / w - 1.0) * half_height * aspect;
                let v = (1.0 - 2.0 * y / h) * half_height;
                let on_film = self.origin + u * self.right + v * self.up;
                if pinhole {
                    return CameraRay {
                        origin: on_film,
                        direction: self.forward,
                    };
                }
                // pbrt-v4's: from the lens point beside the film point, to the film point's
                // image on the focal plane (pbrt-v3 leaves the film point out of the origin).
                let offset = self.lens_offset(lens);
                CameraRay {
                    origin: on_film + offset,
                    direction: (self.lens.focal_distance * self.forward - offset).normalize(),
                }
            }
            Optics::Environment => {
                let theta = PI * y / h;
                let phi = 2.0 * PI * x / w;
                let (sin_theta, cos_theta) = theta.sin_cos();
                let (sin_phi, cos_phi) = phi.sin_cos();
                let direction = sin_theta * cos_phi * self.right
                    + cos_theta * self.up
                    + sin_theta * sin_phi * self.forward;
                CameraRay {
                    origin: self.origin,
                    direction: direction.normalize(),
                }
            }
        }
    }

    /// The ray through full-film position (`x`, `y`) and the lens's centre: what pilots,
    /// probes and surveys follow, one ray standing for the pixel's whole aperture.
    pub fn chief_ray(&self, x: f32, y: f32) -> CameraRay {
        let pinhole = Self {
            lens: ThinLens {
                radius: 0.0,
                ..self.lens
            },
            ..*self
        };
        pinhole.ray(x, y, (0.0, 0.0))
    }

    /// The lens point of sample `u`, as an offset from the lens's centre (polar mapping: area
    /// preserving, so stratified samples stay stratified over the disc).
    fn lens_offset(&self, u: (f32, f32)) -> Vec3 {
        let (a, b) = uniform_disc(u);
        self.lens.radius * (a * self.right + b * self.up)
    }

    /// Whether `point` lies in the full film's view (in front of the camera, within the
    /// image's bounds widened by the lens's circle of confusion at the point's depth; not
    /// whether something hides it).
    pub fn sees(&self, point: Vec3) -> bool {
        let d = point - self.origin;
        let aspect = self.film_width as f32 / self.film_height as f32;
        match self.optics {
            Optics::Perspective { tan_half } => {
                let depth = d.dot(self.forward);
                // The lens images the point to a disc of this radius on the plane one unit deep.
                let blur = self.lens.radius * (1.0 / self.lens.focal_distance - 1.0 / depth).abs();
                let (half_u, half_v) = (tan_half * aspect, tan_half);
                // As the pinhole camera always computed it: a guide's landings keep their worth.
                let u = d.dot(self.right) / (depth * tan_half * aspect);
                let v = d.dot(self.up) / (depth * tan_half);
                // A NaN depth (a point at infinity) fails every comparison.
                depth > 0.0 && u.abs() <= 1.0 + blur / half_u && v.abs() <= 1.0 + blur / half_v
            }
            Optics::Orthographic { half_height } => {
                let depth = d.dot(self.forward);
                // The rays reaching the point start within this of the film point it images to.
                let blur = self.lens.radius * (1.0 - depth / self.lens.focal_distance).abs();
                depth >= 0.0
                    && d.dot(self.right).abs() <= half_height * aspect + blur
                    && d.dot(self.up).abs() <= half_height + blur
            }
            // The film covers every direction.
            Optics::Environment => d.is_finite() && d != Vec3::ZERO,
        }
    }
}
