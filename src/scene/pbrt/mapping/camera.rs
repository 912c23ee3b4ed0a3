//! pbrt's `Camera` as dpm places it: the `perspective` (its `fov` spans the shorter image
//! axis), `orthographic` (its `screenwindow`) and `environment` (pbrt-v3's lat-long) cameras,
//! each with pbrt's thin lens where it has one (`lensradius`, `focaldistance`), and the film's
//! crop window carried along. pbrt's camera space is left-handed; dpm records which way the
//! image's x axis runs instead. Owns the camera's mapping; must not read the film's other
//! settings (that is `film`).

use super::super::Place;
use super::super::parser::{CameraItem, Item};
use super::{Mapper, param_error, value_error};
use crate::scene::{Camera, CropWindow, Handedness, Projection, SceneError, ThinLens, rules};
use glam::{Mat4, Vec3};
use std::path::PathBuf;

/// pbrt's default perspective field of view, degrees.
const DEFAULT_FOV: f32 = 90.0;
/// How far a screen window may be from centred and from the film's aspect, relatively.
const SCREEN_TOLERANCE: f32 = 1e-4;

impl Mapper<'_> {
    pub(super) fn camera(
        &mut self,
        camera: Option<&CameraItem>,
        resolution: [u32; 2],
        crop: CropWindow,
    ) -> Result<Camera, SceneError> {
        let [width, height] = resolution;
        let (camera_to_world, projection, lens) = match camera {
            None => (
                Mat4::IDENTITY,
                perspective(DEFAULT_FOV, resolution),
                ThinLens::PINHOLE,
            ),
            Some(c) => {
                let (projection, lens) = self.optics(&c.item, resolution)?;
                self.unused(&c.item, "Camera");
                (c.camera_to_world, projection, lens)
            }
        };
        let position = camera_to_world.transform_point3(Vec3::ZERO);
        let forward = camera_to_world
            .transform_vector3(Vec3::Z)
            .normalize_or_zero();
        let up = camera_to_world.transform_vector3(Vec3::Y);
        let right = camera_to_world.transform_vector3(Vec3::X);
        let at = camera.map(|c| c.item.at.clone()).unwrap_or(Place {
            file: PathBuf::new(),
            line: 1,
            column: 1,
        });
        if forward == Vec3::ZERO || forward.cross(up).length() < 1e-9 * up.length() {
            return Err(at.error(
                "Camera",
                "the camera transform has no usable view direction and up vector",
            ));
        }
        // pbrt's raster x runs along the camera's +x; dpm's along forward × up unless mirrored.
        let handedness = if right.dot(forward.cross(up)) >= 0.0 {
            Handedness::Right
        } else {
            Handedness::Left
        };
        Ok(Camera {
            position,
            look_at: (position + forward),
            up: up.normalize(),
            projection,
            lens,
            width,
            height,
            handedness,
            crop,
        })
    }

    /// The projection and lens of a `Camera` directive.
    fn optics(
        &mut self,
        item: &Item,
        resolution: [u32; 2],
    ) -> Result<(Projection, ThinLens), SceneError> {
        let p = |e| param_error("Camera", e);
        let projection = match item.kind.as_str() {
            "perspective" => {
                let fov = item.params.float("fov").map_err(p)?.unwrap_or(DEFAULT_FOV);
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(value_error(
                        item,
                        "Camera",
                        "fov",
                        format!("{fov} is not in (0, 180) degrees"),
                    ));
                }
                perspective(fov, resolution)
            }
            "orthographic" => orthographic(item, resolution)?,
            // pbrt-v3's environment camera has no lens: its lens parameters go unread.
            "environment" => return Ok((Projection::Environment, ThinLens::PINHOLE)),
            other => {
                return Err(item.at.error(
                    "Camera",
                    format!(
                        "\"{other}\": dpm has the \"perspective\", \"orthographic\" and \"environment\" cameras{}",
                        if other == "realistic" {
                            " (not pbrt's realistic lens systems)"
                        } else {
                            ""
                        }
                    ),
                ));
            }
        };
        let radius = item
            .params
            .float("lensradius")
            .map_err(p)?
            .unwrap_or(ThinLens::PINHOLE.radius);
        let radius = rules::lens_radius("lensradius", radius)
            .map_err(|e| value_error(item, "Camera", "lensradius", e.message))?;
        let focal_distance = match item.params.float("focaldistance").map_err(p)? {
            None => ThinLens::PINHOLE.focal_distance,
            Some(f) => rules::positive("focaldistance", f)
                .map_err(|e| value_error(item, "Camera", "focaldistance", e.message))?,
        };
        Ok((
            projection,
            ThinLens {
                radius,
                focal_distance,
            },
        ))
    }
}

/// A perspective camera whose `fov` spans the shorter image axis, as pbrt's does (dpm's spans
/// the height).
fn perspective(fov: f32, [width, height]: [u32; 2]) -> Projection {
    let fov_y = if width < height {
        let half = (fov as f64).to_radians() * 0.5;
        (2.0 * (half.tan() * height as f64 / width as f64)
            .atan()
            .to_degrees()) as f32
    } else {
        fov
    };
    Projection::Perspective {
        fov_y_degrees: fov_y,
    }
}

/// pbrt's orthographic screen window: by default ±1 on the shorter axis of a frame of
/// `frameaspectratio` (the film's aspect unless given), or `screenwindow` [x0 x1 y0 y1] in
/// camera-space units. dpm's is centred and keeps square pixels, so other windows are refused.
fn orthographic(item: &Item, [width, height]: [u32; 2]) -> Result<Projection, SceneError> {
    let p = |e| param_error("Camera", e);
    let film_aspect = width as f32 / height as f32;
    let frame = item
        .params
        .float("frameaspectratio")
        .map_err(p)?
        .unwrap_or(film_aspect);
    if !(frame.is_finite() && frame > 0.0) {
        return Err(value_error(
            item,
            "Camera",
            "frameaspectratio",
            format!("{frame} is not a positive aspect ratio"),
        ));
    }
    let (mut window, mut name) = (
        if frame > 1.0 {
            [-frame, frame, -1.0, 1.0]
        } else {
            [-1.0, 1.0, -1.0 / frame, 1.0 / frame]
        },
        "frameaspectratio",
    );
    if let Some(given) = item.params.floats("screenwindow").map_err(p)? {
        let Ok(given) = <[f32; 4]>::try_from(given.as_slice()) else {
            return Err(value_error(
                item,
                "Camera",
                "screenwindow",
                format!("has {} values; it takes 4: x0 x1 y0 y1", given.len()),
            ));
        };
        (window, name) = (given, "screenwindow");
    }
    let [x0, x1, y0, y1] = window;
    let (w, h) = (x1 - x0, y1 - y0);
    let off_centre = (x0 + x1).abs() > SCREEN_TOLERANCE * w.abs()
        || (y0 + y1).abs() > SCREEN_TOLERANCE * h.abs();
    let stretched = (w / h / film_aspect - 1.0).abs() > SCREEN_TOLERANCE;
    if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) || off_centre || stretched {
        return Err(value_error(
            item,
            "Camera",
            name,
            format!(
                "the screen window [{x0} {x1} {y0} {y1}] is not one dpm renders: it must be centred (x0 = -x1, y0 = -y1), ordered, and as wide over high as the {width} × {height} film"
            ),
        ));
    }
    Ok(Projection::Orthographic { view_height: h })
}
