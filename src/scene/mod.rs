//! Scene description: reads the TOML scene format (docs/scene-format.md) and the OBJ/MTL meshes
//! it names, checks every value, and resolves it all into plain world-space data
//! ([`SceneDescription`]). This module owns parsing and error reporting: every problem becomes
//! a [`SceneError`] naming the file, the 1-based line and the field path, and nothing here
//! panics on bad input. It must not call Embree or trace anything; the [`crate::world`] module
//! turns a [`SceneDescription`] into an Embree scene.
//!
//! Inside: `document` holds the spanned TOML text and turns byte offsets into lines and field
//! paths, `format` holds the serde structs of the file format, `validate` checks them and builds
//! the public types, `rules` holds the value rules the public types obey (shared by `validate`
//! and by [`check_light`] and [`check_material`], for descriptions built in code), `mesh` reads
//! OBJ/MTL files, `transform` places meshes in the world, `tessellate` turns curved and
//! subdivision surfaces into triangles in their own space, `curves` holds Bézier curves.

pub mod check;
mod curves;
pub mod dipole;
mod document;
pub mod environment;
pub mod files;
mod format;
mod medium;
mod mesh;
pub mod metals;
mod obj_fast;
mod pbrt;
pub mod ply;
mod rules;
pub(crate) mod tessellate;
pub mod texture;
mod toml_bsdf;
mod toml_media;
mod toml_mix;
mod toml_texture;
pub(crate) mod transform;
mod transport;
mod validate;

pub use curves::{CurveKind, Curves, check_curves};
pub use environment::{EnvironmentMap, SphereMapping};
pub use medium::{Medium, MediumBoundary, MediumId, MediumInterface, MediumKind, SceneMedia};
pub use rules::{InvalidField, check_light, check_material, check_materials, check_mesh};
pub use texture::{Cutout, Texture, TexturedMaterial, TexturedParameter};
pub use transport::{PBRT_DEFAULT_MAX_DEPTH, Transport};

use glam::{Mat3, Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    /// The scene file this was read from.
    pub source: PathBuf,
    pub camera: Camera,
    pub lights: Vec<Light>,
    /// Scene materials in name order, then materials taken from MTL files in order of first use.
    pub materials: Vec<Material>,
    pub shapes: Vec<Shape>,
    /// Groups of shapes defined once and placed by [`SceneDescription::instances`].
    pub prototypes: Vec<Prototype>,
    pub instances: Vec<Instance>,
    /// The materials some of whose parameters are textures, each once; empty in a scene
    /// without textures (which renders exactly as before textures existed).
    pub textured_materials: Vec<TexturedMaterial>,
    /// What the written image's pixels are multiplied by (pbrt's film settings; the TOML
    /// format leaves every image as rendered).
    pub response: ImageResponse,
    /// How far light is followed: a pbrt `Integrator` line's cap, or dpm's own.
    pub transport: Transport,
    /// Participating media, the surfaces that bound them and what sits in them.
    pub media: SceneMedia,
}

/// A linear map from the rendered radiance to the written pixel values: a white balance (a
/// 3×3 matrix on linear sRGB, rows first) and then a scale. The default, the identity, leaves
/// images byte for byte as rendered.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageResponse {
    pub scale: f64,
    pub white_balance: Option<[[f64; 3]; 3]>,
}

impl Default for ImageResponse {
    fn default() -> Self {
        ImageResponse {
            scale: 1.0,
            white_balance: None,
        }
    }
}

impl ImageResponse {
    pub fn is_identity(&self) -> bool {
        *self == ImageResponse::default()
    }

    /// The written value of rendered linear sRGB `rgb`.
    pub fn apply(&self, rgb: [f64; 3]) -> [f64; 3] {
        let balanced = match &self.white_balance {
            None => rgb,
            Some(m) => m.map(|row| row[0] * rgb[0] + row[1] * rgb[1] + row[2] * rgb[2]),
        };
        balanced.map(|v| v * self.scale)
    }
}

/// The camera: where it stands and looks, how film positions become rays ([`Projection`],
/// [`ThinLens`]), the full film's size, and the part of the film that is rendered and written
/// ([`CropWindow`]). `up` is not parallel to `look_at - position`, which is not zero.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    pub projection: Projection,
    /// Depth of field (perspective and orthographic; radius 0 is a pinhole).
    pub lens: ThinLens,
    /// The full film, in pixels: the projection spans it whatever the crop.
    pub width: u32,
    pub height: u32,
    /// Which way the image's x axis runs.
    pub handedness: Handedness,
    pub crop: CropWindow,
}

