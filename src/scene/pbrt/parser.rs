//! pbrt's directives, read in order with pbrt's graphics state: the current transform, the
//! attribute and transform stacks, named coordinate systems, the current and named materials,
//! the current area light and `ReverseOrientation`. The result is a [`Parsed`] list of
//! cameras, lights, shapes and material definitions, each with its transform and place in the
//! files, for [`super::mapping`] to turn into dpm's types. Owns the directives that record
//! scene objects (the graphics state's are [`graphics_state`]'s, files' [`include`]'s); must
//! not decide what dpm can render.

mod graphics_state;
mod include;
mod instancing;

use super::args::Args;
use super::cursor::Cursor;
use super::lexer::{Token, TokenKind};
use super::params::{ParamList, show};
use super::{Dialect, PbrtError, Place};
use crate::scene::files::SceneFiles;
use glam::Mat4;
use graphics_state::{AttributeTarget, GraphicsState, Pushed};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

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
    /// The outside medium of the `MediumInterface` in force ("" for none): where it shines.
    pub medium: String,
}

/// `MakeNamedMedium`: its name, its parameters (`kind` its "string type") and the transform
/// in force, which places a grid.
#[derive(Debug)]
pub(super) struct MediumItem {
    pub name: String,
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
    /// Index into [`Parsed::objects`] when the shape belongs to an object definition.
    pub object: Option<usize>,
    /// The `MediumInterface` in force: the media inside and outside it ("" for none).
    pub media: (String, String),
}

/// An `ObjectBegin` definition.
#[derive(Debug)]
pub(super) struct ObjectItem {
    pub name: String,
    pub at: Place,
}

/// An `ObjectInstance`: which object, placed by which transform.
#[derive(Debug)]
pub(super) struct InstanceItem {
    /// Index into [`Parsed::objects`].
    pub object: usize,
    pub ctm: Mat4,
    pub at: Place,
}

/// A `Texture` directive: its name, its type as written (`spectrum`, `color` or `float`) and
/// its class (`item.kind`) with its parameters.
#[derive(Debug)]
pub(super) struct TextureItem {
    pub name: String,
    pub ty: String,
    pub item: Item,
}

/// What the files say, in order, with their transforms resolved.
#[derive(Debug, Default)]
pub(super) struct Parsed {
    pub files: Vec<PathBuf>,
    pub camera: Option<CameraItem>,
    pub film: Option<Item>,
    /// The `Integrator` line: how far pbrt follows light.
    pub integrator: Option<Item>,
    pub lights: Vec<LightItem>,
    pub shapes: Vec<ShapeItem>,
    /// `Material` and `MakeNamedMaterial` definitions; a named one carries its name.
    pub materials: Vec<(Option<String>, Item)>,
    pub area_lights: Vec<Item>,
    pub objects: Vec<ObjectItem>,
    pub instances: Vec<InstanceItem>,
    /// In the order they are defined.
    pub textures: Vec<TextureItem>,
    pub media: Vec<MediumItem>,
    /// The outside medium of the `MediumInterface` in force at `Camera` (pbrt-v4's camera
    /// medium) and at `WorldEnd` or the end of the files (pbrt-v3's).
    pub camera_medium: (String, String),
    /// Directives read and deliberately not used (Sampler, PixelFilter, ...), for the report.
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
    /// The files open around the `Import`s being read, for cycle checks.
    importing: Vec<PathBuf>,
    /// Whether `WorldEnd` was read (pbrt-v3 takes the camera's medium there).
    world_ended: bool,
    /// The object being defined (between ObjectBegin and ObjectEnd).
    object: Option<usize>,
    named_objects: HashMap<String, usize>,
}

