//! pbrt's image environments as dpm's [`EnvironmentMap`]: pbrt-v3's `infinite` `mapname` (a
//! lat-long image, each texel times `L` and `scale`) and pbrt-v4's `infinite` `filename` (an
//! equal-area octahedral square, times `scale`, or scaled so that an upward surface receives
//! `illuminance`). Also owns reading the images scene files name (EXR, PFM, PNG, TGA) through
//! [`crate::scene::files::SceneFiles`]; must not sample the map.

use super::super::parser::{Item, Parser};
use super::{Mapper, param_error, value_error};
use crate::image_io::{Image, SceneImageFormat, decode_linear};
use crate::scene::{EnvironmentMap, Light, SceneError, SphereMapping};
use glam::{Mat3, Mat4, Vec3};

/// Texels past this are taken for a corrupt header, not a sky.
const MAX_TEXELS: usize = 1 << 28;

impl Mapper<'_> {
    /// Reads the image parameter `name` of `item` names, decoded to linear RGB (8-bit images
    /// from sRGB unless `srgb` is false).
    pub(super) fn read_image(
        &self,
        item: &Item,
        directive: &str,
        name: &str,
        file: &str,
        srgb: bool,
    ) -> Result<Image, SceneError> {
        let path = Parser::resolve(&self.folder, file);
        let refuse = |message: String| {
            value_error(
                item,
                directive,
                name,
                format!("`{}`: {message}", path.display()),
            )
        };
        let format = SceneImageFormat::of(&path).ok_or_else(|| {
            refuse("dpm reads EXR, PFM, PNG and TGA images (by the name's extension)".into())
        })?;
        let bytes = self
            .files
            .read(&path)
            .map_err(|e| refuse(format!("cannot read it: {e}")))?;
        let image = decode_linear(&bytes, format, srgb).map_err(refuse)?;
        if image.pixels.len() > MAX_TEXELS {
            return Err(refuse(format!(
                "{}x{} is too large",
                image.width, image.height
            )));
        }
        Ok(image)
    }

    /// An `infinite` light with an image: `image` is `mapname` (pbrt-v3) or `filename`
    /// (pbrt-v4), `ctm` the light's transform.
    pub(super) fn environment_map(
        &mut self,
        item: &Item,
        image: &str,
        ctm: &Mat4,
    ) -> Result<Light, SceneError> {
        let p = |e| param_error("LightSource", e);
        let Some(file) = item.params.string(image).map_err(p)? else {
            return Err(value_error(
                item,
                "LightSource",
                image,
                "is not a string".into(),
            ));
        };
        let read = self.read_image(item, "LightSource", image, &file, true)?;
        let mapping = if image == "mapname" {
            SphereMapping::LatLong
        } else {
            if read.width != read.height {
                return Err(value_error(
                    item,
                    "LightSource",
                    image,
                    format!(
                        "`{file}` is {}x{}: pbrt-v4's equal-area environment images are square",
                        read.width, read.height
                    ),
                ));
            }
            SphereMapping::EqualAreaOctahedral
        };
        let light_to_world = orthonormal(Mat3::from_mat4(*ctm)).ok_or_else(|| {
            item.at.error(
                "LightSource",
                "infinite: the light's transform is not a rotation (with at most a mirror and a uniform scale), so the map's directions would not keep their solid angles",
            )
        })?;
        if let Some(i) = (read.pixels.iter()).position(|t| !t.is_finite()) {
            return Err(value_error(
                item,
                "LightSource",
                image,
                format!("`{file}`: texel {i} is {}, not finite", read.pixels[i]),
            ));
        }
        let negative = read.pixels.iter().filter(|t| t.min_element() < 0.0).count();
        if negative > 0 {
            self.warn(
                &item.at.clone(),
                format!("infinite: `{file}` has {negative} texels below zero, taken as black"),
            );
        }
        item.params.string("portal").map_err(p)?;
        let mut map = EnvironmentMap {
            width: read.width as u32,
            height: read.height as u32,
            texels: Vec::new().into(),
            mapping,
            light_to_world,
        };
        let mut scale = self.emission(item, "L")?;
        if let Some(e) = item.params.float("illuminance").map_err(p)? {
            let texels: Vec<Vec3> = read.pixels.iter().map(|t| t.max(Vec3::ZERO)).collect();
            map.texels = texels.into();
            let upward = upward_illuminance(&map);
            if upward > 0.0 {
                scale *= e / upward;
            }
        }
        let texels: Vec<Vec3> = (read.pixels.iter())
            .map(|t| t.max(Vec3::ZERO) * scale)
            .collect();
        map.texels = texels.into();
        Ok(Light::EnvironmentMap(map))
    }
}

/// The luminance an upward surface (the map's +z) receives: Σ Y(L) cos θ Ω over the texels
/// above its horizon.
fn upward_illuminance(map: &EnvironmentMap) -> f32 {
    (map.texels.iter().enumerate())
        .map(|(i, l)| {
            let cos = map.local_centre(i).z;
            if cos > 0.0 {
                l.dot(Vec3::new(0.2126, 0.7152, 0.0722)) * cos * map.texel_solid_angle(i)
            } else {
                0.0
            }
        })
        .sum()
}

/// `m` with its uniform scale taken out, when it is a rotation (possibly with a mirror).
fn orthonormal(m: Mat3) -> Option<Mat3> {
    let scale = m.determinant().abs().cbrt();
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    let r = m * (1.0 / scale);
    let off = (r.transpose() * r - Mat3::IDENTITY).to_cols_array();
    off.iter().all(|x| x.abs() < 1e-3).then_some(r)
}
