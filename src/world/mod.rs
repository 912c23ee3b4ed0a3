//! The world: a scene description turned into one committed Embree scene, plus what light
//! transport asks of a hit (position, normals, material or emitter), of the lights
//! ([`lights`], each prepared once as a [`lights::LightSource`]) and of a ray that leaves the
//! scene (the environment's radiance), and a material's values at a hit ([`texturing`]). Owns the link between Embree geometry ids and scene objects; must not store
//! photons, estimate radiance or know about images.

pub mod aim;
pub mod aim_grid;
pub mod aim_guide;
mod cutout;
mod hit_normals;
mod instancing;
pub mod lights;
pub mod participating;
mod ribbon;
pub mod texturing;

use crate::embree::{self, EmbreeError};
use crate::scene::{CurveKind, Light, Material, SceneDescription, Shape, TriangleMesh};
use glam::{Vec2, Vec3};
use hit_normals::{HitNormals, TriangleNormals, normals_at, sphere_normals};
use instancing::Instancing;
use lights::LightSource;
use std::sync::Arc;

/// What was hit: a surface with a material, or an area light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    Material(u32),
    Light(usize),
}

/// A ray's closest hit, resolved for shading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interaction {
    pub t: f32,
    pub position: Vec3,
    /// Unit geometric normal, oriented by the geometry (outward for spheres and tubes, by
    /// winding for meshes, by the normals for ribbons, towards the ray for flat curves).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated vertex normals), on the geometric normal's side.
    pub shading_normal: Vec3,
    pub surface: Surface,
    /// Where on its geometry the hit lies, for textures: the Embree geometry, the triangle
    /// and its barycentric weights of corners 1 and 2 (a curve: the segment, Embree's u along
    /// it and v across it; on a textured tube, pbrt's v, which `resolve` works out).
    pub(crate) geometry: u32,
    pub(crate) primitive: u32,
    pub(crate) barycentric: Vec2,
    /// The instance the hit went through (`geometry` is then its prototype's), or `u32::MAX`.
    pub(crate) instance: u32,
}

impl Interaction {
    /// Whether a ray along `dir` arrives on the side the geometric normal points to.
    #[inline]
    pub fn entering(&self, dir: Vec3) -> bool {
        dir.dot(self.geometric_normal) < 0.0
    }

    /// The geometric and shading normals turned towards the side a ray along `dir` arrives
    /// from: the one place photon paths, eye paths and probes orient a hit.
    #[inline]
    pub fn facing(&self, dir: Vec3) -> (Vec3, Vec3) {
        if self.entering(dir) {
            (self.geometric_normal, self.shading_normal)
        } else {
            (-self.geometric_normal, -self.shading_normal)
        }
    }
}

/// Embree reads a scene's meshes where they lie: the world and the tracer share one copy.
impl embree::SharedTriangles for TriangleMesh {
    fn positions(&self) -> &Vec<Vec3> {
        &self.positions
    }
    fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
}

/// Gives each mesh the room past its last vertex that lets Embree read it where it lies: free
/// where the vector has spare capacity, one copy of the positions where not. A mesh someone
/// else holds too is left as it is, and Embree copies it.
fn pad_meshes(shapes: &mut [Shape]) {
    for shape in shapes {
        if let Shape::Triangles(mesh) = shape
            && let Some(mesh) = Arc::get_mut(mesh)
        {
            embree::pad_for_embree(&mut mesh.positions);
        }
    }
}

