//! What the parsed pbrt directives become in dpm: the film ([`film`]: resolution, crop window
//! and what pbrt does to the written image), how far light is followed ([`integrator`]), the camera ([`camera`]), the lights (pbrt gives intensity or radiance,
//! dpm's lights carry total flux), the materials ([`materials`]) and the shapes ([`shapes`], the tessellated ones in
//! [`tessellated`], curves in [`curves`]).
//! Warnings (one per approximated material, ignored parameters) go to the [`LoadReport`].
//! Owns the mapping; must not parse text.

mod camera;
mod conductors;
mod curves;
mod environment;
mod film;
mod glossy;
mod integrator;
mod lights;
mod materials;
mod media;
mod media_presets;
mod mix;
mod shapes;
mod subsurface;
mod tessellated;
mod textures;

use super::params::ParamError;
use super::parser::{Item, Parsed};
use super::{Dialect, Place};
use crate::scene::files::SceneFiles;
use crate::scene::{
    Instance, LoadOptions, LoadReport, Material, MediumBoundary, Prototype, SceneDescription,
    SceneError, SceneMedia, Texture, TexturedMaterial, validate,
};
use glam::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

pub(super) struct Mapper<'f> {
    files: &'f dyn SceneFiles,
    folder: PathBuf,
    strict: bool,
    /// Whether a file without an `Integrator` line gets pbrt's default one.
    default_integrator: bool,
    dialect: (Dialect, String),
    report: LoadReport,
    materials: Vec<Material>,
    /// Scene material index of each parsed material definition (`usize::MAX`: pbrt's
    /// default), filled on first use.
    material_index: HashMap<usize, u32>,
    /// The named textures defined so far, with what they give, or why they cannot be used.
    textures: HashMap<String, (textures::TextureType, Result<Texture, SceneError>)>,
    /// The materials mapped so far that have textured parameters.
    textured_materials: Vec<TexturedMaterial>,
}

/// A parameter's error, placed where the parameter was written (after an `Include`, maybe
/// not in its directive's file).
pub(super) fn param_error(directive: &str, e: ParamError) -> SceneError {
    SceneError {
        file: e.file,
        line: Some(e.line),
        column: Some(e.column),
        field: format!("{directive} {}", e.field),
        message: e.message,
    }
}

