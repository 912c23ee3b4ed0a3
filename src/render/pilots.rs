//! Pilot rays, once per render before any pass: one through every pixel's centre and one
//! through every pixel corner (neighbours share corners: about two rays a pixel), each
//! followed along every branch of its mirror and glass chains, as camera paths are. What they
//! find plans each pixel for the whole render ([`PixelPlan`]):
//!
//! - **Emission apart** (`--emission-samples`): a chain's last ray meets a light, leaves the
//!   scene under a lit environment, or passes within the pixel's spread of a light, so a light
//!   image smaller than the pilots' spacing may lie inside the pixel ([`super::emission`]).
//! - **Edge** (`--edge-samples`): the pilots disagree on what the pixel shows — other objects
//!   along their chains, another chain shape, normals more than 30° apart, or a light point
//!   visible from one pilot's diffuse hit and hidden from another's (a shadow's edge). A
//!   pixel's value there is the mean of a step across it, which camera samples resolve slowly;
//!   such pixels take more camera samples a pass, where they cost little beside the image.
//!
//! Decided from the geometry alone, so that every pass, thread count and shard agrees. Owns
//! that plan; must not shade or estimate.

use super::camera::PinholeCamera;
use crate::optics::{fresnel_dielectric, reflect, refract};
use crate::scene::Material;
use crate::world::lights::LightShape;
use crate::world::{BoundingSphere, Surface, World};
use glam::Vec3;
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
}

const EMISSION: u8 = 1;
const EDGE: u8 = 2;

impl PixelPlan {
    /// The plan for `camera`'s pixels: pilots follow mirrors and glass for `max_depth`
    /// bounces, as camera paths do. With both counts 0 no pilot is traced. `None` if an
    /// interruption was requested meanwhile.
    pub fn survey(
        camera: &PinholeCamera,
        world: &World,
        max_depth: u32,
        emission_samples: u32,
        edge_samples: u32,
    ) -> Option<Self> {
        let (w, h) = (camera.width(), camera.height());
        let mut plan = Self {
            flags: vec![0; w * h],
            emission_samples,
            edge_samples,
        };
        if emission_samples == 0 && edge_samples == 0 {
            return Some(plan);
        }
        let survey = Survey::new(world, max_depth);
        let pilot = |x: f32, y: f32| survey.pilot(camera.origin(), camera.direction(x, y));
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
        let corners = rows(h + 1, w + 1, &|x, y| pilot(x as f32, y as f32));
        let centres = rows(h, w, &|x, y| pilot(x as f32 + 0.5, y as f32 + 0.5));
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
        Some(plan)
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
    /// Points on the lights whose visibility tells a shadow's edge.
    probes: Vec<Probe>,
}

/// A point a shadow ray is aimed at: on a light, or a direction to infinity.
#[derive(Clone, Copy, Debug)]
enum Probe {
    Point(Vec3),
    /// A sphere light: four points of its silhouette seen from the hit.
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
        let probes = shapes.iter().flat_map(shadow_probes).collect();
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
        let mut last_rays: Vec<(Vec3, Vec3)> = Vec::new();
        let mut branches = vec![(origin, dir, 0u32, 1.0f32)];
        let mut followed = 0;
        while let Some((o, d, depth, weight)) = branches.pop() {
            followed += 1;
            if followed > MAX_PILOT_BRANCHES {
                pilot.sees_emission = true;
                pilot.tangled = true;
                break;
            }
            let Some(closest) = world.closest_hit(o, d, 0.0, f32::INFINITY) else {
                pilot.sees_emission |= world.background() != Vec3::ZERO;
                pilot.shape.add(u64::MAX);
                last_rays.push((o, d));
                continue;
            };
            pilot.shape.add(closest.geometry() as u64);
            let m = match closest.surface {
                Surface::Light(_) => {
                    pilot.sees_emission = true;
                    last_rays.push((o, d));
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
            match world.material(m) {
                Material::Diffuse { .. } => {
                    last_rays.push((o, d));
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
                        branches.push((spawn(r), r, depth + 1, weight));
                    }
                }
                Material::Glass { ior, .. } => {
                    let eta = if hit.entering(d) { 1.0 / ior } else { *ior };
                    let f = fresnel_dielectric(-d.dot(ns), eta);
                    if f * weight >= MIN_BRANCH_WEIGHT {
                        let r = reflect(d, ns);
                        branches.push((spawn(r), r, depth + 1, f * weight));
                    }
                    let refracted = refract(d, ns, eta).filter(|_| f < 1.0);
                    match refracted {
                        Some(t) if (1.0 - f) * weight >= MIN_BRANCH_WEIGHT => {
                            branches.push((spawn(t), t, depth + 1, (1.0 - f) * weight));
                        }
                        // Total internal reflection, or a branch too thin: the shape says so.
                        _ => pilot.shape.add(u64::MAX - 1),
                    }
                }
            }
        }
        pilot.cone = bounding_cone(last_rays.iter().map(|&(_, d)| d));
        for &(o, d) in &last_rays {
            for light in &self.visible {
                pilot.light_gap = pilot.light_gap.min(angle_to_sphere(o, d, light));
            }
        }
        pilot
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
                Probe::Sphere { center, radius } => {
                    let axis = (center - p).normalize_or(Vec3::Z);
                    let (t, b) = crate::sampling::basis(axis);
                    // Just inside the silhouette, so the probe lies on the light.
                    for side in [t, -t, b, -b] {
                        test(towards(center + 0.95 * radius * side));
                    }
                }
            }
        }
        bits
    }
}

