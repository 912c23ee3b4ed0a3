//! The rules on values that the public scene types obey (finite numbers, positive radii, light
//! powers finite, >= 0 and not all zero, albedo and tints in [0, 1], ior >= 1, unit directions,
//! spot cone angles, parallelograms with area, meshes with valid indices and no zero-area
//! triangles), each failure an [`InvalidField`] naming the offending field relative to the
//! value checked. The one place these rules live: `validate` applies them to the scene file
//! (and adds the file's line), and [`check_light`], [`check_material`] and [`check_mesh`] apply
//! them to descriptions built in code (another scene format's reader). Must not know TOML,
//! read files or report lines.

use super::{CropWindow, Light, Material, TriangleMesh};
use glam::Vec3;

/// Directions closer than this (sine of the angle between them) count as parallel.
pub(crate) const PARALLEL_SINE: f32 = 1e-4;

/// A triangle whose edge vectors span less than this sine of an angle has no usable normal.
pub(crate) const DEGENERATE_SINE: f32 = 1e-6;

/// How far from 1 the length of a direction that must be unit may be.
const UNIT_TOLERANCE: f32 = 1e-3;

/// A value that breaks a rule: the field, relative to the light, material or mesh checked
/// (`power[1]`, `cone_angle_degrees`, `mesh.triangles[4]`), and why. Displays as
/// `field: message`; `String::from` gives that text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct InvalidField {
    pub field: String,
    pub message: String,
}

impl From<InvalidField> for String {
    fn from(e: InvalidField) -> String {
        e.to_string()
    }
}

impl InvalidField {
    pub(crate) fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            message: message.into(),
        }
    }

    /// The same problem, its field named inside `parent` (`mesh` + `positions[3]`).
    fn within(self, parent: &str) -> Self {
        Self {
            field: format!("{parent}.{}", self.field),
            ..self
        }
    }
}

type Checked<T> = Result<T, InvalidField>;

/// Checks a light against the rules the scene file's lights obey; the error names the field
/// as the [`Light`] variant spells it (`direction`, `falloff_start_degrees`, `mesh.positions[2]`).
pub fn check_light(light: &Light) -> Result<(), InvalidField> {
    match light {
        Light::Point { position, power } => {
            finite3("position", *position)?;
            flux("power", *power, WATTS)?;
        }
        Light::Sphere {
            center,
            radius,
            power,
        } => {
            finite3("center", *center)?;
            positive("radius", *radius)?;
            flux("power", *power, WATTS)?;
        }
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            power,
        } => {
            parallelogram(*corner, *edge_u, *edge_v)?;
            flux("power", *power, WATTS)?;
        }
        Light::Spot {
            position,
            direction,
            cone_angle_degrees,
            falloff_start_degrees,
            falloff: _,
            power,
        } => {
            finite3("position", *position)?;
            unit_direction("direction", *direction)?;
            spot_cone(*cone_angle_degrees, *falloff_start_degrees)?;
            flux("power", *power, WATTS)?;
        }
        Light::Distant {
            direction,
            irradiance,
        } => {
            unit_direction("direction", *direction)?;
            flux("irradiance", *irradiance, "W/m²")?;
        }
        Light::Environment { radiance } => {
            flux("radiance", *radiance, "W/(m² sr)")?;
        }
        Light::EnvironmentMap(map) => environment_map(map)?,
        Light::Mesh { mesh, power, .. } => {
            check_mesh(mesh).map_err(|e| e.within("mesh"))?;
            flux("power", *power, WATTS)?;
        }
    }
    Ok(())
}

/// Checks a material: albedo and tints in [0, 1] per channel, ior finite and >= 1.
pub fn check_material(material: &Material) -> Result<(), InvalidField> {
    match material {
        Material::Diffuse { albedo } => unit_rgb("albedo", *albedo).map(drop),
        Material::Mirror { tint } => unit_rgb("tint", *tint).map(drop),
        Material::Glass {
            ior: index,
            reflect_tint,
            transmit_tint,
        } => {
            ior("ior", *index)?;
            unit_rgb("reflect_tint", *reflect_tint)?;
            unit_rgb("transmit_tint", *transmit_tint).map(drop)
        }
        Material::Bsdf(model) => check_model(model),
        Material::Mix { amount, .. } => {
            if (0.0..=1.0).contains(amount) {
                Ok(())
            } else {
                Err(InvalidField::new(
                    "amount",
                    format!("{amount} is not in [0, 1]"),
                ))
            }
        }
    }
}

