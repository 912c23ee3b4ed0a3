//! Photon maps of the lights pbrt scenes bring, and of tinted mirrors and glass, against
//! closed forms and invariants: a spot's maps hold its power (both falloffs, caustic photons
//! aimed or not), a mesh emitter's photons carry its power and aim at a mirror as a quad's do,
//! the environment and a distant light give a plane their irradiance (π L, E cos θ) as photon
//! density, and tints scale the caustic power of what each branch carries.

mod support;

use dpm::estimate::{KnnEstimate, Query, RadialKernel, RadianceEstimate, Scratch};
use dpm::photon::PhotonMap;
use dpm::photon::tracer::MapKind;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;
use support::photons::*;
use support::*;

/// A spot at (0, 1, 0) shining down.
fn spot(cone: f64, start: f64, falloff: &str) -> String {
    format!(
        "type = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\n\
         cone_angle = {cone}\nfalloff_start = {start}\nfalloff = \"{falloff}\"\n\
         power = [100.0, 100.0, 100.0]"
    )
}

/// A scene of `light` (a `[[lights]]` entry), the diffuse material `grey`, the `materials`
/// and the `objects` given (TOML), and a 200 × 200 grey ceiling at y = 2 facing down.
fn scene_under_a_ceiling(light: &str, materials: &str, objects: &str) -> String {
    format!(
        r#"
[camera]
position = [0.0, 0.0, 8.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 45.0
resolution = [8, 8]

[[lights]]
{light}

[materials.grey]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]

{materials}

{objects}

[[objects]]
type = "quad"
corner = [-100.0, 2.0, -100.0]
edge_u = [200.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 200.0]
material = "grey"
"#
    )
}

/// `light` over a 2 × 2 mirror of `tint` at y = -2 facing up, under the ceiling, which takes
/// every photon the mirror sends up.
fn mirror_scene(light: &str, tint: &str) -> String {
    scene_under_a_ceiling(
        light,
        &format!("[materials.chrome]\ntype = \"mirror\"\ntint = {tint}"),
        "[[objects]]\ntype = \"quad\"\ncorner = [-1.0, -2.0, -1.0]\nedge_u = [0.0, 0.0, 2.0]\n\
         edge_v = [2.0, 0.0, 0.0]\nmaterial = \"chrome\"",
    )
}

/// The spot's whole power Φ lands in each map when every photon reaches the receiver: the
/// global map of a spot over a 200 × 200 plane (every path stores once: tolerance 0.5%, the
/// photons' shared-exponent power rounding), and the caustic map of a narrow spot (15°) whose
/// cone falls wholly on a mirror that sends it to the ceiling; for both falloffs (the spot's
/// photons follow its intensity, so each carries Φ whatever the falloff). A wide spot (80°,
/// aimed: its photons come from the cones towards the mirror, the narrower set) sends the
/// mirror the share Ω_mirror / ∫f dω of Φ (the mirror lies within the falloff start): 20 000
/// photons, binomial σ ≈ 0.5%; tolerance 2%.
#[test]
fn spot_light_maps_hold_the_spot_power() {
    for falloff in ["smoothstep", "quartic"] {
        let global = square_plane_scene(&spot(40.0, 25.0, falloff), 100.0);
        assert_stored_power(&global, 100.0, 1.0, 20_000, 1e-3);

        let narrow = world(&mirror_scene(&spot(15.0, 10.0, falloff), "[1.0, 1.0, 1.0]"));
        let (map, counts) = trace(&narrow, MapKind::Caustic, 20_000, 3);
        assert_eq!(
            counts.stored, counts.emitted,
            "every photon reaches the ceiling"
        );
        let total = dvec(map.total_power());
        assert!(
            rel_err(total.x, 100.0) < 5e-3,
            "{falloff}: caustic power {total}"
        );

        let wide = world(&mirror_scene(&spot(80.0, 70.0, falloff), "[1.0, 1.0, 1.0]"));
        let (map, counts) = trace(&wide, MapKind::Caustic, 20_000, 3);
        let (cos_a, cos_b) = (80f64.to_radians().cos(), 70f64.to_radians().cos());
        let band = if falloff == "smoothstep" { 0.5 } else { 0.2 };
        let weighted_solid_angle = 2.0 * PI * ((1.0 - cos_b) + (cos_b - cos_a) * band);
        let mirror = 4.0 * PI * rectangle_fraction(1.0, 1.0, 3.0);
        let want = 100.0 * mirror / weighted_solid_angle;
        let total = dvec(map.total_power());
        eprintln!("{falloff}, aimed: {counts:?}, caustic power {total} vs {want}");
        assert!(
            counts.emitted < 2 * counts.stored,
            "aimed: most photons reach the mirror ({counts:?})"
        );
        assert!(
            rel_err(total.x, want) < 0.02,
            "{falloff}: aimed caustic power {total} vs {want}"
        );
    }
}