pub(super) fn scene(
    path: &Path,
    parsed: Parsed,
    files: &dyn SceneFiles,
    options: &LoadOptions,
) -> Result<(SceneDescription, LoadReport), SceneError> {
    let mut m = Mapper {
        files,
        folder: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        strict: options.strict,
        default_integrator: options.pbrt_default_integrator,
        dialect: parsed.dialect.dialect(),
        report: LoadReport::default(),
        materials: Vec::new(),
        material_index: HashMap::new(),
        textures: HashMap::new(),
        textured_materials: Vec::new(),
    };
    m.report.warnings.extend(parsed.warnings.iter().cloned());
    let version = match m.dialect.0 {
        Dialect::V3 => 3,
        Dialect::V4 => 4,
    };
    m.report
        .notes
        .push(format!("read as pbrt-v{version}: {}", m.dialect.1));
    m.report.notes.extend(
        parsed
            .ignored
            .iter()
            .map(|i| format!("{i}: ignored (dpm's own settings and flags apply)")),
    );
    m.define_textures(&parsed.textures)?;
    let film = m.film(parsed.film.as_ref(), parsed.camera.as_ref())?;
    let transport = m.transport(parsed.integrator.as_ref())?;
    let camera = m.camera(parsed.camera.as_ref(), film.resolution, film.crop)?;
    let mut media = Vec::new();
    for medium in &parsed.media {
        media.extend(m.medium(medium)?);
    }
    for medium in &mut media {
        medium.bounded_by = (parsed.shapes.iter())
            .filter(|s| s.media.0 == medium.name || s.media.1 == medium.name)
            .count();
    }
    // pbrt-v4 resolves the names once the whole file is read, so a medium may be defined
    // after the shapes that name it; a name defined nowhere is an error.
    for shape in &parsed.shapes {
        for name in [&shape.media.0, &shape.media.1] {
            if !name.is_empty() && !parsed.media.iter().any(|m| &m.name == name) {
                return Err(shape.item.at.error(
                    "MediumInterface",
                    format!("the shape's MediumInterface names \"{name}\", which no MakeNamedMedium defines"),
                ));
            }
        }
    }
    let mut lights = Vec::new();
    let mut light_media = Vec::new();
    for light in &parsed.lights {
        if let Some(medium) = media::named(&light.medium, &media) {
            light_media.push((lights.len(), medium));
        }
        lights.push(m.light(&light.item, &light.ctm)?);
        m.unused(&light.item, "LightSource");
    }
    let mut shapes = Vec::new();
    let mut prototypes: Vec<Prototype> = (parsed.objects.iter())
        .map(|o| Prototype {
            name: o.name.clone(),
            shapes: Vec::new(),
        })
        .collect();
    let camera_medium = match m.dialect.0 {
        Dialect::V3 => &parsed.camera_medium.1,
        Dialect::V4 => &parsed.camera_medium.0,
    };
    let mut scene_media = SceneMedia {
        camera: media::named(camera_medium, &media),
        light_media,
        media,
        ..SceneMedia::default()
    };
    // The medium under each subsurface material's surface, made once per material.
    let mut under_surface = std::collections::HashMap::new();
    for shape in &parsed.shapes {
        let mut interface = media::interface_of(shape, &scene_media.media);
        if let Some(i) = shape.material
            && subsurface::is_subsurface(&parsed.materials[i].1.kind)
        {
            let inside = match under_surface.get(&i) {
                Some(&id) => id,
                None => {
                    let item = &parsed.materials[i].1;
                    scene_media.media.push(m.subsurface_medium(item)?);
                    let id = (scene_media.media.len() - 1) as crate::scene::MediumId;
                    under_surface.insert(i, id);
                    id
                }
            };
            scene_media.media[inside as usize].bounded_by += 1;
            interface.inside = Some(inside);
        }
        if shape.area_light.is_none()
            && let Some(i) = shape.material
            && matches!(
                parsed.materials[i].1.kind.as_str(),
                "interface" | "" | "none"
            )
        {
            // A surface that only bounds media: rays cross it without a bounce.
            if shape.object.is_some() {
                m.warn(
                    &shape.item.at,
                    "a medium boundary inside an object is not instanced: the shape is left out"
                        .into(),
                );
                continue;
            }
            let material = m.material_of(None, &parsed)?;
            for boundary in m.shape(shape, material)? {
                scene_media.boundaries.push(MediumBoundary {
                    interface: media::oriented(interface, &boundary, shape),
                    shape: boundary,
                });
            }
            m.unused(&shape.item, "Shape");
            continue;
        }
        if let Some(object) = shape.object {
            if shape.area_light.is_some() {
                m.warn(
                    &shape.item.at,
                    "an area light inside an object is not instanced (as in pbrt): the shape is placed without it".into(),
                );
            }
            let material = m.material_of(shape.material, &parsed)?;
            prototypes[object].shapes.extend(m.shape(shape, material)?);
            m.unused(&shape.item, "Shape");
            continue;
        }
        match shape.area_light {
            Some(a) => {
                let area = &parsed.area_lights[a];
                if let Some(medium) = interface.outside {
                    scene_media.light_media.push((lights.len(), medium));
                }
                lights.push(m.area_light(shape, area)?);
                m.unused(area, "AreaLightSource");
            }
            None => {
                let material = m.material_of(shape.material, &parsed)?;
                let placed = m.shape(shape, material)?;
                if interface.is_transition() {
                    let sides = (placed.iter().enumerate())
                        .map(|(i, p)| (shapes.len() + i, media::oriented(interface, p, shape)));
                    scene_media.shape_interfaces.extend(sides);
                }
                shapes.extend(placed);
            }
        }
        m.unused(&shape.item, "Shape");
    }
    let first = || Place {
        file: path.to_path_buf(),
        line: 1,
        column: 1,
    };
    if lights.is_empty() {
        return Err(first().error(
            "LightSource",
            "the scene has no light dpm can use (LightSource or AreaLightSource)",
        ));
    }
    let instances = instances(&parsed, &prototypes)?;
    if shapes.is_empty() && instances.is_empty() && scene_media.boundaries.is_empty() {
        return Err(first().error("Shape", "the scene has no shapes besides its lights"));
    }
    let scene = SceneDescription {
        source: path.to_path_buf(),
        camera,
        lights,
        materials: m.materials,
        shapes,
        prototypes,
        instances,
        response: film.response,
        textured_materials: m.textured_materials,
        transport,
        media: scene_media,
    };
    let mut report = m.report;
    report
        .warnings
        .extend(validate::enclosed_light_warnings(&scene));
    Ok((scene, report))
}