impl Camera {
    /// The full vertical field of view of a perspective camera.
    pub fn fov_y_degrees(&self) -> Option<f32> {
        match self.projection {
            Projection::Perspective { fov_y_degrees } => Some(fov_y_degrees),
            _ => None,
        }
    }

    /// The film pixels rendered and written: [`CropWindow::pixels`] of this film.
    pub fn crop_pixels(&self) -> [u32; 4] {
        self.crop.pixels(self.width, self.height)
    }

    /// The written image's size in pixels (the crop's; zero where the crop holds no pixel).
    pub fn image_size(&self) -> (u32, u32) {
        let [x0, x1, y0, y1] = self.crop_pixels();
        (x1 - x0, y1 - y0)
    }
}

/// How the camera turns film positions into ray directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Rays from one point; the full vertical field of view is in (0, 180) degrees.
    Perspective { fov_y_degrees: f32 },
    /// Parallel rays along the view direction from a film `view_height` world units tall
    /// (> 0), as wide as the film's aspect makes it, centred on the view axis.
    Orthographic { view_height: f32 },
    /// pbrt-v3's lat-long camera: the film covers the whole sphere, θ from the top of the
    /// image (θ = 0 along `up`) and φ from its left edge, the direction in camera space
    /// (x right, y up, z forward) being (sin θ cos φ, cos θ, sin θ sin φ).
    Environment,
}

/// A thin lens of `radius` (>= 0; 0 is a pinhole) focused on the plane `focal_distance` (> 0)
/// ahead along the view direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    pub radius: f32,
    pub focal_distance: f32,
}

impl ThinLens {
    /// pbrt's defaults: a pinhole, focused at 10⁶.
    pub const PINHOLE: ThinLens = ThinLens {
        radius: 0.0,
        focal_distance: 1e6,
    };
}

impl Default for ThinLens {
    fn default() -> Self {
        Self::PINHOLE
    }
}

/// The part of the film rendered, as fractions of its width (`x`, from the left) and height
/// (`y`, from the top), each pair ordered, within [0, 1] and holding at least one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CropWindow {
    pub x: [f32; 2],
    pub y: [f32; 2],
}

impl CropWindow {
    pub const FULL: CropWindow = CropWindow {
        x: [0.0, 1.0],
        y: [0.0, 1.0],
    };

    /// The pixels of a `width` × `height` film inside the window, `[x0, x1) × [y0, y1)` as
    /// `[x0, x1, y0, y1]`, rounded as pbrt rounds them: each edge at the first pixel whose
    /// left (top) side is at or past the window's, the product taken in f32 as pbrt takes it
    /// (0.2 of 30 pixels is pixel 6, not the 7 that 0.2's f32 value times 30 exactly gives).
    pub fn pixels(&self, width: u32, height: u32) -> [u32; 4] {
        let edge =
            |fraction: f32, pixels: u32| ((fraction * pixels as f32).ceil() as u32).min(pixels);
        let [x0, x1] = self.x.map(|f| edge(f, width));
        let [y0, y1] = self.y.map(|f| edge(f, height));
        [x0, x1.max(x0), y0, y1.max(y0)]
    }
}

impl Default for CropWindow {
    fn default() -> Self {
        Self::FULL
    }
}

/// The image's x axis runs along `forward × up` (right-handed, dpm's TOML default) or along
/// `up × forward` (left-handed, as pbrt's camera space: a pbrt `LookAt` camera).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Handedness {
    #[default]
    Right,
    Left,
}

