//! Photon map files (`dpm render --save-photons` / `--load-photons`), so a long photon pass is
//! never redone. Owns the file format and the check that a stored map fits a render; knows
//! nothing of estimates or images.
//!
//! Format, version 1 (every number little-endian):
//!
//! | offset | bytes | content |
//! |---|---|---|
//! | 0 | 8 | magic `DPMPHMAP` |
//! | 8 | 4 | format version (u32) = 1 |
//! | 12 | 4 | number of maps n (u32, 0 to 2) |
//! | 16 | 8 | scene fingerprint (u64, [`scene_fingerprint`]) |
//! | 24 | 8 | seed (u64) |
//! | 32 | 32 n | per map: kind (u32: 0 caustic, 1 global, 2 global with direct hits), the caustic guide's pilot paths (u32; 0: unguided, as every file written before the guide has it), photons asked for (u64), paths emitted (u64), photons stored (u64) |
//! | … | 20 per photon | each map's photons in turn: position x, y, z (f32 bits), power (RGBE, 4 bytes), direction and normal (octahedral, 2 bytes each) |
//! | end − 8 | 8 | checksum: FNV-1a 64 of every byte before it |
//!
//! Photons are stored in the order tracing produced them (the order given to
//! [`PhotonMap::build`]), not in tree order, so a loaded map is rebuilt into exactly the same
//! tree and every estimate, and so the image, is identical to one from the traced map.
//!
//! Reading refuses, each with its own error naming the file: a file that does not start with
//! the magic (a foreign file), another format version, a file shorter or longer than its
//! header says (truncated), a checksum mismatch (corrupt), and impossible contents. Writing is
//! atomic (temporary file, sync, rename), like the images.

mod fingerprint;

pub use fingerprint::{Fnv64, scene_fingerprint};

use super::tracer::MapKind;
use super::{Photon, PhotonMap};
use crate::image_io::{self, ImageError};
use std::fs::File;
use std::io::{self, BufReader, Read, Write};
use std::path::{Path, PathBuf};

pub const MAGIC: [u8; 8] = *b"DPMPHMAP";
pub const VERSION: u32 = 1;
const FIXED_HEADER: u64 = 32;
const MAP_HEADER: u64 = 32;
const PHOTON_BYTES: u64 = 20;
const CHECKSUM_BYTES: u64 = 8;
/// Photons encoded or decoded per chunk while streaming.
const CHUNK_PHOTONS: usize = 1 << 14;

/// Which map, and for how many photons it was traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapInfo {
    pub kind: MapKind,
    /// Photons the pass was asked to store (`--caustic-photons` / `--global-photons`).
    pub target: u64,
    /// Pilot paths of the caustic guide its photons were drawn through (`--guide-paths`; 0:
    /// unguided, and always 0 for a global map).
    pub guide: u32,
}

/// A map read from a file.
#[derive(Clone, Debug)]
pub struct StoredMap {
    pub info: MapInfo,
    /// Rebuilt from the stored photons; `emitted` as stored.
    pub map: PhotonMap,
}

/// A photon map file's contents.
#[derive(Clone, Debug)]
pub struct PhotonFile {
    pub path: PathBuf,
    pub scene: u64,
    pub seed: u64,
    pub maps: Vec<StoredMap>,
}

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("{path}: cannot read the photon map file: {source}")]
    Read { path: PathBuf, source: io::Error },
    #[error("{0}")]
    Write(#[from] ImageError),
    #[error("{path}: not a dpm photon map file (it does not start with \"DPMPHMAP\")")]
    Foreign { path: PathBuf },
    #[error(
        "{path}: photon map file format version {found}, but this dpm reads version {supported} \
         only; trace the photons again"
    )]
    UnsupportedVersion {
        path: PathBuf,
        found: u32,
        supported: u32,
    },
    #[error(
        "{path}: truncated photon map file: it has {actual} bytes where its header needs \
         {expected}"
    )]
    Truncated {
        path: PathBuf,
        expected: u64,
        actual: u64,
    },
    #[error(
        "{path}: photon map file is corrupt: checksum {computed:016x} does not match the stored \
         {stored:016x}"
    )]
    Checksum {
        path: PathBuf,
        stored: u64,
        computed: u64,
    },
    #[error("{path}: photon map file is corrupt: {reason}")]
    Corrupt { path: PathBuf, reason: String },
    #[error("{path}: {reason}; trace the photons again (leave out --load-photons)")]
    Mismatch { path: PathBuf, reason: String },
}

