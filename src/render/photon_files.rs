//! `--save-photons` and `--load-photons`: pass 0's maps to and from a photon map file
//! ([`crate::photon::store`]), and the checks of those two flags before any work is done. Owns
//! that glue; the file format is the store's, the pass loop is [`super::pipeline`]'s.

use super::pass::PassMaps;
use super::pipeline::{RenderArgs, RenderError};
use crate::image_io;
use crate::photon::PhotonMap;
use crate::photon::store::{self, MapInfo};
use crate::photon::tracer::{MapKind, TraceCounts};
use crate::timing::PhaseTimes;
use std::path::Path;
use std::time::Instant;

/// Pass 0's maps from --load-photons.
pub(super) fn load_maps(
    args: &RenderArgs,
    scene: u64,
    wanted: &[MapInfo],
    times: &mut PhaseTimes,
) -> Result<PassMaps, RenderError> {
    let path = args.load_photons.as_ref().expect("asked for");
    let start = Instant::now();
    let mut file = store::read(path)?;
    file.check_fits(scene, args.seed, wanted)?;
    let with_counts = |map: PhotonMap| {
        let counts = TraceCounts {
            emitted: map.emitted,
            stored: map.len() as u64,
        };
        (map, counts)
    };
    let maps = PassMaps {
        caustic: file.take(MapKind::Caustic).map(with_counts),
        global: file
            .take(MapKind::Global { with_direct: false })
            .map(with_counts),
        // Photon files hold surface maps only: a scene with media is refused by `check_fits`.
        volume: Default::default(),
    };
    let stored = |m: &Option<(PhotonMap, TraceCounts)>| m.as_ref().map_or(0, |(_, c)| c.stored);
    times.record(
        "load photons",
        start.elapsed(),
        &[
            ("caustic", stored(&maps.caustic)),
            ("global", stored(&maps.global)),
        ],
    );
    Ok(maps)
}

/// Saves pass 0's maps to --save-photons.
pub(super) fn save_maps(
    path: &Path,
    scene: u64,
    seed: u64,
    wanted: &[MapInfo],
    maps: &PassMaps,
    times: &mut PhaseTimes,
) -> Result<(), RenderError> {
    let start = Instant::now();
    let list: Vec<(MapInfo, &PhotonMap)> = wanted
        .iter()
        .zip(maps.caustic.iter().chain(maps.global.iter()))
        .map(|(info, (map, _))| (*info, map))
        .collect();
    let bytes = store::write(path, scene, seed, &list)?;
    times.record("save photons", start.elapsed(), &[("bytes", bytes)]);
    Ok(())
}

/// Checks `--save-photons` / `--load-photons` before any work: a file to load exists, a file
/// to save goes to an existing directory and is not the output image.
pub(super) fn validate_photon_files(args: &RenderArgs, output: &Path) -> Result<(), RenderError> {
    if let Some(path) = &args.load_photons
        && !path.is_file()
    {
        let why = if path.exists() {
            "is not a file"
        } else {
            "does not exist"
        };
        return Err(RenderError::Invalid(format!(
            "--load-photons {}: {why}",
            path.display()
        )));
    }
    if let Some(path) = &args.save_photons {
        if path == output {
            return Err(RenderError::Invalid(format!(
                "--save-photons {}: is also the output image",
                path.display()
            )));
        }
        if path.is_dir() {
            return Err(RenderError::Invalid(format!(
                "--save-photons {}: is a directory",
                path.display()
            )));
        }
        if let Some(dir) = image_io::missing_output_directory(path) {
            return Err(RenderError::Invalid(format!(
                "--save-photons {}: directory {} does not exist",
                path.display(),
                dir.display()
            )));
        }
    }
    Ok(())
}