/// A light. `power`, where a light has one, is its total emitted flux in watts per channel
/// (finite, >= 0, not all zero: [`check_light`] holds every variant's rules).
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Emits equally in every direction: intensity `power / 4π` W/sr.
    Point { position: Vec3, power: Vec3 },
    /// A diffuse emitter over a sphere's surface.
    Sphere {
        center: Vec3,
        radius: f32,
        power: Vec3,
    },
    /// Emits from one side only: the side `edge_u × edge_v` points to.
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        power: Vec3,
    },
    /// A point light emitting into a cone (pbrt's "spot"): full intensity within
    /// `falloff_start_degrees` of `direction`, none beyond `cone_angle_degrees` (both
    /// half-angles, 0 < cone_angle <= 180 and 0 <= falloff_start <= cone_angle), the transition
    /// shaped by `falloff`. `direction` is unit. The intensity on the axis is
    /// `power / falloff.solid_angle(cone_angle_degrees, falloff_start_degrees)`.
    Spot {
        position: Vec3,
        direction: Vec3,
        cone_angle_degrees: f32,
        falloff_start_degrees: f32,
        falloff: SpotFalloff,
        power: Vec3,
    },
    /// Parallel light from infinitely far (pbrt's "distant"): `direction` is the unit direction
    /// the light travels; `irradiance` is W/m² per channel on a surface facing the light.
    Distant { direction: Vec3, irradiance: Vec3 },
    /// Constant radiance from every direction (pbrt's "infinite" with a constant L),
    /// W/(m² sr) per channel. Eye rays that leave the scene see it.
    Environment { radiance: Vec3 },
    /// Radiance from every direction by an image (pbrt's "infinite" with `mapname` or
    /// `filename`). Eye rays that leave the scene see it.
    EnvironmentMap(EnvironmentMap),
    /// A diffuse emitter over a triangle mesh (pbrt's AreaLightSource "diffuse" on a
    /// trianglemesh or plymesh): uniform radiance over its area, `power` the total flux. It
    /// emits on the side its triangles' geometric normals point to (counter-clockwise winding,
    /// as [`TriangleMesh`] documents), on both sides when `two_sided`; its radiance is
    /// `power / (π A)` one-sided, `power / (2π A)` two-sided, for the total area `A`. The
    /// mesh's `material` is unused (set 0) and so are its vertex normals.
    Mesh {
        mesh: TriangleMesh,
        power: Vec3,
        two_sided: bool,
    },
}

/// How a spot light's intensity falls from full at `falloff_start` to none at `cone_angle`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpotFalloff {
    /// pbrt-v4: smoothstep(cos cone_angle, cos falloff_start, cos θ).
    Smoothstep,
    /// pbrt-v3: ((cos θ − cos cone_angle)/(cos falloff_start − cos cone_angle))^4.
    Quartic,
}

impl SpotFalloff {
    /// The intensity at angle θ from the axis relative to the axis's, given the cosines of θ,
    /// of the cone angle and of the falloff start: 1 inside the falloff start, 0 outside the
    /// cone (a step there when the two angles are equal).
    #[inline]
    pub fn factor(self, cos_theta: f32, cos_cone: f32, cos_start: f32) -> f32 {
        if cos_theta >= cos_start {
            return 1.0;
        }
        if cos_theta <= cos_cone {
            return 0.0;
        }
        let t = ((cos_theta - cos_cone) / (cos_start - cos_cone)).clamp(0.0, 1.0);
        match self {
            SpotFalloff::Smoothstep => t * t * (3.0 - 2.0 * t),
            SpotFalloff::Quartic => (t * t) * (t * t),
        }
    }

    /// ∫ factor dω over the sphere of directions, in steradians: a spot of axis intensity I
    /// emits Φ = I · this. With α the cone angle and β the falloff start it is
    /// 2π (1 − (cos α + cos β)/2) for smoothstep and 2π ((1 − cos β) + (cos β − cos α)/5) for
    /// quartic (the band's mean factor is 1/2 and 1/5).
    pub fn solid_angle(self, cone_angle_degrees: f32, falloff_start_degrees: f32) -> f32 {
        let (cos_cone, cos_start) = (
            cone_angle_degrees.to_radians().cos(),
            falloff_start_degrees.to_radians().cos(),
        );
        2.0 * std::f32::consts::PI * ((1.0 - cos_start) + (cos_start - cos_cone) * self.band_mean())
    }

    /// The mean factor over the band between the falloff start and the cone, in cos θ.
    pub(crate) fn band_mean(self) -> f32 {
        match self {
            SpotFalloff::Smoothstep => 0.5,
            SpotFalloff::Quartic => 0.2,
        }
    }
}

