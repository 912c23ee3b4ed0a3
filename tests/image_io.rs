//! Tests of the image output stage: round trips, row order, tone map and atomic writes.

use dpm::image_io::{
    ExrPrecision, Image, ImageError, NonFinitePolicy, WriteOptions, read_pfm, tone_map,
    write_atomically, write_image,
};
use glam::Vec3;
use std::fs;
use std::io::Write;
use std::path::Path;

/// An image whose every pixel is distinct, with awkward float values.
fn test_image(width: usize, height: usize) -> Image {
    Image::from_fn(width, height, |x, y| {
        let i = (y * width + x) as f32;
        Vec3::new(i * 0.1 + 1e-7, -i * 1.5e3, (i + 0.5).sqrt() * 1e-20)
    })
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}

#[test]
fn pfm_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.pfm");
    let image = test_image(7, 5);
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    let back = read_pfm(&path).unwrap();
    assert_eq!((back.width, back.height), (7, 5));
    for (a, b) in image.pixels.iter().zip(&back.pixels) {
        assert_eq!(
            a.to_array().map(f32::to_bits),
            b.to_array().map(f32::to_bits)
        );
    }
}

#[test]
fn pfm_header_and_row_order_follow_the_format() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rows.pfm");
    // Row 0 (the top) is red, row 1 (the bottom) is blue.
    let image = Image::from_fn(2, 2, |_, y| if y == 0 { Vec3::X } else { Vec3::Z });
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    let bytes = fs::read(&path).unwrap();
    let header = b"PF\n2 2\n-1.0\n";
    assert_eq!(&bytes[..header.len()], header);
    let raster: Vec<f32> = bytes[header.len()..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    assert_eq!(raster.len(), 12);
    // The file starts with the bottom row (blue) and ends with the top row (red).
    assert_eq!(&raster[..3], &[0.0, 0.0, 1.0]);
    assert_eq!(&raster[9..], &[1.0, 0.0, 0.0]);
}

#[test]
fn big_endian_and_grey_pfm_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("be.pfm");
    let mut bytes = b"Pf\n1 2\n1.0\n".to_vec();
    for v in [2.0f32, 3.0] {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    fs::write(&path, bytes).unwrap();
    let image = read_pfm(&path).unwrap();
    assert_eq!(image.pixels, vec![Vec3::splat(3.0), Vec3::splat(2.0)]);
}

#[test]
fn truncated_pfm_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("short.pfm");
    fs::write(&path, b"PF\n4 4\n-1.0\n\0\0\0\0").unwrap();
    assert!(matches!(read_pfm(&path), Err(ImageError::BadPfm { .. })));
}

fn read_exr(path: &Path) -> Image {
    let read = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| Image::new(size.0, size.1),
        |image: &mut Image, pos: exr::math::Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            image.set(pos.0, pos.1, Vec3::new(r, g, b))
        },
    )
    .unwrap();
    read.layer_data.channel_data.pixels
}

#[test]
fn exr_round_trip_f32_is_exact_and_f16_is_close() {
    let dir = tempfile::tempdir().unwrap();
    let image = Image::from_fn(9, 4, |x, y| {
        Vec3::new(x as f32 * 0.37, y as f32 * 11.0, 1e-3)
    });
    let path = dir.path().join("a.exr");
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    assert_eq!(read_exr(&path), image);

    let path = dir.path().join("h.EXR");
    let options = WriteOptions {
        exr_precision: ExrPrecision::F16,
        ..Default::default()
    };
    write_image(&path, &image, &options).unwrap();
    let back = read_exr(&path);
    assert_eq!((back.width, back.height), (9, 4));
    for (a, b) in image.pixels.iter().zip(&back.pixels) {
        assert!(
            (*a - *b).abs().max_element() <= a.abs().max_element() * 1e-3 + 1e-6,
            "{a} {b}"
        );
    }
    assert_ne!(back, image, "half precision should round something");
}

