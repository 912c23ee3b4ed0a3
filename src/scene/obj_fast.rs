//! The OBJ fast path: the statements big meshes are made of (`v`, `vt`, `vn`, `f`, `o`, `g`,
//! `usemtl`, `mtllib`) read in parallel, a piece of the file a thread, then put together into
//! exactly the models and vertex order tobj gives (triangulated, one index a vertex). Whatever
//! it does not handle in the same way (relative or forward indices, `l` lines, `v` with a
//! weight or a colour, a number that does not parse or is not finite, a zero normal) it hands
//! back, and the caller reads the file with tobj, whose errors it knows how to place. Owns the
//! parallel reading only; must not map materials or place meshes.

use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::cell::Cell;
use std::collections::HashMap;
use std::path::Path;

/// Bytes of text a thread reads at a time (cut at a line's end).
const PIECE_BYTES: usize = 1 << 20;
const MISSING: u32 = u32::MAX;

/// A face corner's position, texture coordinate and normal (0-based, [`MISSING`] if absent).
type Corner = [u32; 3];

/// A statement that shapes the models, in file order with the faces read before it.
enum Statement {
    /// `o` or `g`: the name of the faces that follow.
    Name(String),
    /// `usemtl`: the material the faces that follow use.
    UseMaterial(String),
    /// `mtllib`, and the byte just past its line (where tobj's reader would stand).
    Library(String, usize),
}

/// What one piece of the file holds, its indices already 0-based.
#[derive(Default)]
struct Piece {
    positions: Vec<f32>,
    texcoords: Vec<f32>,
    normals: Vec<f32>,
    corners: Vec<Corner>,
    /// Where each face's corners end in `corners`.
    face_ends: Vec<u32>,
    statements: Vec<(usize, Statement)>,
    /// The most positions (texture coordinates, normals) earlier pieces must hold for this
    /// piece's faces to refer only backwards.
    needs_before: [usize; 3],
}

/// Reads `text` as tobj would with triangulation and single indices, calling `load_library`
/// on each `mtllib` (after setting `consumed` past its line, as tobj's reader would stand).
/// `None` when the file needs tobj.
pub(super) fn load(
    text: &str,
    consumed: &Cell<usize>,
    load_library: impl Fn(&Path) -> tobj::MTLLoadResult,
) -> Option<tobj::LoadResult> {
    load_in_pieces(text, PIECE_BYTES, consumed, load_library)
}

fn load_in_pieces(
    text: &str,
    piece_bytes: usize,
    consumed: &Cell<usize>,
    load_library: impl Fn(&Path) -> tobj::MTLLoadResult,
) -> Option<tobj::LoadResult> {
    let mut cuts = vec![0];
    while let Some(&last) = cuts.last()
        && last + piece_bytes < text.len()
    {
        let past = text.as_bytes()[last + piece_bytes..]
            .iter()
            .position(|&b| b == b'\n');
        cuts.push(past.map_or(text.len(), |k| last + piece_bytes + k + 1));
    }
    cuts.push(text.len());
    cuts.dedup();
    let pieces: Vec<Piece> = (cuts.par_windows(2))
        .map(|w| read_piece(&text[w[0]..w[1]], w[0]))
        .collect::<Option<_>>()?;

    // Every index must point at an element read before its face, as tobj checks.
    let mut before = [0usize; 3];
    for piece in &pieces {
        if (0..3).any(|k| piece.needs_before[k] > before[k]) {
            return None;
        }
        before[0] += piece.positions.len() / 3;
        before[1] += piece.texcoords.len() / 2;
        before[2] += piece.normals.len() / 3;
    }
    let join = |field: fn(&Piece) -> &Vec<f32>| -> Vec<f32> {
        let mut all = Vec::with_capacity(pieces.iter().map(|p| field(p).len()).sum());
        pieces.iter().for_each(|p| all.extend_from_slice(field(p)));
        all
    };
    let vertices = Vertices {
        positions: join(|p| &p.positions),
        texcoords: join(|p| &p.texcoords),
        normals: join(|p| &p.normals),
    };

    // The models, in tobj's order: a name or a new material closes the faces before it.
    let mut models = Vec::new();
    let mut materials: Vec<tobj::Material> = Vec::new();
    let mut by_name: HashMap<String, usize> = HashMap::new();
    let mut library_error = None;
    let mut name = "unnamed_object".to_string();
    let mut material: Option<usize> = None;
    let mut open: Vec<&[Corner]> = Vec::new();
    let mut close = |open: &mut Vec<&[Corner]>, name: &str, material| {
        let mesh = vertices.mesh(open, material);
        models.push(tobj::Model::new(mesh, name.to_string()));
        open.clear();
    };
    for piece in &pieces {
        let mut face = 0;
        for (faces_before, statement) in &piece.statements {
            piece.open_faces(&mut open, &mut face, *faces_before);
            match statement {
                Statement::Name(new) => {
                    if !open.is_empty() {
                        close(&mut open, &name, material);
                    }
                    name = if new.is_empty() {
                        "unnamed_object".into()
                    } else {
                        new.clone()
                    };
                }
                Statement::UseMaterial(wanted) => {
                    let new = by_name.get(wanted).copied();
                    if material != new && !open.is_empty() {
                        close(&mut open, &name, material);
                    }
                    material = new;
                }
                Statement::Library(file, past) => {
                    consumed.set(*past);
                    match load_library(Path::new(file)) {
                        Ok((mut more, map)) => {
                            let offset = materials.len();
                            materials.append(&mut more);
                            by_name.extend(map.into_iter().map(|(k, v)| (k, v + offset)));
                        }
                        Err(e) => library_error = Some(e),
                    }
                }
            }
        }
        piece.open_faces(&mut open, &mut face, piece.face_ends.len());
    }
    close(&mut open, &name, material);
    let materials = match library_error {
        Some(e) if materials.is_empty() => Err(e),
        _ => Ok(materials),
    };
    Some(Ok((models, materials)))
}

