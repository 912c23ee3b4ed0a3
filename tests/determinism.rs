//! Determinism, through the built binary: for every caustic estimate, the same seed gives
//! byte-identical images and photon map files with 1 and 2 threads, and a render from a saved
//! photon map (--load-photons) is byte-identical to the render that traced it; so does the
//! scene with a spot, a distant light, the environment and a mesh emitter.

mod reliability_support;

use reliability_support::*;
use std::path::Path;

const ESTIMATORS: [&str; 5] = ["simple", "cone", "gaussian", "epanechnikov", "diffusion"];

fn render(scene: &Path, output: &Path, estimator: &str, threads: &str, extra: &[&str]) {
    let mut args: Vec<std::ffi::OsString> = vec![
        "render".into(),
        scene.into(),
        "-o".into(),
        output.into(),
        "--estimator".into(),
        estimator.into(),
        "--threads".into(),
        threads.into(),
    ];
    for a in [
        "--seed",
        "7",
        "--spp",
        "2",
        "--caustic-photons",
        "3000",
        "--global-photons",
        "2000",
        "--final-gather",
        "2",
        "--global-k",
        "20",
        "--k",
        "30",
    ] {
        args.push(a.into());
    }
    args.extend(extra.iter().map(Into::into));
    let out = dpm(args);
    assert_succeeds(&out, &format!("{estimator} with {threads} threads"));
}

/// Renders `estimator` with 1 and 2 threads (saving the photon maps) and with 2 threads from
/// the saved maps, and compares the bytes.
fn check(estimator: &str) {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "caustics.toml", &caustic_scene(1.0, 40, 30));
    let file = |name: &str| dir.path().join(name);
    let (one, two, loaded) = (file("1.pfm"), file("2.pfm"), file("loaded.pfm"));
    let (photons_one, photons_two) = (file("1.photons"), file("2.photons"));
    render(
        &scene,
        &one,
        estimator,
        "1",
        &["--save-photons", photons_one.to_str().unwrap()],
    );
    render(
        &scene,
        &two,
        estimator,
        "2",
        &["--save-photons", photons_two.to_str().unwrap()],
    );
    render(
        &scene,
        &loaded,
        estimator,
        "2",
        &["--load-photons", photons_one.to_str().unwrap()],
    );

    let image = std::fs::read(&one).unwrap();
    assert!(
        image == std::fs::read(&two).unwrap(),
        "{estimator}: the image differs between 1 and 2 threads"
    );
    assert!(
        std::fs::read(&photons_one).unwrap() == std::fs::read(&photons_two).unwrap(),
        "{estimator}: the photon maps differ between 1 and 2 threads"
    );
    assert!(
        image == std::fs::read(&loaded).unwrap(),
        "{estimator}: the render from the loaded photon map differs from the traced one"
    );

    // Both maps were traced and used, and the picture is not black (else this proves little).
    let maps = dpm::photon::store::read(&photons_one).unwrap().maps;
    let stored: Vec<usize> = maps.iter().map(|m| m.map.len()).collect();
    assert_eq!(
        stored,
        [3000, 2000],
        "{estimator}: caustic and global photons stored"
    );
    let (_, _, pixels) = pfm_pixels(&one);
    assert!(pixels.iter().any(|&v| v > 0.0), "{estimator}: black image");
}

#[test]
fn simple() {
    check("simple");
}

#[test]
fn cone() {
    check("cone");
}

#[test]
fn gaussian() {
    check("gaussian");
}

#[test]
fn epanechnikov() {
    check("epanechnikov");
}

#[test]
fn diffusion() {
    check("diffusion");
}

/// scenes/spot-and-sky.toml (every new light, tinted mirror and glass): the same image and
/// photon maps, byte for byte, with 1 and 2 threads, and a lit picture.
#[test]
fn the_new_lights_give_the_same_bytes_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("scenes/spot-and-sky.toml");
    let file = |name: &str| dir.path().join(name);
    for threads in ["1", "2"] {
        let photons = file(&format!("{threads}.photons"));
        render(
            &scene,
            &file(&format!("{threads}.pfm")),
            "diffusion",
            threads,
            &[
                "--resolution",
                "48x36",
                "--save-photons",
                photons.to_str().unwrap(),
            ],
        );
    }
    let read = |name: &str| std::fs::read(file(name)).unwrap();
    assert!(
        read("1.pfm") == read("2.pfm"),
        "the image differs between 1 and 2 threads"
    );
    assert!(
        read("1.photons") == read("2.photons"),
        "the photon maps differ between 1 and 2 threads"
    );
    let (width, height, pixels) = pfm_pixels(&file("1.pfm"));
    assert_eq!((width, height), (48, 36));
    assert!(pixels.iter().all(|v| v.is_finite()) && pixels.iter().any(|&v| v > 0.0));
}

#[test]
fn every_estimator_is_checked() {
    use clap::ValueEnum;
    let all: Vec<String> = dpm::estimate::settings::EstimatorKind::value_variants()
        .iter()
        .map(|v| v.to_possible_value().unwrap().get_name().to_string())
        .collect();
    assert_eq!(all, ESTIMATORS);
}