#[test]
fn png_has_the_right_size_and_the_tone_map_is_monotonic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.png");
    let image = Image::from_fn(6, 3, |x, _| Vec3::splat(x as f32 / 5.0));
    write_image(&path, &image, &WriteOptions::default()).unwrap();
    let png = image::open(&path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (6, 3));
    let row: Vec<u8> = (0..6).map(|x| png.get_pixel(x, 1)[0]).collect();
    assert!(row.windows(2).all(|w| w[0] < w[1]), "{row:?}");
    assert_eq!((row[0], row[5]), (0, 255));

    let mut last = 0;
    for i in 0..=2000 {
        let code = tone_map(i as f32 / 1000.0, 0.0);
        assert!(code >= last);
        last = code;
    }
    assert_eq!(tone_map(0.5, 1.0), 255, "one stop up doubles");
    assert_eq!(tone_map(-1.0, 0.0), 0);
    assert_eq!(tone_map(0.215_861, 0.0), 128, "sRGB code 128");
}

#[test]
fn unknown_extension_is_named() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.jpg", "noext"] {
        let err = write_image(
            &dir.path().join(name),
            &test_image(2, 2),
            &WriteOptions::default(),
        )
        .unwrap_err();
        assert!(matches!(err, ImageError::UnknownExtension { .. }), "{err}");
        if name == "a.jpg" {
            assert!(err.to_string().contains("\"jpg\""), "{err}");
        }
    }
    assert!(files_in(dir.path()).is_empty());
}

#[test]
fn missing_directory_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nope");
    let err = write_image(
        &missing.join("a.pfm"),
        &test_image(2, 2),
        &WriteOptions::default(),
    )
    .unwrap_err();
    match &err {
        ImageError::MissingDirectory { dir, .. } => assert_eq!(dir, &missing),
        other => panic!("{other}"),
    }
    assert!(err.to_string().contains("nope"));
}

#[test]
fn a_failing_encoder_leaves_the_earlier_file_intact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.pfm");
    let first = test_image(3, 3);
    write_image(&path, &first, &WriteOptions::default()).unwrap();
    let before = fs::read(&path).unwrap();

    let err = write_atomically(&path, |out| {
        out.write_all(b"PF\n9 9\n-1.0\nhalf a raster")
            .map_err(|e| e.to_string())?;
        out.flush().map_err(|e| e.to_string())?;
        Err("disk on fire".into())
    })
    .unwrap_err();
    assert!(err.to_string().contains("disk on fire"));
    assert_eq!(fs::read(&path).unwrap(), before);
    assert_eq!(
        files_in(dir.path()),
        vec!["out.pfm".to_string()],
        "temporary file left behind"
    );
}

#[test]
fn non_finite_pixels_are_rejected_by_name_or_zeroed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.pfm");
    write_image(&path, &test_image(3, 2), &WriteOptions::default()).unwrap();
    let before = fs::read(&path).unwrap();

    let mut bad = test_image(3, 2);
    bad.set(2, 1, Vec3::new(0.0, f32::NAN, 0.0));
    bad.set(0, 0, Vec3::splat(f32::INFINITY));
    let err = write_image(&path, &bad, &WriteOptions::default()).unwrap_err();
    match err {
        ImageError::NonFinite { x, y, count, .. } => assert_eq!((x, y, count), (0, 0, 2)),
        other => panic!("{other}"),
    }
    assert_eq!(fs::read(&path).unwrap(), before);

    let options = WriteOptions {
        non_finite: NonFinitePolicy::Zero,
        ..Default::default()
    };
    write_image(&path, &bad, &options).unwrap();
    let back = read_pfm(&path).unwrap();
    assert_eq!(back.get(2, 1), Vec3::ZERO);
    assert_eq!(back.get(1, 1), bad.get(1, 1));
}

#[test]
fn a_rename_onto_a_directory_fails_and_cleans_up() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("taken.pfm");
    fs::create_dir(&target).unwrap();
    fs::write(target.join("keep"), b"x").unwrap();
    let err = write_image(&target, &test_image(2, 2), &WriteOptions::default()).unwrap_err();
    assert!(matches!(err, ImageError::Io { .. }), "{err}");
    assert!(target.join("keep").exists());
    assert_eq!(files_in(dir.path()), vec!["taken.pfm".to_string()]);
}

#[test]
fn inconsistent_dimensions_are_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let image = Image {
        width: 3,
        height: 3,
        pixels: vec![Vec3::ZERO; 8],
    };
    let err = write_image(&dir.path().join("a.png"), &image, &WriteOptions::default()).unwrap_err();
    assert!(matches!(err, ImageError::BadDimensions { .. }));
}