/// Checks a scene's material table: each material as [`check_material`] does, and every mix's
/// materials (field `materials[i].materials`) in the table and nested at most
/// [`super::MAX_MIX_DEPTH`] deep, which also rules out a mix that reaches itself.
pub fn check_materials(materials: &[Material]) -> Result<(), InvalidField> {
    let within = |i: usize, e: InvalidField| e.within(&format!("materials[{i}]"));
    for (i, material) in materials.iter().enumerate() {
        check_material(material).map_err(|e| within(i, e))?;
    }
    match mix_problem(materials) {
        None => Ok(()),
        Some((i, e)) => Err(within(i, e)),
    }
}

/// The first mix (by index) whose materials are missing, reach it again or nest too deep, and
/// why.
pub(crate) fn mix_problem(materials: &[Material]) -> Option<(usize, InvalidField)> {
    let mut heights = vec![None; materials.len()];
    (0..materials.len())
        .find_map(|i| (mix_height(materials, i, 0, &mut heights).err()).map(|e| (i, e)))
}

/// How many mixes nest in material `id`, itself included (0: not a mix), with `depth` mixes
/// above it; each material's is worked out once, in `heights`.
fn mix_height(
    materials: &[Material],
    id: usize,
    depth: usize,
    heights: &mut [Option<usize>],
) -> Result<usize, InvalidField> {
    let too_deep = || {
        InvalidField::new(
            "materials",
            format!(
                "mixes nest more than {} deep, or a mix reaches itself",
                super::MAX_MIX_DEPTH
            ),
        )
    };
    if let Some(height) = heights[id] {
        return Ok(height);
    }
    let Material::Mix {
        materials: pair, ..
    } = materials[id]
    else {
        heights[id] = Some(0);
        return Ok(0);
    };
    if depth >= super::MAX_MIX_DEPTH {
        return Err(too_deep());
    }
    let mut height = 0;
    for part in pair {
        if part as usize >= materials.len() {
            return Err(InvalidField::new(
                "materials",
                format!(
                    "material {part} does not exist (there are {})",
                    materials.len()
                ),
            ));
        }
        height = height.max(1 + mix_height(materials, part as usize, depth + 1, heights)?);
    }
    if height > super::MAX_MIX_DEPTH {
        return Err(too_deep());
    }
    heights[id] = Some(height);
    Ok(height)
}

