//! `dpm merge`: films of disjoint pass ranges of one render (same scene, seed and settings),
//! rendered in different runs or on different machines, combined into one film and its image.
//! Overlapping passes, or a film of another scene, seed or setting, are refused naming both
//! files; passes missing below the highest one are reported (and refused with `--expect`).
//! Owns the command; the arithmetic is [`Film::merge`].

use super::film::{Film, FilmError, range_text};
use super::film_file::{self, FilmFileError};
use super::output::{write_film_image, write_kernel_field};
use crate::image_io::{self, ImageError, ImageFormat};
use std::path::PathBuf;

#[derive(Clone, Debug, clap::Args)]
pub struct MergeArgs {
    /// Films to combine (from `dpm render --film`).
    #[arg(required = true, num_args = 1..)]
    pub films: Vec<PathBuf>,
    /// The merged image (.png, .exr with layers, or .pfm), written atomically.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also save the merged film.
    #[arg(long, value_name = "FILE")]
    pub film: Option<PathBuf>,
    /// Require passes 0 to N−1, all of them: a missing pass is an error.
    #[arg(long, value_name = "N")]
    pub expect: Option<u64>,
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Also write the kernel field picture (films of the diffusion estimate with it).
    #[arg(long, value_name = "OUT")]
    pub kernel_field: Option<PathBuf>,
}

#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error("{0}")]
    Film(#[from] FilmFileError),
    #[error("{0}")]
    Image(#[from] ImageError),
    #[error("cannot merge {} into {}: {why}", other.display(), first.display())]
    Incompatible {
        first: PathBuf,
        other: PathBuf,
        why: FilmError,
    },
    #[error("{0}")]
    Invalid(String),
}

impl MergeError {
    pub fn exit_code(&self) -> i32 {
        match self {
            MergeError::Film(e) => e.exit_code(),
            MergeError::Image(ImageError::Io { .. } | ImageError::Encode { .. }) => 1,
            _ => 2,
        }
    }
}

/// What a merge made.
#[derive(Debug)]
pub struct MergeOutcome {
    pub film: Film,
    /// Pass ranges below the highest held that no film had.
    pub missing: Vec<(u64, u64)>,
}

impl MergeOutcome {
    /// "passes 2-3, 7 are missing" or None.
    pub fn missing_text(&self) -> Option<String> {
        (!self.missing.is_empty()).then(|| missing_text(&self.missing))
    }
}

/// "pass 2 is missing", "passes 2-3, 7 are missing": every range, so a scale-out user sees
/// which shards to rerun.
pub fn missing_text(missing: &[(u64, u64)]) -> String {
    let list: Vec<String> = missing.iter().map(|r| range_text(*r)).collect();
    let count: u64 = missing.iter().map(|(a, b)| b - a).sum();
    if count == 1 {
        format!("pass {} is missing", list.join(", "))
    } else {
        format!("passes {} are missing", list.join(", "))
    }
}

pub fn run(args: &MergeArgs) -> Result<MergeOutcome, MergeError> {
    ImageFormat::from_path(&args.output)?;
    for path in [
        Some(&args.output),
        args.film.as_ref(),
        args.kernel_field.as_ref(),
    ]
    .into_iter()
    .flatten()
    {
        if let Some(dir) = image_io::missing_output_directory(path) {
            return Err(ImageError::MissingDirectory {
                path: path.clone(),
                dir: dir.to_path_buf(),
            }
            .into());
        }
    }
    if args.film.as_ref() == Some(&args.output) {
        return Err(MergeError::Invalid(format!(
            "--film {}: is also the output image",
            args.output.display()
        )));
    }
    if let Some(p) = args.films.iter().find(|p| !p.is_file()) {
        return Err(MergeError::Invalid(format!(
            "{}: no such film (or not a file)",
            p.display()
        )));
    }
    let mut merged = film_file::read(&args.films[0])?;
    // Which file brought which passes, to name the one a clashing pass came from.
    let mut holders = vec![(args.films[0].clone(), merged.passes().clone())];
    for path in &args.films[1..] {
        let film = film_file::read(path)?;
        if let Err(why) = merged.merge(&film) {
            let first = match &why {
                FilmError::Overlap(p) => holders.iter().find(|(_, set)| set.contains(*p)),
                _ => None,
            }
            .map_or_else(|| args.films[0].clone(), |(path, _)| path.clone());
            return Err(MergeError::Incompatible {
                first,
                other: path.clone(),
                why,
            });
        }
        holders.push((path.clone(), film.passes().clone()));
    }
    let mut missing = merged.passes().missing();
    if let Some(n) = args.expect {
        if merged.passes().end() < n {
            missing.push((merged.passes().end(), n));
        }
        if !missing.is_empty() {
            let count: u64 = missing.iter().map(|(a, b)| b - a).sum();
            return Err(MergeError::Invalid(format!(
                "--expect {n}: {} ({count} of {n}); rerun them with --first-pass and --passes",
                missing_text(&missing)
            )));
        }
    }
    write_film_image(&args.output, &merged, args.exposure)?;
    if let Some(path) = &args.film {
        film_file::write(path, &merged)?;
    }
    if let Some(path) = &args.kernel_field
        && !write_kernel_field(path, &merged)?
    {
        return Err(MergeError::Invalid(format!(
            "--kernel-field {}: the films carry no kernel field (diffusion estimate, EXR or \
                 --kernel-field output)",
            path.display()
        )));
    }
    Ok(MergeOutcome {
        film: merged,
        missing,
    })
}