impl Piece {
    /// Adds this piece's faces from `*face` up to `end` to the open model.
    fn open_faces<'a>(&'a self, open: &mut Vec<&'a [Corner]>, face: &mut usize, end: usize) {
        while *face < end {
            let start = if *face == 0 {
                0
            } else {
                self.face_ends[*face - 1]
            };
            let stop = self.face_ends[*face];
            open.push(&self.corners[start as usize..stop as usize]);
            *face += 1;
        }
    }
}

/// The file's vertex data, all pieces joined.
struct Vertices {
    positions: Vec<f32>,
    texcoords: Vec<f32>,
    normals: Vec<f32>,
}

impl Vertices {
    /// One model's mesh: its faces fanned into triangles, each distinct corner a vertex, in
    /// the order corners are first met (tobj's single index).
    fn mesh(&self, faces: &[&[Corner]], material: Option<usize>) -> tobj::Mesh {
        let mut mesh = tobj::Mesh {
            material_id: material,
            ..Default::default()
        };
        // FxHash: SipHash's defence against chosen keys buys nothing here and cost a third of
        // the read.
        let mut index: FxHashMap<Corner, u32> = FxHashMap::default();
        let mut add = |corner: &Corner| {
            let next = index.len() as u32;
            let i = *index.entry(*corner).or_insert_with(|| {
                let [v, t, n] = corner.map(|i| i as usize);
                mesh.positions
                    .extend_from_slice(&self.positions[3 * v..3 * v + 3]);
                if t != MISSING as usize {
                    mesh.texcoords
                        .extend_from_slice(&self.texcoords[2 * t..2 * t + 2]);
                }
                if n != MISSING as usize {
                    mesh.normals
                        .extend_from_slice(&self.normals[3 * n..3 * n + 3]);
                }
                next
            });
            mesh.indices.push(i);
        };
        for face in faces {
            match face {
                [a, b, c, d] => [a, b, c, a, c, d].into_iter().for_each(&mut add),
                [a, rest @ ..] => {
                    for pair in rest.windows(2) {
                        [a, &pair[0], &pair[1]].into_iter().for_each(&mut add);
                    }
                }
                [] => {}
            }
        }
        mesh
    }
}

