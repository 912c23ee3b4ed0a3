//! pbrt's directives, read in order with pbrt's graphics state: the current transform, the
//! attribute and transform stacks, named coordinate systems, the current and named materials,
//! the current area light and `ReverseOrientation`. The result is a [`Parsed`] list of
//! cameras, lights, shapes and material definitions, each with its transform and place in the
//! files, for [`super::mapping`] to turn into dpm's types. Owns the language and `Include`;
//! must not decide what dpm can render.

use super::args::Args;
use super::lexer::{Token, TokenKind, tokens};
use super::params::{ParamList, show};
use super::{Dialect, PbrtError, Place};
use crate::scene::files::SceneFiles;
use crate::scene::transform::rotation;
use glam::{Mat4, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Deeper `Include` nesting than this is taken for a cycle nobody meant.
const MAX_INCLUDE_DEPTH: usize = 32;

/// A directive with a type and parameters, where it was written.
#[derive(Debug)]
pub(super) struct Item {
    pub kind: String,
    pub params: ParamList,
    pub at: Place,
}

#[derive(Debug)]
pub(super) struct CameraItem {
    pub item: Item,
    pub camera_to_world: Mat4,
}

#[derive(Debug)]
pub(super) struct LightItem {
    pub item: Item,
    pub ctm: Mat4,
}

#[derive(Debug)]
pub(super) struct ShapeItem {
    pub item: Item,
    pub ctm: Mat4,
    pub reverse_orientation: bool,
    /// Index into [`Parsed::materials`]; `None` is pbrt's default material.
    pub material: Option<usize>,
    /// Index into [`Parsed::area_lights`].
    pub area_light: Option<usize>,
}

/// What the files say, in order, with their transforms resolved.
#[derive(Debug, Default)]
pub(super) struct Parsed {
    pub files: Vec<PathBuf>,
    pub camera: Option<CameraItem>,
    pub film: Option<Item>,
    pub lights: Vec<LightItem>,
    pub shapes: Vec<ShapeItem>,
    /// `Material` and `MakeNamedMaterial` definitions; a named one carries its name.
    pub materials: Vec<(Option<String>, Item)>,
    pub area_lights: Vec<Item>,
    /// Directives read and deliberately not used (Sampler, Integrator, ...), for the report.
    pub ignored: Vec<String>,
    pub warnings: Vec<String>,
    pub dialect: DialectEvidence,
}

/// Which pbrt version the files look like, and why.
#[derive(Debug, Default)]
pub(super) struct DialectEvidence {
    pub v3: Option<String>,
    pub v4: Option<String>,
}

impl DialectEvidence {
    pub fn dialect(&self) -> (Dialect, String) {
        match (&self.v4, &self.v3) {
            (Some(why), _) => (Dialect::V4, why.clone()),
            (None, Some(why)) => (Dialect::V3, why.clone()),
            (None, None) => (
                Dialect::V4,
                "nothing in the files tells the versions apart".into(),
            ),
        }
    }
}

#[derive(Clone, Debug)]
struct GraphicsState {
    ctm: Mat4,
    reverse_orientation: bool,
    material: Option<usize>,
    area_light: Option<usize>,
}

enum Pushed {
    Attributes(GraphicsState, Place),
    Transform(Mat4, Place),
}

pub(super) struct Parser<'f> {
    files: &'f dyn SceneFiles,
    out: Parsed,
    state: GraphicsState,
    stack: Vec<Pushed>,
    named_frames: HashMap<String, Mat4>,
    named_materials: HashMap<String, usize>,
    in_world: bool,
    /// After `ActiveTransform EndTime`, transform directives change nothing (no motion blur).
    ignore_transforms: bool,
    search_folder: PathBuf,
    include_stack: Vec<PathBuf>,
}