/// Reads `path` and everything it includes from `files`.
pub(super) fn parse(path: &Path, files: &dyn SceneFiles) -> Result<Parsed, PbrtError> {
    let mut parser = Parser {
        files,
        out: Parsed::default(),
        state: GraphicsState::default(),
        stack: Vec::new(),
        named_frames: HashMap::new(),
        named_materials: HashMap::new(),
        in_world: false,
        ignore_transforms: false,
        search_folder: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        importing: Vec::new(),
        world_ended: false,
        object: None,
        named_objects: HashMap::new(),
    };
    let (tokens, identity) = parser.open_file(path, None, None)?;
    parser.run(&mut Cursor::new(tokens, identity))?;
    if !parser.world_ended {
        parser.out.camera_medium.1 = parser.state.media.1.clone();
    }
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
    /// Reads directives from `tokens` to their end.
    fn run(&mut self, tokens: &mut Cursor) -> Result<(), PbrtError> {
        while let Some(t) = tokens.next() {
            let place = place_of(&t);
            let TokenKind::Word(directive) = &t.kind else {
                return Err(place.error(
                    "syntax",
                    format!("expected a directive, found {}", show(&t.kind)),
                ));
            };
            let mut args = Args {
                tokens,
                place: &place,
                directive,
            };
            if !self.state_directive(directive, &mut args)? {
                self.directive(directive, &mut args)?;
            }
        }
        Ok(())
    }

    /// A parameter list; the warnings about parameters given twice join the parser's.
    fn params(&mut self, args: &mut Args) -> Result<ParamList, PbrtError> {
        let mut params = args.params()?;
        self.out.warnings.append(&mut params.replaced);
        Ok(params)
    }

    /// `"type" params`, with the `Attribute` defaults of `target` for what it does not give.
    fn item(
        &mut self,
        args: &mut Args,
        target: Option<AttributeTarget>,
    ) -> Result<Item, PbrtError> {
        let mut item = args.item()?;
        self.out.warnings.append(&mut item.params.replaced);
        if let Some(target) = target {
            item.params.add_defaults(&self.state.defaults_for(target));
        }
        Ok(item)
    }

    fn directive(&mut self, directive: &str, args: &mut Args) -> Result<(), PbrtError> {
        let place = args.place.clone();
        match directive {
            "WorldBegin" => {
                if self.in_world {
                    return Err(place.error("WorldBegin", "appears twice"));
                }
                self.in_world = true;
                self.state.ctm = Mat4::IDENTITY;
                self.named_frames.insert("world".into(), Mat4::IDENTITY);
            }
            "WorldEnd" => {
                self.world_ended = true;
                self.out.camera_medium.1 = self.state.media.1.clone();
                self.out.dialect.v3.get_or_insert_with(|| format!("{place}: WorldEnd (pbrt-v3 ends the world with it; pbrt-v4 has no WorldEnd)"));
            }
            "Camera" => {
                self.before_world(&place, directive)?;
                let item = self.item(args, None)?;
                let camera_to_world = self.state.ctm.inverse();
                if !camera_to_world.is_finite() {
                    return Err(place.error("Camera", "the current transform is not invertible"));
                }
                self.named_frames.insert("camera".into(), camera_to_world);
                self.out.camera_medium.0 = self.state.media.1.clone();
                self.out.camera = Some(CameraItem {
                    item,
                    camera_to_world,
                });
            }
            "Film" => {
                self.before_world(&place, directive)?;
                let item = self.item(args, None)?;
                if matches!(item.kind.as_str(), "rgb" | "gbuffer" | "spectral") {
                    self.v4(&place, &format!("Film \"{}\"", item.kind));
                }
                self.out.film = Some(item);
            }
            "Integrator" => {
                self.before_world(&place, directive)?;
                self.out.integrator = Some(self.item(args, None)?);
            }
            "Sampler" | "PixelFilter" | "Accelerator" | "SurfaceIntegrator"
            | "VolumeIntegrator" | "Renderer" => {
                self.before_world(&place, directive)?;
                let item = self.item(args, None)?;
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
                let item = self.params(args)?;
                let names: Vec<_> = item.params.iter().map(|p| p.name.clone()).collect();
                self.out
                    .ignored
                    .push(format!("{place}: Option {}", names.join(", ")));
            }
            "Material" => {
                self.in_world(&place, directive)?;
                let item = self.item(args, Some(AttributeTarget::Material))?;
                self.note_material_dialect(&place, &item.kind);
                self.out.materials.push((None, item));
                self.state.material = Some(self.out.materials.len() - 1);
            }
            "MakeNamedMaterial" => {
                self.in_world(&place, directive)?;
                let name = args.string("name")?;
                let mut params = self.params(args)?;
                params.add_defaults(&self.state.defaults_for(AttributeTarget::Material));
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
                    // pbrt-v3 reports it and goes on with the current material.
                    None => self.out.warnings.push(format!(
                        "{place}: NamedMaterial: no material is named \"{name}\" yet (MakeNamedMaterial must come first): the shapes that follow keep the current material, as pbrt does"
                    )),
                }
            }
            "Texture" => {
                self.in_world(&place, directive)?;
                let name = args.string("name")?;
                let ty = args.string("type")?;
                let class = args.string("class")?;
                let mut params = self.params(args)?;
                params.add_defaults(&self.state.defaults_for(AttributeTarget::Texture));
                self.out.textures.push(TextureItem {
                    name,
                    ty,
                    item: Item {
                        kind: class,
                        params,
                        at: place,
                    },
                });
            }
            "MakeNamedMedium" => {
                let name = args.string("name")?;
                let mut params = self.params(args)?;
                params.add_defaults(&self.state.defaults_for(AttributeTarget::Medium));
                let kind = (params.string("type"))
                    .map_err(|e| args.param_error(e))?
                    .ok_or_else(|| {
                        place.error(
                            "MakeNamedMedium",
                            format!("\"{name}\" has no \"string type\""),
                        )
                    })?;
                self.out.media.push(MediumItem {
                    name,
                    item: Item {
                        kind,
                        params,
                        at: place,
                    },
                    ctm: self.state.ctm,
                });
            }
            "MediumInterface" => {
                let mut names = vec![args.string("interior medium")?];
                if let Some(Token {
                    kind: TokenKind::Str(s),
                    ..
                }) = args.tokens.peek()
                    && !s.contains(' ')
                {
                    names.push(s.clone());
                    args.tokens.next();
                }
                // One name is both sides.
                let outside = names.get(1).unwrap_or(&names[0]).clone();
                self.state.media = (names[0].clone(), outside);
            }
            "LightSource" => {
                self.in_world(&place, directive)?;
                let item = self.item(args, Some(AttributeTarget::Light))?;
                self.out.lights.push(LightItem {
                    item,
                    ctm: self.state.ctm,
                    medium: self.state.media.1.clone(),
                });
            }
            "AreaLightSource" => {
                self.in_world(&place, directive)?;
                let item = self.item(args, Some(AttributeTarget::Light))?;
                self.out.area_lights.push(item);
                self.state.area_light = Some(self.out.area_lights.len() - 1);
            }
            "Shape" => {
                self.in_world(&place, directive)?;
                let item = self.item(args, Some(AttributeTarget::Shape))?;
                if item.kind == "bilinearmesh" {
                    self.v4(&place, "Shape \"bilinearmesh\"");
                }
                self.out.shapes.push(ShapeItem {
                    item,
                    ctm: self.state.ctm,
                    reverse_orientation: self.state.reverse_orientation,
                    material: self.state.material,
                    area_light: self.state.area_light,
                    object: self.object,
                    media: self.state.media.clone(),
                });
            }
            "Include" | "Import" => self.include(directive, args)?,
            "ObjectBegin" | "ObjectEnd" | "ObjectInstance" => {
                self.object_directive(directive, args, place)?;
            }
            other => {
                return Err(place.error("syntax", format!("`{other}` is not a pbrt directive")));
            }
        }
        Ok(())
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

/// Where token `t` was written.
fn place_of(t: &Token) -> Place {
    Place {
        file: t.file.to_path_buf(),
        line: t.line,
        column: t.column,
    }
}
