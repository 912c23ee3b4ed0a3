//! Property tests: mutated scene files (lines deleted, duplicated, swapped or replaced by
//! junk, bytes flipped, numbers changed to nan, inf, -1, 1e30 and the like, text truncated)
//! and mutated OBJ/MTL files never make `scene::parse` or `scene::load` panic; every error
//! they give names a field and a line.

use dpm::scene::{self, SceneError};
use proptest::prelude::*;
use proptest::sample::Index;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// Every valid scene in scenes/, with its text.
fn scenes() -> &'static [(PathBuf, String)] {
    static SCENES: OnceLock<Vec<(PathBuf, String)>> = OnceLock::new();
    SCENES.get_or_init(|| {
        let mut all: Vec<(PathBuf, String)> = std::fs::read_dir(repo("scenes"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .map(|p| {
                let text = std::fs::read_to_string(&p).unwrap();
                (p, text)
            })
            .collect();
        all.sort();
        assert!(all.len() >= 4);
        all
    })
}

const NUMBERS: &[&str] = &[
    "nan",
    "-nan",
    "inf",
    "-inf",
    "+inf",
    "-1",
    "0",
    "-0.0",
    "1e30",
    "-1e30",
    "1e39",
    "-1e39",
    "1e-45",
    "1e-300",
    "1e308",
    "4294967296",
    "99999999999999999999999",
    "0x10",
    "0b1",
    "1_000",
    "\"1\"",
    "[]",
    "[1, 2]",
    "true",
    "{}",
    "",
];

const JUNK: &[&str] = &[
    "",
    "[",
    "]]",
    "=",
    "\"",
    "'''",
    "[camera]",
    "[[objects]]",
    "[[lights]]",
    "[materials.x]",
    "type = \"mesh\"",
    "type = \"sphere\"",
    "type = \"quad\"",
    "type = \"glass\"",
    "file = \"/\"",
    "file = \"..\"",
    "file = \"\"",
    "file = \"meshes\"",
    "file = \"/dev/null\"",
    "material = \"\"",
    "resolution = [0, 0]",
    "resolution = [4294967295, 4294967295]",
    "radius = nan",
    "scale = [0, 0, 0]",
    "scale = -1",
    "rotate = [1e30, 0, 0]",
    "up = [0, 0, 0]",
    "\u{0}",
    "\u{feff}",
    "é = 1",
];

#[derive(Clone, Debug)]
enum Mutation {
    DeleteLine(Index),
    DuplicateLine(Index),
    ReplaceLine(Index, Index),
    SwapLines(Index, Index),
    JunkLine(Index, Index),
    ChangeNumber(Index, Index),
    FlipByte(Index, u8),
    Truncate(Index),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        1 => any::<Index>().prop_map(Mutation::DeleteLine),
        1 => any::<Index>().prop_map(Mutation::DuplicateLine),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::ReplaceLine(a, b)),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::JunkLine(a, b)),
        3 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::ChangeNumber(a, b)),
        1 => (any::<Index>(), any::<u8>()).prop_map(|(a, b)| Mutation::FlipByte(a, b)),
        1 => any::<Index>().prop_map(Mutation::Truncate),
    ]
}

/// Byte ranges of the number-like tokens in `text`.
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut found = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || (matches!(text[i], b'-' | b'+' | b'.')
                && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        if starts {
            let start = i;
            i += 1;
            while i < text.len()
                && (text[i].is_ascii_alphanumeric() || matches!(text[i], b'.' | b'_' | b'-' | b'+'))
            {
                i += 1;
            }
            found.push((start, i));
        } else {
            i += 1;
        }
    }
    found
}

fn apply(text: &[u8], m: &Mutation) -> Vec<u8> {
    let mut lines: Vec<Vec<u8>> = text.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
    let join = |lines: Vec<Vec<u8>>| lines.join(&b'\n');
    match m {
        Mutation::DeleteLine(i) => {
            lines.remove(i.index(lines.len()));
            join(lines)
        }
        Mutation::DuplicateLine(i) => {
            let i = i.index(lines.len());
            lines.insert(i, lines[i].clone());
            join(lines)
        }
        Mutation::ReplaceLine(a, b) => {
            let (a, b) = (a.index(lines.len()), b.index(lines.len()));
            lines[a] = lines[b].clone();
            join(lines)
        }
        Mutation::SwapLines(a, b) => {
            let (a, b) = (a.index(lines.len()), b.index(lines.len()));
            lines.swap(a, b);
            join(lines)
        }
        Mutation::JunkLine(a, j) => {
            let a = a.index(lines.len() + 1);
            lines.insert(a, JUNK[j.index(JUNK.len())].as_bytes().to_vec());
            join(lines)
        }
        Mutation::ChangeNumber(n, v) => {
            let found = numbers(text);
            if found.is_empty() {
                return text.to_vec();
            }
            let (start, end) = found[n.index(found.len())];
            let mut out = text[..start].to_vec();
            out.extend_from_slice(NUMBERS[v.index(NUMBERS.len())].as_bytes());
            out.extend_from_slice(&text[end..]);
            out
        }
        Mutation::FlipByte(i, x) => {
            let mut out = text.to_vec();
            if !out.is_empty() {
                let i = i.index(out.len());
                out[i] ^= x.max(&1);
            }
            out
        }
        Mutation::Truncate(i) => text[..i.index(text.len() + 1)].to_vec(),
    }
}