/// Reads one piece of the file (starting at byte `offset` of it); `None` at anything the
/// fast path leaves to tobj.
fn read_piece(text: &str, offset: usize) -> Option<Piece> {
    let mut piece = Piece::default();
    let mut at = 0;
    for raw in text.split_inclusive('\n') {
        let past = offset + at + raw.len();
        at += raw.len();
        let line = raw.strip_suffix('\n').unwrap_or(raw);
        let line = line.strip_suffix('\r').unwrap_or(line);
        let mut words = line.split_whitespace();
        let Some(first) = words.next() else { continue };
        // tobj reads a name from the line's second character on: only a line that starts
        // with its keyword reads the same.
        let starts = line.starts_with(first);
        match first {
            "v" => {
                numbers(&mut words, &mut piece.positions, 3, false)?;
                words.next().is_none().then_some(())?;
            }
            "vt" => {
                numbers(&mut words, &mut piece.texcoords, 2, false)?;
                // A third coordinate tobj ignores, but a non-finite one the slow path refuses.
                let third = words.next().and_then(|w| w.parse::<f32>().ok());
                third.is_none_or(f32::is_finite).then_some(())?;
            }
            "vn" => numbers(&mut words, &mut piece.normals, 3, true)?,
            "f" => face(words, &mut piece)?,
            "l" => return None,
            "o" | "g" if starts => {
                let name = line[1..].trim().to_string();
                piece
                    .statements
                    .push((piece.face_ends.len(), Statement::Name(name)));
            }
            "usemtl" if starts => {
                let name = line.split_once(' ').unwrap_or_default().1.trim();
                (!name.is_empty()).then_some(())?;
                let statement = Statement::UseMaterial(name.to_string());
                piece.statements.push((piece.face_ends.len(), statement));
            }
            "mtllib" if starts => {
                let file = line
                    .split_once(' ')
                    .unwrap_or_default()
                    .1
                    .trim()
                    .to_string();
                let statement = Statement::Library(file, past);
                piece.statements.push((piece.face_ends.len(), statement));
            }
            "o" | "g" | "usemtl" | "mtllib" => return None,
            // tobj skips every other statement.
            _ => {}
        }
    }
    Some(piece)
}

/// Appends `n` finite numbers from `words` (tobj reads the first `n` and ignores the rest);
/// a zero vector is refused where `non_zero`.
fn numbers(
    words: &mut std::str::SplitWhitespace,
    out: &mut Vec<f32>,
    n: usize,
    non_zero: bool,
) -> Option<()> {
    let start = out.len();
    for word in words.take(n) {
        out.push(word.parse::<f32>().ok().filter(|x| x.is_finite())?);
    }
    let read = &out[start..];
    (read.len() == n && !(non_zero && read.iter().all(|&x| x == 0.0))).then_some(())
}