/// A BSDF model's colours in [0, 1] (pbrt's uber and plastic may sum above 1, as in pbrt),
/// its indices and roughnesses finite and in range.
fn check_model(model: &crate::bsdf::Model) -> Result<(), InvalidField> {
    use crate::bsdf::Model;
    let alpha = |name: &str, a: glam::Vec2| {
        if a.is_finite() && a.min_element() >= 0.0 && a.max_element() <= 10.0 {
            Ok(())
        } else {
            Err(InvalidField::new(
                name,
                format!("roughness α {a} is not in [0, 10]"),
            ))
        }
    };
    let conductor = |eta: Vec3, k: Vec3| {
        if eta.is_finite() && k.is_finite() && eta.min_element() > 0.0 && k.min_element() >= 0.0 {
            Ok(())
        } else {
            Err(InvalidField::new(
                "eta",
                format!("conductor η {eta}, k {k}: η must be positive, k at least 0"),
            ))
        }
    };
    match *model {
        Model::Plastic { kd, ks, alpha: a } | Model::Substrate { kd, ks, alpha: a } => {
            unit_rgb("kd", kd)?;
            unit_rgb("ks", ks)?;
            alpha("roughness", a)
        }
        Model::Uber {
            kd,
            ks,
            kr,
            kt,
            alpha: a,
            eta,
            opacity,
        } => {
            for (name, c) in [
                ("kd", kd),
                ("ks", ks),
                ("kr", kr),
                ("kt", kt),
                ("opacity", opacity),
            ] {
                unit_rgb(name, c)?;
            }
            ior("ior", eta)?;
            alpha("roughness", a)
        }
        Model::Translucent {
            kd,
            ks,
            reflect,
            transmit,
            alpha: a,
        } => {
            for (name, c) in [
                ("kd", kd),
                ("ks", ks),
                ("reflect", reflect),
                ("transmit", transmit),
            ] {
                unit_rgb(name, c)?;
            }
            alpha("roughness", a)
        }
        Model::Conductor { eta, k, alpha: a } => {
            conductor(eta, k)?;
            alpha("roughness", a)
        }
        Model::Dielectric {
            eta,
            alpha: a,
            reflect_tint,
            transmit_tint,
        } => {
            ior("ior", eta)?;
            unit_rgb("reflect_tint", reflect_tint)?;
            unit_rgb("transmit_tint", transmit_tint)?;
            alpha("roughness", a)
        }
        Model::ThinDielectric { eta } => ior("eta", eta).map(drop),
        Model::CoatedDiffuse {
            reflectance,
            alpha: a,
            eta,
            thickness,
            albedo,
            g,
        } => {
            unit_rgb("reflectance", reflectance)?;
            unit_rgb("albedo", albedo)?;
            ior("eta", eta)?;
            layer(thickness, g)?;
            alpha("roughness", a)
        }
        Model::CoatedConductor {
            interface_alpha,
            interface_eta,
            thickness,
            albedo,
            g,
            conductor_eta,
            conductor_k,
            conductor_alpha,
        } => {
            ior("interface.eta", interface_eta)?;
            unit_rgb("albedo", albedo)?;
            layer(thickness, g)?;
            conductor(conductor_eta, conductor_k)?;
            alpha("interface.roughness", interface_alpha)?;
            alpha("conductor.roughness", conductor_alpha)
        }
        Model::DiffuseTransmission {
            reflectance,
            transmittance,
        } => {
            unit_rgb("reflectance", reflectance)?;
            unit_rgb("transmittance", transmittance).map(drop)
        }
    }
}

fn layer(thickness: f32, g: f32) -> Result<(), InvalidField> {
    if !(thickness.is_finite() && thickness > 0.0) {
        return Err(InvalidField::new(
            "thickness",
            format!("{thickness} is not a positive length"),
        ));
    }
    if !(g.is_finite() && g.abs() < 1.0) {
        return Err(InvalidField::new("g", format!("{g} is not in (−1, 1)")));
    }
    Ok(())
}

/// Checks a triangle mesh: at least one triangle, finite positions, indices in range, no
/// zero-area triangle, and vertex normals (when given) one per position, finite and non-zero.
pub fn check_mesh(mesh: &TriangleMesh) -> Result<(), InvalidField> {
    if mesh.triangles.is_empty() {
        return Err(InvalidField::new("triangles", "is empty: no surface"));
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        finite3(&format!("positions[{i}]"), *p)?;
    }
    let count = mesh.positions.len();
    for (i, triangle) in mesh.triangles.iter().enumerate() {
        let field = format!("triangles[{i}]");
        if let Some(bad) = triangle.iter().find(|&&v| v as usize >= count) {
            return Err(InvalidField::new(
                field,
                format!("index {bad} is out of range ({count} positions)"),
            ));
        }
        if has_zero_area(&mesh.positions, *triangle) {
            return Err(InvalidField::new(field, "has zero area"));
        }
    }
    if let Some(normals) = &mesh.normals {
        if normals.len() != count {
            return Err(InvalidField::new(
                "normals",
                format!("{} normals for {count} positions", normals.len()),
            ));
        }
        for (i, n) in normals.iter().enumerate() {
            let field = format!("normals[{i}]");
            finite3(&field, *n)?;
            if n.length_squared() == 0.0 {
                return Err(InvalidField::new(field, "has zero length"));
            }
        }
    }
    Ok(())
}

pub(crate) const WATTS: &str = "watts";

/// Every component finite; a bad one is reported as `field[i]`.
pub(crate) fn finite3(field: &str, v: Vec3) -> Checked<Vec3> {
    for (i, x) in v.to_array().into_iter().enumerate() {
        if !x.is_finite() {
            return Err(InvalidField::new(
                format!("{field}[{i}]"),
                format!("{x} is not a finite number"),
            ));
        }
    }
    Ok(v)
}

