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

use super::camera::RayCamera;
use super::light_images::{self, LightImage, Seed};
use crate::optics::{fresnel_dielectric, reflect, refract};
use crate::scene::Material;
use crate::world::lights::LightShape;
use crate::world::{BoundingSphere, Surface, World};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

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

/// Branches a pilot follows at most; past them its pixel counts as seeing a light and as
/// holding an edge (a maze of glass).
const MAX_PILOT_BRANCHES: usize = 64;
/// Fresnel weight below which a pilot's branch is not followed: a light seen there would
/// still be `1e-3` of its radiance, but chains that thin are many and each adds a ray.
const MIN_BRANCH_WEIGHT: f32 = 1e-3;
/// How far beyond the pilots' own spread a light may lie and still flag the pixel: the
/// directions across a pixel curve between its pilots on a curved mirror.
const SPREAD_MARGIN: f32 = 1.5;
/// Normals of one object further apart than this (cos 30°) across a pixel make an edge.
const CREASE_COS: f32 = 0.866;
/// Light points a pilot's diffuse hit tests for visibility, at most (the first lights').
const MAX_VISIBILITY_BITS: usize = 64;

/// What the pilots share: the lights' visible bounds and the points their shadows are
/// tested against.
struct Survey<'w> {
    world: &'w World,
    max_depth: u32,
    /// Spheres round the lights a camera can see.
    visible: Vec<BoundingSphere>,
    /// One point on each light whose visibility tells a shadow's edge.
    probes: Vec<Probe>,
}

/// Where a pilot's shadow ray is aimed: a point on a light, or a direction to infinity.
#[derive(Clone, Copy, Debug)]
enum Probe {
    Point(Vec3),
    /// A sphere light: the point of its surface nearest the hit.
    Sphere {
        center: Vec3,
        radius: f32,
    },
    Direction(Vec3),
}

impl<'w> Survey<'w> {
    fn new(world: &'w World, max_depth: u32) -> Self {
        let shapes: Vec<LightShape> = world.light_sources.iter().map(|l| l.shape()).collect();
        let visible = shapes.iter().flat_map(visible_bounds).collect();
        let probes = shapes.iter().filter_map(shadow_probe).collect();
        Self {
            world,
            max_depth,
            visible,
            probes,
        }
    }

    fn pilot(&self, origin: Vec3, dir: Vec3) -> Pilot {
        let world = self.world;
        let mut pilot = Pilot::default();
        // (origin, direction, depth, Fresnel weight, branch code).
        let mut branches = vec![(origin, dir, 0u32, 1.0f32, BranchCode::ROOT)];
        let mut last_rays: Vec<(Vec3, Vec3, BranchCode)> = Vec::new();
        let mut followed = 0;
        while let Some((o, d, depth, weight, code)) = branches.pop() {
            followed += 1;
            if followed > MAX_PILOT_BRANCHES {
                pilot.tangled = true;
                break;
            }
            let Some(closest) = world.closest_hit(o, d, 0.0, f32::INFINITY) else {
                // A constant environment gives every leaving ray the same radiance: a camera
                // sample sees it exactly, through glass split as camera paths split it, with no
                // lottery to take apart. An image environment's bright texels (a sun) are one.
                pilot.emitting +=
                    u32::from(world.has_sky_map() && world.background(d) != Vec3::ZERO);
                pilot.shape.add(u64::MAX);
                last_rays.push((o, d, code));
                continue;
            };
            pilot.shape.add(closest.geometry());
            let m = match closest.surface {
                Surface::Light(_) => {
                    pilot.emitting += 1;
                    last_rays.push((o, d, code));
                    continue;
                }
                Surface::Material(m) => m,
            };
            let hit = world.resolve(closest);
            let (ng, ns) = hit.facing(d);
            let spawn = |next: Vec3| {
                let side = if next.dot(ng) >= 0.0 { ng } else { -ng };
                hit.position + side * world.ray_epsilon()
            };
            match &world.material_at(m, &hit) {
                // A camera path reads the photon maps at a BSDF's Lambert lobes and follows
                // its other lobes stochastically: the pilot stops there as at a diffuse one
                // (`material_at` never gives a mix).
                Material::Diffuse { .. } | Material::Bsdf(_) | Material::Mix { .. } => {
                    last_rays.push((o, d, code));
                    if pilot.normal.is_none() {
                        pilot.normal = Some(ns);
                        pilot.visible = self.visibility(spawn(ns), ns);
                    }
                }
                // Camera paths see nothing past the depth limit.
                _ if depth >= self.max_depth => {}
                Material::Mirror { tint } => {
                    if tint.max_element() > 0.0 {
                        let r = reflect(d, ns);
                        branches.push((spawn(r), r, depth + 1, weight, code.then(0)));
                    }
                }
                Material::Glass { ior, .. } => {
                    let eta = if hit.entering(d) { 1.0 / ior } else { *ior };
                    let f = fresnel_dielectric(-d.dot(ns), eta);
                    if f * weight >= MIN_BRANCH_WEIGHT {
                        let r = reflect(d, ns);
                        branches.push((spawn(r), r, depth + 1, f * weight, code.then(0)));
                    }
                    let refracted = refract(d, ns, eta).filter(|_| f < 1.0);
                    match refracted {
                        Some(t) if (1.0 - f) * weight >= MIN_BRANCH_WEIGHT => {
                            let next = (spawn(t), t, depth + 1, (1.0 - f) * weight, code.then(1));
                            branches.push(next);
                        }
                        // Total internal reflection, or a branch too thin: the shape says so.
                        _ => pilot.shape.add(u64::MAX - 1),
                    }
                }
            }
        }
        pilot.last_rays = (last_rays.iter())
            .map(|&(o, d, code)| {
                let (light, light_gap) = (self.visible.iter())
                    .map(|light| gap_to_sphere(o, d, light))
                    .enumerate()
                    .fold((u32::MAX, f32::INFINITY), |best, (i, gap)| {
                        if gap < best.1 { (i as u32, gap) } else { best }
                    });
                LastRay {
                    code,
                    origin: o,
                    direction: d,
                    light_gap,
                    light,
                }
            })
            .collect();
        pilot
    }