/// Adds `shape` to `builder`: how its hits find their normals, its box and its material.
fn add_shape(
    builder: &mut embree::SceneBuilder,
    shape: &Shape,
) -> Result<(HitNormals, (Vec3, Vec3), u32), EmbreeError> {
    Ok(match shape {
        Shape::Sphere {
            center,
            radius,
            material,
            ..
        } => {
            builder.add_spheres(&[(*center, *radius)])?;
            let r = Vec3::splat(*radius);
            (
                sphere_normals(*center, *radius),
                (*center - r, *center + r),
                *material,
            )
        }
        Shape::Triangles(mesh) => {
            let cutout = (mesh.cutout.as_ref()).map(|cutout| {
                Arc::new(cutout::CutoutFilter::new(mesh.clone(), cutout))
                    as Arc<dyn embree::HitFilter>
            });
            builder.add_shared_triangles(mesh.clone(), cutout)?;
            let hit_normals = HitNormals::Triangles(TriangleNormals::new(mesh.clone()));
            (hit_normals, mesh.bounds(), mesh.material)
        }
        Shape::Curves(curves) => {
            let (kind, normals) = match curves.kind {
                CurveKind::Flat => (embree::CurveKind::Flat, HitNormals::FlatCurve),
                CurveKind::Cylinder => (
                    embree::CurveKind::Round,
                    HitNormals::Tube(
                        (curves
                            .points
                            .chunks_exact(4)
                            .zip(curves.radii.chunks_exact(4)))
                        .map(|(p, r)| ([p[0], p[1], p[2], p[3]], [r[0], r[1], r[2], r[3]]))
                        .collect(),
                    ),
                ),
                CurveKind::Ribbon => {
                    let control = curves.normals.as_deref().unwrap_or_default();
                    let ribbon = Arc::new(ribbon::Ribbon::new(control));
                    (embree::CurveKind::Flat, HitNormals::Ribbon(ribbon))
                }
            };
            let points: Vec<[f32; 4]> = (curves.points.iter().zip(&curves.radii))
                .map(|(p, r)| [p.x, p.y, p.z, *r])
                .collect();
            let first: Vec<u32> = (0..curves.segment_count() as u32).map(|k| 4 * k).collect();
            match &normals {
                HitNormals::Ribbon(ribbon) => {
                    let filter: Arc<dyn embree::HitFilter> = ribbon.clone();
                    builder.add_filtered_curves(kind, &points, &first, filter)?
                }
                _ => builder.add_curves(kind, &points, &first, None)?,
            };
            (normals, curves.bounds(), curves.material)
        }
    })
}

/// A bounding sphere, used to aim caustic photons at specular objects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    pub center: Vec3,
    pub radius: f32,
}

impl BoundingSphere {
    /// The sphere through the corners of the box `lo`..`hi`, a little larger: a relative margin
    /// only, since an absolute one would change the aim, and so the picture, with the scene's
    /// units (valid shapes always have extent, so the radius is > 0).
    pub(crate) fn around_box(lo: Vec3, hi: Vec3) -> Self {
        Self {
            center: 0.5 * (lo + hi),
            radius: 0.5 * (hi - lo).length() * 1.001,
        }
    }
}

/// A closest hit as Embree reports it, with what was hit but not yet the normals: a caustic
/// path that reaches a diffuse surface before any specular one ends there without them, and
/// resolving a mesh hit reads three vertices (cache misses on big meshes).
#[derive(Clone, Copy, Debug)]
pub struct ClosestHit {
    hit: embree::Hit,
    origin: Vec3,
    dir: Vec3,
    pub surface: Surface,
}

impl ClosestHit {
    pub fn t(&self) -> f32 {
        self.hit.t
    }

    /// The object hit (its Embree geometry, and the instance it was hit through), the same
    /// for every hit of one placed shape.
    pub fn geometry(&self) -> u64 {
        let instance = self.hit.instance.map_or(0, |i| u64::from(i) + 1);
        (instance << 32) | u64::from(self.hit.geometry)
    }
}

/// The largest ray offset off a surface at a point, relative to the point's distance from
/// the origin: some 8,000 times f32's rounding there, and far below any gap a scene models.
pub const LOCAL_EPSILON: f32 = 1e-3;

/// Below this cosine between a hit's shading and geometric normals the shading normal is
/// taken to lie far from the face (pbrt's `"normal N"` may even lie in it): direct light from
/// a uniform environment is then sampled wide
/// ([`lights::LightSource::sample_incident_wide`]) and photons leave by the cosine to the
/// face, so that the light a Lambert surface sends is the same in every direction, as pbrt's
/// path tracer has it. Above it, as the shading normal says.
pub const SHADING_AGREEMENT_MIN_COS: f32 = 0.9;

/// The smallest ray offset a small instance's bound may leave, relative to the point's
/// distance from the origin: 2⁻¹⁶, 128 times f32's rounding there.
pub const ROUNDING_MARGIN: f32 = 1.0 / 65536.0;