impl StoreError {
    /// 1 when writing failed on the way (disk full, permissions), 2 for a bad file or path.
    pub fn exit_code(&self) -> i32 {
        match self {
            StoreError::Write(ImageError::Io { .. } | ImageError::Encode { .. }) => 1,
            _ => 2,
        }
    }
}

fn kind_code(kind: MapKind) -> u32 {
    match kind {
        MapKind::Caustic => 0,
        MapKind::Global { with_direct: false } => 1,
        MapKind::Global { with_direct: true } => 2,
    }
}

fn kind_from_code(code: u32) -> Option<MapKind> {
    match code {
        0 => Some(MapKind::Caustic),
        1 => Some(MapKind::Global { with_direct: false }),
        2 => Some(MapKind::Global { with_direct: true }),
        _ => None,
    }
}

fn kind_name(kind: MapKind) -> &'static str {
    match kind {
        MapKind::Caustic => "caustic",
        MapKind::Global { .. } => "global",
    }
}

fn count_flag(kind: MapKind) -> &'static str {
    match kind {
        MapKind::Caustic => "--caustic-photons",
        MapKind::Global { .. } => "--global-photons",
    }
}

/// A writer that hashes what passes through it.
struct Hashing<'a, W: Write> {
    out: &'a mut W,
    hash: Fnv64,
}

impl<W: Write> Hashing<'_, W> {
    fn put(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.hash.update(bytes);
        self.out.write_all(bytes)
    }
}

/// The map's photons in the order they were given to [`PhotonMap::build`].
fn build_order(map: &PhotonMap) -> Vec<Photon> {
    let mut photons = vec![Photon::default(); map.len()];
    for (slot, photon) in map.photons().enumerate() {
        photons[map.tree().source_index(slot) as usize] = photon;
    }
    photons
}

/// Writes `maps` (at most one of each kind) to `path` atomically; returns the file's size.
pub fn write(
    path: &Path,
    scene: u64,
    seed: u64,
    maps: &[(MapInfo, &PhotonMap)],
) -> Result<u64, StoreError> {
    assert!(maps.len() <= 2, "at most a caustic and a global map");
    let mut size = 0u64;
    image_io::write_atomically(path, |out| {
        let mut w = Hashing {
            out,
            hash: Fnv64::default(),
        };
        let mut header = Vec::with_capacity((FIXED_HEADER + MAP_HEADER * 2) as usize);
        header.extend_from_slice(&MAGIC);
        header.extend_from_slice(&VERSION.to_le_bytes());
        header.extend_from_slice(&(maps.len() as u32).to_le_bytes());
        header.extend_from_slice(&scene.to_le_bytes());
        header.extend_from_slice(&seed.to_le_bytes());
        for (info, map) in maps {
            header.extend_from_slice(&kind_code(info.kind).to_le_bytes());
            header.extend_from_slice(&info.guide.to_le_bytes());
            header.extend_from_slice(&info.target.to_le_bytes());
            header.extend_from_slice(&map.emitted.to_le_bytes());
            header.extend_from_slice(&(map.len() as u64).to_le_bytes());
        }
        w.put(&header).map_err(|e| e.to_string())?;
        size += header.len() as u64;
        let mut chunk = Vec::with_capacity(CHUNK_PHOTONS * PHOTON_BYTES as usize);
        for (_, map) in maps {
            for photons in build_order(map).chunks(CHUNK_PHOTONS) {
                chunk.clear();
                photons
                    .iter()
                    .for_each(|p| chunk.extend_from_slice(&p.to_le_bytes()));
                w.put(&chunk).map_err(|e| e.to_string())?;
                size += chunk.len() as u64;
            }
        }
        let checksum = w.hash.finish();
        w.out
            .write_all(&checksum.to_le_bytes())
            .map_err(|e| e.to_string())?;
        size += CHECKSUM_BYTES;
        Ok(())
    })?;
    Ok(size)
}