    /// Where a pixel's search for light images starts: its pilots' last rays (each pilot
    /// with its offset in the pixel whose film corner is `corner`), one per chain and light,
    /// nearest the light first.
    fn seeds(&self, pilots: &[(&Pilot, Vec2); 5], corner: Vec2) -> Vec<Seed> {
        let rays = || pilots.iter().flat_map(|(p, _)| p.last_rays.iter());
        let whole = widest(rays());
        let mut near: Vec<(&LastRay, Vec2)> = (pilots.iter())
            .flat_map(|(p, offset)| p.last_rays.iter().map(move |r| (r, *offset)))
            .filter(|(r, _)| r.light != u32::MAX && r.light_gap <= SPREAD_MARGIN * whole)
            .collect();
        near.sort_by(|a, b| a.0.light_gap.total_cmp(&b.0.light_gap));
        let mut seeds: Vec<(Seed, u32)> = Vec::new();
        for (ray, offset) in near {
            if seeds.len() == light_images::MAX_SEEDS {
                break;
            }
            if seeds
                .iter()
                .any(|(s, l)| s.code == ray.code.0 && *l == ray.light)
            {
                continue;
            }
            // As for the flag: a light further from a ray than its branch's spread across
            // the pixel allows is seen elsewhere, and Newton's method would leave the pixel.
            let matched =
                (pilots.iter()).all(|(p, _)| p.last_rays.iter().any(|r| r.code == ray.code));
            if matched
                && ray.light_gap > SPREAD_MARGIN * widest(rays().filter(|r| r.code == ray.code))
            {
                continue;
            }
            let seed = Seed {
                film: corner + offset,
                code: ray.code.0,
                target: self.visible[ray.light as usize],
                sees: ray.light_gap <= 0.0,
                last_ray: (ray.origin, ray.direction),
            };
            seeds.push((seed, ray.light));
        }
        seeds.into_iter().map(|(s, _)| s).collect()
    }

    /// Which of the lights' probe points the diffuse point `p` (normal `n`) sees, one bit each.
    fn visibility(&self, p: Vec3, n: Vec3) -> u64 {
        let mut bits = 0u64;
        let mut bit = 0;
        let mut test = |target: Option<(Vec3, f32)>| {
            if bit < MAX_VISIBILITY_BITS
                && let Some((dir, distance)) = target
                && n.dot(dir) > 0.0
                && !self.world.occluded(p, dir, 0.0, distance * (1.0 - 1e-4))
            {
                bits |= 1 << bit;
            }
            bit += 1;
        };
        let towards = |q: Vec3| {
            let v = q - p;
            let distance = v.length();
            (distance > 0.0).then(|| (v / distance, distance))
        };
        for probe in &self.probes {
            match *probe {
                Probe::Point(q) => test(towards(q)),
                Probe::Direction(d) => test(Some((d, f32::INFINITY))),
                // The ray stops short of the light's own surface, as shadow rays do.
                Probe::Sphere { center, radius } => test(towards(
                    center + radius * (p - center).normalize_or(Vec3::Z),
                )),
            }
        }
        bits
    }
}

