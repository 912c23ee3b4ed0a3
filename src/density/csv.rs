//! Text in and out of the density command: the photon CSV reader (`x,y` or `x,y,power`, one
//! photon a line) and the grid-values CSV writer. Owns parsing and formatting only; it must not
//! build photon maps or evaluate estimates.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A photon in the plane as read from a file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanePhoton {
    pub x: f32,
    pub y: f32,
    pub power: f32,
}

/// A malformed line: the file, its 1-based line number, the field and what is wrong.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}:{line}: field {field}: {message}", path.display())]
pub struct CsvError {
    pub path: PathBuf,
    pub line: usize,
    /// `x`, `y`, `power`, or `fields` when the number of fields is wrong.
    pub field: &'static str,
    pub message: String,
}

/// Parses photon lines. Blank lines and lines starting with `#` are skipped, and so is a header
/// line `x,y` or `x,y,power` on the first line that has content. Power defaults to 1; it must be
/// finite and not negative, and coordinates must be finite.
pub fn parse_photons(path: &Path, text: &str) -> Result<Vec<PlanePhoton>, CsvError> {
    let mut photons = Vec::new();
    let mut seen_content = false;
    for (index, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let first_content = !seen_content;
        seen_content = true;
        if first_content && is_header(&fields) {
            continue;
        }
        let error = |field, message: String| CsvError {
            path: path.to_path_buf(),
            line: index + 1,
            field,
            message,
        };
        if !(2..=3).contains(&fields.len()) {
            return Err(error(
                "fields",
                format!("{} fields, expected x,y or x,y,power", fields.len()),
            ));
        }
        let number = |field: &'static str, text: &str| -> Result<f32, CsvError> {
            let v: f32 = text
                .parse()
                .map_err(|_| error(field, format!("{text:?} is not a number")))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(error(field, format!("{text:?} is not finite")))
            }
        };
        let x = number("x", fields[0])?;
        let y = number("y", fields[1])?;
        let power = match fields.get(2) {
            Some(t) => number("power", t)?,
            None => 1.0,
        };
        if power < 0.0 {
            return Err(error("power", format!("{power} is negative")));
        }
        photons.push(PlanePhoton { x, y, power });
    }
    Ok(photons)
}

fn is_header(fields: &[&str]) -> bool {
    let lower: Vec<String> = fields.iter().map(|f| f.to_ascii_lowercase()).collect();
    lower == ["x", "y"] || lower == ["x", "y", "power"]
}

/// The grid values as CSV: `row,col,x,y,estimate` and `truth` when known; row 0 is the top.
/// `values[row * width + col]`; `centres(row, col)` gives the pixel centre.
pub fn format_grid(
    width: usize,
    values: &[f64],
    truth: Option<&[f64]>,
    centre: impl Fn(usize, usize) -> (f64, f64),
) -> String {
    let mut out = String::with_capacity(values.len() * 48);
    out.push_str(if truth.is_some() {
        "row,col,x,y,estimate,truth\n"
    } else {
        "row,col,x,y,estimate\n"
    });
    for (i, v) in values.iter().enumerate() {
        let (row, col) = (i / width, i % width);
        let (x, y) = centre(row, col);
        let _ = write!(out, "{row},{col},{x},{y},{v}");
        if let Some(t) = truth {
            let _ = write!(out, ",{}", t[i]);
        }
        out.push('\n');
    }
    out
}
