//! The scene file format as serde structs (documented field by field in docs/scene-format.md),
//! and the walk over the document's top level that picks each `[[lights]]`, `[materials.*]`
//! and `[[objects]]` entry's struct by its `type` tag. Owns the shape of the format only: it
//! checks types and field names, not values (that is `validate`), and reads no other files.

use super::SceneError;
use super::document::{Document, Value, child_path, quoted_list};
use super::toml_media::take_name;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use std::fmt;
use toml::de::DeValue;

const TOP_LEVEL_FIELDS: [&str; 5] = ["camera", "lights", "materials", "objects", "media"];
const LIGHT_TYPES: [&str; 7] = [
    "point",
    "sphere",
    "quad",
    "spot",
    "distant",
    "environment",
    "mesh",
];
const MATERIAL_TYPES: [&str; 14] = [
    "diffuse",
    "mirror",
    "glass",
    "plastic",
    "uber",
    "substrate",
    "translucent",
    "conductor",
    "rough_glass",
    "thin_glass",
    "coated_diffuse",
    "coated_conductor",
    "diffuse_transmission",
    "mix",
];
const OBJECT_TYPES: [&str; 3] = ["sphere", "quad", "mesh"];

/// The whole file, typed but not yet checked.
pub(crate) struct SceneSpec {
    pub camera: CameraSpec,
    pub lights: Vec<LightSpec>,
    /// In name order.
    pub materials: Vec<(String, MaterialSpec)>,
    pub objects: Vec<ObjectSpec>,
    /// The media the camera, each light and each object's two sides name (`medium`,
    /// `inside`, `outside`; docs/scene-format.md), taken out of their tables.
    pub media_names: MediaNames,
}

/// What the camera, the lights and the objects say of media, by name.
#[derive(Default)]
pub(crate) struct MediaNames {
    pub camera: Option<String>,
    pub lights: Vec<Option<String>>,
    pub objects: Vec<(Option<String>, Option<String>)>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CameraSpec {
    pub position: [f32; 3],
    pub look_at: [f32; 3],
    pub up: [f32; 3],
    /// `"perspective"` (default), `"orthographic"` or `"environment"`.
    #[serde(default)]
    pub projection: ProjectionSpec,
    /// Vertical field of view in degrees (perspective only, required there).
    pub fov_y: Option<f32>,
    /// World-space height of the film (orthographic only, required there).
    pub view_height: Option<f32>,
    /// Thin-lens radius (default 0: a pinhole) and focal distance (default 1e6).
    pub lens_radius: Option<f32>,
    pub focal_distance: Option<f32>,
    /// [width, height] in pixels.
    pub resolution: [u32; 2],
    /// `"right"` (default) or `"left"` (pbrt's camera).
    #[serde(default)]
    pub handedness: HandednessSpec,
    /// [x0, x1, y0, y1], fractions of the film from its top-left corner (default [0, 1, 0, 1]).
    pub crop_window: Option<[f32; 4]>,
}

#[derive(Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(crate) enum ProjectionSpec {
    #[default]
    Perspective,
    Orthographic,
    Environment,
}

impl ProjectionSpec {
    /// As the scene file spells it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ProjectionSpec::Perspective => "perspective",
            ProjectionSpec::Orthographic => "orthographic",
            ProjectionSpec::Environment => "environment",
        }
    }
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub(crate) enum HandednessSpec {
    #[default]
    Right,
    Left,
}

