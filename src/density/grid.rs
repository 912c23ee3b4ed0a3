//! The pixel grid of the density command: where each pixel's centre lies in the plane, and the
//! parallel evaluation of an estimate at every centre. Owns the pixel ↔ plane mapping and the
//! work split; it must not know which estimate runs or what the true density is.
//!
//! Rows are evaluated in parallel, with one [`Scratch`] per rayon job; every pixel depends only
//! on its own centre, so the values are identical whatever the thread count.

use crate::estimate::{Query, RadianceEstimate, Scratch};
use crate::photon::PhotonMap;
use glam::{DVec2, Vec3};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::io::IsTerminal;

/// A rectangle of the plane, `x0 < x1`, `y0 < y1`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Extent {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl Extent {
    pub const UNIT: Extent = Extent {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
    };
}

impl std::str::FromStr for Extent {
    type Err = String;
    /// `X0,Y0,X1,Y1`.
    fn from_str(s: &str) -> Result<Self, String> {
        let v: Vec<f64> = s
            .split(',')
            .map(|t| {
                t.trim()
                    .parse::<f64>()
                    .map_err(|_| format!("{t:?} is not a number"))
            })
            .collect::<Result<_, _>>()?;
        let [x0, y0, x1, y1] = v[..] else {
            return Err(format!("expected X0,Y0,X1,Y1, got {} numbers", v.len()));
        };
        if !v.iter().all(|c| c.is_finite()) || x0 >= x1 || y0 >= y1 {
            return Err(format!("{s:?}: need finite X0 < X1 and Y0 < Y1"));
        }
        Ok(Extent { x0, y0, x1, y1 })
    }
}

/// `width × height` pixels covering `extent`; row 0 is the top (`y1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub width: usize,
    pub height: usize,
    pub extent: Extent,
}

impl Grid {
    pub fn pixel_size(&self) -> DVec2 {
        DVec2::new(
            (self.extent.x1 - self.extent.x0) / self.width as f64,
            (self.extent.y1 - self.extent.y0) / self.height as f64,
        )
    }

    pub fn pixel_area(&self) -> f64 {
        let s = self.pixel_size();
        s.x * s.y
    }

    pub fn len(&self) -> usize {
        self.width * self.height
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The centre of the pixel at `row` (0 = top), `col` (0 = left).
    pub fn centre(&self, row: usize, col: usize) -> DVec2 {
        let s = self.pixel_size();
        DVec2::new(
            self.extent.x0 + (col as f64 + 0.5) * s.x,
            self.extent.y1 - (row as f64 + 0.5) * s.y,
        )
    }

    /// The centre of pixel `index` (row by row).
    pub fn centre_of(&self, index: usize) -> DVec2 {
        self.centre(index / self.width, index % self.width)
    }

    /// `f` at every pixel centre, row by row, in parallel.
    pub fn map<T: Send>(&self, f: impl Fn(DVec2) -> T + Sync) -> Vec<T> {
        (0..self.len())
            .into_par_iter()
            .map(|i| f(self.centre_of(i)))
            .collect()
    }
}

/// A progress bar over `rows` on stderr, drawn only when stderr is a terminal.
pub fn progress_bar(rows: usize, label: &str) -> ProgressBar {
    let target = if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(rows as u64), target);
    if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, {eta} left")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(label.to_string());
    bar
}

/// The estimate at every pixel centre of `grid` (in the plane z = 0, normal +z), row by row.
pub fn evaluate(
    grid: &Grid,
    map: &PhotonMap,
    estimate: &dyn RadianceEstimate,
    bar: &ProgressBar,
) -> Vec<Vec3> {
    let mut values = vec![Vec3::ZERO; grid.len()];
    // One row per job: rows differ in cost by an order of magnitude (bright shapes against the
    // background), and rayon's adaptive splitting otherwise leaves one thread with the last
    // expensive block while the other idles.
    values
        .par_chunks_mut(grid.width)
        .with_max_len(1)
        .enumerate()
        .for_each_init(Scratch::default, |scratch, (row, out)| {
            for (col, value) in out.iter_mut().enumerate() {
                let c = grid.centre(row, col);
                let query = Query {
                    position: Vec3::new(c.x as f32, c.y as f32, 0.0),
                    normal: Vec3::Z,
                };
                *value = estimate.irradiance(map, &query, scratch);
            }
            bar.inc(1);
        });
    bar.finish_and_clear();
    values
}