pub(crate) fn positive(field: &str, x: f32) -> Checked<f32> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(InvalidField::new(
            field,
            format!("{x} must be a finite number greater than 0"),
        ))
    }
}

/// A thin lens's radius: finite and >= 0 (0 is a pinhole).
pub(crate) fn lens_radius(field: &str, x: f32) -> Checked<f32> {
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(InvalidField::new(
            field,
            format!("{x} is not a lens radius (a finite number >= 0; 0 is a pinhole)"),
        ))
    }
}

/// A crop window `[x0, x1, y0, y1]` of fractions in [0, 1], each pair put in order as pbrt
/// does, spanning some width and height.
pub(crate) fn crop_window(field: &str, [x0, x1, y0, y1]: [f32; 4]) -> Checked<CropWindow> {
    if let Some(x) = [x0, x1, y0, y1]
        .into_iter()
        .find(|x| !(0.0..=1.0).contains(x))
    {
        return Err(InvalidField::new(
            field,
            format!("{x} is not a fraction of the film in [0, 1]"),
        ));
    }
    let (x, y) = ([x0.min(x1), x0.max(x1)], [y0.min(y1), y0.max(y1)]);
    if x[0] == x[1] || y[0] == y[1] {
        return Err(InvalidField::new(
            field,
            format!("[{x0}, {x1}, {y0}, {y1}] is empty (x0 = x1 or y0 = y1)"),
        ));
    }
    Ok(CropWindow { x, y })
}

/// A crop window that holds at least one pixel of a `width` × `height` film.
pub(crate) fn crop_holds_pixels(
    field: &str,
    crop: &CropWindow,
    width: u32,
    height: u32,
) -> Checked<()> {
    let [x0, x1, y0, y1] = crop.pixels(width, height);
    if x0 < x1 && y0 < y1 {
        return Ok(());
    }
    Err(InvalidField::new(
        field,
        format!(
            "[{}, {}, {}, {}] holds no whole pixel of the {width} × {height} film",
            crop.x[0], crop.x[1], crop.y[0], crop.y[1]
        ),
    ))
}

/// A light's flux, irradiance or radiance in `unit` per channel: finite, >= 0, not all zero.
/// An environment map: a size that matches its texels, finite non-negative texels, not all
/// black, and an orthonormal frame.
fn environment_map(map: &crate::scene::EnvironmentMap) -> Checked<()> {
    if map.width == 0 || map.height == 0 || map.texels.len() != (map.width * map.height) as usize {
        return Err(InvalidField::new(
            "texels",
            format!(
                "{} texels for a {}x{} image",
                map.texels.len(),
                map.width,
                map.height
            ),
        ));
    }
    if let Some(i) = (map.texels.iter()).position(|t| !(t.is_finite() && t.min_element() >= 0.0)) {
        return Err(InvalidField::new(
            format!("texels[{i}]"),
            format!("{} W/(m² sr) must be finite and >= 0", map.texels[i]),
        ));
    }
    if map.texels.iter().all(|&t| t == Vec3::ZERO) {
        return Err(InvalidField::new(
            "texels",
            "every texel is black: the light emits nothing",
        ));
    }
    let m = map.light_to_world;
    let off = (m.transpose() * m - glam::Mat3::IDENTITY).to_cols_array();
    if !off.iter().all(|x| x.abs() < 1e-4) {
        return Err(InvalidField::new(
            "light_to_world",
            "is not orthonormal (a rotation, optionally with a mirror)",
        ));
    }
    Ok(())
}

pub(crate) fn flux(field: &str, rgb: Vec3, unit: &str) -> Checked<Vec3> {
    for (i, x) in rgb.to_array().into_iter().enumerate() {
        if !(x.is_finite() && x >= 0.0) {
            return Err(InvalidField::new(
                format!("{field}[{i}]"),
                format!("{x} {unit} must be finite and >= 0"),
            ));
        }
    }
    if rgb == Vec3::ZERO {
        return Err(InvalidField::new(
            field,
            "is zero in every channel: the light emits nothing",
        ));
    }
    Ok(rgb)
}