/// Reads and checks a photon map file, rebuilding its maps.
pub fn read(path: &Path) -> Result<PhotonFile, StoreError> {
    let read_error = |source| StoreError::Read {
        path: path.to_path_buf(),
        source,
    };
    let corrupt = |reason: String| StoreError::Corrupt {
        path: path.to_path_buf(),
        reason,
    };
    let truncated = |expected: u64, actual: u64| StoreError::Truncated {
        path: path.to_path_buf(),
        expected,
        actual,
    };
    if path.is_dir() {
        return Err(read_error(io::Error::other(
            "is a directory, not a photon map file",
        )));
    }
    let file = File::open(path).map_err(read_error)?;
    let actual = file.metadata().map_err(read_error)?.len();
    let mut input = BufReader::with_capacity(1 << 20, file);
    let mut hash = Fnv64::default();

    // The fixed header: magic first, so a foreign file is called foreign even when short.
    let mut fixed = [0u8; FIXED_HEADER as usize];
    let have = read_up_to(&mut input, &mut fixed).map_err(read_error)?;
    let magic_len = have.min(MAGIC.len());
    if fixed[..magic_len] != MAGIC[..magic_len] {
        return Err(StoreError::Foreign {
            path: path.to_path_buf(),
        });
    }
    let word = |i: usize| u32::from_le_bytes(fixed[i..i + 4].try_into().expect("4 bytes"));
    let long = |i: usize| u64::from_le_bytes(fixed[i..i + 8].try_into().expect("8 bytes"));
    if have >= 12 && word(8) != VERSION {
        return Err(StoreError::UnsupportedVersion {
            path: path.to_path_buf(),
            found: word(8),
            supported: VERSION,
        });
    }
    if (have as u64) < FIXED_HEADER {
        return Err(truncated(FIXED_HEADER, actual));
    }
    hash.update(&fixed);
    let count = word(12);
    if count > 2 {
        return Err(corrupt(format!(
            "{count} maps (at most 2: caustic and global)"
        )));
    }
    let (scene, seed) = (long(16), long(24));

    let headers_end = FIXED_HEADER + MAP_HEADER * count as u64;
    if actual < headers_end {
        return Err(truncated(headers_end, actual));
    }
    let mut headers = Vec::new();
    for _ in 0..count {
        let mut h = [0u8; MAP_HEADER as usize];
        input.read_exact(&mut h).map_err(read_error)?;
        hash.update(&h);
        let long = |i: usize| u64::from_le_bytes(h[i..i + 8].try_into().expect("8 bytes"));
        let code = u32::from_le_bytes(h[0..4].try_into().expect("4 bytes"));
        let guide = u32::from_le_bytes(h[4..8].try_into().expect("4 bytes"));
        // (kind code, guide, target, emitted, stored); the kind is checked after the checksum.
        headers.push((code, guide, long(8), long(16), long(24)));
    }
    let expected = headers
        .iter()
        .try_fold(headers_end + CHECKSUM_BYTES, |acc, &(.., stored)| {
            stored.checked_mul(PHOTON_BYTES)?.checked_add(acc)
        })
        .ok_or_else(|| corrupt("photon counts overflow".into()))?;
    if actual < expected {
        return Err(truncated(expected, actual));
    }
    if actual > expected {
        return Err(corrupt(format!(
            "{} bytes after the end its header gives ({expected} bytes)",
            actual - expected
        )));
    }

    // Photons, streamed: the file's size bounds every allocation.
    let mut photon_lists = Vec::new();
    let mut chunk = vec![0u8; CHUNK_PHOTONS * PHOTON_BYTES as usize];
    for &(.., stored) in &headers {
        let mut photons = Vec::with_capacity(stored as usize);
        let mut left = stored as usize;
        while left > 0 {
            let n = left.min(CHUNK_PHOTONS);
            let bytes = &mut chunk[..n * PHOTON_BYTES as usize];
            input.read_exact(bytes).map_err(read_error)?;
            hash.update(bytes);
            photons.extend(
                bytes
                    .chunks_exact(PHOTON_BYTES as usize)
                    .map(|b| Photon::from_le_bytes(b.try_into().expect("20 bytes"))),
            );
            left -= n;
        }
        photon_lists.push(photons);
    }
    let mut stored_checksum = [0u8; CHECKSUM_BYTES as usize];
    input.read_exact(&mut stored_checksum).map_err(read_error)?;
    let stored = u64::from_le_bytes(stored_checksum);
    let computed = hash.finish();
    if stored != computed {
        return Err(StoreError::Checksum {
            path: path.to_path_buf(),
            stored,
            computed,
        });
    }

    // The checksum holds; now the contents must make sense.
    let mut maps: Vec<StoredMap> = Vec::new();
    for ((code, guide, target, emitted, stored), photons) in headers.into_iter().zip(photon_lists) {
        let kind =
            kind_from_code(code).ok_or_else(|| corrupt(format!("unknown map kind {code}")))?;
        if maps
            .iter()
            .any(|m| kind_name(m.info.kind) == kind_name(kind))
        {
            return Err(corrupt(format!("two {} maps", kind_name(kind))));
        }
        if stored > target || (stored > 0 && emitted == 0) {
            return Err(corrupt(format!(
                "{} map: {stored} photons stored from {emitted} paths for {target} asked for",
                kind_name(kind)
            )));
        }
        if let Some(i) = photons.iter().position(|p| !p.position().is_finite()) {
            return Err(corrupt(format!(
                "{} map: photon {i} has a non-finite position",
                kind_name(kind)
            )));
        }
        maps.push(StoredMap {
            info: MapInfo {
                kind,
                target,
                guide,
            },
            map: PhotonMap::build(photons, emitted),
        });
    }
    Ok(PhotonFile {
        path: path.to_path_buf(),
        scene,
        seed,
        maps,
    })
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn read_up_to(input: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut have = 0;
    while have < buf.len() {
        match input.read(&mut buf[have..]) {
            Ok(0) => break,
            Ok(n) => have += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        }
    }
    Ok(have)
}

impl PhotonFile {
    /// Checks that the file holds exactly the maps a render would trace (`wanted`) for this
    /// scene and seed, so using them gives the image tracing would give.
    pub fn check_fits(&self, scene: u64, seed: u64, wanted: &[MapInfo]) -> Result<(), StoreError> {
        let mismatch = |reason: String| StoreError::Mismatch {
            path: self.path.clone(),
            reason,
        };
        if self.scene != scene {
            return Err(mismatch(
                "its photons were traced in another scene (the lights, materials or geometry \
                 differ from this scene's)"
                    .into(),
            ));
        }
        if self.seed != seed {
            return Err(mismatch(format!(
                "its photons were traced with --seed {}, this render uses --seed {seed}",
                self.seed
            )));
        }
        for want in wanted {
            let name = kind_name(want.kind);
            let Some(have) = self.maps.iter().find(|m| kind_name(m.info.kind) == name) else {
                return Err(mismatch(format!(
                    "it holds no {name} map, but this render needs one ({} {})",
                    count_flag(want.kind),
                    want.target
                )));
            };
            if have.info.target != want.target {
                return Err(mismatch(format!(
                    "its {name} map was traced for {flag} {}, this render asks for {flag} {}",
                    have.info.target,
                    want.target,
                    flag = count_flag(want.kind)
                )));
            }
            if have.info.guide != want.guide {
                return Err(mismatch(format!(
                    "its {name} map was traced with --guide-paths {}, this render uses \
                     --guide-paths {} (the guide changes which photons are traced)",
                    have.info.guide, want.guide
                )));
            }
            if let (MapKind::Global { with_direct: had }, MapKind::Global { with_direct: wants }) =
                (have.info.kind, want.kind)
            {
                if had == wants {
                    continue;
                }
                let gather = |direct: bool| if direct { "> 0" } else { "0" };
                return Err(mismatch(format!(
                    "its global map was traced for --final-gather {}, this render uses \
                     --final-gather {}",
                    gather(had),
                    gather(wants)
                )));
            }
        }
        for have in &self.maps {
            let name = kind_name(have.info.kind);
            if !wanted.iter().any(|w| kind_name(w.kind) == name) {
                return Err(mismatch(format!(
                    "it holds a {name} map ({} {}), but this render traces none",
                    count_flag(have.info.kind),
                    have.info.target
                )));
            }
        }
        Ok(())
    }

    /// Takes the map of `kind`'s family (caustic or global) out of the file.
    pub fn take(&mut self, kind: MapKind) -> Option<PhotonMap> {
        let i = self
            .maps
            .iter()
            .position(|m| kind_name(m.info.kind) == kind_name(kind))?;
        Some(self.maps.remove(i).map)
    }
}

#[cfg(test)]
mod tests;
