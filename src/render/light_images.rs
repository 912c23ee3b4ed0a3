//! Where a small light's image lies inside a pixel that samples its emission apart, and the
//! emission samples aimed at it. Through glass or in a curved mirror a light is often an
//! image far smaller than the pixel: samples spread over the pixel find it once in
//! thousands, each find thousands of times the pixel's mean, and those finds are the error
//! of a render that has little else left (the torus knot's). Once per render, for each
//! flagged pixel, Newton's method moves a pilot's film point along the pilot's own chain of
//! reflect and refract choices until the chain's last ray passes through a light's centre;
//! the chain's Jacobian there (film offset to miss distance at the light) maps the light's
//! disc back onto the film as an ellipse. Where the ellipse would be larger than the pixel, or
//! no centre is found though the chain met the light near the pixel (a reflection in glass,
//! chosen one time in twenty, is a lottery of its own), the whole pixel along that chain is
//! the target instead. In every pass half of the pixel's emission samples go to the targets,
//! each forced along its chain, and half across the pixel as before, and every sample is
//! weighed by the balance heuristic over both groups (multi-sample importance sampling): the
//! estimate's expectation is the pixel's whatever a target misses, since the spread half
//! covers the whole pixel and every chain. Owns the image search and the samples' placement
//! and weights; must not flag pixels ([`super::pilots`]), trace the emission
//! ([`super::emission`]) or shade.

use super::camera::RayCamera;
use super::integrator::chosen_specular;
use crate::world::{BoundingSphere, Surface, World};
use glam::{Mat2, Vec2, Vec3};

/// Newton steps before a seed is given up.
const MAX_ITERATIONS: usize = 12;
/// Times a Newton step is halved, at most, before its seed is given up.
const MAX_HALVINGS: usize = 6;
/// Film step of the Jacobian's finite differences, in pixels: small beside a pixel, large
/// beside `f32`'s rounding of a film position and of a miss distance.
const DIFFERENCE_STEP: f32 = 1e-2;
/// A chain has found a light's centre when it passes this close, in the light's radii.
const TOLERANCE: f32 = 0.02;
/// Aimed samples cover the linearised image enlarged this many times: the chain bends
/// across the image.
const REACH: f32 = 2.0;
/// An ellipse larger than this (in pixels) is no target: the whole pixel aims at its chain
/// instead.
pub const MAX_ELLIPSE_AREA: f32 = 1.0;
/// Images kept per pixel at most.
pub const MAX_IMAGES: usize = 4;
/// Seeds tried per pixel at most, nearest their light first.
pub const MAX_SEEDS: usize = 4;

/// Where a Newton search starts: a pilot's film point, the chain it followed (reflect and
/// refract choices, first bounce in the highest bit below a leading 1) and the light's
/// bounding sphere its last ray passed nearest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seed {
    pub film: Vec2,
    pub code: u64,
    pub target: BoundingSphere,
    /// The pilot's chain meets the target there.
    pub sees: bool,
    /// The pilot's last ray there (origin, unit direction): Newton's first point, traced.
    pub last_ray: (Vec3, Vec3),
}

/// A light's image on the film, linearised about the film point whose chain passes through
/// the light's centre: the film points whose miss distance `to_miss · (x − centre)` is within
/// `reach` form the ellipse aimed samples fill uniformly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightImage {
    centre: Vec2,
    to_miss: Mat2,
    from_miss: Mat2,
    reach: f32,
    /// 1 / the ellipse's area in pixels: aimed samples' density on the film.
    density: f32,
    /// Not an ellipse but the whole pixel (whose centre is `centre`): the chain is forced,
    /// the film point spread.
    whole: bool,
    /// The chain of choices that sees the light there (as [`Seed::code`]).
    code: u64,
}

impl LightImage {
    /// The image of a light of radius `radius` whose centre chain `code` through `centre`
    /// meets, where moving on the film by `δ` moves the chain's miss distance by
    /// `to_miss · δ`. `None` where the ellipse is degenerate or no smaller than
    /// [`MAX_ELLIPSE_AREA`].
    pub fn new(centre: Vec2, to_miss: Mat2, radius: f32, code: u64) -> Option<Self> {
        let reach = REACH * radius;
        let area = std::f32::consts::PI * reach * reach / to_miss.determinant().abs();
        (area.is_finite() && area > 0.0 && area <= MAX_ELLIPSE_AREA).then(|| Self {
            centre,
            to_miss,
            from_miss: to_miss.inverse(),
            reach,
            density: 1.0 / area,
            whole: false,
            code,
        })
    }

