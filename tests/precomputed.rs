//! Precomputed irradiance for final gathering (issue 16): on a uniform density the table's
//! lookup agrees with the full k-NN estimate and with the analytic irradiance, and reads only
//! the surface it is asked about; a final-gather render of the Cornell box with the table
//! agrees with one running the estimate per gather ray; and the image does not depend on the
//! thread count. Also `--light-samples`: N stratified shadow rays per area light keep the
//! mean and cut the noise by more than N independent ones would.

mod support;

use dpm::estimate::Scratch;
use dpm::estimate::precomputed::ShownIrradiance;
use dpm::estimate::{KnnEstimate, PrecomputedIrradiance, Query, RadialKernel, RadianceEstimate};
use dpm::photon::{Photon, PhotonMap};
use dpm::render::pipeline;
use dpm::sampling::{Rng, Stream};
use glam::Vec3;
use indicatif::ProgressBar;
use support::*;

/// Photons per unit area on the top face of the test plane.
const DENSITY: usize = 200_000;
const K: usize = 100;

/// `DENSITY` photons of power 1/DENSITY spread uniformly over the unit square at z = 0, lit from
/// above (irradiance exactly 1), and a thin wall's underside 1e-3 below it, four times as
/// bright, facing down.
fn thin_wall() -> PhotonMap {
    let mut rng = Rng::for_index(3, Stream::Distribution, 0);
    let p = 1.0 / DENSITY as f32;
    let mut photons = Vec::with_capacity(2 * DENSITY);
    for _ in 0..DENSITY {
        let (x, y) = rng.next_2d();
        photons.push(Photon::new(
            Vec3::new(x, y, 0.0),
            Vec3::splat(p),
            -Vec3::Z,
            Vec3::Z,
        ));
        let (x, y) = rng.next_2d();
        photons.push(Photon::new(
            Vec3::new(x, y, -1e-3),
            Vec3::splat(4.0 * p),
            Vec3::Z,
            -Vec3::Z,
        ));
    }
    PhotonMap::build(photons, DENSITY as u64)
}

#[test]
fn lookups_agree_with_the_full_estimate_and_the_analytic_irradiance() {
    let map = thin_wall();
    // The global estimate's own cap: the k-equivalent radius (about 0.0126 here).
    let reach = dpm::estimate::settings::k_equivalent_radius(&map, K).expect("radius");
    let estimate = KnnEstimate::new(RadialKernel::Constant, K, Some(reach));
    let table =
        PrecomputedIrradiance::build(&map, &estimate, 4, Some(reach), &ProgressBar::hidden());
    // One photon in 4, chosen at random: 100,000 ± 274.
    let expected = map.len() as f64 / 4.0;
    assert!(
        (table.len() as f64 / expected - 1.0).abs() < 0.01,
        "{} points",
        table.len()
    );
    let mut scratch = Scratch::default();
    let mut rng = Rng::for_index(4, Stream::Distribution, 0);
    let (mut full, mut looked, mut diff2, mut noise2) = ([0.0f64; 2], [0.0f64; 2], 0.0, 0.0);
    let queries = 2000;
    let mut fallbacks = 0;
    for _ in 0..queries {
        let (x, y) = rng.next_2d();
        // Away from the square's edges, where the estimate loses part of its disc.
        let position = Vec3::new(0.05 + 0.9 * x, 0.05 + 0.9 * y, 0.0);
        for (side, (z, normal, truth)) in [(0.0, Vec3::Z, 1.0), (-1e-3, -Vec3::Z, 4.0)]
            .into_iter()
            .enumerate()
        {
            let q = Query {
                position: position + Vec3::new(0.0, 0.0, z),
                normal,
            };
            let f = estimate.irradiance(&map, &q, &mut scratch).x as f64 / truth;
            // No agreeing point among the 8 nearest: the integrator runs the full estimate.
            let l = match table.lookup(&q, &mut scratch) {
                Some(e) => e.x as f64 / truth,
                None => {
                    fallbacks += 1;
                    f
                }
            };
            full[side] += f;
            looked[side] += l;
            diff2 += (f - l).powi(2);
            noise2 += (f - 1.0).powi(2);
        }
    }
    let n = queries as f64;
    // The faces' points are mixed at random in the table, so all 8 nearest lie on the other
    // face for about 1 query in 2⁸.
    assert!(
        fallbacks < 2 * queries / 100,
        "{fallbacks} lookups found no agreeing point"
    );
    for side in 0..2 {
        let (f, l) = (full[side] / n, looked[side] / n);
        // Each estimate has a relative sd of 1/√99 ≈ 10%; 2000 queries, most with their own
        // photons, put the means within about 0.5% of the truth. A lookup reading the other
        // face would be off by 4× (or ¼).
        assert!(
            (f - 1.0).abs() < 0.02,
            "side {side}: full estimate mean {f}"
        );
        assert!((l - 1.0).abs() < 0.02, "side {side}: lookup mean {l}");
    }
    // A lookup is the estimate at a point a fraction of a radius away: it differs from the
    // estimate at the query by less than the estimate's own noise (√2 of it if independent).
    let (rms_diff, rms_noise) = ((diff2 / (2.0 * n)).sqrt(), (noise2 / (2.0 * n)).sqrt());
    assert!(
        rms_diff < 1.2 * rms_noise && rms_noise < 0.15,
        "lookup − estimate rms {rms_diff}, estimate noise {rms_noise}"
    );
}

