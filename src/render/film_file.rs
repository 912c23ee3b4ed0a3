//! The film file: a [`Film`] on disk, versioned and checksummed, written atomically, so a render
//! can be resumed, and films from different runs or machines merged.
//!
//! | offset | bytes | what |
//! |---|---|---|
//! | 0 | 8 | magic `DPMFILM\0` |
//! | 8 | 4 | version (2), little-endian |
//! | 12 | 4 | header length `H` (at most 1 MiB) |
//! | 16 | H | header: UTF-8 TOML (the [`FilmHeader`] and the pass ranges) |
//! | 16 + H | 8·W·H'·C | the sums, f64 little-endian, pixel-major, C channels per pixel |
//! | end − 8 | 8 | checksum: FNV-1a 64 of every byte before it |
//!
//! Reading checks the size the header implies against the file's real size before allocating
//! anything, so a header that claims a huge image is refused, not allocated. Owns the format;
//! must not accumulate or compare films (that is [`super::film`]).

use super::film::{Film, FilmHeader, PassSet};
use crate::image_io::{ImageError, write_atomically};
use crate::photon::store::Fnv64;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"DPMFILM\0";
/// 2: the settings gained `irradiance-stride` and `light-samples`, and light and gather
/// samples became stratified, so version-1 films would not merge with new passes anyway.
pub const VERSION: u32 = 2;
const MAX_HEADER: u64 = 1 << 20;

#[derive(Debug, thiserror::Error)]
pub enum FilmFileError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a dpm film ({why})", path.display())]
    Invalid { path: PathBuf, why: String },
    #[error("{}: film header, {why}", path.display())]
    Header { path: PathBuf, why: String },
    #[error(
        "{}: film is corrupt: checksum {computed:016x} does not match the stored {stored:016x}",
        path.display()
    )]
    Checksum {
        path: PathBuf,
        computed: u64,
        stored: u64,
    },
    #[error("{0}")]
    Write(#[from] ImageError),
}

impl FilmFileError {
    /// 2 for a file that is not a usable film, 1 for failing to read or write one.
    pub fn exit_code(&self) -> i32 {
        match self {
            FilmFileError::Io { .. } | FilmFileError::Write(_) => 1,
            _ => 2,
        }
    }
}

#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StoredHeader {
    film: FilmHeader,
    /// Half-open ranges of the passes summed.
    passes: Vec<[u64; 2]>,
}

/// Writes `film` to `path` atomically.
pub fn write(path: &Path, film: &Film) -> Result<(), FilmFileError> {
    let stored = StoredHeader {
        film: film.header.clone(),
        passes: film
            .passes()
            .ranges()
            .iter()
            .map(|&(a, b)| [a, b])
            .collect(),
    };
    let header = toml::to_string(&stored).expect("film headers serialise");
    write_atomically(path, |out| {
        let mut hash = Fnv64::default();
        let mut put = |bytes: &[u8]| {
            hash.update(bytes);
            out.write_all(bytes).map_err(|e| e.to_string())
        };
        put(MAGIC)?;
        put(&VERSION.to_le_bytes())?;
        put(&(header.len() as u32).to_le_bytes())?;
        put(header.as_bytes())?;
        let mut block = Vec::with_capacity(8 * 4096);
        for chunk in film.sums().chunks(4096) {
            block.clear();
            for v in chunk {
                block.extend_from_slice(&v.to_le_bytes());
            }
            put(&block)?;
        }
        let checksum = hash.finish();
        out.write_all(&checksum.to_le_bytes())
            .map_err(|e| e.to_string())
    })?;
    Ok(())
}

/// Reads a film written by [`write`].
pub fn read(path: &Path) -> Result<Film, FilmFileError> {
    let io = |source| FilmFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let invalid = |why: String| FilmFileError::Invalid {
        path: path.to_path_buf(),
        why,
    };
    let header_error = |why: String| FilmFileError::Header {
        path: path.to_path_buf(),
        why,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let size = file.metadata().map_err(io)?.len();
    let mut fixed = [0u8; 16];
    if size < 24 {
        return Err(invalid(format!("{size} bytes is too short")));
    }
    file.read_exact(&mut fixed).map_err(io)?;
    if &fixed[..8] != MAGIC {
        return Err(invalid("wrong magic".into()));
    }
    let version = u32::from_le_bytes(fixed[8..12].try_into().expect("4 bytes"));
    if version != VERSION {
        return Err(invalid(format!(
            "version {version}; this dpm reads version {VERSION}"
        )));
    }
    let header_len = u32::from_le_bytes(fixed[12..16].try_into().expect("4 bytes")) as u64;
    if header_len > MAX_HEADER || 16 + header_len + 8 > size {
        return Err(invalid(format!(
            "header length {header_len} does not fit a {size}-byte file"
        )));
    }
    let mut header = vec![0u8; header_len as usize];
    file.read_exact(&mut header).map_err(io)?;
    let text = std::str::from_utf8(&header).map_err(|e| header_error(format!("not UTF-8: {e}")))?;
    let stored: StoredHeader =
        toml::from_str(text).map_err(|e| header_error(toml_place(&e, text)))?;
    let h = &stored.film;
    let values = (h.width as u64)
        .checked_mul(h.height as u64)
        .and_then(|p| p.checked_mul(h.channels() as u64));
    let expected = values.and_then(|v| v.checked_mul(8));
    let body = size - 16 - header_len - 8;
    if expected != Some(body) {
        return Err(header_error(format!(
            "width {} × height {} × {} channels needs {} bytes of sums, the file holds {body}",
            h.width,
            h.height,
            h.channels(),
            expected.map_or("more than 2^64".into(), |e| e.to_string())
        )));
    }
    let ranges: Vec<(u64, u64)> = stored.passes.iter().map(|r| (r[0], r[1])).collect();
    let passes = PassSet::from_ranges(&ranges)
        .map_err(|why| header_error(format!("field passes: {why}")))?;
    if passes.is_empty() {
        return Err(header_error("field passes: the film holds no pass".into()));
    }
    let mut hash = Fnv64::default();
    hash.update(&fixed);
    hash.update(&header);
    let mut sums = Vec::with_capacity(body as usize / 8);
    let mut block = vec![0u8; 8 * 4096];
    let mut left = body as usize;
    while left > 0 {
        let n = left.min(block.len());
        file.read_exact(&mut block[..n]).map_err(io)?;
        hash.update(&block[..n]);
        sums.extend(
            block[..n]
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))),
        );
        left -= n;
    }
    let mut tail = [0u8; 8];
    file.read_exact(&mut tail).map_err(io)?;
    let stored_sum = u64::from_le_bytes(tail);
    let computed = hash.finish();
    if stored_sum != computed {
        return Err(FilmFileError::Checksum {
            path: path.to_path_buf(),
            computed,
            stored: stored_sum,
        });
    }
    if let Some(i) = sums.iter().position(|v| !v.is_finite()) {
        return Err(invalid(format!("sum {i} is not finite")));
    }
    Ok(Film::from_parts(stored.film, passes, sums))
}

/// A TOML error as "line L, column C: message".
fn toml_place(e: &toml::de::Error, text: &str) -> String {
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {column}: {}", e.message())
        }
        None => e.message().to_string(),
    }
}