/// Appends a face of three or more corners of 1-based indices that refer backwards.
fn face(words: std::str::SplitWhitespace, piece: &mut Piece) -> Option<()> {
    let counts = [
        piece.positions.len() / 3,
        piece.texcoords.len() / 2,
        piece.normals.len() / 3,
    ];
    let start = piece.corners.len();
    for word in words {
        let mut corner = [MISSING; 3];
        for (k, part) in word.split('/').enumerate() {
            if part.is_empty() {
                continue;
            }
            let slot = corner.get_mut(k)?;
            let one_based: u32 = part.parse().ok().filter(|i| (1..MISSING).contains(i))?;
            *slot = one_based - 1;
            // An index past what this piece has read must be met by the pieces before it.
            let need = (one_based as usize).saturating_sub(counts[k]);
            piece.needs_before[k] = piece.needs_before[k].max(need);
        }
        (corner[0] != MISSING).then_some(())?;
        piece.corners.push(corner);
    }
    (piece.corners.len() - start >= 3).then_some(())?;
    piece.face_ends.push(piece.corners.len() as u32);
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Stream};

    const OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };

    /// Two libraries: `a.mtl` holds red and glass, `b.mtl` holds glass again (it wins) and
    /// gold; anything else fails to load.
    fn library(path: &Path) -> tobj::MTLLoadResult {
        let text = match path.to_str() {
            Some("a.mtl") => "newmtl red\nKd 1 0 0\nnewmtl glass\nNi 1.5\n",
            Some("b.mtl") => "newmtl glass\nNi 1.4\nnewmtl gold\nKs 1 0.8 0\n",
            _ => return Err(tobj::LoadError::OpenFileFailed),
        };
        tobj::load_mtl_buf(&mut text.as_bytes())
    }

    /// The fast path's reading of `text` in pieces of `piece_bytes`, against tobj's.
    fn assert_reads_as_tobj(text: &str, piece_bytes: usize) {
        let fast = load_in_pieces(text, piece_bytes, &Cell::new(0), library)
            .expect("the fast path reads this file")
            .unwrap();
        let slow = tobj::load_obj_buf(&mut text.as_bytes(), &OPTIONS, library).unwrap();
        assert_eq!(fast.0.len(), slow.0.len(), "models");
        for (f, s) in fast.0.iter().zip(&slow.0) {
            assert_eq!(f.name, s.name);
            let (f, s) = (&f.mesh, &s.mesh);
            assert_eq!(f.material_id, s.material_id, "material");
            assert_eq!(f.indices, s.indices, "indices");
            assert_eq!(f.positions, s.positions, "positions");
            assert_eq!(f.normals, s.normals, "normals");
            assert_eq!(f.texcoords, s.texcoords, "texcoords");
            assert!(s.face_arities.is_empty() && s.vertex_color.is_empty());
        }
        let names = |m: Result<Vec<tobj::Material>, _>| {
            format!(
                "{:?}",
                m.map(|m| m.iter().map(|m| m.name.clone()).collect::<Vec<_>>())
            )
        };
        assert_eq!(names(fast.1), names(slow.1));
    }

    /// A random OBJ of every statement the fast path reads, faces of 3 to 6 corners in each
    /// index form, names and materials switching (to known, unknown and the same ones).
    fn random_obj(rng: &mut Rng, statements: usize) -> String {
        let mut text = String::from("# random\nmtllib a.mtl\n");
        let (mut v, mut vt, mut vn) = (0u32, 0u32, 0u32);
        let pick = |rng: &mut Rng, n: u32| 1 + (rng.next_f32() * n as f32) as u32 % n;
        for k in 0..statements {
            let roll = rng.next_f32();
            let line = if roll < 0.3 || v < 3 {
                v += 1;
                format!(
                    "v {} {} {}",
                    rng.next_f32(),
                    rng.next_f32() - 0.5,
                    k as f32 * 0.01
                )
            } else if roll < 0.4 {
                vt += 1;
                format!("vt {} {}", rng.next_f32(), rng.next_f32())
            } else if roll < 0.5 {
                vn += 1;
                format!("vn 0 {} 1", rng.next_f32())
            } else if roll < 0.9 {
                let corners = 3 + (rng.next_f32() * 4.0) as usize;
                let form = (rng.next_f32() * 4.0) as u32;
                let mut f = String::from("f");
                for _ in 0..corners {
                    let p = pick(rng, v);
                    f += &match form {
                        1 if vt > 0 => format!(" {p}/{}", pick(rng, vt)),
                        2 if vn > 0 => format!(" {p}//{}", pick(rng, vn)),
                        3 if vt > 0 && vn > 0 => {
                            format!(" {p}/{}/{}", pick(rng, vt), pick(rng, vn))
                        }
                        _ => format!(" {p}"),
                    };
                }
                f
            } else {
                let names = [
                    "o part",
                    "g",
                    "g two words",
                    "usemtl red",
                    "usemtl glass",
                    "usemtl gold",
                    "usemtl none",
                    "mtllib b.mtl",
                    "mtllib missing.mtl",
                    "s 1",
                ];
                names[(rng.next_f32() * names.len() as f32) as usize % names.len()].to_string()
            };
            text += &line;
            text += if k % 7 == 0 { "\r\n" } else { "\n" };
        }
        text
    }

    #[test]
    fn random_files_read_as_tobj_reads_them_whatever_the_pieces() {
        let mut rng = Rng::for_index(41, Stream::Distribution, 0);
        for trial in 0..40 {
            let text = random_obj(&mut rng, 50 + 40 * trial);
            for piece_bytes in [1, 64, 1000, PIECE_BYTES] {
                assert_reads_as_tobj(&text, piece_bytes);
            }
        }
    }

    #[test]
    fn the_repository_s_meshes_read_as_tobj_reads_them() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut read = 0;
        for folder in ["scenes/meshes", "tests/fixtures/meshes"] {
            for entry in std::fs::read_dir(root.join(folder)).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "obj") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    if load(&text, &Cell::new(0), library).is_some() {
                        assert_reads_as_tobj(&text, 256);
                        read += 1;
                    }
                }
            }
        }
        assert!(read >= 3, "{read} meshes took the fast path");
    }

    #[test]
    fn what_tobj_reads_differently_or_refuses_is_left_to_it() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n";
        for tail in [
            "f -3 -2 -1",       // relative indices
            "f 1 2 4\nv 1 1 0", // a forward index
            "f 1 2",            // a line, not a face
            "l 1 2 3",
            "f 1 2 0",
            "f 1/1/1/1 2 3",
            "v 1 2 3 0.5", // a weight
            "v 1 2 nan",
            "vn 0 0 0",
            "vt 0.5 0.5 inf",
            "f 1 2 x",
            "  o indented",
            "usemtl",
        ] {
            let text = format!("{base}{tail}\n");
            assert!(load(&text, &Cell::new(0), library).is_none(), "{tail}");
        }
        assert!(load(&format!("{base}f 1//1 2//1 3//1\n"), &Cell::new(0), library).is_some());
    }
}