/// The albedo and tint rule, shared with MTL `Kd` and `Ks`.
pub(crate) fn is_unit_channel(x: f32) -> bool {
    (0.0..=1.0).contains(&x)
}

/// The index of refraction rule, shared with MTL `Ni`.
pub(crate) fn is_ior(x: f32) -> bool {
    x.is_finite() && x >= 1.0
}

/// Every channel in [0, 1] (an albedo or a tint).
pub(crate) fn unit_rgb(field: &str, rgb: Vec3) -> Checked<Vec3> {
    for (i, x) in rgb.to_array().into_iter().enumerate() {
        if !is_unit_channel(x) {
            return Err(InvalidField::new(
                format!("{field}[{i}]"),
                format!("{x} is not in [0, 1]"),
            ));
        }
    }
    Ok(rgb)
}

pub(crate) fn ior(field: &str, x: f32) -> Checked<f32> {
    if is_ior(x) {
        Ok(x)
    } else {
        Err(InvalidField::new(
            field,
            format!("{x} must be a finite index of refraction >= 1"),
        ))
    }
}

/// A finite, non-zero vector, brought to unit length (a direction as the scene file gives it).
pub(crate) fn direction(field: &str, v: Vec3) -> Checked<Vec3> {
    finite3(field, v)?;
    let length = v.length();
    if !(length > 0.0 && length.is_finite()) {
        return Err(InvalidField::new(field, "has zero length: no direction"));
    }
    Ok(v / length)
}

/// A direction that must already be unit.
fn unit_direction(field: &str, v: Vec3) -> Checked<Vec3> {
    direction(field, v)?;
    let length = v.length();
    if (length - 1.0).abs() > UNIT_TOLERANCE {
        return Err(InvalidField::new(
            field,
            format!("has length {length}, not 1: give a unit vector"),
        ));
    }
    Ok(v)
}

/// A spot light's half-angles: the cone in (0, 180] degrees, the falloff start in [0, cone].
pub(crate) fn spot_cone(cone_angle: f32, falloff_start: f32) -> Checked<()> {
    if !(cone_angle.is_finite() && cone_angle > 0.0 && cone_angle <= 180.0) {
        return Err(InvalidField::new(
            "cone_angle_degrees",
            format!("{cone_angle} is not in (0, 180] degrees"),
        ));
    }
    if !(falloff_start.is_finite() && (0.0..=cone_angle).contains(&falloff_start)) {
        return Err(InvalidField::new(
            "falloff_start_degrees",
            format!("{falloff_start} is not in [0, {cone_angle}] degrees (0 up to the cone angle)"),
        ));
    }
    Ok(())
}

/// `corner`, `edge_u`, `edge_v`: finite, edges non-zero and not parallel.
pub(crate) fn parallelogram(corner: Vec3, edge_u: Vec3, edge_v: Vec3) -> Checked<()> {
    finite3("corner", corner)?;
    finite3("edge_u", edge_u)?;
    finite3("edge_v", edge_v)?;
    if edge_u.length_squared() == 0.0 {
        return Err(InvalidField::new("edge_u", "has zero length"));
    }
    if edge_v.length_squared() == 0.0 {
        return Err(InvalidField::new("edge_v", "has zero length"));
    }
    if edge_u.normalize().cross(edge_v.normalize()).length() < PARALLEL_SINE {
        return Err(InvalidField::new(
            "edge_v",
            "is parallel to edge_u: the quad has no area",
        ));
    }
    Ok(())
}

/// Whether a triangle's corners are repeated or collinear (relative to its edges' lengths).
pub(crate) fn has_zero_area(positions: &[Vec3], [a, b, c]: [u32; 3]) -> bool {
    let p0 = positions[a as usize];
    let e1 = positions[b as usize] - p0;
    let e2 = positions[c as usize] - p0;
    // Relative test: |e1 × e2| = |e1| |e2| sin(angle).
    let cross = e1.cross(e2).length();
    cross.is_nan() || cross <= DEGENERATE_SINE * e1.length() * e2.length()
}

#[cfg(test)]
#[path = "rules_tests.rs"]
mod tests;
