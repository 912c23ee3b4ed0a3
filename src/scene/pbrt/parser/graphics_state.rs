//! pbrt's graphics state and the directives that change it: the current transform
//! (`Translate` ... `CoordSysTransform`, `ActiveTransform`), `ReverseOrientation`, the
//! attribute and transform stacks, and pbrt-v4's `Attribute` defaults. Owns the state's
//! rules; must not read files or record scene objects.

use super::super::args::Args;
use super::super::params::Param;
use super::super::{PbrtError, Place};
use super::Parser;
use crate::scene::transform::rotation;
use glam::{Mat4, Vec3};

/// The directive kinds pbrt-v4's `Attribute` gives defaults for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum AttributeTarget {
    Shape,
    Light,
    Material,
    Medium,
    Texture,
}

const TARGETS: [(&str, AttributeTarget); 5] = [
    ("shape", AttributeTarget::Shape),
    ("light", AttributeTarget::Light),
    ("material", AttributeTarget::Material),
    ("medium", AttributeTarget::Medium),
    ("texture", AttributeTarget::Texture),
];

#[derive(Clone, Debug)]
pub(super) struct GraphicsState {
    pub ctm: Mat4,
    pub reverse_orientation: bool,
    pub material: Option<usize>,
    pub area_light: Option<usize>,
    /// `Attribute` defaults per target, latest last.
    pub defaults: Vec<(AttributeTarget, Param)>,
    /// The `MediumInterface` in force: the media inside and outside ("" for none).
    pub media: (String, String),
}

impl Default for GraphicsState {
    fn default() -> Self {
        GraphicsState {
            ctm: Mat4::IDENTITY,
            reverse_orientation: false,
            material: None,
            area_light: None,
            defaults: Vec::new(),
            media: (String::new(), String::new()),
        }
    }
}

impl GraphicsState {
    /// The `Attribute` defaults for `target`.
    pub fn defaults_for(&self, target: AttributeTarget) -> Vec<Param> {
        (self.defaults.iter())
            .filter(|(t, _)| *t == target)
            .map(|(_, p)| p.clone())
            .collect()
    }
}

pub(super) enum Pushed {
    Attributes(GraphicsState, Place),
    Transform(Mat4, Place),
}

impl Parser<'_> {
    /// Runs `directive` if it is one of the graphics state's; false if it is not.
    pub(super) fn state_directive(
        &mut self,
        directive: &str,
        args: &mut Args,
    ) -> Result<bool, PbrtError> {
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
                let m = look_at(eye, look, up).map_err(|m| place.error("LookAt", m))?;
                self.transform(m, false);
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
            "AttributeEnd" | "TransformEnd" => self.pop(directive, &place)?,
            "Attribute" => self.attribute(args)?,
            _ => return Ok(false),
        }
        Ok(true)
    }

    pub(super) fn pop(&mut self, directive: &str, place: &Place) -> Result<(), PbrtError> {
        let want_attributes = directive == "AttributeEnd";
        let (begin, other) = if want_attributes {
            ("AttributeBegin", "TransformBegin")
        } else {
            ("TransformBegin", "AttributeBegin")
        };
        match self.stack.pop() {
            Some(Pushed::Attributes(state, _)) if want_attributes => self.state = state,
            Some(Pushed::Transform(ctm, _)) if !want_attributes => self.state.ctm = ctm,
            Some(Pushed::Attributes(_, open) | Pushed::Transform(_, open)) => {
                return Err(place.error(directive, format!("does not match the {other} at {open}")));
            }
            None => return Err(place.error(directive, format!("has no {begin} to close"))),
        }
        Ok(())
    }

    /// pbrt-v4's `Attribute "target" params`: defaults for the target's later directives in
    /// this attribute scope (a directive's own parameters win).
    fn attribute(&mut self, args: &mut Args) -> Result<(), PbrtError> {
        let place = args.place.clone();
        self.v4(&place, "Attribute");
        let name = args.string("target")?;
        let Some(&(_, target)) = TARGETS.iter().find(|(n, _)| *n == name) else {
            return Err(place.error(
                "Attribute",
                format!("\"{name}\" is not shape, light, material, medium or texture"),
            ));
        };
        let params = self.params(args)?;
        for p in params.params {
            self.state
                .defaults
                .retain(|(t, old)| !(*t == target && old.name == p.name));
            self.state.defaults.push((target, p));
        }
        Ok(())
    }

    pub(super) fn transform(&mut self, m: Mat4, replace: bool) {
        if self.ignore_transforms {
            return;
        }
        self.state.ctm = if replace { m } else { self.state.ctm * m };
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