/// `n` photons of power 1/n spread uniformly over the unit square at z = 0, lit from above:
/// irradiance exactly 1.
fn uniform_square(n: usize, seed: u64) -> Vec<Photon> {
    let mut rng = Rng::for_index(seed, Stream::Distribution, 0);
    let p = 1.0 / n as f32;
    (0..n)
        .map(|_| {
            let (x, y) = rng.next_2d();
            Photon::new(Vec3::new(x, y, 0.0), Vec3::splat(p), -Vec3::Z, Vec3::Z)
        })
        .collect()
}

#[test]
fn a_shown_map_table_is_as_unbiased_and_as_noisy_as_the_estimate() {
    // A small k, where reading each photon's own estimate at the nearest photon would come out
    // 4.5% low (a random point's nearest photon tends to have a large empty cell around it,
    // so a low estimate; 9% at k = 10, 0.85% at k = 100).
    let (n, k) = (20_000, 20);
    let map = PhotonMap::build(uniform_square(n, 5), n as u64);
    let estimate = KnnEstimate::new(RadialKernel::Constant, k, None);
    let table = ShownIrradiance::build(&map, &estimate, &ProgressBar::hidden());
    assert_eq!(table.len(), n);
    let mut scratch = Scratch::default();
    let mut rng = Rng::for_index(6, Stream::Distribution, 0);
    let (mut looked, mut full, mut answered) = ([0.0f64; 2], [0.0f64; 2], 0usize);
    let queries = 40_000;
    for _ in 0..queries {
        let (x, y) = rng.next_2d();
        let q = Query {
            position: Vec3::new(0.1 + 0.8 * x, 0.1 + 0.8 * y, 0.0),
            normal: Vec3::Z,
        };
        let f = estimate.irradiance(&map, &q, &mut scratch).x as f64;
        full[0] += f;
        full[1] += (f - 1.0).powi(2);
        if let Some(e) = table.lookup(&q, &mut scratch) {
            let e = e.x as f64;
            looked[0] += e;
            looked[1] += (e - 1.0).powi(2);
            answered += 1;
        }
    }
    // A site answers within half its radius, which holds about k/8 sites of its half: inside
    // the photons most lookups find one in both halves (e^(−2.5) misses one at k = 20).
    assert!(
        answered > queries / 2,
        "{answered} of {queries} lookups answered"
    );
    let (mean, full_mean) = (looked[0] / answered as f64, full[0] / queries as f64);
    let (rms, full_rms) = (
        (looked[1] / answered as f64).sqrt(),
        (full[1] / queries as f64).sqrt(),
    );
    eprintln!("lookup mean {mean:.4} rms {rms:.4}; estimate mean {full_mean:.4} rms {full_rms:.4}");
    // Neighbouring queries share sites and photons: the means are good to about 1%.
    assert!((mean - 1.0).abs() < 0.025, "mean lookup {mean}");
    assert!((full_mean - 1.0).abs() < 0.025, "mean estimate {full_mean}");
    // Two half-maps' estimates at k/2, averaged: the noise of the whole map's at k.
    assert!(
        rms < 1.25 * full_rms,
        "lookup rms {rms} vs estimate rms {full_rms}"
    );
    // Past the edge of the photons, farther than half a radius from every site, the
    // table does not answer (the caller runs the estimate, which fades out over a radius).
    let outside = Query {
        position: Vec3::new(1.03, 0.5, 0.0),
        normal: Vec3::Z,
    };
    assert_eq!(table.lookup(&outside, &mut scratch), None);
    // Nor on the far side of the surface.
    let below = Query {
        position: Vec3::new(0.5, 0.5, 0.0),
        normal: -Vec3::Z,
    };
    assert_eq!(table.lookup(&below, &mut scratch), None);
}

const FG: [&str; 10] = [
    "--caustic-photons",
    "0",
    "--global-photons",
    "20000",
    "--final-gather",
    "16",
    "--spp",
    "2",
    "--seed",
    "3",
];

fn render(
    scene: &std::path::Path,
    out: &std::path::Path,
    extra: &[&str],
) -> pipeline::RenderOutcome {
    let mut args = vec![path_str(scene), "-o", path_str(out)];
    args.extend_from_slice(&FG);
    args.extend_from_slice(extra);
    pipeline::run(&render_args(&args)).unwrap_or_else(|e| panic!("{args:?}: {e}"))
}