/// A mirror tinted [0.5, 1, 1] halves the red of the caustic map's power and nothing else:
/// the same paths are traced (tints draw no numbers), so the ratio is 0.5 up to the rounding
/// of the photons' shared-exponent power (0.4%).
#[test]
fn a_tinted_mirror_halves_the_red_caustic_power() {
    let light = spot(15.0, 10.0, "smoothstep");
    let clear = world(&mirror_scene(&light, "[1.0, 1.0, 1.0]"));
    let tinted = world(&mirror_scene(&light, "[0.5, 1.0, 1.0]"));
    let (a, ca) = trace(&clear, MapKind::Caustic, 10_000, 4);
    let (b, cb) = trace(&tinted, MapKind::Caustic, 10_000, 4);
    assert_eq!(ca, cb);
    let ratio = dvec(b.total_power()) / dvec(a.total_power());
    assert!(
        (ratio - DVec3::new(0.5, 1.0, 1.0)).abs().max_element() < 5e-3,
        "{ratio}"
    );
}

/// A spot over a flat 4 × 4 glass interface at y = 0, a floor at y = -1 below it and a
/// ceiling at y = 2 above: the floor takes the transmitted caustic photons, the ceiling the
/// reflected ones. Glass whose reflections halve the red and whose transmissions halve the
/// green halves the red of the ceiling's power and the green of the floor's, and leaves the
/// rest, against clear glass on the same paths.
#[test]
fn glass_tints_scale_the_reflected_and_transmitted_caustic_power() {
    let scene = |reflect: &str, transmit: &str| {
        let glass = format!(
            "[materials.glass]\ntype = \"glass\"\nior = 1.5\nreflect_tint = {reflect}\n\
             transmit_tint = {transmit}"
        );
        let objects = "[[objects]]\ntype = \"quad\"\ncorner = [-2.0, 0.0, -2.0]\n\
                       edge_u = [0.0, 0.0, 4.0]\nedge_v = [4.0, 0.0, 0.0]\nmaterial = \"glass\"\n\n\
                       [[objects]]\ntype = \"quad\"\ncorner = [-100.0, -1.0, -100.0]\n\
                       edge_u = [0.0, 0.0, 200.0]\nedge_v = [200.0, 0.0, 0.0]\nmaterial = \"grey\"";
        scene_under_a_ceiling(&spot(30.0, 25.0, "smoothstep"), &glass, objects)
    };
    let clear = world(&scene("[1.0, 1.0, 1.0]", "[1.0, 1.0, 1.0]"));
    let tinted = world(&scene("[0.5, 1.0, 1.0]", "[1.0, 0.5, 1.0]"));
    let (a, ca) = trace(&clear, MapKind::Caustic, 20_000, 6);
    let (b, cb) = trace(&tinted, MapKind::Caustic, 20_000, 6);
    assert_eq!(ca, cb);
    // Power on the ceiling (reflected) and on the floor (transmitted).
    let split = |map: &PhotonMap| {
        let (mut up, mut down) = (DVec3::ZERO, DVec3::ZERO);
        for p in map.photons() {
            if p.position().y > 0.0 {
                up += dvec(p.power());
            } else {
                down += dvec(p.power());
            }
        }
        (up, down)
    };
    let ((up_a, down_a), (up_b, down_b)) = (split(&a), split(&b));
    // Fresnel at normal incidence is 4%, more at the cone's edge: some hundreds reflected.
    assert!(
        up_a.x > 0.02 * down_a.x && down_a.x > 0.9 * 100.0,
        "{up_a} {down_a}"
    );
    let reflected = up_b / up_a;
    let transmitted = down_b / down_a;
    assert!(
        (reflected - DVec3::new(0.5, 1.0, 1.0)).abs().max_element() < 5e-3,
        "reflected {reflected}"
    );
    assert!(
        (transmitted - DVec3::new(1.0, 0.5, 1.0))
            .abs()
            .max_element()
            < 5e-3,
        "transmitted {transmitted}"
    );
}

/// A 1 × 1 square in the xz plane, centred on the origin, wound so that its normal is -y.
const SQUARE_OBJ: &str =
    "v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\nf 1 2 3\nf 1 3 4\n";

/// The square as a mesh light of 100 W at y = 1, facing down; and the quad light it matches.
fn square_lights(obj: &std::path::Path) -> [String; 2] {
    [
        format!(
            "type = \"mesh\"\nfile = \"{}\"\ntranslate = [0.0, 1.0, 0.0]\npower = [100.0, 100.0, 100.0]",
            obj.display()
        ),
        "type = \"quad\"\ncorner = [-0.5, 1.0, -0.5]\nedge_u = [1.0, 0.0, 0.0]\n\
         edge_v = [0.0, 0.0, 1.0]\npower = [100.0, 100.0, 100.0]"
            .to_string(),
    ]
}