/// Spheres whose union holds the part of a light the eye can see, hugging it closely enough
/// that a ray passing near one passes near the light: a sphere light itself, a quad's 4 × 4
/// cells, a mesh light's triangles; none for lights the eye cannot see (points, spots,
/// distant lights; the environment is seen by every ray that leaves the scene).
fn visible_bounds(shape: &LightShape) -> Vec<BoundingSphere> {
    match shape {
        LightShape::Sphere(s) => vec![*s],
        LightShape::Quad {
            corner,
            edge_u,
            edge_v,
        } => {
            // Cells small enough that a quad seen edge-on (a ceiling light) is not flagged
            // in a band as tall as the quad is wide.
            const CELLS: usize = 4;
            let (u, v) = (*edge_u / CELLS as f32, *edge_v / CELLS as f32);
            let radius = 0.5 * (u + v).length().max((u - v).length());
            (0..CELLS * CELLS)
                .map(|c| BoundingSphere {
                    center: *corner
                        + (c % CELLS) as f32 * u
                        + (c / CELLS) as f32 * v
                        + 0.5 * (u + v),
                    radius,
                })
                .collect()
        }
        LightShape::Mesh { spheres, .. } => spheres.clone(),
        LightShape::Point(_) | LightShape::Direction(_) | LightShape::Everywhere => Vec::new(),
    }
}

/// The one point (or direction) of a light that a pilot's shadow ray tests: a point or spot
/// light's position, a distant light's direction, a sphere's surface nearest the hit, a
/// quad's centre, a point of a mesh light's largest triangle; none for the environment.
/// Where one pilot sees it and another does not, a shadow's middle crosses the pixel: a
/// small light's shadow steps there. A large light's penumbra is smooth across many pixels
/// (the light samples' business); its middle alone is flagged.
fn shadow_probe(shape: &LightShape) -> Option<Probe> {
    match shape {
        LightShape::Point(p) => Some(Probe::Point(*p)),
        LightShape::Direction(d) => Some(Probe::Direction(*d)),
        LightShape::Sphere(s) => Some(Probe::Sphere {
            center: s.center,
            radius: s.radius,
        }),
        LightShape::Quad {
            corner,
            edge_u,
            edge_v,
        } => Some(Probe::Point(*corner + 0.5 * (*edge_u + *edge_v))),
        LightShape::Mesh { point, .. } => point.map(Probe::Point),
        LightShape::Everywhere => None,
    }
}

/// Which branch of a pilot's chains a ray is on: the reflected (0) and refracted (1) choices
/// at each bounce so far, and how many, so that the same branch of neighbouring pilots can be
/// compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct BranchCode(u64);

impl BranchCode {
    const ROOT: BranchCode = BranchCode(1);

    /// The branch one bounce on, `choice` 0 or 1 (a leading 1 bit keeps depths apart; past
    /// 63 bounces codes wrap, which only makes two branches look alike).
    fn then(self, choice: u64) -> BranchCode {
        BranchCode(self.0.wrapping_shl(1) | choice)
    }
}

/// The last ray of one branch of a pilot's chains.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LastRay {
    code: BranchCode,
    origin: Vec3,
    direction: Vec3,
    /// How near it passes a light's bounding sphere ([`gap_to_sphere`]: at most the angle in
    /// radians; negative inside the sphere; infinite without visible lights).
    light_gap: f32,
    /// Which of the visible spheres that gap is to (`u32::MAX`: none).
    light: u32,
}

/// What one pilot ray learns.
#[derive(Clone, Debug, PartialEq)]
struct Pilot {
    /// The chains' last rays, one per branch followed to its end.
    last_rays: Vec<LastRay>,
    /// Last rays that meet a light, or leave the scene under an image environment.
    emitting: u32,
    /// The chains were too many to follow.
    tangled: bool,
    /// The objects met along the chains, in order, hashed.
    shape: ShapeHash,
    /// The shading normal at the first diffuse hit.
    normal: Option<Vec3>,
    /// The light probes visible from the first diffuse hit, one bit each.
    visible: u64,
}