pub struct World {
    pub description: SceneDescription,
    accel: embree::Scene,
    /// What each geometry id shows: its material, or the light it is.
    surfaces: Vec<Surface>,
    /// How each geometry id's hits find their normals.
    normals: Vec<HitNormals>,
    /// The prototypes hits through an instance resolve in.
    instancing: Instancing,
    /// Where caustic photons are aimed: a sphere around each mirror and glass object, or one
    /// around them all past [`aim::MAX_TARGETS`]; empty when the scene has none.
    pub caustic_targets: Vec<BoundingSphere>,
    /// How each light spreads its aimed caustic photons over its cones, learnt once per render
    /// (`photon::guide`), by light in the scene's order; empty or `None`: uniformly.
    pub caustic_guide: Vec<Option<Arc<aim_guide::ConeCells>>>,
    /// Diagonal of the scene's bounding box: sets the ray epsilon and the default radii.
    pub scale: f32,
    /// Whether any shape, placed or in an object, is a tube (whose hits start rays further
    /// off them, [`World::offset_from`]).
    has_tubes: bool,
    /// Around every shape and light with a place: where the lights at infinity send photons from.
    pub bounds: BoundingSphere,
    /// The scene's lights prepared for sampling, in [`SceneDescription::lights`]' order.
    pub light_sources: Vec<LightSource>,
    /// Which lights a shading point samples: all of them, or draws from a light tree.
    pub light_sampler: lights::sampler::LightSampler,
    /// What a ray that leaves the scene sees whatever its direction: the constant
    /// environments' radiance summed.
    background: Vec3,
    /// The image environments, whose radiance a leaving ray adds by its direction.
    sky_maps: Vec<LightSource>,
    /// The textured materials and the texture coordinates of their geometries.
    texturing: texturing::Texturing,
    /// Microfacet reflection at least this rough (Trowbridge–Reitz α) reads photons; smoother
    /// lobes are followed ([`crate::bsdf::Part`]).
    pub glossy_min_alpha: f32,
    /// The probability with which a global photon's diffuse bounce is aimed at the caustic
    /// targets instead of drawn by the cosine ([`World::diffuse_bounce_aim`]).
    pub diffuse_bounce_aim: f32,
    /// Whether the global photons' aimed bounces go towards the objects (an open scene,
    /// [`World::aim_bounces_at_objects`]) rather than the caustic targets.
    bounces_aim_at_objects: bool,
    /// A sphere round each shape.
    object_spheres: Vec<BoundingSphere>,
    /// By material id, whether it is a mix that reads photons
    /// ([`World::keeps_photon_on_mix`]); empty in a scene without mixes.
    mixes_reading_photons: Vec<bool>,
    /// The participating media; `None` in a scene without them.
    pub media: Option<participating::Participating>,
}

/// [`World::diffuse_bounce_aim`] in a scene whose one diffuse object sees itself only through
/// its mirrors and glass: a cosine-drawn bounce that misses them leaves the scene, one aimed at
/// them mostly comes back. Not 1: a concave object still lights itself directly.
const LONE_DIFFUSE_BOUNCE_AIM: f32 = 0.75;

impl World {
    /// The world of `description`, its BSDFs split at [`crate::bsdf::ESTIMATED_MIN_ALPHA`].
    pub fn new(description: SceneDescription) -> Result<Self, EmbreeError> {
        World::with_glossy_min_alpha(description, crate::bsdf::ESTIMATED_MIN_ALPHA)
    }