    /// The whole pixel whose corner is `pixel`, seen along chain `code`: where a pilot sees a
    /// light along a chain too unlikely for spread samples to take often (a reflection in
    /// glass) and no ellipse is found for it, or one larger than [`MAX_ELLIPSE_AREA`].
    pub fn whole_pixel(pixel: Vec2, code: u64) -> Self {
        Self {
            centre: pixel + Vec2::splat(0.5),
            to_miss: Mat2::ZERO,
            from_miss: Mat2::ZERO,
            reach: 0.0,
            density: 1.0,
            whole: true,
            code,
        }
    }

    pub fn centre(&self) -> Vec2 {
        self.centre
    }

    /// The ellipse's area in square pixels.
    pub fn area(&self) -> f32 {
        1.0 / self.density
    }

    /// Whether the ellipse's bounding box overlaps the pixel whose corner is `pixel`: no aimed
    /// sample of an image beside the pixel would land in it.
    pub fn meets(&self, pixel: Vec2) -> bool {
        if self.whole {
            return true;
        }
        let half = self.reach
            * Vec2::new(
                self.from_miss.row(0).length(),
                self.from_miss.row(1).length(),
            );
        let (low, high) = (self.centre - half - pixel, self.centre + half - pixel);
        high.cmpgt(Vec2::ZERO).all() && low.cmplt(Vec2::ONE).all()
    }

    /// The film point of unit-square numbers `u`, uniform over the ellipse.
    pub fn point(&self, u: (f32, f32)) -> Vec2 {
        if self.whole {
            return self.centre - Vec2::splat(0.5) + Vec2::new(u.0, u.1);
        }
        let (a, b) = crate::sampling::uniform_disc(u);
        self.centre + self.from_miss * (self.reach * Vec2::new(a, b))
    }

    /// The density of [`Self::point`] at film point `x`, per square pixel.
    pub fn density(&self, x: Vec2) -> f32 {
        if self.whole {
            return 1.0;
        }
        let miss = self.to_miss * (x - self.centre);
        if miss.length_squared() <= self.reach * self.reach {
            self.density
        } else {
            0.0
        }
    }
}

/// How a pixel's `count` emission samples a pass are shared out: samples `0..spread` across
/// the pixel, the rest aimed at its images in turn.
#[derive(Clone, Copy, Debug)]
pub struct Aim<'a> {
    images: &'a [LightImage],
    count: u32,
    spread: u32,
}

impl<'a> Aim<'a> {
    /// Half the samples aim where there are images (the odd one spreads); none otherwise.
    pub fn new(images: &'a [LightImage], count: u32) -> Self {
        let aimed = if images.is_empty() { 0 } else { count / 2 };
        Self {
            images,
            count,
            spread: count - aimed,
        }
    }

    /// Whether any sample aims at an image.
    pub fn aims(&self) -> bool {
        self.spread < self.count
    }

    /// Sample `j`'s film point in the pixel whose corner is `pixel`, from unit-square numbers
    /// `u`, and the chain an aimed sample follows (a spread one draws its own); `None` where
    /// an aimed sample falls outside the pixel (it counts, as a zero).
    pub fn point(&self, j: u32, u: (f32, f32), pixel: Vec2) -> Option<(Vec2, Option<u64>)> {
        if j < self.spread {
            return Some((pixel + Vec2::new(u.0, u.1), None));
        }
        let image = &self.images[(j - self.spread) as usize % self.images.len()];
        let x = image.point(u);
        let inside = (x - pixel).cmpge(Vec2::ZERO).all() && (x - pixel).cmplt(Vec2::ONE).all();
        inside.then_some((x, Some(image.code)))
    }