/// Reads `path` and everything it includes from `files`.
pub(super) fn parse(path: &Path, files: &dyn SceneFiles) -> Result<Parsed, PbrtError> {
    let mut parser = Parser {
        files,
        out: Parsed::default(),
        state: GraphicsState {
            ctm: Mat4::IDENTITY,
            reverse_orientation: false,
            material: None,
            area_light: None,
        },
        stack: Vec::new(),
        named_frames: HashMap::new(),
        named_materials: HashMap::new(),
        in_world: false,
        ignore_transforms: false,
        search_folder: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        include_stack: Vec::new(),
    };
    parser.file(path, None)?;
    if let Some(Pushed::Attributes(_, at) | Pushed::Transform(_, at)) = parser.stack.last() {
        return Err(at.error("AttributeBegin", "is never closed (no AttributeEnd)"));
    }
    if !parser.in_world {
        let file = parser.out.files.len().saturating_sub(1);
        return Err(PbrtError {
            file: parser.out.files.first().cloned().unwrap_or_default(),
            line: None,
            column: None,
            field: "WorldBegin".into(),
            message: format!("the scene has no WorldBegin (read {} file(s))", file + 1),
        });
    }
    Ok(parser.out)
}

impl Parser<'_> {
    /// Resolves a path named in the files: relative to the main file's folder, as pbrt does.
    pub(super) fn resolve(folder: &Path, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            folder.join(p)
        }
    }

    fn file(&mut self, path: &Path, included_at: Option<&Place>) -> Result<(), PbrtError> {
        let refuse = |message: String| match included_at {
            Some(at) => at.error("Include", message),
            None => PbrtError {
                file: path.to_path_buf(),
                line: None,
                column: None,
                field: "scene".into(),
                message,
            },
        };
        if self.include_stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(refuse(format!(
                "includes nest deeper than {MAX_INCLUDE_DEPTH} files (a cycle?)"
            )));
        }
        let canonical = self.files.identity(path);
        if self.include_stack.contains(&canonical) {
            return Err(refuse(format!("`{}` includes itself", path.display())));
        }
        let bytes = (self.files.read(path))
            .map_err(|err| refuse(format!("cannot read `{}`: {err}", path.display())))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| refuse(format!("`{}` is not UTF-8 text", path.display())))?;
        let file = self.out.files.len();
        self.out.files.push(path.to_path_buf());
        let tokens = tokens(&text).map_err(|e| PbrtError {
            file: path.to_path_buf(),
            line: Some(e.line),
            column: Some(e.column),
            field: "syntax".into(),
            message: e.message,
        })?;
        self.include_stack.push(canonical);
        let result = self.directives(file, &tokens);
        self.include_stack.pop();
        result
    }

    fn place(&self, file: usize, t: &Token) -> Place {
        Place {
            file: self.out.files[file].clone(),
            line: t.line,
            column: t.column,
        }
    }

    fn directives(&mut self, file: usize, tokens: &[Token]) -> Result<(), PbrtError> {
        let mut at = 0;
        while let Some(t) = tokens.get(at) {
            let place = self.place(file, t);
            let TokenKind::Word(directive) = &t.kind else {
                return Err(place.error(
                    "syntax",
                    format!("expected a directive, found {}", show(&t.kind)),
                ));
            };
            at += 1;
            let mut args = Args {
                tokens,
                at: &mut at,
                place: &place,
                directive,
            };
            self.directive(directive, &mut args)?;
        }
        Ok(())
    }

    fn directive(&mut self, directive: &str, args: &mut Args) -> Result<(), PbrtError> {
        let place = args.place.clone();
        match directive {
            "Identity" => self.transform(Mat4::IDENTITY, true),
            "Translate" => {
                let [x, y, z] = args.numbers::<3>()?;
                self.transform(Mat4::from_translation(Vec3::new(x, y, z)), false);
            }
            "Scale" => {
                let [x, y, z] = args.numbers::<3>()?;
                self.transform(Mat4::from_scale(Vec3::new(x, y, z)), false);
            }
            "Rotate" => {
                let [angle, x, y, z] = args.numbers::<4>()?;
                let axis = Vec3::new(x, y, z);
                if axis.length_squared() == 0.0 {
                    return Err(place.error("Rotate", "the rotation axis is the zero vector"));
                }
                self.transform(Mat4::from_mat3(rotation(axis.normalize(), angle)), false);
            }
            "LookAt" => {
                let v = args.numbers::<9>()?;
                let eye = Vec3::new(v[0], v[1], v[2]);
                let look = Vec3::new(v[3], v[4], v[5]);
                let up = Vec3::new(v[6], v[7], v[8]);
                self.transform(
                    look_at(eye, look, up).map_err(|m| place.error("LookAt", m))?,
                    false,
                );
            }
            "Transform" | "ConcatTransform" => {
                let m = args.matrix()?;
                self.transform(m, directive == "Transform");
            }
            "CoordinateSystem" => {
                let name = args.string("name")?;
                self.named_frames.insert(name, self.state.ctm);
            }
            "CoordSysTransform" => {
                let name = args.string("name")?;
                match self.named_frames.get(&name) {
                    Some(m) => self.state.ctm = *m,
                    None => {
                        return Err(place.error(
                            "CoordSysTransform",
                            format!("no coordinate system is named \"{name}\""),
                        ));
                    }
                }
            }
            "TransformTimes" => {
                args.numbers::<2>()?;
            }
            "ActiveTransform" => match args.word()?.as_str() {
                "StartTime" | "All" => self.ignore_transforms = false,
                "EndTime" => {
                    self.ignore_transforms = true;
                    self.out.warnings.push(format!(
                        "{place}: ActiveTransform EndTime: motion blur is not supported; end-time transforms are ignored"
                    ));
                }
                other => {
                    return Err(place.error(
                        "ActiveTransform",
                        format!("`{other}` is not StartTime, EndTime or All"),
                    ));
                }
            },
            "ReverseOrientation" => self.state.reverse_orientation ^= true,
            "AttributeBegin" => self
                .stack
                .push(Pushed::Attributes(self.state.clone(), place)),
            "TransformBegin" => self.stack.push(Pushed::Transform(self.state.ctm, place)),
            "AttributeEnd" | "TransformEnd" => {
                let want_attributes = directive == "AttributeEnd";
                match self.stack.pop() {
                    Some(Pushed::Attributes(state, _)) if want_attributes => self.state = state,
                    Some(Pushed::Transform(ctm, _)) if !want_attributes => self.state.ctm = ctm,
                    Some(Pushed::Attributes(_, open) | Pushed::Transform(_, open)) => {
                        return Err(place.error(
                            directive,
                            format!(
                                "does not match the {} at {open}",
                                if want_attributes {
                                    "TransformBegin"
                                } else {
                                    "AttributeBegin"
                                }
                            ),
                        ));
                    }
                    None => {
                        let begin = if want_attributes {
                            "AttributeBegin"
                        } else {
                            "TransformBegin"
                        };
                        return Err(place.error(directive, format!("has no {begin} to close")));
                    }
                }
            }
            "WorldBegin" => {
                if self.in_world {
                    return Err(place.error("WorldBegin", "appears twice"));
                }
                self.in_world = true;
                self.state.ctm = Mat4::IDENTITY;
                self.named_frames.insert("world".into(), Mat4::IDENTITY);
            }
            "WorldEnd" => {
                self.out.dialect.v3.get_or_insert_with(|| format!("{place}: WorldEnd (pbrt-v3 ends the world with it; pbrt-v4 has no WorldEnd)"));
            }
            "Camera" => {
                self.before_world(&place, directive)?;
                let item = args.item()?;
                let camera_to_world = self.state.ctm.inverse();
                if !camera_to_world.is_finite() {
                    return Err(place.error("Camera", "the current transform is not invertible"));
                }
                self.named_frames.insert("camera".into(), camera_to_world);
                self.out.camera = Some(CameraItem {
                    item,
                    camera_to_world,
                });
            }
            "Film" => {
                self.before_world(&place, directive)?;
                let item = args.item()?;
                if matches!(item.kind.as_str(), "rgb" | "gbuffer" | "spectral") {
                    self.v4(&place, &format!("Film \"{}\"", item.kind));
                }
                self.out.film = Some(item);
            }
            "Sampler" | "Integrator" | "PixelFilter" | "Accelerator" | "SurfaceIntegrator"
            | "VolumeIntegrator" | "Renderer" => {
                self.before_world(&place, directive)?;
                let item = args.item()?;
                self.out
                    .ignored
                    .push(format!("{place}: {directive} \"{}\"", item.kind));
            }
            "ColorSpace" => {
                self.v4(&place, "ColorSpace");
                let name = args.string("name")?;
                if name != "srgb" {
                    return Err(place.error(
                        "ColorSpace",
                        format!("\"{name}\": dpm renders in sRGB's primaries only"),
                    ));
                }
            }
            "Option" => {
                self.v4(&place, "Option");
                let item =
                    ParamList::read(args.tokens, args.at).map_err(|e| args.param_error(e))?;
                let names: Vec<_> = item.params.iter().map(|p| p.name.clone()).collect();
                self.out
                    .ignored
                    .push(format!("{place}: Option {}", names.join(", ")));
            }
            "Material" => {
                self.in_world(&place, directive)?;
                let item = args.item()?;
                self.note_material_dialect(&place, &item.kind);
                self.out.materials.push((None, item));
                self.state.material = Some(self.out.materials.len() - 1);
            }
            "MakeNamedMaterial" => {
                self.in_world(&place, directive)?;
                let name = args.string("name")?;
                let params =
                    ParamList::read(args.tokens, args.at).map_err(|e| args.param_error(e))?;
                let kind = params
                    .string("type")
                    .map_err(|e| args.param_error(e))?
                    .ok_or_else(|| {
                        place.error(
                            "MakeNamedMaterial",
                            format!("\"{name}\" has no \"string type\""),
                        )
                    })?;
                self.note_material_dialect(&place, &kind);
                self.out.materials.push((
                    Some(name.clone()),
                    Item {
                        kind,
                        params,
                        at: place,
                    },
                ));
                self.named_materials
                    .insert(name, self.out.materials.len() - 1);
            }
            "NamedMaterial" => {
                self.in_world(&place, directive)?;
                let name = args.string("name")?;
                match self.named_materials.get(&name) {
                    Some(&i) => self.state.material = Some(i),
                    None => {
                        return Err(place.error("NamedMaterial", format!("no material is named \"{name}\" (MakeNamedMaterial must come first)")));
                    }
                }
            }
            "Texture" => {
                self.in_world(&place, directive)?;
                let name = args.string("name")?;
                let _ty = args.string("type")?;
                let class = args.string("class")?;
                ParamList::read(args.tokens, args.at).map_err(|e| args.param_error(e))?;
                self.out.ignored.push(format!("{place}: Texture \"{name}\" ({class}): textures are not supported; a material that uses it is refused"));
            }
            "MakeNamedMedium" => {
                args.string("name")?;
                ParamList::read(args.tokens, args.at).map_err(|e| args.param_error(e))?;
                self.media_ignored(&place, directive);
            }
            "MediumInterface" => {
                args.string("inside medium")?;
                if let Some(Token {
                    kind: TokenKind::Str(s),
                    ..
                }) = args.tokens.get(*args.at)
                    && !s.contains(' ')
                {
                    *args.at += 1;
                }
                self.media_ignored(&place, directive);
            }
            "LightSource" => {
                self.in_world(&place, directive)?;
                let item = args.item()?;
                self.out.lights.push(LightItem {
                    item,
                    ctm: self.state.ctm,
                });
            }
            "AreaLightSource" => {
                self.in_world(&place, directive)?;
                let item = args.item()?;
                self.out.area_lights.push(item);
                self.state.area_light = Some(self.out.area_lights.len() - 1);
            }
            "Shape" => {
                self.in_world(&place, directive)?;
                let item = args.item()?;
                if item.kind == "bilinearmesh" {
                    self.v4(&place, "Shape \"bilinearmesh\"");
                }
                self.out.shapes.push(ShapeItem {
                    item,
                    ctm: self.state.ctm,
                    reverse_orientation: self.state.reverse_orientation,
                    material: self.state.material,
                    area_light: self.state.area_light,
                });
            }
            "Include" | "Import" => {
                if directive == "Import" {
                    self.v4(&place, "Import");
                }
                let name = args.string("file name")?;
                let path = Self::resolve(&self.search_folder, &name);
                // Import shares named things but not the graphics state.
                let saved = (directive == "Import").then(|| self.state.clone());
                self.file(&path, Some(&place))?;
                if let Some(state) = saved {
                    self.state = state;
                }
            }
            "ObjectBegin" | "ObjectEnd" | "ObjectInstance" => {
                return Err(place.error(
                    directive,
                    "object instancing is not supported: flatten the instances into shapes",
                ));
            }
            "Attribute" => {
                return Err(place.error("Attribute", "pbrt-v4's default-parameter `Attribute` is not supported: give the parameters on each directive"));
            }
            other => {
                return Err(place.error("syntax", format!("`{other}` is not a pbrt directive")));
            }
        }
        Ok(())
    }

    fn transform(&mut self, m: Mat4, replace: bool) {
        if self.ignore_transforms {
            return;
        }
        self.state.ctm = if replace { m } else { self.state.ctm * m };
    }

    fn before_world(&self, place: &Place, directive: &str) -> Result<(), PbrtError> {
        if self.in_world {
            return Err(place.error(directive, "belongs before WorldBegin"));
        }
        Ok(())
    }

    fn in_world(&self, place: &Place, directive: &str) -> Result<(), PbrtError> {
        if !self.in_world {
            return Err(place.error(directive, "belongs after WorldBegin"));
        }
        Ok(())
    }

    fn media_ignored(&mut self, place: &Place, directive: &str) {
        self.out.warnings.push(format!(
            "{place}: {directive}: participating media are not supported and are ignored"
        ));
    }

    fn v4(&mut self, place: &Place, what: &str) {
        self.out
            .dialect
            .v4
            .get_or_insert_with(|| format!("{place}: {what} is pbrt-v4's"));
    }

    fn note_material_dialect(&mut self, place: &Place, kind: &str) {
        const V4: &[&str] = &[
            "diffuse",
            "dielectric",
            "conductor",
            "coateddiffuse",
            "coatedconductor",
            "thindielectric",
            "diffusetransmission",
        ];
        const V3: &[&str] = &[
            "matte",
            "glass",
            "plastic",
            "uber",
            "substrate",
            "metal",
            "translucent",
        ];
        if V4.contains(&kind) {
            self.v4(place, &format!("material \"{kind}\""));
        } else if V3.contains(&kind) {
            self.out
                .dialect
                .v3
                .get_or_insert_with(|| format!("{place}: material \"{kind}\" is pbrt-v3's"));
        }
    }
}

/// pbrt's LookAt: the world-to-camera transform of an eye at `eye` looking at `look`.
fn look_at(eye: Vec3, look: Vec3, up: Vec3) -> Result<Mat4, String> {
    let dir = (look - eye).normalize_or_zero();
    if dir == Vec3::ZERO {
        return Err("the eye and the look-at point are the same".into());
    }
    let right = up.normalize_or_zero().cross(dir);
    if right.length() < 1e-9 {
        return Err("the up vector is zero or parallel to the view direction".into());
    }
    let right = right.normalize();
    let new_up = dir.cross(right);
    let camera_to_world = Mat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    );
    Ok(camera_to_world.inverse())
}