/// A mesh emitter's photons carry its power: over a 200 × 200 plane (which takes all but
/// about (1/100)² of a Lambertian emitter's power, as for the quad light in
/// tests/photon_tracing.rs) the stored power is Φ within 1%. Aimed at a 2 × 2 mirror 3 below
/// (caustic photons, per point), it sends the mirror the same power as the quad light of the
/// same shape (both unbiased estimates; 20 000 photons each, σ ≈ 0.7% each; tolerance 3%), and
/// needs no more paths for it than the quad light's aim grid (within 10%).
#[test]
fn mesh_light_photons_carry_its_power_and_aim_like_a_quad() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("square.obj");
    std::fs::write(&obj, SQUARE_OBJ).unwrap();
    let [mesh, quad] = square_lights(&obj);
    assert_stored_power(&square_plane_scene(&mesh, 100.0), 100.0, 1.0, 5_000, 0.01);

    let caustic = |light: &str| {
        let text = mirror_scene(light, "[1.0, 1.0, 1.0]")
            .replace("corner = [-1.0, -2.0, -1.0]", "corner = [-1.0, -3.0, -1.0]");
        let (map, counts) = trace(&world(&text), MapKind::Caustic, 20_000, 8);
        (dvec(map.total_power()).x, counts)
    };
    let ((from_mesh, mesh_counts), (from_quad, quad_counts)) = (caustic(&mesh), caustic(&quad));
    eprintln!("mesh {from_mesh} W ({mesh_counts:?}), quad {from_quad} W ({quad_counts:?})");
    assert!(
        rel_err(from_mesh, from_quad) < 0.03,
        "mesh {from_mesh} vs quad {from_quad}"
    );
    assert!(
        (mesh_counts.emitted as f64) < 1.1 * quad_counts.emitted as f64,
        "mesh {mesh_counts:?} vs quad {quad_counts:?}"
    );
}

/// Photon density on a lone 4 × 4 plane (global map, direct photons included) under a light
/// at infinity: the power of the photons stored on its top side within |x|, |z| < 1.5, over
/// that area, is the irradiance, π L under the environment and E cos θ under a distant light
/// at 36.9°; tolerance 1.5% (about 50 000 photons in the square, σ ≈ 0.45%, and the shared
/// rounding of the photons' equal powers, ≤ 0.4%). The k-NN estimate (k = 400, constant
/// kernel) at 25 points of the square agrees too: each within 25% (5σ), their mean within 2%.
#[test]
fn lights_at_infinity_give_a_plane_their_irradiance_in_photons() {
    let cases = [
        (
            "type = \"environment\"\nradiance = [0.5, 0.5, 0.5]",
            PI * 0.5,
        ),
        (
            "type = \"distant\"\ndirection = [0.6, -0.8, 0.0]\nirradiance = [2.0, 2.0, 2.0]",
            2.0 * 0.8,
        ),
    ];
    for (light, want) in cases {
        let plane = world(&square_plane_scene(light, 2.0));
        let (map, counts) = trace(&plane, GLOBAL_ALL, 200_000, 12);
        let (mut power, mut inside) = (0.0, 0);
        for p in map.photons() {
            let q = p.position();
            if p.normal().y > 0.0 && q.x.abs() < 1.5 && q.z.abs() < 1.5 {
                power += p.power().x as f64;
                inside += 1;
            }
        }
        let density = power / 9.0;
        eprintln!("{light}: {counts:?}, {inside} photons in the square, E = {density} vs {want}");
        assert!(inside > 40_000, "{inside}");
        assert!(
            rel_err(density, want) < 0.015,
            "{light}: {density} vs {want}"
        );

        let estimate = KnnEstimate::new(RadialKernel::Constant, 400, None);
        let mut scratch = Scratch::default();
        let mut sum = 0.0;
        for i in 0..5 {
            for j in 0..5 {
                let query = Query {
                    position: Vec3::new(-1.0 + 0.5 * i as f32, 0.0, -1.0 + 0.5 * j as f32),
                    normal: Vec3::Y,
                };
                let e = estimate.irradiance(&map, &query, &mut scratch).x as f64;
                assert!(rel_err(e, want) < 0.25, "{light}: k-NN {e} vs {want}");
                sum += e;
            }
        }
        assert!(
            rel_err(sum / 25.0, want) < 0.02,
            "{light}: k-NN mean {} vs {want}",
            sum / 25.0
        );
    }
}
