//! Where a scene's files come from: the disk, or an in-memory set (the fuzz targets, which
//! must stay hermetic, and tests). Every reader of scene, mesh, material and include files goes
//! through [`SceneFiles`]; this module owns nothing else.

use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};

/// A source of the files a scene names.
pub trait SceneFiles {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>>;
    fn is_dir(&self, path: &Path) -> bool;
    /// The name two paths to one file share (for include cycles).
    fn identity(&self, path: &Path) -> PathBuf;
}

/// The file system.
#[derive(Clone, Copy, Debug, Default)]
pub struct Disk;

impl SceneFiles for Disk {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        if path.is_dir() {
            return Err(io::Error::other("is a directory, not a file"));
        }
        std::fs::read(path)
    }

    fn is_dir(&self, path: &Path) -> bool {
        path.is_dir()
    }

    fn identity(&self, path: &Path) -> PathBuf {
        path.canonicalize().unwrap_or_else(|_| path.to_path_buf())
    }
}

/// Files held in memory by path; anything else does not exist.
#[derive(Clone, Debug, Default)]
pub struct InMemory {
    files: HashMap<PathBuf, Vec<u8>>,
}

impl InMemory {
    pub fn insert(&mut self, path: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) {
        self.files.insert(normal(&path.into()), bytes.into());
    }
}

/// `a/./b/../c` as `a/c`, so that a path reached through `..` finds its file.
fn normal(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

impl SceneFiles for InMemory {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        self.files
            .get(&normal(path))
            .cloned()
            .ok_or_else(|| io::Error::new(io::ErrorKind::NotFound, "no such file"))
    }

    fn is_dir(&self, _path: &Path) -> bool {
        false
    }

    fn identity(&self, path: &Path) -> PathBuf {
        normal(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_memory_files_are_found_through_dot_and_dot_dot() {
        let mut files = InMemory::default();
        files.insert("fuzz/meshes/a.obj", "v 0 0 0");
        assert_eq!(
            files.read(Path::new("fuzz/./x/../meshes/a.obj")).unwrap(),
            b"v 0 0 0"
        );
        assert_eq!(
            files.read(Path::new("fuzz/b.obj")).unwrap_err().kind(),
            io::ErrorKind::NotFound
        );
        assert_eq!(
            files.identity(Path::new("fuzz/./meshes/a.obj")),
            files.identity(Path::new("fuzz/meshes/a.obj"))
        );
    }

    #[test]
    fn the_disk_refuses_a_directory() {
        let dir = std::env::temp_dir();
        assert!(Disk.is_dir(&dir));
        assert!(Disk.read(&dir).is_err());
    }
}