/// Spheres whose union holds the part of a light the eye can see, hugging it closely enough
/// that a ray passing near one passes near the light: a sphere light itself, a quad's 2 × 2
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
            let (u, v) = (*edge_u / 2.0, *edge_v / 2.0);
            let radius = 0.5 * (u + v).length().max((u - v).length());
            [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(s, t)| BoundingSphere {
                    center: *corner + s * u + t * v + 0.5 * (u + v),
                    radius,
                })
                .to_vec()
        }
        LightShape::Mesh(spheres) => spheres.clone(),
        LightShape::Point(_) | LightShape::Direction(_) | LightShape::Everywhere => Vec::new(),
    }
}

/// The points (or directions) a pilot's shadow rays test on a light: a point or spot light's
/// position, a distant light's direction, four points of a sphere's silhouette, a quad's
/// corners, the silhouette of a sphere round a mesh light; none for the environment. A
/// shadow's edge falls between two pilots when some probe is seen from one and not the other;
/// a light whose every probe is seen (or hidden) from both is taken as wholly seen (or hidden).
fn shadow_probes(shape: &LightShape) -> Vec<Probe> {
    match shape {
        LightShape::Point(p) => vec![Probe::Point(*p)],
        LightShape::Direction(d) => vec![Probe::Direction(*d)],
        LightShape::Sphere(s) => vec![Probe::Sphere {
            center: s.center,
            radius: s.radius,
        }],
        LightShape::Quad {
            corner,
            edge_u,
            edge_v,
        } => {
            // Corners pulled 5% inwards, so that each lies on the light.
            let at = |s: f32, t: f32| *corner + s * *edge_u + t * *edge_v;
            [(0.05, 0.05), (0.95, 0.05), (0.05, 0.95), (0.95, 0.95)]
                .map(|(s, t)| Probe::Point(at(s, t)))
                .to_vec()
        }
        LightShape::Mesh(spheres) if !spheres.is_empty() => {
            let center = spheres.iter().map(|s| s.center).sum::<Vec3>() / spheres.len() as f32;
            let radius = (spheres.iter())
                .map(|s| s.center.distance(center) + s.radius)
                .fold(0.0, f32::max);
            vec![Probe::Sphere { center, radius }]
        }
        LightShape::Mesh(_) | LightShape::Everywhere => Vec::new(),
    }
}

