//! pbrt-v3 and pbrt-v4 scene files (`.pbrt`), read into the same [`SceneDescription`] the TOML
//! format gives: the part of the format that photon mapping with dpm's materials can
//! represent is mapped (docs/scene-format.md, "pbrt scenes", lists what is read, mapped with a
//! warning, and refused), the rest is refused with an error naming file, line and column.
//! Owns pbrt's language (`lexer`, `cursor`, `params`, `args`, `parser`) and its mapping onto dpm's types
//! (`mapping`); must not call Embree, and leaves the checks every scene gets to the
//! [`super`] module's validation.

mod args;
mod cursor;
mod lexer;
mod mapping;
mod params;
mod parser;

use super::files::SceneFiles;
use super::{LoadOptions, LoadReport, SceneDescription, SceneError};
use std::fmt;
use std::path::{Path, PathBuf};

type PbrtError = SceneError;

/// Which pbrt wrote the file, where the versions read a parameter differently (the spot
/// light's falloff curve, a blackbody's normalisation, the film's exposure and white balance).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Dialect {
    V3,
    V4,
}

/// A place in a scene file: file, 1-based line and column.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Place {
    pub file: PathBuf,
    pub line: usize,
    pub column: usize,
}

impl Place {
    fn error(&self, field: &str, message: impl Into<String>) -> PbrtError {
        SceneError {
            file: self.file.clone(),
            line: Some(self.line),
            column: Some(self.column),
            field: field.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.column)
    }
}

/// Reads the pbrt scene at `path` and the files it includes from `files`.
pub(crate) fn load(
    path: &Path,
    files: &dyn SceneFiles,
    options: &LoadOptions,
) -> Result<(SceneDescription, LoadReport), SceneError> {
    let parsed = parser::parse(path, files)?;
    mapping::scene(path, parsed, files, options)
}
