//! The diffusion kernel of volumetric caustics rendered whole, on the close-up of the repository's
//! volumetric caustic (`scenes/fog-caustic-cone.pbrt`, small): shaping the kernels moves light
//! within the cone but keeps its total (each ellipsoid integrates to one, as the round kernel
//! does), and the image is the same on one thread and two. The ellipsoid's line integral, the
//! eigen-decomposition and the shaping of sheets and filaments are tested beside their code.

mod support;

use glam::DVec3;
use support::*;

fn cone(extra: &[&str]) -> dpm::image_io::Image {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cone.pfm");
    let scene = repo_path("scenes/fog-caustic-cone.pbrt");
    let mut args = vec![
        path_str(&scene),
        "-o",
        path_str(&out),
        "--resolution",
        "60x45",
    ];
    args.extend_from_slice(&["--passes", "3", "--global-photons", "30000"]);
    args.extend_from_slice(extra);
    dpm::render::pipeline::run(&render_args(&args))
        .unwrap()
        .image
}

fn total(image: &dpm::image_io::Image) -> DVec3 {
    image.pixels.iter().map(|p| p.as_dvec3()).sum()
}

#[test]
fn shaped_kernels_keep_the_caustics_light_and_the_same_image_on_any_thread_count() {
    let round = cone(&["--volume-contrast", "0", "--threads", "2"]);
    let one = cone(&["--threads", "1"]);
    let two = cone(&["--threads", "2"]);
    assert_eq!(one.pixels, two.pixels);
    // Shaped: light moved between pixels ...
    let moved = (round.pixels.iter().zip(&two.pixels))
        .filter(|(a, b)| (**a - **b).abs().max_element() > 0.05 * a.max_element().max(1e-3))
        .count();
    assert!(moved * 20 > round.pixels.len(), "{moved} pixels changed");
    // ... but none made or lost: the whole image within 1%.
    let (a, b) = (total(&round), total(&two));
    for c in 0..3 {
        assert!((b[c] / a[c] - 1.0).abs() < 0.01, "round {a}, shaped {b}");
    }
}
