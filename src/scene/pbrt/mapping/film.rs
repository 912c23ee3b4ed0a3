//! pbrt's `Film` as dpm applies it: the resolution, the crop window, and what pbrt does to the written image —
//! pbrt-v3's `scale`, pbrt-v4's imaging ratio (exposure time · ISO / 100, the exposure time
//! being the camera's shutter interval unless the film gives `exposuretime`) and its white
//! balance (Bradford adaptation from the daylight white of `whitebalance` kelvin to D65), as
//! one [`ImageResponse`]. Owns those settings; must not place the camera.

use super::super::Dialect;
use super::super::parser::{CameraItem, Item};
use super::{Mapper, param_error, value_error};
use crate::scene::{CropWindow, ImageResponse, SceneError, rules};
use crate::spectrum;

/// pbrt's default film size.
const DEFAULT_RESOLUTION: [u32; 2] = [640, 480];
/// A side longer than this is surely a typo, and its film would not fit in memory.
const MAX_RESOLUTION: i64 = 1 << 16;

impl Mapper<'_> {
    /// The film's settings; reports the film parameters not read.
    pub(super) fn film(
        &mut self,
        film: Option<&Item>,
        camera: Option<&CameraItem>,
    ) -> Result<FilmSettings, SceneError> {
        let mut resolution = DEFAULT_RESOLUTION;
        let mut response = ImageResponse::default();
        let mut crop = CropWindow::FULL;
        if let Some(film) = film {
            let p = |e| param_error("Film", e);
            for (axis, name) in ["xresolution", "yresolution"].into_iter().enumerate() {
                if let Some(n) = film.params.integer(name).map_err(p)? {
                    if !(1..=MAX_RESOLUTION).contains(&n) {
                        return Err(value_error(
                            film,
                            "Film",
                            name,
                            format!("{n} is not from 1 to {MAX_RESOLUTION}"),
                        ));
                    }
                    resolution[axis] = n as u32;
                }
            }
            film.params.string("filename").map_err(p)?;
            if let Some(window) = film.params.floats("cropwindow").map_err(p)? {
                crop = crop_window(film, &window, resolution)?;
            }
            response.scale = positive(film, "scale")?.unwrap_or(1.0);
            if self.dialect.0 == Dialect::V4 {
                self.sensor(film, camera, &mut response)?;
            }
            self.unused(film, "Film");
        }
        Ok(FilmSettings {
            resolution,
            response,
            crop,
        })
    }

    /// pbrt-v4's sensor: the imaging ratio and the white balance.
    fn sensor(
        &mut self,
        film: &Item,
        camera: Option<&CameraItem>,
        response: &mut ImageResponse,
    ) -> Result<(), SceneError> {
        let p = |e| param_error("Film", e);
        let iso = positive(film, "iso")?.unwrap_or(100.0);
        let exposure = match positive(film, "exposuretime")? {
            Some(t) => t,
            None => shutter_interval(camera)?,
        };
        response.scale *= exposure * iso / 100.0;
        let sensor = film.params.string("sensor").map_err(p)?;
        let mut kelvin = film.params.float("whitebalance").map_err(p)?.unwrap_or(0.0);
        if let Some(name) = sensor.filter(|s| s != "cie1931") {
            self.warn(
                &film.at,
                format!("Film \"sensor\" \"{name}\": dpm has no camera sensor curves; the image is the CIE 1931 observer's, white-balanced as pbrt does for a named sensor"),
            );
            if kelvin == 0.0 {
                kelvin = 6500.0;
            }
        }
        if kelvin < 0.0 {
            return Err(value_error(
                film,
                "Film",
                "whitebalance",
                format!("{kelvin} is not a colour temperature (kelvin > 0, or 0 for none)"),
            ));
        }
        if kelvin > 0.0 {
            let m = spectrum::white_balance_srgb(kelvin as f64);
            response.white_balance = Some(m.transpose().to_cols_array_2d());
        }
        Ok(())
    }
}

/// What the film gives the scene.
pub(super) struct FilmSettings {
    /// The full film's [width, height] in pixels.
    pub resolution: [u32; 2],
    pub response: ImageResponse,
    pub crop: CropWindow,
}

/// pbrt's `cropwindow` [x0 x1 y0 y1]: fractions of the film in [0, 1] (pbrt clamps them; dpm
/// refuses what pbrt would clamp), holding at least one pixel.
fn crop_window(
    film: &Item,
    window: &[f32],
    resolution: [u32; 2],
) -> Result<CropWindow, SceneError> {
    let refuse = |message: String| value_error(film, "Film", "cropwindow", message);
    let Ok(window) = <[f32; 4]>::try_from(window) else {
        return Err(refuse(format!(
            "has {} values; it takes 4: x0 x1 y0 y1",
            window.len()
        )));
    };
    let crop = rules::crop_window("cropwindow", window).map_err(|e| refuse(e.message))?;
    rules::crop_holds_pixels("cropwindow", &crop, resolution[0], resolution[1])
        .map_err(|e| refuse(e.message))?;
    Ok(crop)
}

/// Float `name` of `item`, refused unless positive.
fn positive(item: &Item, name: &str) -> Result<Option<f64>, SceneError> {
    let value = item
        .params
        .float(name)
        .map_err(|e| param_error("Film", e))?;
    match value {
        Some(v) if v <= 0.0 => Err(value_error(
            item,
            "Film",
            name,
            format!("{v} is not positive"),
        )),
        other => Ok(other.map(f64::from)),
    }
}

/// pbrt-v4's exposure time: the camera's `shutterclose` − `shutteropen` (default 1 − 0).
fn shutter_interval(camera: Option<&CameraItem>) -> Result<f64, SceneError> {
    let Some(camera) = camera else {
        return Ok(1.0);
    };
    let p = |e| param_error("Camera", e);
    let open = camera.item.params.float("shutteropen").map_err(p)?;
    let close = camera.item.params.float("shutterclose").map_err(p)?;
    let interval = close.unwrap_or(1.0) as f64 - open.unwrap_or(0.0) as f64;
    if interval <= 0.0 {
        return Err(camera.item.at.error(
            "Camera",
            format!("the shutter opens at {open:?} and closes at {close:?}: it never opens (pbrt-v4 exposes the film for shutterclose − shutteropen)"),
        ));
    }
    Ok(interval)
}