/// A material. Every albedo and tint channel lies in [0, 1] ([`check_material`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector.
    Diffuse { albedo: Vec3 },
    /// Perfect specular reflector; `tint` scales what it reflects (pbrt's Kr).
    Mirror { tint: Vec3 },
    /// Dielectric with index of refraction `ior >= 1` (outside is vacuum): what it reflects
    /// is scaled by `reflect_tint` (pbrt's Kr), what it transmits by `transmit_tint` (Kt).
    Glass {
        ior: f32,
        reflect_tint: Vec3,
        transmit_tint: Vec3,
    },
    /// A material modelled by its BSDF (pbrt's plastic, uber, rough metals and glass, ...):
    /// its Lambert lobes read the photon maps as a diffuse surface does, its other lobes are
    /// sampled and followed. Diffuse, mirror and smooth glass keep their own variants, so a
    /// scene of those alone renders as it always has.
    Bsdf(crate::bsdf::Model),
    /// At each point of the surface one of two materials (ids into
    /// [`SceneDescription::materials`], either maybe a mix itself): `materials[1]` with
    /// probability `amount` (in [0, 1]), else `materials[0]`, as pbrt-v4 chooses. The world
    /// picks one by a hash of the hit point ([`crate::world::World::material_at`]), so
    /// nothing that shades or scatters ever sees a mix.
    Mix { materials: [u32; 2], amount: f32 },
}

/// How deep mixes of mixes may nest: deeper (or a cycle, which only a description built in
/// code could hold) is refused by [`check_materials`], and a hit there shows black.
pub const MAX_MIX_DEPTH: usize = 16;

impl Material {
    /// Whether photons stay on it (it has a lobe read from photons, microfacet reflection
    /// counting from `glossy_min_alpha`) and a camera path reads the photon maps there; a
    /// mix (its materials looked up in `materials`) where either of its materials does.
    pub fn is_diffuse_receiver(&self, materials: &[Material], glossy_min_alpha: f32) -> bool {
        self.any_shown(materials, &|m| match m {
            Material::Diffuse { .. } => true,
            Material::Bsdf(model) => crate::bsdf::Bsdf::split_at(model, glossy_min_alpha)
                .has(crate::bsdf::Part::Estimated),
            _ => false,
        })
    }

    /// Whether light leaving it can focus into a caustic: it has a lobe that is followed
    /// rather than estimated from photons (a mirror, glass, a glossy coat smoother than
    /// `glossy_min_alpha`); a mix where either of its materials does.
    pub fn makes_caustics(&self, materials: &[Material], glossy_min_alpha: f32) -> bool {
        self.any_shown(materials, &|m| match m {
            Material::Mirror { .. } | Material::Glass { .. } => true,
            Material::Bsdf(model) => crate::bsdf::Bsdf::split_at(model, glossy_min_alpha)
                .has(crate::bsdf::Part::Followed),
            _ => false,
        })
    }

    /// Whether `test` holds for a material a point of this one may show: itself, or any
    /// material a mix reaches in `materials` (down to [`MAX_MIX_DEPTH`]). `test` never sees a
    /// mix.
    pub fn any_shown(&self, materials: &[Material], test: &dyn Fn(&Material) -> bool) -> bool {
        fn reach(
            m: &Material,
            materials: &[Material],
            test: &dyn Fn(&Material) -> bool,
            depth: usize,
        ) -> bool {
            match m {
                Material::Mix {
                    materials: pair, ..
                } => {
                    depth < MAX_MIX_DEPTH
                        && pair.iter().any(|&id| {
                            (materials.get(id as usize))
                                .is_some_and(|m| reach(m, materials, test, depth + 1))
                        })
                }
                leaf => test(leaf),
            }
        }
        reach(self, materials, test, 0)
    }

    /// A mirror that reflects everything.
    pub const MIRROR: Material = Material::Mirror { tint: Vec3::ONE };

