//! The caustic guide (`photon::guide`, `world::aim_guide`) moves photons, never light: under a
//! flat mirror the reflected light is that of the light's mirror image, known in closed form,
//! and a guided map must store it as an unguided one does while putting more of its photons
//! where the guide's worth says; and `dpm render` learns the same guide whatever the thread
//! count.

mod support;

use dpm::photon::PhotonMap;
use dpm::photon::guide::learn_caustic_guide;
use dpm::photon::tracer::{MapKind, trace_map};
use dpm::world::World;
use indicatif::ProgressBar;
use std::f64::consts::PI;
use support::*;

const POWER: f64 = 100.0;
/// The light's height and the mirror's: the light's image is at 2·MIRROR − LIGHT.
const LIGHT: f64 = 0.2;
const MIRROR: f64 = 1.0;

/// A point light under a square mirror (side 1, facing down) above a large diffuse floor: the
/// caustic is the light of a point source at height 2·MIRROR − LIGHT = 1.8 over the floor,
/// within the mirror's shadow from that source ([−1.125, 1.125]²).
fn mirror_scene() -> String {
    format!(
        r#"
[camera]
position = [0.0, 6.0, 0.01]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
resolution = [64, 64]

[[lights]]
type = "point"
position = [0.0, {LIGHT}, 0.0]
power = [{POWER}, {POWER}, {POWER}]

[materials.floor]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]

[materials.mirror]
type = "mirror"

[[objects]]
type = "quad"
corner = [-0.5, {MIRROR}, -0.5]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
material = "mirror"

[[objects]]
type = "quad"
corner = [-10.0, 0.0, -10.0]
edge_u = [0.0, 0.0, 20.0]
edge_v = [20.0, 0.0, 0.0]
material = "floor"
"#
    )
}

/// Solid angle of the floor rectangle [x0, x1] × [z0, z1] seen from height `h` above the
/// origin, from the corner formula Ω(a, b) = atan(ab / (h √(h² + a² + b²))) (odd in a and b).
fn solid_angle(h: f64, x0: f64, x1: f64, z0: f64, z1: f64) -> f64 {
    let corner = |a: f64, b: f64| (a * b / (h * (h * h + a * a + b * b).sqrt())).atan();
    corner(x1, z1) - corner(x0, z1) - corner(x1, z0) + corner(x0, z0)
}

/// Photons and power (mean over the channels) stored in the floor rectangle.
fn stored_in(map: &PhotonMap, x0: f32, x1: f32, z0: f32, z1: f32) -> (usize, f64) {
    let inside = map.photons().filter(|p| {
        let q = p.position();
        (x0..x1).contains(&q.x) && (z0..z1).contains(&q.z)
    });
    inside.fold((0, 0.0), |(n, e), p| {
        (n + 1, e + f64::from(p.power().element_sum()) / 3.0)
    })
}

fn caustic_map(world: &World, seed: u64) -> PhotonMap {
    in_pool(2, || {
        trace_map(
            world,
            MapKind::Caustic,
            200_000,
            seed,
            &ProgressBar::hidden(),
        )
        .0
    })
}

#[test]
fn a_guided_map_moves_photons_but_stores_the_mirrors_light() {
    let mut world = world(&mirror_scene());
    let unguided = caustic_map(&world, 3);
    // Worth only on the +x side of the floor: the guide sends photons there.
    let guide = in_pool(2, || {
        learn_caustic_guide(&world, 5, 50_000, |landings, _| {
            (landings.iter())
                .map(|l| if l.position.x > 0.0 { 1.0 } else { 0.0 })
                .collect()
        })
    });
    assert_eq!(guide.guided_lights(), 1);
    // 50,000 asked for, 128 a cell traced: 64 cells a cone, a cone a target.
    let cells = 64 * world.caustic_targets.len() as u64;
    assert_eq!(guide.paths, 128 * cells);
    assert!(guide.landings > 4_000, "{} landings", guide.landings);
    world.caustic_guide = guide.cells;
    let guided = caustic_map(&world, 3);

    let h = 2.0 * MIRROR - LIGHT;
    let expected =
        |x0: f64, x1: f64, z0: f64, z1: f64| POWER / (4.0 * PI) * solid_angle(h, x0, x1, z0, z1);
    // Inside the mirror's shadow, away from its edges (where the image source's light stops).
    let regions = [
        (0.2, 1.0, -0.6, 0.6),
        (-1.0, -0.2, -0.6, 0.6),
        (-0.3, 0.3, 0.2, 0.9),
    ];
    for (x0, x1, z0, z1) in regions {
        let want = expected(x0, x1, z0, z1);
        for (name, map) in [("unguided", &unguided), ("guided", &guided)] {
            let (n, got) = stored_in(map, x0 as f32, x1 as f32, z0 as f32, z1 as f32);
            // Poisson noise of n photons, at most 2.5× apart in power: 4σ ≈ 4 · 1.6 / √n.
            let tolerance = 6.5 / (n as f64).sqrt();
            assert!(
                (got / want - 1.0).abs() < tolerance,
                "{name}, x {x0}..{x1}, z {z0}..{z1}: {got} W against {want} W ({n} photons)"
            );
        }
    }
    // Half the photons land at x > 0 unguided; guided, the uniform share's half plus most of
    // the rest.
    let share = |map: &PhotonMap| {
        let (n, _) = stored_in(map, 0.0, 10.0, -10.0, 10.0);
        n as f64 / map.len() as f64
    };
    let (before, after) = (share(&unguided), share(&guided));
    assert!((before - 0.5).abs() < 0.01, "unguided share {before}");
    assert!(after > 0.75, "guided share {after}");
}

/// The guide is learnt on its own stream, in fixed runs of paths: the same guide, so the same
/// image, on one and two threads; and a different one than without it.
#[test]
fn guided_renders_are_the_same_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "mirror.toml", &mirror_scene());
    let render = |threads: &str, guide: &str| {
        let out = dir.path().join(format!("t{threads}-g{guide}.pfm"));
        let args = render_args(&[
            path_str(&scene),
            "-o",
            path_str(&out),
            "--threads",
            threads,
            "--passes",
            "2",
            "--caustic-photons",
            "20000",
            "--guide-paths",
            guide,
        ]);
        dpm::render::pipeline::run(&args).expect("render");
        std::fs::read(&out).unwrap()
    };
    let one = render("1", "20000");
    let two = render("2", "20000");
    assert!(one == two, "1 and 2 threads wrote different bytes");
    assert!(render("2", "0") != two, "the guide changed nothing");
}
