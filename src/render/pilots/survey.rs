//! The pilot rays themselves: each followed along every branch of its mirror and glass
//! chains as camera paths are, recording what [`super::pilot::Pilot`] holds; the lights'
//! visible bounds and shadow probes they are measured against; and where a flagged pixel's
//! search for light images starts. Owns the tracing of pilots; must not decide a pixel's plan.

use super::pilot::{BranchCode, LastRay, Pilot, SPREAD_MARGIN, gap_to_sphere, near_light, widest};
use crate::optics::{fresnel_dielectric, reflect, refract};
use crate::render::light_images::{self, Seed};
use crate::scene::Material;
use crate::world::lights::{LightShape, weight};
use crate::world::{BoundingSphere, Surface, World};
use glam::{Vec2, Vec3};

/// Branches a pilot follows at most; past them its pixel counts as seeing a light and as
/// holding an edge (a maze of glass).
const MAX_PILOT_BRANCHES: usize = 64;
/// Fresnel weight below which a pilot's branch is not followed: a light seen there would
/// still be `1e-3` of its radiance, but chains that thin are many and each adds a ray.
const MIN_BRANCH_WEIGHT: f32 = 1e-3;
/// Light points a pilot's diffuse hit tests for visibility, at most (the first lights').
const MAX_VISIBILITY_BITS: usize = 64;

/// What the pilots share: the lights' visible bounds and the points their shadows are
/// tested against.
pub(super) struct Survey<'w> {
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
    pub(super) fn new(world: &'w World, max_depth: u32) -> Self {
        let shapes: Vec<LightShape> = world.light_sources.iter().map(|l| l.shape()).collect();
        let visible = shapes.iter().flat_map(visible_bounds).collect();
        let probed = probed_lights(world);
        let probes = (shapes.iter().zip(probed))
            .filter(|(_, probed)| *probed)
            .filter_map(|(shape, _)| shadow_probe(shape))
            .collect();
        Self {
            world,
            max_depth,
            visible,
            probes,
        }
    }

    pub(super) fn pilot(&self, origin: Vec3, dir: Vec3) -> Pilot {
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
                world.offset_from(&hit, side)
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
    pub(super) fn seeds(&self, pilots: &[(&Pilot, Vec2); 5], corner: Vec2) -> Vec<Seed> {
        let alone = pilots.map(|(p, _)| p);
        let whole = widest(alone.iter().flat_map(|p| p.last_rays.iter()));
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
            if !near_light(&alone, ray, whole) {
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

/// Power share below which a light drawn from the light tree gets no shadow probe: its
/// shadow's edge is too faint to flag a pixel for.
const MIN_PROBED_SHARE: f32 = 0.02;

/// Which lights a pilot's shadow probes test: every light where each shading point samples
/// every light; past that, the lights at infinity and those holding at least
/// [`MIN_PROBED_SHARE`] of the bounded lights' power (among a thousand even lights no one
/// shadow shows, and testing each would cost a thousand rays a pilot).
fn probed_lights(world: &World) -> Vec<bool> {
    let lights = &world.light_sampler;
    if lights.samples_every_light() {
        return vec![true; world.light_sources.len()];
    }
    let everywhere = lights.everywhere();
    let power = |l: usize| weight(world.light_sources[l].power());
    let bounded: f32 = (0..world.light_sources.len())
        .filter(|l| !everywhere.contains(l))
        .map(power)
        .sum();
    (0..world.light_sources.len())
        .map(|l| everywhere.contains(&l) || power(l) >= MIN_PROBED_SHARE * bounded)
        .collect()
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
