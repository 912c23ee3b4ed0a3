//! The eye pass's closed-form cases, shared by the render tests: a unit sphere of glass or
//! mirror (tinted or not) before a 100 × 100 quad emitter, with the Fresnel series of the
//! glass traced here in f64; the Whitted integrator on it; and renders of a diffuse plane
//! checked pixel by pixel against a radiance given in closed form.

use super::*;
use dpm::estimate::Scratch;
use dpm::image_io::Image;
use dpm::render::RayCamera;
use dpm::render::integrator::{Indirect, Integrator};
use dpm::render::pipeline;
use dpm::sampling::{PathSampler, Rng, Stream};
use dpm::world::World;
use glam::DVec3;
use std::f64::consts::PI;

pub const IOR: f64 = 1.5;
/// The emitter: a 100 × 100 quad at z = -5 facing +z (edge_u × edge_v = x × y = z).
pub const LIGHT_CORNER: DVec3 = DVec3::new(-50.0, -50.0, -5.0);
pub const LIGHT_U: DVec3 = DVec3::new(100.0, 0.0, 0.0);
pub const LIGHT_V: DVec3 = DVec3::new(0.0, 100.0, 0.0);
pub const LIGHT_POWER: DVec3 = DVec3::new(20000.0, 10000.0, 5000.0);

/// A unit sphere of `material` at the origin in front of the big quad light.
pub fn sphere_scene(material: &str) -> String {
    format!(
        r#"
[camera]
position = [0.0, 0.0, 10.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 30.0
resolution = [33, 33]

[[lights]]
type = "quad"
corner = [-50.0, -50.0, -5.0]
edge_u = [100.0, 0.0, 0.0]
edge_v = [0.0, 100.0, 0.0]
power = [20000.0, 10000.0, 5000.0]

[materials.glass]
type = "glass"
ior = {IOR}

[materials.chrome]
type = "mirror"

# Tinted: red halved in what each reflects or transmits.
[materials.red_halving_chrome]
type = "mirror"
tint = [0.5, 1.0, 1.0]

[materials.red_halving_reflection]
type = "glass"
ior = {IOR}
reflect_tint = [0.5, 1.0, 1.0]

[materials.red_halving_transmission]
type = "glass"
ior = {IOR}
transmit_tint = [0.5, 1.0, 1.0]

[[objects]]
type = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "{material}"
"#
    )
}

/// The emitter's radiance Φ / (π A).
pub fn emitter_radiance() -> DVec3 {
    LIGHT_POWER / (PI * LIGHT_U.cross(LIGHT_V).length())
}

/// Whether the ray reaches the emitter. The rays the tests use stay clear of its edges (where
/// f32 and f64 could disagree); a ray within 0.1 of an edge is a mistake in the test.
pub fn hits_light(o: DVec3, d: DVec3) -> bool {
    let inner = hit_parallelogram(
        o,
        d,
        LIGHT_CORNER + DVec3::new(0.1, 0.1, 0.0),
        LIGHT_U - 0.2 * DVec3::X,
        LIGHT_V - 0.2 * DVec3::Y,
    );
    let outer = hit_parallelogram(
        o,
        d,
        LIGHT_CORNER - DVec3::new(0.1, 0.1, 0.0),
        LIGHT_U + 0.2 * DVec3::X,
        LIGHT_V + 0.2 * DVec3::Y,
    );
    assert_eq!(
        inner.is_some(),
        outer.is_some(),
        "test ray {o} + t {d} grazes the emitter's edge"
    );
    inner.is_some()
}

/// Radiance along the ray from (b, 0, 10) in direction -z, relative to the emitter's, as the
/// Whitted recursion with `max_depth` should give it, traced here in f64. The ray meets the
/// unit sphere at angle of incidence θ (sin θ = b). Every internal hit of a sphere has the
/// same angle (the refracted angle θt), so the same Fresnel reflectance F: the entry reflects
/// F, transmits 1 − F, and internal hit j (j ≥ 1) lets out (1 − F)² F^(j−1). Each ray that
/// leaves the sphere counts only when it reaches the emitter. Depths: the entry is hit at
/// depth 0 and internal hit j at depth j; a glass hit at depth ≥ max_depth contributes
/// nothing, so internal hits 1 ..= max_depth − 1 are followed.
///
/// For b = 0 the exits alternate between forward (to the light, even j − 1) and backward, so
/// with a deep recursion the radiance is (1 − R)² Σ R^(2k) = (1 − R)² / (1 − R²) = (1 − R)/(1 + R)
/// with R = ((n − 1)/(n + 1))².
pub fn glass_sphere_radiance(b: f64, max_depth: u32) -> f64 {
    tinted_glass_sphere_radiance(b, max_depth, 1.0, 1.0)
}

/// [`glass_sphere_radiance`] for glass that scales what it reflects by `reflect_tint` and what
/// it transmits by `transmit_tint` (one channel's): every reflection, the entry's and the
/// internal ones, takes the first, every crossing of the surface (in and out) the second.
pub fn tinted_glass_sphere_radiance(
    b: f64,
    max_depth: u32,
    reflect_tint: f64,
    transmit_tint: f64,
) -> f64 {
    if max_depth == 0 {
        return 0.0;
    }
    let d = DVec3::NEG_Z;
    let x1 = DVec3::new(b, 0.0, (1.0 - b * b).sqrt());
    let f0 = fresnel(-d.dot(x1), 1.0, IOR);
    let mut total = 0.0;
    if hits_light(x1, reflect(d, x1)) {
        total += f0 * reflect_tint;
    }
    let mut dir = refract(d, x1, 1.0 / IOR).expect("entering never reflects totally");
    let mut x = x1;
    let mut weight = (1.0 - f0) * transmit_tint;
    for _ in 1..max_depth {
        x += -2.0 * x.dot(dir) * dir; // the chord to the sphere's far side
        let inward = -x; // unit normal facing the inside, where the ray arrives from
        let f = fresnel(-dir.dot(inward), IOR, 1.0);
        if let Some(out) = refract(dir, inward, IOR)
            && hits_light(x, out)
        {
            total += weight * (1.0 - f) * transmit_tint;
        }
        dir = reflect(dir, inward);
        weight *= f * reflect_tint;
    }
    total
}

pub fn whitted(world: &World, max_depth: u32) -> Integrator<'_> {
    Integrator {
        world,
        caustics: None,
        indirect: Indirect::None,
        max_depth,
        light_samples: 1,
        glass_split_depth: u32::MAX,
        volume: Default::default(),
    }
}