    /// Clear glass of index `ior`: untinted reflection and transmission.
    pub fn clear_glass(ior: f32) -> Material {
        Material::Glass {
            ior,
            reflect_tint: Vec3::ONE,
            transmit_tint: Vec3::ONE,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `material` indexes [`SceneDescription::materials`].
    Sphere {
        center: Vec3,
        radius: f32,
        material: u32,
        /// From the world's axes to the sphere's own (orthonormal, a mirror allowed): where
        /// its (u, v) are measured. pbrt's spheres turn with their transform; TOML spheres
        /// keep the world's axes (the identity).
        to_object: Mat3,
    },
    /// Shared, not copied, with the tracer: Embree reads the positions and triangles where
    /// they lie, and shading reads the normals and (u, v) from the same mesh.
    Triangles(Arc<TriangleMesh>),
    Curves(Curves),
}

impl Shape {
    /// The corners of a box around the shape.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Shape::Sphere { center, radius, .. } => (*center - *radius, *center + *radius),
            Shape::Triangles(mesh) => mesh.bounds(),
            Shape::Curves(curves) => curves.bounds(),
        }
    }

    /// The shape's material: an index into [`SceneDescription::materials`].
    pub fn material(&self) -> u32 {
        match self {
            Shape::Sphere { material, .. } => *material,
            Shape::Triangles(mesh) => mesh.material,
            Shape::Curves(curves) => curves.material,
        }
    }
}

/// Shapes defined once in a space of their own and placed any number of times (pbrt's
/// `ObjectBegin`/`ObjectInstance`): their materials index [`SceneDescription::materials`];
/// they carry no lights.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Prototype {
    pub name: String,
    pub shapes: Vec<Shape>,
}

/// One placement of a [`Prototype`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Indexes [`SceneDescription::prototypes`].
    pub prototype: u32,
    /// From the prototype's space to the world's: affine and invertible.
    pub object_to_world: glam::Mat4,
}

/// World-space triangles with one material; `normals`, when present, are per vertex and unit;
/// `uvs`, when present, are per-vertex texture coordinates (without them a triangle's corners
/// take pbrt's (0, 0), (1, 0), (1, 1)). Triangles are wound counter-clockwise seen from the
/// side their geometric normal points to; none has zero area.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub triangles: Vec<[u32; 3]>,
    /// Indexes [`SceneDescription::materials`].
    pub material: u32,
    /// Where the mesh is cut away, read at the hit's texture coordinates.
    pub cutout: Option<Cutout>,
}

/// The corners' (u, v) of a triangle of a mesh without texture coordinates: pbrt's.
pub const DEFAULT_CORNER_UVS: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::ONE];

impl TriangleMesh {
    /// Triangle `t`'s corners' (u, v).
    #[inline]
    pub fn corner_uvs(&self, t: usize) -> [Vec2; 3] {
        match &self.uvs {
            Some(uvs) => self.triangles[t].map(|i| uvs[i as usize]),
            None => DEFAULT_CORNER_UVS,
        }
    }

    /// The corners of a box around the mesh.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.positions.iter()).fold((Vec3::MAX, Vec3::MIN), |(a, b), p| (a.min(*p), b.max(*p)))
    }
}

/// A scene error names the file, the line (when known) and the field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{}{}: {field}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default(), column.map(|c| format!(":{c}")).unwrap_or_default())]
pub struct SceneError {
    /// The scene file, or the OBJ/MTL file when the problem lies inside one.
    pub file: PathBuf,
    /// 1-based line in `file`.
    pub line: Option<usize>,
    /// 1-based column in `line`, where the format has a finer place than the line (pbrt).
    pub column: Option<usize>,
    /// Field path in the scene file, e.g. `objects[2].radius` or `camera.fov_y`.
    pub field: String,
    pub message: String,
}

/// What loading noticed and repaired without failing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// Zero-area mesh triangles left out (they would give NaN normals).
    pub degenerate_triangles_dropped: usize,
    /// Problems that do not stop a render but probably spoil it (e.g. a light sealed inside
    /// a closed opaque object the camera is outside of).
    pub warnings: Vec<String>,
    /// What was read and deliberately not used (a pbrt file's Sampler or Integrator).
    pub notes: Vec<String>,
}

/// How to read a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Refuse what would otherwise be mapped with a warning (a pbrt material dpm cannot
    /// represent exactly).
    pub strict: bool,
    /// Read a pbrt scene without an `Integrator` line as pbrt renders it (`path`, maxdepth
    /// 5) instead of with dpm's own transport.
    pub pbrt_default_integrator: bool,
}

impl LoadOptions {
    /// `--strict`: refusing what dpm would approximate, nothing else changed.
    pub fn strict() -> Self {
        Self {
            strict: true,
            ..Self::default()
        }
    }
}