fn mutate(text: &str, mutations: &[Mutation]) -> Vec<u8> {
    mutations
        .iter()
        .fold(text.as_bytes().to_vec(), |t, m| apply(&t, m))
}

/// An error must say where: a field, and a line in the file it names.
fn check_error(e: &SceneError) -> Result<(), TestCaseError> {
    prop_assert!(!e.field.is_empty(), "no field: {e}");
    prop_assert!(!e.message.is_empty(), "no message: {e}");
    let line = e.line;
    prop_assert!(line.is_some_and(|l| l >= 1), "no line: {e}");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Mutated text, parsed in place of a real scene (so its meshes resolve), never panics.
    #[test]
    fn mutated_scene_text_never_panics(
        which in any::<Index>(),
        mutations in prop::collection::vec(mutation(), 1..5),
    ) {
        let (path, text) = &scenes()[which.index(scenes().len())];
        let mutated = mutate(text, &mutations);
        let mutated = String::from_utf8_lossy(&mutated);
        if let Err(e) = scene::parse(&mutated, path) {
            check_error(&e)?;
        }
    }

    /// Mutated bytes in a file (invalid UTF-8 included), loaded from disk, never panic.
    #[test]
    fn mutated_scene_files_never_panic(
        which in any::<Index>(),
        mutations in prop::collection::vec(mutation(), 1..5),
    ) {
        let (path, text) = &scenes()[which.index(scenes().len())];
        let dir = tempfile::tempdir().unwrap();
        std::os::unix::fs::symlink(repo("scenes/meshes"), dir.path().join("meshes")).unwrap();
        let copy = dir.path().join(path.file_name().unwrap());
        std::fs::write(&copy, mutate(text, &mutations)).unwrap();
        if let Err(e) = scene::load(&copy) {
            check_error(&e)?;
        }
    }

    /// A scene whose OBJ or MTL file is mutated never panics.
    #[test]
    fn mutated_meshes_never_panic(
        mutate_mtl in any::<bool>(),
        mutations in prop::collection::vec(mutation(), 1..5),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let obj = std::fs::read_to_string(repo("tests/fixtures/meshes/materials.obj")).unwrap();
        let mtl = std::fs::read_to_string(repo("tests/fixtures/meshes/materials.mtl")).unwrap();
        let (obj, mtl) = if mutate_mtl {
            (obj.into_bytes(), mutate(&mtl, &mutations))
        } else {
            (mutate(&obj, &mutations), mtl.into_bytes())
        };
        std::fs::write(dir.path().join("materials.obj"), obj).unwrap();
        std::fs::write(dir.path().join("materials.mtl"), mtl).unwrap();
        let text = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\n\
                    fov_y = 40\nresolution = [64, 48]\n\n[[lights]]\ntype = \"point\"\n\
                    position = [0.0, 3.0, 0.0]\npower = [10, 10, 10]\n\n\
                    [[objects]]\ntype = \"mesh\"\nfile = \"materials.obj\"\n";
        if let Err(e) = scene::parse(text, &dir.path().join("scene.toml")) {
            check_error(&e)?;
        }
    }
}

#[test]
fn number_tokens_are_found() {
    let text = b"a = 1\nb = [2.5, -3e4, +inf]\nc = \"x9\"\nd = 1_000";
    let found: Vec<&[u8]> = numbers(text).iter().map(|&(a, b)| &text[a..b]).collect();
    assert_eq!(found, [&b"1"[..], b"2.5", b"-3e4", b"9", b"1_000"]);
}

/// Found by `mutated_meshes_never_panic`: tobj 4 panicked on an MTL colour with fewer than
/// three numbers.
#[test]
fn short_mtl_colour_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl grey\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl grey\nKd 0.3 0.3\n").unwrap();
    let text = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\n\
                fov_y = 40\nresolution = [64, 48]\n\n[[lights]]\ntype = \"point\"\n\
                position = [0.0, 3.0, 0.0]\npower = [10, 10, 10]\n\n\
                [[objects]]\ntype = \"mesh\"\nfile = \"m.obj\"\n";
    let e = scene::parse(text, &dir.path().join("scene.toml")).unwrap_err();
    assert_eq!(e.file, dir.path().join("m.mtl"));
    assert_eq!(e.line, Some(2));
    assert_eq!(e.field, "objects[0].file");
    assert!(e.message.contains("Kd needs three numbers"), "{e}");
}