    /// What a sample's value at film point `x` (inside the pixel) is multiplied by, its
    /// chain `code` having had `probability` there (the product of its Fresnel choices'):
    /// the balance heuristic over the spread samples (film density 1, the pixel's area being
    /// 1, times that probability) and the images of that chain, so that the sum over the
    /// pass's samples estimates the pixel's mean.
    pub fn weight(&self, x: Vec2, code: u64, probability: f32) -> f32 {
        let aimed = self.count - self.spread;
        let k = self.images.len() as u32;
        let mut aimed_density = 0.0;
        for (i, image) in self.images.iter().enumerate() {
            if image.code == code {
                let share = aimed / k + u32::from((i as u32) < aimed % k);
                aimed_density += share as f32 * image.density(x);
            }
        }
        let denominator = self.spread as f32 * probability + aimed_density;
        if denominator > 0.0 {
            probability / denominator
        } else {
            0.0
        }
    }
}

/// The images that `seeds` lead to from the pixel whose film corner is `pixel`, at most
/// [`MAX_IMAGES`], none twice.
pub fn find(world: &World, camera: &RayCamera, pixel: Vec2, seeds: &[Seed]) -> Vec<LightImage> {
    let mut images: Vec<LightImage> = Vec::new();
    for seed in seeds {
        if images.len() == MAX_IMAGES {
            break;
        }
        let image = solve(world, camera, pixel, seed)
            .filter(|i| i.meets(pixel))
            .or_else(|| seed.sees.then(|| LightImage::whole_pixel(pixel, seed.code)));
        if let Some(image) = image
            && !images.iter().any(|i| {
                if image.whole || i.whole {
                    image.whole == i.whole && image.code == i.code
                } else {
                    image.density(i.centre) > 0.0
                }
            })
        {
            images.push(image);
        }
    }
    images
}

/// The choices of chain `code` (as [`Seed::code`]), first bounce first: refract or not.
pub fn chain_choices(code: u64) -> impl ExactSizeIterator<Item = bool> {
    (0..63 - code.max(1).leading_zeros())
        .rev()
        .map(move |i| (code >> i) & 1 == 1)
}

/// The last ray (origin, unit direction) of the chain of choices `code` through film point
/// `film`, or `None` where the chain cannot be followed there (it meets a light, a diffuse
/// surface or nothing early, or totally reflects where it should refract).
pub fn chain_end(world: &World, camera: &RayCamera, film: Vec2, code: u64) -> Option<(Vec3, Vec3)> {
    let ray = camera.chief_ray(film.x, film.y);
    let (mut origin, mut dir) = (ray.origin, ray.direction);
    for refracts in chain_choices(code) {
        let hit = world.intersect(origin, dir, 0.0, f32::INFINITY)?;
        let Surface::Material(m) = hit.surface else {
            return None;
        };
        let (ng, ns) = hit.facing(dir);
        let (next, _, _) = chosen_specular(&world.material_at(m, &hit), &hit, dir, ns, refracts)?;
        let side = if next.dot(ng) >= 0.0 { ng } else { -ng };
        origin = world.offset_from(&hit, side);
        dir = next;
    }
    Some((origin, dir))
}

/// The image `seed` leads to from the pixel whose film corner is `pixel`: an ellipse where
/// Newton's method finds the film point whose chain passes through the target's centre
/// ([`newton`]), the whole pixel along the seed's chain where it finds none but the chain
/// meets the target's disc in or near the pixel (at the pilot, or at a Newton step).
fn solve(world: &World, camera: &RayCamera, pixel: Vec2, seed: &Seed) -> Option<LightImage> {
    let touched = std::cell::Cell::new(seed.sees);
    newton(world, camera, pixel, seed, &touched).or_else(|| {
        touched
            .get()
            .then(|| LightImage::whole_pixel(pixel, seed.code))
    })
}