impl Default for Pilot {
    fn default() -> Self {
        Self {
            last_rays: Vec::new(),
            emitting: 0,
            tangled: false,
            shape: ShapeHash(0xCBF2_9CE4_8422_2325),
            normal: None,
            visible: 0,
        }
    }
}

/// FNV-1a over the objects a pilot's chains meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct ShapeHash(u64);

impl ShapeHash {
    fn add(&mut self, word: u64) {
        for byte in word.to_le_bytes() {
            self.0 = (self.0 ^ byte as u64).wrapping_mul(0x100_0000_01B3);
        }
    }
}

/// How near the ray from `o` along unit `d` passes `sphere`: `sin θ − sin α` for a sphere
/// in front, θ the angle between `d` and the sphere's centre and α its angular radius, which
/// is never more than the angle `θ − α` between the ray and the sphere's silhouette (so a
/// test against an angle errs towards flagging), without an inverse sine or cosine per
/// sphere; `1 − sin α` for a sphere behind (at least a right angle away), −1 inside it.
fn gap_to_sphere(o: Vec3, d: Vec3, sphere: &BoundingSphere) -> f32 {
    let to = sphere.center - o;
    let dist = to.length();
    if dist <= sphere.radius {
        return -1.0;
    }
    let sin_radius = sphere.radius / dist;
    if d.dot(to) <= 0.0 {
        return 1.0 - sin_radius;
    }
    d.cross(to).length() / dist - sin_radius
}

/// Whether a pixel with these pilots (its centre and corners) samples its emitted light
/// apart. Yes where the chains were too many to follow. No where every last ray of every
/// pilot meets a light (the pixel lies inside the light's image: each camera sample sees it,
/// no lottery). Yes where some last ray meets a light (its image's edge crosses the pixel).
/// Otherwise yes where a light lies within the pixel's spread of a last ray, with a margin:
/// an image smaller than the pilots' spacing may lie between them. The spread of a branch is
/// the widest angle between the last rays of that branch across the five pilots; a branch
/// that some pilot lacks (a silhouette or a total reflection's edge inside the pixel) takes
/// the widest angle between any two last rays of the pixel.
fn sees_emission(pilots: &[&Pilot; 5]) -> bool {
    if pilots.iter().any(|p| p.tangled) {
        return true;
    }
    if pilots
        .iter()
        .all(|p| !p.last_rays.is_empty() && p.emitting as usize == p.last_rays.len())
    {
        return false;
    }
    if pilots.iter().any(|p| p.emitting > 0) {
        return true;
    }
    let rays = || pilots.iter().flat_map(|p| p.last_rays.iter());
    let gap = rays().map(|r| r.light_gap).fold(f32::INFINITY, f32::min);
    if !gap.is_finite() {
        return false;
    }
    // The pixel's widest angle bounds every branch's spread: most pixels stop here.
    let whole = widest(rays());
    for ray in rays().filter(|r| r.light_gap <= SPREAD_MARGIN * whole) {
        let matched = (pilots.iter()).all(|p| p.last_rays.iter().any(|r| r.code == ray.code));
        let spread = if matched {
            widest(rays().filter(|r| r.code == ray.code))
        } else {
            whole
        };
        if ray.light_gap <= SPREAD_MARGIN * spread {
            return true;
        }
    }
    false
}

/// The widest angle between two of the rays' directions (one inverse cosine, of the smallest
/// dot product).
fn widest<'a>(rays: impl Iterator<Item = &'a LastRay> + Clone) -> f32 {
    let mut least = 1.0f32;
    for (i, a) in rays.clone().enumerate() {
        for b in rays.clone().skip(i + 1) {
            least = least.min(a.direction.dot(b.direction));
        }
    }
    least.clamp(-1.0, 1.0).acos()
}

