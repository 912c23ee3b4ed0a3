//! Object instancing: `ObjectBegin "name"` … `ObjectEnd` collects the shapes between them into
//! a named object (with the transforms they were given there, and as `AttributeBegin`/`End`
//! scope the graphics state), and `ObjectInstance "name"` places it by the current transform.
//! As in pbrt, objects do not nest, an instance names an object defined before it, and an area
//! light inside an object is dropped with a warning. Owns the bookkeeping; must not map shapes.

use super::super::args::Args;
use super::super::{PbrtError, Place};
use super::graphics_state::Pushed;
use super::{InstanceItem, ObjectItem, Parser};

impl Parser<'_> {
    pub(super) fn object_directive(
        &mut self,
        directive: &str,
        args: &mut Args,
        place: Place,
    ) -> Result<(), PbrtError> {
        self.in_world(&place, directive)?;
        match directive {
            "ObjectBegin" => {
                let name = args.string("name")?;
                if let Some(open) = self.object {
                    let open = &self.out.objects[open];
                    return Err(place.error(
                        "ObjectBegin",
                        format!(
                            "\"{name}\" begins inside object \"{}\" (begun at {}): objects do not nest",
                            open.name, open.at
                        ),
                    ));
                }
                self.stack
                    .push(Pushed::Attributes(self.state.clone(), place.clone()));
                self.out.objects.push(ObjectItem {
                    name: name.clone(),
                    at: place,
                });
                let index = self.out.objects.len() - 1;
                if let Some(earlier) = self.named_objects.insert(name.clone(), index) {
                    let earlier = self.out.objects[earlier].at.clone();
                    self.out.warnings.push(format!(
                        "{}: ObjectBegin \"{name}\" again (first at {earlier}): later instances place the new one",
                        self.out.objects[index].at
                    ));
                }
                self.object = Some(index);
            }
            "ObjectEnd" => {
                if self.object.take().is_none() {
                    return Err(place.error("ObjectEnd", "has no ObjectBegin to close"));
                }
                match self.stack.last() {
                    Some(Pushed::Attributes(..)) => self.pop("AttributeEnd", &place)?,
                    _ => {
                        return Err(place.error(
                            "ObjectEnd",
                            "an AttributeBegin or TransformBegin inside the object is still open",
                        ));
                    }
                }
            }
            _ => {
                let name = args.string("name")?;
                if let Some(open) = self.object {
                    return Err(place.error(
                        "ObjectInstance",
                        format!(
                            "\"{name}\" is placed inside object \"{}\": instances do not nest",
                            self.out.objects[open].name
                        ),
                    ));
                }
                let Some(&object) = self.named_objects.get(&name) else {
                    return Err(place.error(
                        "ObjectInstance",
                        format!("no object is named \"{name}\" (ObjectBegin must come first)"),
                    ));
                };
                self.out.instances.push(InstanceItem {
                    object,
                    ctm: self.state.ctm,
                    at: place,
                });
            }
        }
        Ok(())
    }
}