pub(crate) enum LightSpec {
    Point(PointLightSpec),
    Sphere(SphereLightSpec),
    Quad(QuadLightSpec),
    Spot(SpotLightSpec),
    Distant(DistantLightSpec),
    Environment(EnvironmentLightSpec),
    Mesh(MeshLightSpec),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PointLightSpec {
    pub position: [f32; 3],
    pub power: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SphereLightSpec {
    pub center: [f32; 3],
    pub radius: f32,
    pub power: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct QuadLightSpec {
    pub corner: [f32; 3],
    pub edge_u: [f32; 3],
    pub edge_v: [f32; 3],
    pub power: [f32; 3],
}

/// pbrt's defaults: `coneangle` 30, `conedelta` 5.
pub(crate) const DEFAULT_CONE_ANGLE: f32 = 30.0;
pub(crate) const DEFAULT_CONE_DELTA: f32 = 5.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SpotLightSpec {
    pub position: [f32; 3],
    /// Where the cone's axis points; any non-zero length.
    pub direction: [f32; 3],
    /// Half-angle in degrees where the light ends.
    #[serde(default = "default_cone_angle")]
    pub cone_angle: f32,
    /// Half-angle in degrees where the falloff begins; default `cone_angle` − 5 (at least 0).
    #[serde(default)]
    pub falloff_start: Option<f32>,
    /// `"smoothstep"` (default) or `"quartic"`.
    #[serde(default)]
    pub falloff: Option<String>,
    pub power: [f32; 3],
}

fn default_cone_angle() -> f32 {
    DEFAULT_CONE_ANGLE
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DistantLightSpec {
    /// The direction the light travels; any non-zero length.
    pub direction: [f32; 3],
    pub irradiance: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct EnvironmentLightSpec {
    pub radiance: [f32; 3],
}

/// An OBJ emitter, placed as mesh objects are ([`MeshSpec`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MeshLightSpec {
    pub file: String,
    #[serde(default)]
    pub translate: [f32; 3],
    #[serde(default)]
    pub rotate: [f32; 3],
    #[serde(default)]
    pub scale: Scale,
    pub power: [f32; 3],
    #[serde(default)]
    pub two_sided: bool,
}

pub(crate) enum MaterialSpec {
    Diffuse(DiffuseSpec),
    Mirror(MirrorSpec),
    Glass(GlassSpec),
    /// Any type past `glass` in `MATERIAL_TYPES` but `mix`, read by [`super::toml_bsdf`].
    Bsdf(&'static str, Box<super::toml_bsdf::BsdfSpec>),
    /// Read by [`super::toml_mix`].
    Mix(MixSpec),
}

/// One of two named materials at each point: the second with probability `amount`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MixSpec {
    pub materials: Vec<String>,
    /// Default 0.5.
    #[serde(default)]
    pub amount: Option<AmountSpec>,
}

/// A mix's amount: a number, or a texture table (the mean of its channels).
#[derive(Deserialize)]
#[serde(untagged)]
pub(crate) enum AmountSpec {
    Number(f32),
    Texture(TextureSpec),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DiffuseSpec {
    pub albedo: ColourSpec,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MirrorSpec {
    /// Default [1, 1, 1].
    #[serde(default)]
    pub tint: Option<ColourSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct GlassSpec {
    pub ior: f32,
    /// Default [1, 1, 1].
    #[serde(default)]
    pub reflect_tint: Option<ColourSpec>,
    /// Default [1, 1, 1].
    #[serde(default)]
    pub transmit_tint: Option<ColourSpec>,
}

/// A material colour: `[r, g, b]`, or a texture table (docs/scene-format.md#textures).
#[derive(Deserialize)]
#[serde(untagged)]
pub(crate) enum ColourSpec {
    Rgb([f32; 3]),
    Texture(TextureSpec),
}

/// A texture: an `image` file or a `checkerboard` of two colours, on the surface's (u, v).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TextureSpec {
    pub image: Option<String>,
    pub checkerboard: Option<[[f32; 3]; 2]>,
    /// Whether the image's values are sRGB-encoded; default: for PNG and TGA files.
    pub srgb: Option<bool>,
    /// `repeat` (default), `black` or `clamp`.
    pub wrap: Option<String>,
    #[serde(default = "unit_pair")]
    pub uv_scale: [f32; 2],
    #[serde(default)]
    pub uv_offset: [f32; 2],
    /// Multiplies the image's values.
    #[serde(default = "one")]
    pub scale: f32,
    /// `1 − value` (at least 0) after the scale.
    #[serde(default)]
    pub invert: bool,
}

fn unit_pair() -> [f32; 2] {
    [1.0, 1.0]
}

fn one() -> f32 {
    1.0
}

pub(crate) enum ObjectSpec {
    Sphere(SphereSpec),
    Quad(QuadSpec),
    Mesh(MeshSpec),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SphereSpec {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct QuadSpec {
    pub corner: [f32; 3],
    pub edge_u: [f32; 3],
    pub edge_v: [f32; 3],
    pub material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MeshSpec {
    /// OBJ path, relative to the scene file's folder.
    pub file: String,
    /// Scene material for every face, overriding the OBJ's MTL materials.
    #[serde(default)]
    pub material: Option<String>,
    #[serde(default)]
    pub translate: [f32; 3],
    /// Degrees about x, then y, then z.
    #[serde(default)]
    pub rotate: [f32; 3],
    #[serde(default)]
    pub scale: Scale,
}

/// `scale = 2.0` or `scale = [1.0, 0.5, 1.0]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(ScaleVisitor)
    }
}

struct ScaleVisitor;

impl<'de> Visitor<'de> for ScaleVisitor {
    type Value = Scale;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or an array of three numbers")
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scale, E> {
        Ok(Scale::Uniform(v as f32))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scale, E> {
        Ok(Scale::Uniform(v as f32))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Scale, E> {
        Ok(Scale::Uniform(v as f32))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Scale, A::Error> {
        let mut factors = [0.0f32; 3];
        for (i, factor) in factors.iter_mut().enumerate() {
            *factor = seq
                .next_element()?
                .ok_or_else(|| de::Error::invalid_length(i, &self))?;
        }
        if seq.next_element::<de::IgnoredAny>()?.is_some() {
            return Err(de::Error::invalid_length(4, &self));
        }
        Ok(Scale::PerAxis(factors))
    }
}

/// Reads the top level: `camera` (required), `lights` and `objects` (required, non-empty arrays
/// of tables), `materials` (a table of named tables, may be absent).
pub(crate) fn read_scene(doc: &Document) -> Result<SceneSpec, SceneError> {
    let root = doc.root();
    for (key, _) in root.iter() {
        if !TOP_LEVEL_FIELDS.contains(&key.get_ref().as_ref()) {
            return Err(doc.error(
                &child_path("", key.get_ref()),
                format!(
                    "unknown field, expected one of {}",
                    quoted_list(&TOP_LEVEL_FIELDS)
                ),
            ));
        }
    }

    let mut media_names = MediaNames::default();
    let camera = match root.get("camera") {
        Some(value) => {
            let (value, medium) = take_name(doc, "camera", value, "medium")?;
            media_names.camera = medium;
            doc.deserialize::<CameraSpec>(&value)?
        }
        None => return Err(doc.error("camera", "missing field")),
    };

    let mut lights = Vec::new();
    for (i, value) in array_of_tables(doc, "lights")?.iter().enumerate() {
        let path = format!("lights[{i}]");
        let (value, medium) = take_name(doc, &path, value, "medium")?;
        media_names.lights.push(medium);
        lights.push(read_light(doc, &path, &value)?);
    }

    let mut materials = Vec::new();
    if let Some(value) = root.get("materials") {
        let DeValue::Table(table) = value.get_ref() else {
            return Err(doc.error("materials", "expected a table of named materials"));
        };
        for (name, value) in table.iter() {
            let path = child_path("materials", name.get_ref());
            materials.push((
                name.get_ref().to_string(),
                read_material(doc, &path, value)?,
            ));
        }
    }

    let mut objects = Vec::new();
    for (i, value) in array_of_tables(doc, "objects")?.iter().enumerate() {
        let path = format!("objects[{i}]");
        let (value, inside) = take_name(doc, &path, value, "inside")?;
        let (value, outside) = take_name(doc, &path, &value, "outside")?;
        media_names.objects.push((inside, outside));
        objects.push(read_object(doc, &path, &value)?);
    }

    Ok(SceneSpec {
        camera,
        lights,
        materials,
        objects,
        media_names,
    })
}

/// The non-empty array of tables at top-level `key` (`[[key]]`).
fn array_of_tables<'d, 't>(
    doc: &'d Document<'t>,
    key: &str,
) -> Result<&'d [Value<'t>], SceneError> {
    let Some(value) = doc.root().get(key) else {
        return Err(doc.error(key, format!("missing field (add at least one [[{key}]])")));
    };
    match value.get_ref() {
        DeValue::Array(items) if items.is_empty() => {
            Err(doc.error(key, format!("needs at least one entry ([[{key}]])")))
        }
        DeValue::Array(items) => Ok(items),
        other => Err(doc.error(
            key,
            format!(
                "expected an array of tables ([[{key}]]), found {}",
                other.type_str()
            ),
        )),
    }
}

fn read_light(doc: &Document, path: &str, value: &Value) -> Result<LightSpec, SceneError> {
    let (kind, fields) = doc.tagged(path, value, &LIGHT_TYPES)?;
    Ok(match kind {
        "point" => LightSpec::Point(doc.deserialize(&fields)?),
        "sphere" => LightSpec::Sphere(doc.deserialize(&fields)?),
        "quad" => LightSpec::Quad(doc.deserialize(&fields)?),
        "spot" => LightSpec::Spot(doc.deserialize(&fields)?),
        "distant" => LightSpec::Distant(doc.deserialize(&fields)?),
        "environment" => LightSpec::Environment(doc.deserialize(&fields)?),
        _ => LightSpec::Mesh(doc.deserialize(&fields)?),
    })
}

fn read_material(doc: &Document, path: &str, value: &Value) -> Result<MaterialSpec, SceneError> {
    let (kind, fields) = doc.tagged(path, value, &MATERIAL_TYPES)?;
    Ok(match kind {
        "diffuse" => MaterialSpec::Diffuse(doc.deserialize(&fields)?),
        "mirror" => MaterialSpec::Mirror(doc.deserialize(&fields)?),
        "glass" => MaterialSpec::Glass(doc.deserialize(&fields)?),
        "mix" => MaterialSpec::Mix(doc.deserialize(&fields)?),
        bsdf => {
            if let DeValue::Table(table) = fields.get_ref() {
                let names = table.iter().map(|(k, _)| k.get_ref().to_string());
                super::toml_bsdf::check_fields(doc, path, bsdf, names)?;
            }
            MaterialSpec::Bsdf(bsdf, doc.deserialize(&fields)?)
        }
    })
}

fn read_object(doc: &Document, path: &str, value: &Value) -> Result<ObjectSpec, SceneError> {
    let (kind, fields) = doc.tagged(path, value, &OBJECT_TYPES)?;
    Ok(match kind {
        "sphere" => ObjectSpec::Sphere(doc.deserialize(&fields)?),
        "quad" => ObjectSpec::Quad(doc.deserialize(&fields)?),
        _ => ObjectSpec::Mesh(doc.deserialize(&fields)?),
    })
}