    /// The world of `description`, microfacet reflection at least `glossy_min_alpha` rough
    /// read from photons and smoother lobes followed.
    pub fn with_glossy_min_alpha(
        mut description: SceneDescription,
        glossy_min_alpha: f32,
    ) -> Result<Self, EmbreeError> {
        let prototypes = description.prototypes.iter_mut();
        for shapes in prototypes
            .map(|p| &mut p.shapes)
            .chain([&mut description.shapes])
        {
            pad_meshes(shapes);
        }
        let device = embree::Device::new()?;
        let mut builder = device.scene_builder()?;
        let mut surfaces = Vec::new();
        let mut normals = Vec::new();
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        let (mut spec_lo, mut spec_hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        let mut specular_shapes = Vec::new();
        let mut object_spheres = Vec::new();
        for shape in &description.shapes {
            let (hit_normals, (a, b), material) = add_shape(&mut builder, shape)?;
            object_spheres.push(BoundingSphere::around_box(a, b));
            surfaces.push(Surface::Material(material));
            normals.push(hit_normals);
            lo = lo.min(a);
            hi = hi.max(b);
            let table = &description.materials;
            if table[material as usize].makes_caustics(table, glossy_min_alpha) {
                spec_lo = spec_lo.min(a);
                spec_hi = spec_hi.max(b);
                specular_shapes.push(shape);
            }
        }
        // Area and mesh lights bound the scene for the lights at infinity, but not its scale:
        // the scale (ray epsilon, default radii) has always been the shapes' and point lights'.
        let (mut light_lo, mut light_hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for (i, light) in description.lights.iter().enumerate() {
            match light {
                Light::Point { position, .. } | Light::Spot { position, .. } => {
                    lo = lo.min(*position);
                    hi = hi.max(*position);
                    continue;
                }
                Light::Distant { .. } | Light::Environment { .. } | Light::EnvironmentMap(_) => {
                    continue;
                }
                Light::Sphere { center, radius, .. } => {
                    builder.add_spheres(&[(*center, *radius)])?;
                    normals.push(sphere_normals(*center, *radius));
                    light_lo = light_lo.min(*center - *radius);
                    light_hi = light_hi.max(*center + *radius);
                }
                Light::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    ..
                } => {
                    let p = [
                        *corner,
                        *corner + *edge_u,
                        *corner + *edge_u + *edge_v,
                        *corner + *edge_v,
                    ];
                    builder.add_triangles(&p, &[[0, 1, 2], [0, 2, 3]])?;
                    normals.push(HitNormals::Fixed(
                        edge_u.cross(*edge_v).normalize_or(Vec3::Z),
                    ));
                    for corner in p {
                        light_lo = light_lo.min(corner);
                        light_hi = light_hi.max(corner);
                    }
                }
                Light::Mesh { mesh, .. } => {
                    builder.add_triangles(&mesh.positions, &mesh.triangles)?;
                    // An emitter is flat: its side is its triangles' geometric normal.
                    let flat = TriangleNormals::flat(Arc::new(mesh.clone()));
                    normals.push(HitNormals::Triangles(flat));
                    for p in &mesh.positions {
                        light_lo = light_lo.min(*p);
                        light_hi = light_hi.max(*p);
                    }
                }
            }
            surfaces.push(Surface::Light(i));
        }
        let (instancing, extent) =
            Instancing::build(&device, &description, glossy_min_alpha, &mut builder)?;
        for (a, b) in &extent.boxes {
            (lo, hi) = (lo.min(*a), hi.max(*b));
        }
        for (a, b) in &extent.specular_boxes {
            (spec_lo, spec_hi) = (spec_lo.min(*a), spec_hi.max(*b));
        }
        let accel = builder.commit()?;
        let specular = specular_shapes.len() + extent.specular_shapes;
        let union = || vec![BoundingSphere::around_box(spec_lo, spec_hi)];
        let caustic_targets = if specular > aim::MAX_TARGETS {
            union()
        } else if extent.specular_shapes == 0 {
            aim::targets(&specular_shapes)
        } else {
            // Placed prototypes' own targets while they fit, else a sphere a placement.
            let mut targets = aim::targets(&specular_shapes);
            if targets.len() + extent.targets.len() <= aim::MAX_TARGETS {
                targets.extend(extent.targets);
            } else if targets.len() + extent.specular_boxes.len() <= aim::MAX_TARGETS {
                let placed = extent.specular_boxes.iter();
                targets.extend(placed.map(|&(a, b)| BoundingSphere::around_box(a, b)));
            } else {
                targets = union();
            }
            targets
        };
        let scale = if lo.x <= hi.x {
            (hi - lo).length().max(1e-12)
        } else {
            1.0
        };
        let (all_lo, all_hi) = (lo.min(light_lo), hi.max(light_hi));
        let bounds = if all_lo.x <= all_hi.x {
            let mut bounds = BoundingSphere::around_box(all_lo, all_hi);
            // A lone point still has a little room around it.
            let extent = bounds.center.abs().max_element().max(1.0);
            bounds.radius = bounds.radius.max(1e-4 * extent);
            bounds
        } else {
            BoundingSphere {
                center: Vec3::ZERO,
                radius: 1.0,
            }
        };
        let light_sources: Vec<LightSource> = (description.lights.iter())
            .map(|light| LightSource::new(light, bounds))
            .collect();
        let background = light_sources
            .iter()
            .map(LightSource::radiance_at_infinity)
            .sum();
        let sky_maps = (light_sources.iter())
            .filter(|l| l.has_directional_sky())
            .cloned()
            .collect();
        let media = participating::Participating::new(
            &device,
            &description.media,
            &description.shapes,
            &description.materials,
            description.lights.len(),
            LOCAL_EPSILON * 1e-2,
        )?;
        let texturing = texturing::Texturing::new(&description);
        let materials = &description.materials;
        let mixes_reading_photons =
            match materials.iter().any(|m| matches!(m, Material::Mix { .. })) {
                false => Vec::new(),
                true => (materials.iter())
                    .map(|m| {
                        matches!(m, Material::Mix { .. })
                            && m.is_diffuse_receiver(materials, glossy_min_alpha)
                    })
                    .collect(),
            };
        let is_tube =
            |shape: &Shape| matches!(shape, Shape::Curves(c) if c.kind == CurveKind::Cylinder);
        let has_tubes = description.shapes.iter().any(is_tube)
            || (description.prototypes.iter()).any(|p| p.shapes.iter().any(is_tube));
        let mut world = Self {
            has_tubes,
            mixes_reading_photons,
            texturing,
            description,
            accel,
            surfaces,
            normals,
            instancing,
            caustic_targets,
            caustic_guide: Vec::new(),
            scale,
            bounds,
            light_sampler: lights::sampler::LightSampler::new(&light_sources),
            light_sources,
            background,
            sky_maps,
            glossy_min_alpha,
            diffuse_bounce_aim: 0.0,
            bounces_aim_at_objects: false,
            object_spheres,
            media,
        };
        if world.lights_itself_alone() {
            world.diffuse_bounce_aim = LONE_DIFFUSE_BOUNCE_AIM;
        }
        Ok(world)
    }

    /// The objects that keep photons, every placement of a prototype counted.
    pub fn diffuse_objects(&self) -> usize {
        let d = &self.description;
        let count = |shapes: &[Shape]| {
            (shapes.iter())
                .filter(|s| self.reads_photons(s.material()))
                .count()
        };
        count(&d.shapes)
            + (d.instances.iter())
                .map(|i| count(&d.prototypes[i.prototype as usize].shapes))
                .sum::<usize>()
    }

    /// `model`'s lobes at a hit, split as this world reads photons.
    #[inline]
    pub fn bsdf(&self, model: &crate::bsdf::Model) -> crate::bsdf::Bsdf {
        crate::bsdf::Bsdf::split_at(model, self.glossy_min_alpha)
    }

    /// Whether photons stay on material `id` and camera paths read the maps there (a mix:
    /// where either of its materials does).
    pub fn reads_photons(&self, id: u32) -> bool {
        let materials = &self.description.materials;
        self.material(id)
            .is_diffuse_receiver(materials, self.glossy_min_alpha)
    }

    /// Whether a photon landing on material `id` where the point shows `shown` (what
    /// [`World::material_at`] gave there) is kept although `shown` keeps none: `id` is a mix
    /// that reads photons elsewhere, and the maps' density counts every photon landing on
    /// the whole surface, whichever material its point shows.
    #[inline]
    pub fn keeps_photon_on_mix(&self, id: u32, shown: &Material) -> bool {
        self.mixes_reading_photons.get(id as usize) == Some(&true)
            && !shown.is_diffuse_receiver(&[], self.glossy_min_alpha)
    }

    /// Offset for spawning rays off a surface: relative to the scene's size so the picture
    /// does not change with the scene's units.
    pub fn ray_epsilon(&self) -> f32 {
        self.scale * 2e-5
    }

    /// Offset for spawning rays off a surface at `p`: [`World::ray_epsilon`], but no more
    /// than [`LOCAL_EPSILON`] of `p`'s distance from the origin (at least one unit), so a
    /// huge ground plane does not lift every ray off it into the objects standing on it.
    #[inline]
    pub fn ray_epsilon_at(&self, p: Vec3) -> f32 {
        self.ray_epsilon()
            .min(LOCAL_EPSILON * p.abs().max_element().max(1.0))
    }

    /// The point a ray leaving `hit` starts from on the side `n` points to (`n` a unit normal
    /// of the hit, or its negation): [`World::ray_epsilon_at`] off it, or off a tube as far as
    /// pbrt starts rays off its curves.
    #[inline]
    pub fn offset_from(&self, hit: &Interaction, n: Vec3) -> Vec3 {
        let mut offset = self.ray_epsilon_at(hit.position);
        if hit.instance != u32::MAX {
            // Still some 128 times f32's rounding at the hit.
            let rounding = ROUNDING_MARGIN * hit.position.abs().max_element();
            offset = offset.min(self.instancing.epsilon(hit.instance).max(rounding));
        }
        if self.has_tubes {
            let (primitive, u) = (hit.primitive, hit.barycentric.x);
            let tube = match hit.instance {
                u32::MAX => hit_normals::tube_offset(
                    &self.normals[hit.geometry as usize],
                    primitive,
                    u,
                    hit.geometric_normal,
                ),
                instance => (self.instancing).tube_offset(
                    instance,
                    hit.geometry,
                    primitive,
                    u,
                    hit.geometric_normal,
                ),
            };
            offset = offset.max(tube.unwrap_or(0.0));
        }
        hit.position + n * offset
    }

    /// The start of a ray leaving `hit` along `d`, on the side of `ng` it points to.
    #[inline]
    pub fn spawn_from(&self, hit: &Interaction, ng: Vec3, d: Vec3) -> Vec3 {
        self.offset_from(hit, if d.dot(ng) >= 0.0 { ng } else { -ng })
    }

    /// Material `id` as the scene gives it: its untextured values (a textured parameter's
    /// typical value). What a hit sees is [`World::material_at`].
    pub fn material(&self, id: u32) -> &Material {
        &self.description.materials[id as usize]
    }

    /// Material `id` at `hit`: its textured parameters evaluated at the hit's (u, v), the
    /// material itself when it has none; a mix resolved (its amount evaluated first) to the
    /// material the hit's point shows, and that one's textures evaluated. Never a mix.
    #[inline(always)]
    pub fn material_at(&self, id: u32, hit: &Interaction) -> Material {
        let mut id = id;
        for _ in 0..=crate::scene::MAX_MIX_DEPTH {
            let base = &self.description.materials[id as usize];
            let material = match self.texturing.textured(id) {
                None => *base,
                Some(textured) => textured.evaluate(base, self.uv_at(hit)),
            };
            match material {
                Material::Mix { materials, amount } => {
                    id = texturing::mix_choice(materials, amount, hit.position)
                }
                shown => return shown,
            }
        }
        // Mixes nested deeper than a checked scene holds them: nothing to show.
        Material::Diffuse { albedo: Vec3::ZERO }
    }

    /// The texture coordinates at `hit` (zero on geometries without textures).
    pub fn uv_at(&self, hit: &Interaction) -> Vec2 {
        if hit.instance == u32::MAX {
            return (self.texturing).uv(hit.geometry, hit.primitive, hit.barycentric, hit.position);
        }
        // Through an instance: the prototype's geometry, at the hit's point in its space.
        let (prototype, local) = self.instancing.in_prototype(hit.instance, hit.position);
        (self.texturing).prototype_uv(
            prototype,
            hit.geometry,
            hit.primitive,
            hit.barycentric,
            local,
        )
    }

    /// Radiance arriving along a ray that leaves the scene along the unit `direction` (the
    /// environments'; black without).
    #[inline]
    pub fn background(&self, direction: Vec3) -> Vec3 {
        let mut sky = self.background;
        for map in &self.sky_maps {
            sky += map.sky_radiance(direction);
        }
        sky
    }

    /// Whether any ray leaving the scene sees light.
    pub fn has_background(&self) -> bool {
        self.background != Vec3::ZERO || !self.sky_maps.is_empty()
    }

    /// Whether what a ray leaving the scene sees depends on its direction (an image
    /// environment).
    pub fn has_sky_map(&self) -> bool {
        !self.sky_maps.is_empty()
    }

    /// Aims a share `aim` of the global photons' diffuse bounces at the scene's objects, for
    /// an open scene where most bounces drawn by the cosine leave it; false (nothing changed)
    /// where the scene has too many objects, instances or media to aim at.
    pub fn aim_bounces_at_objects(&mut self, aim: f32) -> bool {
        let few = (2..=aim::MAX_TARGETS).contains(&self.object_spheres.len());
        if !few || !self.description.instances.is_empty() || self.media.is_some() {
            return false;
        }
        self.bounces_aim_at_objects = true;
        self.diffuse_bounce_aim = aim;
        true
    }

    /// Where an open scene's global photons aim their diffuse bounces: a sphere round each
    /// object; `None` where they aim at the caustic targets (a lone object's) or not at all.
    pub fn bounce_targets(&self) -> Option<&[BoundingSphere]> {
        self.bounces_aim_at_objects
            .then_some(self.object_spheres.as_slice())
    }

    /// Whether the scene's one diffuse object can only light itself through its mirrors,
    /// glass and glossy surfaces (a floor under a glass): its global map is a lone object's.
    pub fn lights_itself_alone(&self) -> bool {
        self.diffuse_objects() == 1 && self.has_specular()
    }

    /// Whether any object is a mirror, glass or glossy (so caustic photons exist) and some
    /// diffuse surface or medium could receive what it focuses: not a convex sphere alone in
    /// empty space, whose own glossy reflections leave it.
    pub fn has_specular(&self) -> bool {
        if self.caustic_targets.is_empty() {
            return false;
        }
        let d = &self.description;
        if !d.instances.is_empty() || d.shapes.len() != 1 || self.media.is_some() {
            return true;
        }
        !matches!(d.shapes[0], Shape::Sphere { .. })
    }

    /// Whether any object is diffuse (so photons have somewhere to be stored).
    pub fn has_diffuse(&self) -> bool {
        (self.surfaces.iter().copied())
            .chain(self.instancing.placed_surfaces())
            .any(|s| matches!(s, Surface::Material(m) if self.reads_photons(m)))
    }

    /// How many of the scene's meshes Embree reads where the world holds them (the rest,
    /// emitters and meshes held elsewhere too, it copies).
    pub fn meshes_read_in_place(&self) -> usize {
        self.accel.meshes_read_in_place()
    }

    pub fn occluded(&self, origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> bool {
        self.accel.occluded(origin, dir, tnear, tfar)
    }

    /// Distance to the closest hit and nothing more: Embree's cost alone, for benchmarks.
    pub fn closest_hit_distance(&self, origin: Vec3, dir: Vec3) -> Option<f32> {
        self.accel
            .intersect(origin, dir, 0.0, f32::INFINITY)
            .map(|hit| hit.t)
    }

    /// The closest hit along a ray with unit `dir`, resolved for shading.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> Option<Interaction> {
        self.closest_hit(origin, dir, tnear, tfar)
            .map(|hit| self.resolve(hit))
    }

    /// The closest hit along a ray with unit `dir`, and what it hit, without its normals.
    #[inline]
    pub fn closest_hit(
        &self,
        origin: Vec3,
        dir: Vec3,
        tnear: f32,
        tfar: f32,
    ) -> Option<ClosestHit> {
        let hit = self.accel.intersect(origin, dir, tnear, tfar)?;
        let surface = match hit.instance {
            None => self.surfaces[hit.geometry as usize],
            Some(instance) => self.instancing.surface(instance, hit.geometry),
        };
        Some(ClosestHit {
            hit,
            origin,
            dir,
            surface,
        })
    }

    /// Position and normals of a hit.
    #[inline(always)]
    pub fn resolve(&self, closest: ClosestHit) -> Interaction {
        let ClosestHit {
            hit,
            origin,
            dir,
            surface,
        } = closest;
        let position = origin + hit.t * dir;
        let (geometric_normal, shading_normal) = match hit.instance {
            None => normals_at(&self.normals[hit.geometry as usize], &hit, position, dir),
            Some(instance) => self.instancing.normals(instance, &hit, position, dir),
        };
        let mut barycentric = Vec2::new(hit.u, hit.v);
        if hit.instance.is_none()
            && let HitNormals::Ribbon(ribbon) = &self.normals[hit.geometry as usize]
        {
            barycentric.y = ribbon.v(hit.primitive, hit.u, hit.v, dir);
        }
        if self.texturing.has_tubes
            && hit.instance.is_none()
            && let Some(v) = (self.texturing).tube_v(
                hit.geometry,
                hit.primitive,
                hit.u,
                hit.normal.normalize_or(-dir),
                dir,
            )
        {
            barycentric.y = v;
        }
        Interaction {
            t: hit.t,
            position,
            geometric_normal,
            shading_normal,
            surface,
            geometry: hit.geometry,
            primitive: hit.primitive,
            barycentric,
            instance: hit.instance.unwrap_or(u32::MAX),
        }
    }
}