pub fn radiance_along(integrator: &Integrator, origin: DVec3, dir: DVec3) -> DVec3 {
    let mut sampler = PathSampler::new(Rng::for_index(1, Stream::Pixels, 0), None);
    let mut scratch = Scratch::default();
    let l = integrator.radiance(
        origin.as_vec3(),
        dir.as_vec3(),
        0,
        &mut sampler,
        &mut scratch,
    );
    // Light reaches these pixels only straight from the emitter: all of it is direct.
    assert_eq!(l.caustic + l.indirect, glam::Vec3::ZERO);
    dvec(l.total())
}

/// The 4 × 4 diffuse plane of scenes/point-plane.toml (x, z in [-2, 2] at y = 0, albedo 0.5)
/// under the lights given as TOML `[[lights]]` entries, seen from that scene's camera.
pub fn plane_scene(lights: &str, width: u32, height: u32) -> String {
    let text = scene_with_resolution("scenes/point-plane.toml", width, height);
    let point =
        "[[lights]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\npower = [100.0, 100.0, 100.0]";
    assert!(text.contains(point), "point-plane.toml's light changed");
    text.replace(point, lights)
}

/// Half the side and the albedo of [`plane_scene`]'s plane.
pub const PLANE_HALF: f64 = 2.0;
pub const PLANE_ALBEDO: f64 = 0.5;

/// A one-pass render of `text` (extra `dpm render` flags in `args`), and the scene. Every
/// pixel takes one camera sample (no edge samples), at the jitter [`check_plane_pixels`]
/// works out again.
pub fn render_scene(
    text: &str,
    args: &[&str],
) -> (pipeline::RenderOutcome, dpm::scene::SceneDescription) {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "scene.toml", text);
    let out = dir.path().join("scene.pfm");
    let mut all = vec![path_str(&scene), "-o", path_str(&out), "--threads", "2"];
    all.extend_from_slice(&["--edge-samples", "0"]);
    all.extend_from_slice(args);
    let outcome = pipeline::run(&render_args(&all)).expect("render");
    let image = dpm::image_io::read_pfm(&out).expect("read the PFM back");
    assert_eq!(image, outcome.image, "the file holds the returned image");
    (outcome, description(text))
}

/// What [`check_plane_pixels`] found.
#[derive(Debug, Default)]
pub struct PlaneCheck {
    pub on_plane: usize,
    pub off_plane: usize,
    /// Pixels that see something before the plane.
    pub in_front: usize,
    /// Largest relative error over the pixels checked relatively.
    pub worst: f64,
}