/// Reads and checks the scene file at `path` (TOML, or pbrt by the `.pbrt` extension); mesh
/// files resolve relative to its folder.
pub fn load(path: &Path) -> Result<SceneDescription, SceneError> {
    load_with_report(path).map(|(scene, _report)| scene)
}

/// [`load`], also returning what was repaired on the way.
pub fn load_with_report(path: &Path) -> Result<(SceneDescription, LoadReport), SceneError> {
    load_with_options(path, &LoadOptions::default())
}

/// [`load_with_report`] with `options`.
pub fn load_with_options(
    path: &Path,
    options: &LoadOptions,
) -> Result<(SceneDescription, LoadReport), SceneError> {
    load_from(path, &files::Disk, options)
}

/// [`load_with_options`], reading the scene and every file it names from `files` (the fuzz
/// targets give an in-memory set).
pub fn load_from(
    path: &Path,
    files: &dyn files::SceneFiles,
    options: &LoadOptions,
) -> Result<(SceneDescription, LoadReport), SceneError> {
    let whole_file_error = |message: String| SceneError {
        file: path.to_path_buf(),
        line: None,
        column: None,
        field: "scene".into(),
        message,
    };
    if files.is_dir(path) {
        return Err(whole_file_error("is a directory, not a scene file".into()));
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pbrt"))
    {
        return pbrt::load(path, files, options);
    }
    let bytes = files
        .read(path)
        .map_err(|err| whole_file_error(format!("cannot read the scene file: {err}")))?;
    let text = String::from_utf8(bytes).map_err(|err| not_utf8(path, err))?;
    parse_with(&text, path, files)
}

/// A scene file that is not UTF-8 text: the error points at the first bad byte's line.
fn not_utf8(path: &Path, err: std::string::FromUtf8Error) -> SceneError {
    let bytes = err.as_bytes();
    let at = err.utf8_error().valid_up_to();
    let line_start = bytes[..at]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    SceneError {
        file: path.to_path_buf(),
        line: Some(1 + bytes[..at].iter().filter(|&&b| b == b'\n').count()),
        column: None,
        field: "scene".into(),
        message: format!(
            "is not UTF-8 text: byte 0x{:02x} at column {} is not valid UTF-8",
            bytes[at],
            1 + at - line_start
        ),
    }
}

/// Reads a scene from `text` as if it were the file `source` (which names it in errors and
/// anchors relative mesh paths; it need not exist when the scene has no meshes).
pub fn parse(text: &str, source: &Path) -> Result<(SceneDescription, LoadReport), SceneError> {
    parse_with(text, source, &files::Disk)
}

/// [`parse`], reading the meshes and material libraries it names from `files`.
pub fn parse_with(
    text: &str,
    source: &Path,
    files: &dyn files::SceneFiles,
) -> Result<(SceneDescription, LoadReport), SceneError> {
    let doc = document::Document::parse(source, text)?;
    let spec = format::read_scene(&doc)?;
    let scene_folder = source.parent().unwrap_or(Path::new("")).to_path_buf();

    let camera = validate::camera(&doc, &spec.camera)?;
    let mut report = LoadReport::default();
    let mut lights = Vec::new();
    for (i, light) in spec.lights.iter().enumerate() {
        let path = format!("lights[{i}]");
        lights.push(match light {
            format::LightSpec::Mesh(mesh_spec) => {
                let placement = validate::mesh_placement(&doc, &path, mesh_spec.into(), None)?;
                let (mesh, dropped) =
                    mesh::load_emitter(&doc, &path, &scene_folder, &placement, files)?;
                report.degenerate_triangles_dropped += dropped;
                validate::mesh_light(&doc, &path, mesh, mesh_spec)?
            }
            other => validate::light(&doc, &path, other)?,
        });
    }
    let mut materials = validate::MaterialTable::default();
    let mut textured_materials = Vec::new();
    let images = toml_texture::ImageSource {
        folder: &scene_folder,
        files,
    };
    // Each entry's index, its place in name order, for mixes to name the others by.
    let names: std::collections::HashMap<&str, u32> = (spec.materials.iter().enumerate())
        .map(|(i, (name, _))| (name.as_str(), i as u32))
        .collect();
    for (name, material) in &spec.materials {
        let path = document::child_path("materials", name);
        let (material, textures) = validate::material(&doc, &path, material, &images, &names)?;
        let index = materials.add_named(name, material);
        debug_assert_eq!(Some(&index), names.get(name.as_str()));
        if !textures.is_empty() {
            textured_materials.push(TexturedMaterial {
                material: index,
                textures,
            });
        }
    }

    toml_mix::check_nesting(&doc, &spec.materials, materials.materials())?;

    let media = toml_media::read_media(&doc)?;
    let names = &spec.media_names;
    let mut scene_media = SceneMedia {
        camera: toml_media::resolve(&doc, "camera.medium", names.camera.as_deref(), &media)?,
        ..SceneMedia::default()
    };
    for (i, name) in names.lights.iter().enumerate() {
        let path = format!("lights[{i}].medium");
        if let Some(m) = toml_media::resolve(&doc, &path, name.as_deref(), &media)? {
            scene_media.light_media.push((i, m));
        }
    }
    let bounds_only = |object: &format::ObjectSpec| match object {
        format::ObjectSpec::Sphere(s) => s.material.is_empty(),
        format::ObjectSpec::Quad(q) => q.material.is_empty(),
        format::ObjectSpec::Mesh(m) => m.material.as_deref() == Some(""),
    };
    if spec.objects.iter().any(bounds_only) {
        // The material "" of objects that only bound media: never shaded.
        materials.add_named("", Material::Diffuse { albedo: Vec3::ZERO });
    }

    let mut shapes = Vec::new();
    for (i, object) in spec.objects.iter().enumerate() {
        let path = format!("objects[{i}]");
        let made = match object {
            format::ObjectSpec::Sphere(sphere) => {
                vec![validate::sphere(&doc, &path, sphere, &materials)?]
            }
            format::ObjectSpec::Quad(quad) => {
                vec![validate::quad(&doc, &path, quad, &materials)?]
            }
            format::ObjectSpec::Mesh(mesh_spec) => {
                let placement =
                    validate::mesh_object_placement(&doc, &path, mesh_spec, &materials)?;
                let loaded = mesh::load(
                    &doc,
                    &path,
                    &scene_folder,
                    &placement,
                    &mut materials,
                    files,
                )?;
                report.degenerate_triangles_dropped += loaded.degenerate_triangles_dropped;
                report.warnings.extend(loaded.warnings);
                loaded
                    .meshes
                    .into_iter()
                    .map(|m| Shape::Triangles(Arc::new(m)))
                    .collect()
            }
        };
        let (inside, outside) = &names.objects[i];
        let sides = (inside.as_deref(), outside.as_deref());
        let interface = toml_media::interface(&doc, &path, sides, &media)?;
        if bounds_only(object) {
            if !interface.is_transition() {
                return Err(doc.error(
                    &document::child_path(&path, "material"),
                    "material \"\" only bounds media: name a different medium inside and outside",
                ));
            }
            let boundaries = made
                .into_iter()
                .map(|shape| MediumBoundary { shape, interface });
            scene_media.boundaries.extend(boundaries);
            continue;
        }
        if interface.is_transition() {
            let first = shapes.len();
            let indices = first..first + made.len();
            scene_media
                .shape_interfaces
                .extend(indices.map(|k| (k, interface)));
        }
        shapes.extend(made);
    }
    scene_media.media = media;
    let named = |m: MediumId| {
        let sides = scene_media.boundaries.iter().map(|b| b.interface);
        let surfaces = scene_media.shape_interfaces.iter().map(|(_, i)| *i);
        (sides.chain(surfaces))
            .filter(|i| i.inside == Some(m) || i.outside == Some(m))
            .count()
    };
    let counts: Vec<usize> = (0..scene_media.media.len())
        .map(|m| named(m as MediumId))
        .collect();
    for (medium, count) in scene_media.media.iter_mut().zip(counts) {
        medium.bounded_by = count;
    }

    let scene = SceneDescription {
        source: source.to_path_buf(),
        camera,
        lights,
        materials: materials.into_materials(),
        shapes,
        prototypes: Vec::new(),
        instances: Vec::new(),
        textured_materials,
        response: ImageResponse::default(),
        transport: Transport::Full,
        media: scene_media,
    };
    report
        .warnings
        .extend(validate::enclosed_light_warnings(&scene));
    Ok((scene, report))
}