/// Whether a pixel with these pilots holds an edge: their chains meet other objects, or their
/// first diffuse hits see other light probes or turn normals more than 30° apart.
fn holds_edge(pilots: &[&Pilot; 5]) -> bool {
    let first = pilots[0];
    pilots.iter().any(|p| {
        p.tangled
            || p.shape != first.shape
            || p.visible != first.visible
            || match (p.normal, first.normal) {
                (Some(a), Some(b)) => a.dot(b) < CREASE_COS,
                (None, None) => false,
                _ => true,
            }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pilot whose last rays are `(branch, angle about y from +z, gap to a light)`.
    fn pilot(rays: &[(BranchCode, f32, f32)]) -> Pilot {
        Pilot {
            last_rays: (rays.iter())
                .map(|&(code, a, gap)| LastRay {
                    code,
                    origin: Vec3::ZERO,
                    direction: Vec3::new(a.sin(), 0.0, a.cos()),
                    light_gap: gap,
                    light: 0,
                })
                .collect(),
            ..Pilot::default()
        }
    }

    fn five(p: &[Pilot]) -> [&Pilot; 5] {
        [&p[0], &p[1], &p[2], &p[3], &p[4]]
    }

    const FAN: [f32; 5] = [-0.01, -0.005, 0.0, 0.005, 0.01];

    #[test]
    fn a_light_within_the_pilots_spread_flags_the_pixel() {
        // Five pilots whose last rays fan over 0.02 rad: a light 0.025 rad from the nearest
        // lies within 1.5 × the spread, one 0.05 rad away does not.
        let root = BranchCode::ROOT;
        let fan = |gap: f32| -> Vec<Pilot> {
            FAN.iter()
                .map(|&a| pilot(&[(root, a, gap + (a + 0.01).abs())]))
                .collect()
        };
        assert!(sees_emission(&five(&fan(0.025))));
        assert!(!sees_emission(&five(&fan(0.05))));
    }

    #[test]
    fn each_branch_is_compared_with_the_same_branch_of_the_other_pilots() {
        // Every pilot splits at glass: a reflected fan near 0 rad and a refracted fan near
        // 1 rad, each 0.02 rad wide; a light 0.1 rad from both is outside either branch's
        // spread. Where one pilot has no refracted branch (a total reflection's edge inside
        // the pixel) the spread is the pixel's widest, about a radian, and the light flags.
        let (r, t) = (BranchCode::ROOT.then(0), BranchCode::ROOT.then(1));
        let split: Vec<Pilot> = FAN
            .iter()
            .map(|&a| pilot(&[(r, a, 0.1), (t, 1.0 + a, 0.1)]))
            .collect();
        assert!(!sees_emission(&five(&split)));
        let mut partial = split.clone();
        partial[2] = pilot(&[(r, 0.0, 0.1)]);
        assert!(sees_emission(&five(&partial)));
    }

    #[test]
    fn a_pixel_inside_a_lights_image_takes_no_emission_samples() {
        let root = BranchCode::ROOT;
        let lit = |emitting: u32| -> Vec<Pilot> {
            FAN.iter()
                .map(|&a| Pilot {
                    emitting,
                    ..pilot(&[(root, a, -1.0)])
                })
                .collect()
        };
        assert!(!sees_emission(&five(&lit(1))));
        let mut edge = lit(1);
        edge[4].emitting = 0;
        assert!(sees_emission(&five(&edge)));
    }

    #[test]
    fn pilots_that_agree_hold_no_edge_and_any_difference_makes_one() {
        let base = Pilot {
            normal: Some(Vec3::Y),
            visible: 0b101,
            ..Pilot::default()
        };
        assert!(!holds_edge(&[&base; 5]));
        let mut shadowed = base.clone();
        shadowed.visible = 0b001;
        let mut other_object = base.clone();
        other_object.shape.add(7);
        let mut turned = base.clone();
        turned.normal = Some(Vec3::new(0.6, 0.8, 0.0));
        let mut slightly = base.clone();
        slightly.normal = Some(Vec3::new(0.3, 0.954, 0.0).normalize());
        for (odd, edge) in [
            (shadowed, true),
            (other_object, true),
            (turned, true),
            (slightly, false),
        ] {
            assert_eq!(holds_edge(&[&base, &base, &odd, &base, &base]), edge);
        }
    }

    #[test]
    fn shape_hashes_tell_orders_and_objects_apart() {
        let hash = |objects: &[u64]| {
            let mut h = Pilot::default().shape;
            objects.iter().for_each(|&o| h.add(o));
            h
        };
        assert_eq!(hash(&[1, 2]), hash(&[1, 2]));
        assert_ne!(hash(&[1, 2]), hash(&[2, 1]));
        assert_ne!(hash(&[1]), hash(&[1, 1]));
    }
}