/// Newton's method from `seed` to the film point whose chain passes through the target's
/// centre, within a pixel of the pixel at `pixel`; the image there, if its chain's last ray
/// meets a light. Sets `touched` where a step's chain, within half a pixel of the pixel,
/// meets the target.
fn newton(
    world: &World,
    camera: &RayCamera,
    pixel: Vec2,
    seed: &Seed,
    touched: &std::cell::Cell<bool>,
) -> Option<LightImage> {
    let (centre, radius) = (seed.target.center, seed.target.radius);
    let first = seed.last_ray;
    let (t1, t2) = crate::sampling::basis(first.1);
    // The target's centre's offset from the chain's last line, across the first direction.
    let offset = |(o, d): (Vec3, Vec3)| -> Option<Vec2> {
        let to = centre - o;
        let along = to.dot(d);
        let off = to - along * d;
        (along > 0.0).then(|| Vec2::new(off.dot(t1), off.dot(t2)))
    };
    let miss = |x: Vec2| offset(chain_end(world, camera, x, seed.code)?);
    let within = |x: Vec2, low: f32, high: f32| {
        (x - pixel).cmpge(Vec2::splat(low)).all() && (x - pixel).cmple(Vec2::splat(high)).all()
    };
    let mut x = seed.film;
    let mut r = offset(first)?;
    for _ in 0..MAX_ITERATIONS {
        // Within half a pixel, an image met there likely crosses into the pixel.
        if r.length() <= radius && within(x, -0.5, 1.5) {
            touched.set(true);
        }
        let h = DIFFERENCE_STEP;
        let jacobian = Mat2::from_cols(
            (miss(x + Vec2::new(h, 0.0))? - r) / h,
            (miss(x + Vec2::new(0.0, h))? - r) / h,
        );
        if r.length() <= TOLERANCE * radius {
            let (o, d) = chain_end(world, camera, x, seed.code)?;
            let lit = world.intersect(o, d, 0.0, f32::INFINITY)?;
            return match lit.surface {
                Surface::Light(_) => Some(
                    LightImage::new(x, jacobian, radius, seed.code)
                        .unwrap_or_else(|| LightImage::whole_pixel(pixel, seed.code)),
                ),
                Surface::Material(_) => None,
            };
        }
        let det = jacobian.determinant();
        if !(det.is_finite() && det != 0.0) {
            return None;
        }
        let step = -(jacobian.inverse() * r);
        // A solution the linear chain puts far from the pixel is given up at once (most
        // seeds); nearer, at most a pixel a step, where the chain is not yet linear.
        if !within(x + step, -1.0, 2.0) {
            return None;
        }
        // Halved until the miss shrinks: the chain's derivative jumps across triangles.
        let mut step = step / step.length().max(1.0);
        let mut closer = None;
        for _ in 0..MAX_HALVINGS {
            if let Some(next) = miss(x + step)
                && next.length() < r.length()
            {
                closer = Some(next);
                break;
            }
            step *= 0.5;
        }
        r = closer?;
        x += step;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_samples_its_own_ellipse_at_its_density() {
        let to_miss = Mat2::from_cols(Vec2::new(3.0, 1.0), Vec2::new(-0.5, 2.0));
        let image = LightImage::new(Vec2::new(10.3, 20.6), to_miss, 0.05, 1).unwrap();
        let area = std::f32::consts::PI * 0.01 / to_miss.determinant();
        assert!((image.area() - area).abs() < 1e-6 * area);
        let mut rng = crate::sampling::Rng::for_index(7, crate::sampling::Stream::Pixels, 0);
        for _ in 0..1000 {
            let x = image.point(rng.next_2d());
            assert!((to_miss * (x - image.centre())).length() <= 0.1 * (1.0 + 1e-5));
        }
        assert_eq!(image.density(image.centre() + Vec2::new(0.5, 0.0)), 0.0);
        assert!(
            LightImage::new(Vec2::ZERO, Mat2::IDENTITY, 1.0, 1).is_none(),
            "too large"
        );
        let whole = LightImage::whole_pixel(Vec2::new(3.0, 4.0), 1);
        assert_eq!(whole.point((0.25, 0.5)), Vec2::new(3.25, 4.5));
        assert_eq!(
            (whole.area(), whole.density(Vec2::new(3.9, 4.1))),
            (1.0, 1.0)
        );
        assert!(
            LightImage::new(Vec2::ZERO, Mat2::ZERO, 0.01, 1).is_none(),
            "degenerate"
        );
    }

    /// The pixel (5, 7) holds a disc of radius 0.01 at (5.42, 7.77) where chain 2 (a
    /// reflection, chosen one time in ten) sees a light of radiance 1000; chain 3 (the
    /// refraction) sees nothing. A sample at `x` along `along`, or a chain it draws: (value,
    /// code, probability).
    fn speck(x: Vec2, along: Option<u64>, rng: &mut crate::sampling::Rng) -> (f32, u64, f32) {
        let code = along.unwrap_or(if rng.next_f32() < 0.1 { 2 } else { 3 });
        let lit = code == 2 && (x - Vec2::new(5.42, 7.77)).length() < 0.01;
        let probability = if code == 2 { 0.1 } else { 0.9 };
        (if lit { 1000.0 } else { 0.0 }, code, probability)
    }

    /// The mean of `passes` estimates of [`speck`]'s pixel mean with `count` samples a pass
    /// aimed by `images`, and their standard deviation.
    fn estimates(images: &[LightImage], count: u32, passes: u32) -> (f64, f64) {
        let aim = Aim::new(images, count);
        let pixel = Vec2::new(5.0, 7.0);
        let mut rng = crate::sampling::Rng::for_index(3, crate::sampling::Stream::Pixels, 0);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..passes {
            let mut e = 0.0f64;
            for j in 0..count {
                if let Some((x, along)) = aim.point(j, rng.next_2d(), pixel) {
                    let (value, code, probability) = speck(x, along, &mut rng);
                    e += (value * aim.weight(x, code, probability)) as f64;
                }
            }
            sum += e;
            sum2 += e * e;
        }
        let mean = sum / passes as f64;
        (mean, (sum2 / passes as f64 - mean * mean).max(0.0).sqrt())
    }

    #[test]
    fn aimed_samples_keep_the_pixels_mean_and_cut_its_noise() {
        let exact = 0.1 * 1000.0 * std::f64::consts::PI * 1e-4;
        // The speck's own ellipse (its radius reached twice over), one off by a third of
        // that reach, one half outside the pixel, one elsewhere beside it; the whole pixel
        // along the speck's chain; the speck's place along the chain that sees nothing there.
        let at = |c: Vec2, code| LightImage::new(c, Mat2::IDENTITY, 0.01, code).unwrap();
        let on = at(Vec2::new(5.42, 7.77), 2);
        let off = at(Vec2::new(5.4267, 7.77), 2);
        let edge = at(Vec2::new(5.0, 7.5), 2);
        let elsewhere = at(Vec2::new(5.8, 7.2), 2);
        let whole = LightImage::whole_pixel(Vec2::new(5.0, 7.0), 2);
        let refracted = at(Vec2::new(5.42, 7.77), 3);
        let passes = 200_000;
        let (spread_mean, spread_sd) = estimates(&[], 16, passes);
        let tolerance = 4.0 * spread_sd / (passes as f64).sqrt();
        assert!((spread_mean - exact).abs() < tolerance);
        for (images, gain) in [
            (vec![on], 0.05),
            (vec![off], 0.05),
            (vec![edge, on], 0.05),
            (vec![elsewhere, off, on], 0.05),
            (vec![refracted, on], 0.05),
            // Forcing the rare chain over the pixel: the chain's lottery gone, the film's kept.
            (vec![whole], 0.5),
        ] {
            let (mean, sd) = estimates(&images, 16, passes);
            let tolerance = 4.0 * sd / (passes as f64).sqrt();
            assert!(
                (mean - exact).abs() < tolerance,
                "{mean} vs {exact} ± {tolerance}"
            );
            assert!(sd < gain * spread_sd, "{sd} against {spread_sd}");
        }
        // Images that miss the speck aim in vain but keep the mean.
        for images in [vec![elsewhere], vec![refracted]] {
            let (mean, sd) = estimates(&images, 16, passes);
            assert!((mean - exact).abs() < 4.0 * sd / (passes as f64).sqrt());
        }
    }

    #[test]
    fn an_image_meets_the_pixels_its_ellipse_overlaps() {
        // Reach 0.2 pixels round (20.3, 11.1), stretched threefold along x.
        let to_miss = Mat2::from_diagonal(Vec2::new(1.0 / 3.0, 1.0));
        let image = LightImage::new(Vec2::new(20.3, 11.1), to_miss, 0.1, 1).unwrap();
        assert!(image.meets(Vec2::new(20.0, 11.0)));
        assert!(image.meets(Vec2::new(19.0, 11.0)), "0.6 reaches x = 19.7");
        assert!(image.meets(Vec2::new(20.0, 10.0)), "0.2 reaches y = 10.9");
        assert!(
            !image.meets(Vec2::new(21.0, 11.0)),
            "0.9 falls short of x = 21"
        );
        assert!(!image.meets(Vec2::new(20.0, 12.0)));
        assert!(!image.meets(Vec2::new(18.0, 11.0)));
        assert!(LightImage::whole_pixel(Vec2::new(3.0, 4.0), 1).meets(Vec2::new(3.0, 4.0)));
    }
}