/// Every pixel of a one-pass, one-sample render of a scene with [`plane_scene`]'s plane as
/// its only object: where the pixel's ray (at the render's own sample position) meets the
/// plane, the pixel must equal `want(p).0`, `p` being the point the integrator shades (the hit
/// lifted by the world's ray epsilon towards the camera), within `tolerance` relative, or
/// within the absolute bound `want(p).1` when it gives one (for values too small for a
/// relative check); elsewhere the pixel must equal `background`. Pixels whose ray grazes the
/// plane's edge are skipped, and so are those whose ray (origin, direction) `in_front` says
/// meets something before the plane: it gives what they must show instead.
pub fn check_plane_pixels(
    image: &Image,
    desc: &dpm::scene::SceneDescription,
    mut want: impl FnMut(DVec3) -> (DVec3, Option<f64>),
    in_front: impl Fn(DVec3, DVec3) -> Option<DVec3>,
    background: DVec3,
    tolerance: f64,
) -> PlaneCheck {
    let (w, h) = (desc.camera.width, desc.camera.height);
    assert_eq!((image.width, image.height), (w as usize, h as usize));
    let camera = RayCamera::new(&desc.camera);
    let epsilon = World::new(desc.clone()).expect("world").ray_epsilon() as f64;
    let samples = dpm::render::PassSamples::new(1, 0, 1);
    let mut check = PlaneCheck::default();
    for y in 0..h {
        for x in 0..w {
            let sample = samples.sample((y * w + x) as u64, 0);
            let (jx, jy) = sample.jitter;
            let ray = camera.ray(x as f32 + jx, y as f32 + jy, sample.lens);
            let (o, d) = (dvec(ray.origin), dvec(ray.direction));
            let got = dvec(image.get(x as usize, y as usize));
            if let Some(shown) = in_front(o, d) {
                check.in_front += 1;
                assert!(
                    (got - shown).abs().max_element() <= 1e-5 * shown.max_element(),
                    "pixel ({x}, {y}) sees something before the plane: {got} vs {shown}"
                );
                continue;
            }
            let t = -o.y / d.y;
            let p = o + t * d;
            let inside = t > 0.0 && p.x.abs() < PLANE_HALF && p.z.abs() < PLANE_HALF;
            let margin = (PLANE_HALF - p.x.abs()).min(PLANE_HALF - p.z.abs()).abs();
            if margin < 1e-3 {
                continue; // grazes the quad's edge: hit or miss is up to rounding
            }
            if !inside {
                check.off_plane += 1;
                assert!(
                    (got - background).abs().max_element() <= 1e-6 * background.max_element(),
                    "pixel ({x}, {y}) misses the plane: {got} vs {background}"
                );
                continue;
            }
            check.on_plane += 1;
            let (value, absolute) = want(p + DVec3::Y * epsilon);
            for c in 0..3 {
                match absolute {
                    None => {
                        let e = rel_err(got[c], value[c]);
                        check.worst = check.worst.max(e);
                        assert!(
                            e < tolerance,
                            "pixel ({x}, {y}) channel {c}: {} vs analytic {} at {p}",
                            got[c],
                            value[c]
                        );
                    }
                    Some(bound) => assert!(
                        (got[c] - value[c]).abs() <= bound,
                        "pixel ({x}, {y}) channel {c}: {} vs analytic {} (± {bound}) at {p}",
                        got[c],
                        value[c]
                    ),
                }
            }
        }
    }
    assert!(
        check.on_plane > 1000,
        "most pixels see the plane: {check:?}"
    );
    assert!(check.off_plane > 50, "some pixels see past it: {check:?}");
    check
}

/// Irradiance at the origin of a surface facing +y from a Lambertian rectangle of radiance 1
/// parallel to it at height `h`, spanning [x0, x1] × [z0, z1]: π times the form factor,
/// summed from the corners' S(a, b) = a/√(a²+h²) atan(b/√(a²+h²)) + b/√(b²+h²) atan(a/√(b²+h²)),
/// which is odd in a and in b (so signed corners add up), E = ½ Σ ± S.
pub fn rectangle_irradiance(h: f64, x0: f64, x1: f64, z0: f64, z1: f64) -> f64 {
    let s = |a: f64, b: f64| {
        let (ra, rb) = ((a * a + h * h).sqrt(), (b * b + h * h).sqrt());
        a / ra * (b / ra).atan() + b / rb * (a / rb).atan()
    };
    0.5 * (s(x1, z1) - s(x0, z1) - s(x1, z0) + s(x0, z0))
}