/// What one pilot ray learns.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pilot {
    /// A chain's last ray meets a light, or leaves the scene under a lit environment, or the
    /// chains were too many to follow.
    sees_emission: bool,
    /// The chains were too many to follow.
    tangled: bool,
    /// A cone (unit axis, half-angle in radians) holding the directions of the chains' last
    /// rays; `None` when no chain got that far.
    cone: Option<(Vec3, f32)>,
    /// The smallest angle between a last ray's direction and a light's bounding sphere seen
    /// from that ray's origin (negative inside the sphere; infinite without visible lights).
    light_gap: f32,
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
            sees_emission: false,
            tangled: false,
            cone: None,
            light_gap: f32::INFINITY,
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

/// A cone (unit axis, half-angle) holding the unit directions `dirs`, or `None` for none.
fn bounding_cone(dirs: impl Iterator<Item = Vec3> + Clone) -> Option<(Vec3, f32)> {
    let sum: Vec3 = dirs.clone().sum();
    let axis = sum.try_normalize()?;
    let half = dirs.map(|d| angle_between(axis, d)).fold(0.0, f32::max);
    Some((axis, half))
}

fn angle_between(a: Vec3, b: Vec3) -> f32 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// The angle between direction `d` from `o` and the nearest point of `sphere`'s silhouette
/// seen from `o` (negative when `o` is inside it).
fn angle_to_sphere(o: Vec3, d: Vec3, sphere: &BoundingSphere) -> f32 {
    let to = sphere.center - o;
    let dist = to.length();
    if dist <= sphere.radius {
        return -1.0;
    }
    angle_between(d, to / dist) - (sphere.radius / dist).asin()
}

/// Whether a pixel with these pilots (its centre and corners) samples its emitted light
/// apart: a pilot sees emission, or a light lies within the pilots' spread (the widest angle
/// their cones span, with a margin) of a pilot's last ray.
fn sees_emission(pilots: &[&Pilot; 5]) -> bool {
    if pilots.iter().any(|p| p.sees_emission) {
        return true;
    }
    let gap = pilots
        .iter()
        .map(|p| p.light_gap)
        .fold(f32::INFINITY, f32::min);
    if !gap.is_finite() {
        return false;
    }
    let cones: Vec<(Vec3, f32)> = pilots.iter().filter_map(|p| p.cone).collect();
    let mut spread = 0.0f32;
    for (i, a) in cones.iter().enumerate() {
        for b in &cones[i..] {
            spread = spread.max(angle_between(a.0, b.0) + a.1 + b.1);
        }
    }
    gap <= SPREAD_MARGIN * spread
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

    fn pilot(cone: (Vec3, f32), gap: f32) -> Pilot {
        Pilot {
            cone: Some(cone),
            light_gap: gap,
            ..Pilot::default()
        }
    }

    #[test]
    fn a_light_within_the_pilots_spread_flags_the_pixel() {
        // Five pilots whose last rays fan over 0.02 rad: a light 0.025 rad from the nearest
        // lies within 1.5 × the spread, one 0.05 rad away does not.
        let fan = |gap: f32| {
            [-0.01f32, -0.005, 0.0, 0.005, 0.01].map(|a| {
                pilot(
                    (Vec3::new(a.sin(), 0.0, a.cos()), 0.0),
                    gap + (a + 0.01).abs(),
                )
            })
        };
        let near = fan(0.025);
        assert!(sees_emission(&[
            &near[0], &near[1], &near[2], &near[3], &near[4]
        ]));
        let far = fan(0.05);
        assert!(!sees_emission(&[
            &far[0], &far[1], &far[2], &far[3], &far[4]
        ]));
    }

    #[test]
    fn pilots_that_agree_hold_no_edge_and_any_difference_makes_one() {
        let base = Pilot {
            normal: Some(Vec3::Y),
            visible: 0b101,
            ..Pilot::default()
        };
        assert!(!holds_edge(&[&base; 5]));
        let mut shadowed = base;
        shadowed.visible = 0b001;
        let mut other_object = base;
        other_object.shape.add(7);
        let mut turned = base;
        turned.normal = Some(Vec3::new(0.6, 0.8, 0.0));
        let mut slightly = base;
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
