use super::*;

const ASCII_QUAD: &str = "ply\nformat ascii 1.0\ncomment a unit square\nelement vertex 4\n\
    property float x\nproperty float y\nproperty float z\nelement face 1\n\
    property list uchar int vertex_indices\nend_header\n\
    0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

fn binary(big: bool) -> Vec<u8> {
    let format = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = format!(
        "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
         element face 1\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    .into_bytes();
    let f = |x: f32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    for p in [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in p.into_iter().chain([0.0, 0.0, 1.0]) {
            b.extend(f(x));
        }
    }
    b.push(3);
    for i in [0u32, 1, 2] {
        b.extend(if big {
            i.to_be_bytes()
        } else {
            i.to_le_bytes()
        });
    }
    b
}

#[test]
fn an_ascii_quad_becomes_two_triangles() {
    let m = parse(ASCII_QUAD.as_bytes()).unwrap();
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.normals, None);
}

#[test]
fn both_byte_orders_read_the_same_mesh() {
    let little = parse(&binary(false)).unwrap();
    let big = parse(&binary(true)).unwrap();
    assert_eq!(little, big);
    assert_eq!(little.positions[1], Vec3::X);
    assert_eq!(little.normals.as_ref().unwrap()[2], Vec3::Z);
    assert_eq!(little.triangles, vec![[0, 1, 2]]);
}

#[test]
fn a_truncated_binary_body_is_refused_without_reading_past_it() {
    let full = binary(false);
    for cut in [full.len() - 1, full.len() - 13, full.len() - 40] {
        let err = parse(&full[..cut]).unwrap_err();
        assert!(
            err.message.contains("ends") || err.message.contains("claims"),
            "cut {cut}: {err:?}"
        );
    }
}

#[test]
fn a_huge_claimed_count_is_refused_before_allocating() {
    let text = ASCII_QUAD.replace("element vertex 4", "element vertex 1000000000000");
    let err = parse(text.as_bytes()).unwrap_err();
    assert_eq!(err.line, Some(4));
    assert!(err.message.contains("claims"), "{err:?}");
    let mut b = binary(false);
    let at = b.windows(9).position(|w| w == b"vertex 3\n").unwrap();
    b.splice(at..at + 9, b"vertex 999999999999\n".iter().copied());
    assert!(parse(&b).unwrap_err().message.contains("claims"));
}

#[test]
fn header_and_body_mistakes_name_their_line() {
    for (from, to, line, needle) in [
        ("ply\n", "plx\n", Some(1), "ply"),
        ("format ascii 1.0", "format ebcdic 1.0", Some(2), "ebcdic"),
        (
            "property float z",
            "property quad z",
            Some(7),
            "not a PLY type",
        ),
        ("4 0 1 2 3", "4 0 1 2 9", Some(15), "not one of the 4"),
        (
            "4 0 1 2 3",
            "5 0 1 2 3 0",
            Some(15),
            "only triangles and quads",
        ),
        ("1 1 0\n", "1 1\n", Some(13), "too few"),
        ("0 1 0\n", "0 1 0 7\n", Some(14), "values"),
        ("end_header\n", "end_headr\n", Some(10), "keyword"),
    ] {
        let text = ASCII_QUAD.replace(from, to);
        let err = parse(text.as_bytes()).unwrap_err();
        assert_eq!(err.line, line, "{to}: {err:?}");
        assert!(err.message.contains(needle), "{to}: {err:?}");
    }
}

/// A random mesh of `vertices` (positions, normals, uv) and `faces` written as PLY in
/// `format`: triangles, except a quad at each index in `quads`, and a corner `bad` (face,
/// value) if given.
fn random_ply(format: &str, faces: usize, quads: &[usize], bad: Option<(usize, u32)>) -> Vec<u8> {
    let vertices = 1000;
    let mut rng = crate::sampling::Rng::for_index(5, crate::sampling::Stream::Pixels, 0);
    let header = format!(
        "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nproperty float nx\nproperty float ny\n\
         property float nz\nproperty float u\nproperty float v\nelement face {faces}\n\
         property list uchar int vertex_indices\nend_header\n"
    );
    let big = format == "binary_big_endian";
    let mut out = header.into_bytes();
    let put = |out: &mut Vec<u8>, bytes: [u8; 4]| match big {
        true => out.extend(bytes.iter().rev()),
        false => out.extend(bytes),
    };
    for _ in 0..vertices {
        let values: Vec<f32> = (0..8).map(|_| rng.next_f32() * 4.0 - 2.0).collect();
        match format {
            "ascii" => out.extend(format!("{values:?}\n").replace([',', '[', ']'], "").bytes()),
            _ => values.iter().for_each(|v| put(&mut out, v.to_le_bytes())),
        }
    }
    for f in 0..faces {
        let n = if quads.contains(&f) { 4 } else { 3 };
        let mut corners: Vec<u32> = (0..n).map(|_| rng.next_u32() % vertices).collect();
        if let Some((_, v)) = bad.filter(|&(at, _)| at == f) {
            corners[1] = v;
        }
        match format {
            "ascii" => out.extend(
                format!("{n} {corners:?}\n")
                    .replace([',', '[', ']'], "")
                    .bytes(),
            ),
            _ => {
                out.push(n as u8);
                corners.iter().for_each(|c| put(&mut out, c.to_le_bytes()));
            }
        }
    }
    out
}

/// `text` with a blank line after line `at` of it: the record-by-record reader's business.
fn with_blank_line(text: &[u8], at: usize) -> Vec<u8> {
    let text = String::from_utf8(text.to_vec()).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.insert(at, "");
    (lines.join("\n") + "\n").into_bytes()
}

#[test]
fn every_reader_parallel_or_not_gives_the_same_mesh() {
    // Both bodies are read in parallel where they can be: binary all-triangle bodies, ASCII
    // bodies a line an element (quads too). A binary quad, or a blank line in an ASCII body,
    // falls back to the record-by-record reader. Every path gives the same mesh.
    for quads in [&[][..], &[17, 1500][..]] {
        let text = random_ply("ascii", 2000, quads, None);
        let ascii = parse(&text).unwrap();
        assert_eq!(ascii.triangles.len(), 2000 + quads.len());
        assert_eq!(ascii.uvs.as_ref().map(Vec::len), Some(1000));
        // Blank lines among the vertices and among the faces (the header has 14 lines).
        let sequential = parse(&with_blank_line(&with_blank_line(&text, 500), 2100)).unwrap();
        assert_eq!(sequential, ascii, "sequential ASCII, quads {quads:?}");
        for format in ["binary_little_endian", "binary_big_endian"] {
            let binary = parse(&random_ply(format, 2000, quads, None)).unwrap();
            assert_eq!(binary, ascii, "{format}, quads {quads:?}");
        }
    }
}

#[test]
fn a_bad_index_in_a_body_read_in_parallel_is_named_by_its_face() {
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let err = parse(&random_ply(format, 2000, &[], Some((1234, 1000)))).unwrap_err();
        assert_eq!(err.field, "face[1234]", "{format}: {err:?}");
        assert!(err.message.contains("vertex index 1000"), "{err:?}");
    }
}