/// Means of the image's 4 × 4 blocks of pixels (luminance-free: the sum of the channels).
fn region_means(image: &dpm::image_io::Image, blocks: usize) -> Vec<f64> {
    let mut sums = vec![0.0f64; blocks * blocks];
    let mut counts = vec![0usize; blocks * blocks];
    for y in 0..image.height {
        for x in 0..image.width {
            let b = (y * blocks / image.height) * blocks + x * blocks / image.width;
            let p = image.pixels[y * image.width + x];
            sums[b] += (p.x + p.y + p.z) as f64;
            counts[b] += 1;
        }
    }
    sums.iter()
        .zip(&counts)
        .map(|(s, c)| s / *c as f64)
        .collect()
}

#[test]
fn cornell_box_final_gather_with_the_table_matches_the_per_ray_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(
        dir.path(),
        "box.toml",
        &scene_with_resolution("scenes/cornell-box.toml", 32, 32),
    );
    let table = render(&scene, &dir.path().join("table.pfm"), &[]);
    let per_ray = render(
        &scene,
        &dir.path().join("per-ray.pfm"),
        &["--irradiance-stride", "0"],
    );
    assert!(
        table
            .times
            .phases
            .iter()
            .any(|p| p.name == "precompute irradiance")
    );
    assert!(
        !per_ray
            .times
            .phases
            .iter()
            .any(|p| p.name == "precompute irradiance")
    );
    // Same photons, same gather directions, same direct light: only the gathered irradiance
    // differs, by the table's noise.
    let (a, b) = (
        region_means(&table.image, 1)[0],
        region_means(&per_ray.image, 1)[0],
    );
    assert!((a / b - 1.0).abs() < 0.01, "image means {a} vs {b}");
    for (i, (a, b)) in region_means(&table.image, 4)
        .iter()
        .zip(region_means(&per_ray.image, 4))
        .enumerate()
    {
        assert!((a / b - 1.0).abs() < 0.05, "block {i}: {a} vs {b}");
    }
    assert_ne!(table.image, per_ray.image, "the table was not read");
}

#[test]
fn the_table_and_light_samples_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(
        dir.path(),
        "box.toml",
        &scene_with_resolution("scenes/cornell-box.toml", 24, 20),
    );
    let extra = ["--light-samples", "4", "--passes", "2"];
    let out1 = dir.path().join("t1.pfm");
    let out2 = dir.path().join("t2.pfm");
    render(&scene, &out1, &[&extra[..], &["--threads", "1"]].concat());
    render(&scene, &out2, &[&extra[..], &["--threads", "2"]].concat());
    assert!(
        std::fs::read(&out1).unwrap() == std::fs::read(&out2).unwrap(),
        "1 and 2 threads wrote different bytes"
    );
}

/// A floor under a 1 × 1 quad light one unit above it, seen obliquely: direct light only.
const QUAD_OVER_FLOOR: &str = r#"
[camera]
position = [0.0, 1.5, 3.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
resolution = [40, 30]

[[lights]]
type = "quad"
corner = [-0.5, 1.0, -0.5]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
power = [10.0, 10.0, 10.0]

[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]

[[objects]]
type = "quad"
corner = [-3.0, 0.0, -3.0]
edge_u = [0.0, 0.0, 6.0]
edge_v = [6.0, 0.0, 0.0]
material = "white"
"#;

/// Mean and mean squared difference of horizontally neighbouring pixels (relative to the
/// mean²): the light's falloff is smooth at this resolution, so the latter is mostly noise.
fn mean_and_roughness(image: &dpm::image_io::Image) -> (f64, f64) {
    let v = |x: usize, y: usize| image.pixels[y * image.width + x].x as f64;
    let mut sum = 0.0;
    let mut rough = 0.0;
    for y in 0..image.height {
        for x in 0..image.width {
            sum += v(x, y);
            if x + 1 < image.width {
                rough += (v(x + 1, y) - v(x, y)).powi(2);
            }
        }
    }
    let n = (image.width * image.height) as f64;
    let mean = sum / n;
    (mean, rough / (n * mean * mean))
}

#[test]
fn light_samples_stratify_the_area_light_and_keep_its_mean() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "quad.toml", QUAD_OVER_FLOOR);
    let run = |n: &str| {
        let out = dir.path().join(format!("l{n}.pfm"));
        let args = [path_str(&scene), "-o", path_str(&out), "--light-samples", n];
        let outcome = pipeline::run(&render_args(&args)).expect("render");
        mean_and_roughness(&outcome.image)
    };
    let (m1, r1) = run("1");
    let (m16, r16) = run("16");
    // One sample a pixel has a relative sd of about 0.65, so the mean of 1200 pixels is
    // within about 2% (seen: 1%); a sum not divided by the count would be 16 times too bright.
    assert!((m16 / m1 - 1.0).abs() < 0.06, "means {m1} vs {m16}");
    // Independent samples would cut the noise variance 16-fold; a stratified set of 16 much
    // more, down to the falloff's own pixel-to-pixel change.
    assert!(
        r16 < r1 / 16.0,
        "roughness {r1} with one sample, {r16} with 16"
    );
}