/// pbrt's `ObjectInstance`s, placing prototypes that have shapes by transforms that can be
/// inverted.
fn instances(parsed: &Parsed, prototypes: &[Prototype]) -> Result<Vec<Instance>, SceneError> {
    let mut instances = Vec::with_capacity(parsed.instances.len());
    for instance in &parsed.instances {
        let m = instance.ctm;
        let affine = m.row(3) == glam::Vec4::W;
        let determinant = m.determinant();
        if !(m.is_finite() && affine && determinant.is_normal()) {
            return Err(instance.at.error(
                "ObjectInstance",
                format!(
                    "the current transform does not place an object (it must be an invertible affine map; determinant {determinant})"
                ),
            ));
        }
        if prototypes[instance.object].shapes.is_empty() {
            continue;
        }
        instances.push(Instance {
            prototype: instance.object as u32,
            object_to_world: m,
        });
    }
    Ok(instances)
}

impl Mapper<'_> {
    pub(super) fn warn(&mut self, at: &Place, message: String) {
        self.report.warnings.push(format!("{at}: {message}"));
    }

    /// Warns once about every parameter of `item` the mapping did not read.
    fn unused(&mut self, item: &Item, directive: &str) {
        let unused = item.params.unused();
        if !unused.is_empty() {
            let at = item.at.clone();
            self.warn(
                &at,
                format!(
                    "{directive} \"{}\": dpm ignores {}",
                    item.kind,
                    unused.join(", ")
                ),
            );
        }
    }

    /// The scene material of a shape's pbrt material, mapping it on first use.
    fn material_of(&mut self, which: Option<usize>, parsed: &Parsed) -> Result<u32, SceneError> {
        self.material_within_mixes(which, parsed, 0)
    }

    /// [`Self::material_of`], `depth` mixes above it (a mix maps its two materials through
    /// here).
    fn material_within_mixes(
        &mut self,
        which: Option<usize>,
        parsed: &Parsed,
        depth: usize,
    ) -> Result<u32, SceneError> {
        let key = which.unwrap_or(usize::MAX);
        if let Some(&i) = self.material_index.get(&key) {
            return Ok(i);
        }
        let (material, textures) = match which {
            None => (
                Material::Diffuse {
                    albedo: Vec3::splat(0.5),
                },
                Vec::new(),
            ),
            Some(i) => {
                let (name, item) = &parsed.materials[i];
                let mapped = match item.kind.as_str() {
                    "mix" => self.mix(i, parsed, depth)?,
                    kind => self.material(kind, &item.params, &item.at)?,
                };
                let label = name
                    .as_ref()
                    .map(|n| format!("material \"{n}\" ({})", item.kind))
                    .unwrap_or_else(|| format!("material \"{}\"", item.kind));
                if let Some(why) = mapped.approximation {
                    if self.strict {
                        return Err(item
                            .at
                            .error("Material", format!("{why} (refused under --strict)")));
                    }
                    let at = item.at.clone();
                    self.warn(&at, why);
                }
                let unused = item.params.unused();
                if !unused.is_empty() {
                    let at = item.at.clone();
                    self.warn(&at, format!("{label}: dpm ignores {}", unused.join(", ")));
                }
                crate::scene::check_material(&mapped.material)
                    .map_err(|why| item.at.error("Material", format!("{label}: {why}")))?;
                (mapped.material, mapped.textures)
            }
        };
        // Counted only now: a mix has just mapped its two materials.
        let index = self.materials.len() as u32;
        if !textures.is_empty() {
            self.textured_materials.push(TexturedMaterial {
                material: index,
                textures,
            });
        }
        self.materials.push(material);
        self.material_index.insert(key, index);
        Ok(index)
    }
}

/// Reads a shape's one parameter list value or fails at it.
pub(super) fn require<T>(
    value: Result<Option<T>, ParamError>,
    item: &Item,
    name: &str,
    directive: &str,
) -> Result<T, SceneError> {
    value
        .map_err(|e| param_error(directive, e))?
        .ok_or_else(|| {
            item.at.error(
                directive,
                format!(
                    "{directive} \"{}\" needs the parameter \"{name}\"",
                    item.kind
                ),
            )
        })
}

/// The parameter list of `item` and its place, for errors about a value.
pub(super) fn value_error(item: &Item, directive: &str, name: &str, message: String) -> SceneError {
    match item.params.error_at(name, message.clone()) {
        Some(e) => param_error(directive, e),
        None => item.at.error(directive, message),
    }
}
