//! The pilot rays' plan (`render::pilots`): which pixels sample their emitted light apart —
//! a light smaller than the pilots' spacing, seen directly or in a mirror, flags its pixel; a
//! mirror that shows nothing near a light does not, nor does a constant sky, while an image
//! sky flags a silhouette against it — and which hold an edge: exactly the column a silhouette
//! or a shadow's edge crosses. Edge pixels' extra camera samples resolve
//! the step inside them where one sample gives all or nothing, and an out-of-range count is
//! refused.

mod support;

use dpm::render::RayCamera;
use dpm::render::pilots::PixelPlan;
use dpm::render::pipeline;
use glam::DVec3;
use std::f64::consts::PI;
use support::*;

const SIDE: usize = 32;

/// The camera at z = 10 looks down −z (30° field of view, 32 × 32 pixels) at `objects`.
fn scene(lights: &str, objects: &str) -> String {
    format!(
        "[camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
         fov_y = 30.0\nresolution = [{SIDE}, {SIDE}]\n\n{lights}\n\
         [materials.grey]\ntype = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\n\
         [materials.chrome]\ntype = \"mirror\"\n\n{objects}"
    )
}

/// A quad in the plane z = `z` covering x < `edge` (and y within ±50).
fn quad_left_of(edge: f64, z: f64, material: &str) -> String {
    format!(
        "[[objects]]\ntype = \"quad\"\ncorner = [-50.0, -50.0, {z}]\nedge_u = [{}, 0.0, 0.0]\n\
         edge_v = [0.0, 100.0, 0.0]\nmaterial = \"{material}\"\n",
        edge + 50.0
    )
}

/// World x on the plane at distance `depth` from the camera where image column `column`
/// (fractional) lies.
fn world_x(column: f64, depth: f64) -> f64 {
    (column / (SIDE as f64 / 2.0) - 1.0) * depth * (15.0f64).to_radians().tan()
}

fn plan(text: &str, emission: u32, edge: u32) -> PixelPlan {
    plan_of(description(text), emission, edge)
}

/// The plan of 16 emission samples, seeking light images or not.
fn plan_with(text: &str, light_images: bool) -> PixelPlan {
    let desc = description(text);
    let camera = RayCamera::new(&desc.camera);
    let world = dpm::world::World::new(desc).expect("world");
    in_pool(2, || {
        PixelPlan::survey(&camera, &world, 10, 16, 0, light_images)
    })
    .expect("not interrupted")
}

fn plan_of(desc: dpm::scene::SceneDescription, emission: u32, edge: u32) -> PixelPlan {
    let camera = RayCamera::new(&desc.camera);
    let world = dpm::world::World::new(desc).expect("world");
    in_pool(2, || {
        PixelPlan::survey(&camera, &world, 10, emission, edge, true)
    })
    .expect("not interrupted")
}

fn flagged(plan: &PixelPlan, which: impl Fn(&PixelPlan, usize) -> bool) -> Vec<(usize, usize)> {
    (0..SIDE * SIDE)
        .filter(|&p| which(plan, p))
        .map(|p| (p % SIDE, p / SIDE))
        .collect()
}

fn emission(plan: &PixelPlan) -> Vec<(usize, usize)> {
    flagged(plan, |plan, p| plan.emission_apart(p))
}

fn edges(plan: &PixelPlan) -> Vec<(usize, usize)> {
    flagged(plan, |plan, p| plan.camera_samples(p, 1) > 1)
}

/// A sphere light a fifth of a pixel across, in front of a grey wall inside pixel (20, 11)
/// — between that pixel's pilots, so no pilot meets it — flags that pixel, and no pixel more
/// than two away (a light within 1.5 × the pixel's spread of a pilot flags it).
#[test]
fn a_light_smaller_than_the_pilots_spacing_flags_its_pixel() {
    let depth = 5.0;
    let (cx, cy) = (world_x(20.3, depth), -world_x(11.3, depth));
    let pixel_size = world_x(1.0, depth) - world_x(0.0, depth);
    let light = format!(
        "[[lights]]\ntype = \"sphere\"\ncenter = [{cx}, {cy}, {}]\nradius = {}\n\
         power = [10.0, 10.0, 10.0]\n",
        10.0 - depth,
        0.1 * pixel_size
    );
    let text = scene(&light, &quad_left_of(50.0, 0.0, "grey"));
    let flags = emission(&plan(&text, 16, 0));
    assert!(flags.contains(&(20, 11)), "{flags:?}");
    assert!(
        flags
            .iter()
            .all(|&(x, y)| x.abs_diff(20) <= 2 && y.abs_diff(11) <= 2),
        "{flags:?}"
    );
}

/// A mirror filling the view reflects the camera's rays back past it: only the pixels whose
/// reflection passes the small light behind the camera flag; the rest of the mirror, which
/// shows only the dark sky, does not.
#[test]
fn a_mirror_flags_only_where_it_reflects_a_light() {
    // Seen in the mirror at z = 0, a light at (x, y, 20) sits where (x, y, −20) would, 30
    // units from the camera.
    let depth = 30.0;
    let (cx, cy) = (world_x(9.5, depth), -world_x(24.5, depth));
    let light = format!(
        "[[lights]]\ntype = \"sphere\"\ncenter = [{cx}, {cy}, 20.0]\nradius = 0.05\n\
         power = [10.0, 10.0, 10.0]\n"
    );
    let text = scene(&light, &quad_left_of(50.0, 0.0, "chrome"));
    let flags = emission(&plan(&text, 16, 0));
    assert!(flags.contains(&(9, 24)), "{flags:?}");
    assert!(
        flags
            .iter()
            .all(|&(x, y)| x.abs_diff(9) <= 2 && y.abs_diff(24) <= 2),
        "{flags:?}"
    );
    // With every pixel counting its own emission, nothing is flagged.
    assert!(emission(&plan(&text, 0, 4)).is_empty());
}

/// The light images a flagged pixel aims at: a sphere light a fifth of a pixel across seen
/// directly, and one seen in a flat mirror, each found where its centre projects, as an
/// ellipse of the light's disc reached twice over (so π (2 · 0.1)² square pixels), and in
/// no pixel that does not hold that centre.
#[test]
fn newton_finds_a_small_lights_image_where_its_centre_projects() {
    // Directly at depth 5 inside pixel (20, 11); in the mirror at z = 0 a light at z = 20 is
    // seen 30 units away, inside pixel (9, 24), its radius a tenth of a pixel there too.
    for (depth, z, column, row, material) in [
        (5.0, 5.0, 20.3, 11.3, "grey"),
        (30.0, 20.0, 9.55, 24.6, "chrome"),
    ] {
        let pixel_size = world_x(1.0, depth) - world_x(0.0, depth);
        let (cx, cy) = (world_x(column, depth), -world_x(row, depth));
        let light = format!(
            "[[lights]]\ntype = \"sphere\"\ncenter = [{cx}, {cy}, {z}]\nradius = {}\n\
             power = [10.0, 10.0, 10.0]\n",
            0.1 * pixel_size
        );
        let text = scene(&light, &quad_left_of(50.0, 0.0, material));
        let planned = plan(&text, 16, 0);
        let (x, y) = (column as usize, row as usize);
        let images = planned.light_images(y * SIDE + x);
        assert_eq!(images.len(), 1, "{material}: {images:?}");
        let found = images[0].centre();
        assert!(
            (found.x as f64 - column).abs() < 1e-3 && (found.y as f64 - row).abs() < 1e-3,
            "{material}: {found} against ({column}, {row})"
        );
        let area = PI * 0.2 * 0.2;
        assert!(
            (images[0].area() as f64 - area).abs() < 0.02 * area,
            "{images:?}"
        );
        assert_eq!(planned.aimed_pixels(), 1, "{material}");
        // Without light images every emission sample spreads.
        let spread = plan_with(&text, false);
        assert!(spread.light_images(y * SIDE + x).is_empty());
        assert!(spread.emission_apart(y * SIDE + x));
    }
}

/// A grey quad covering x < edge against the empty background, lit by a point light: the
/// column the silhouette crosses holds an edge, every other pixel agrees with its pilots.
#[test]
fn a_silhouette_makes_exactly_its_column_an_edge() {
    let light =
        "[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 5.0]\npower = [100.0, 100.0, 100.0]\n";
    let text = scene(light, &quad_left_of(world_x(21.37, 10.0), 0.0, "grey"));
    let planned = plan(&text, 16, 4);
    let flags = edges(&planned);
    assert_eq!(flags, (0..SIDE).map(|y| (21, y)).collect::<Vec<_>>());
    assert_eq!(planned.camera_samples(21, 1), 4);
    assert_eq!(planned.camera_samples(20, 1), 1);
    // A render asking for more samples everywhere keeps its own count.
    assert_eq!(planned.camera_samples(21, 8), 8);
    // Without edge samples every pixel takes `spp`.
    assert!(edges(&plan(&text, 16, 0)).is_empty());
}

/// A grey quad's silhouette against a constant sky: every ray that leaves the scene sees the
/// same radiance, so camera samples count it exactly and no pixel samples its emission apart.
/// Against an image sky of that same radiance (its texels could hold a sun) the silhouette's
/// column does, and only it.
#[test]
fn a_constant_sky_flags_no_pixel_and_an_image_sky_flags_the_silhouette() {
    let edge = world_x(21.37, 10.0);
    let sky = "[[lights]]\ntype = \"environment\"\nradiance = [0.2, 0.2, 0.2]\n";
    let text = scene(sky, &quad_left_of(edge, 0.0, "grey"));
    assert!(emission(&plan(&text, 16, 0)).is_empty());

    let dir = tempfile::tempdir().unwrap();
    let map = dpm::image_io::Image::from_fn(8, 4, |_, _| glam::Vec3::splat(0.2));
    let options = dpm::image_io::WriteOptions::default();
    dpm::image_io::write_image(&dir.path().join("sky.pfm"), &map, &options).unwrap();
    let pbrt = format!(
        "LookAt 0 0 10  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"image\" \"integer xresolution\" {SIDE} \"integer yresolution\" {SIDE}\n\
         WorldBegin\nLightSource \"infinite\" \"string mapname\" \"sky.pfm\"\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point3 P\" [-50 -50 0  {edge} -50 0  {edge} 50 0  -50 50 0]\nWorldEnd\n"
    );
    let path = dir.path().join("sky.pbrt");
    std::fs::write(&path, pbrt).unwrap();
    let flags = emission(&plan_of(dpm::scene::load(&path).unwrap(), 16, 0));
    let column = flags.first().expect("the silhouette's column is flagged").0;
    assert_eq!(flags, (0..SIDE).map(|y| (column, y)).collect::<Vec<_>>());
    assert!(column == 21 || column == SIDE - 1 - 21, "{column}");
}

/// A wall filling the view under a distant light from the right at 45°; a quad out of sight
/// (z = 1, right of the view) shadows the wall right of image column `column`.
fn shadow_scene(column: f64) -> String {
    // The light travels along (−1, 0, −1): the occluder's edge at (e, z = 1) shadows the wall
    // (z = 0) from x = e − 1 on.
    let shadow_x = world_x(column, 10.0);
    let light = "[[lights]]\ntype = \"distant\"\ndirection = [-1.0, 0.0, -1.0]\nirradiance = [2.0, 2.0, 2.0]\n";
    let occluder = format!(
        "[[objects]]\ntype = \"quad\"\ncorner = [{}, -50.0, 1.0]\nedge_u = [0.0, 100.0, 0.0]\n\
         edge_v = [40.0, 0.0, 0.0]\nmaterial = \"grey\"\n",
        shadow_x + 1.0
    );
    scene(
        light,
        &format!("{}{occluder}", quad_left_of(50.0, 0.0, "grey")),
    )
}

#[test]
fn a_shadows_edge_makes_exactly_its_column_an_edge() {
    let text = shadow_scene(27.37);
    let flags = edges(&plan(&text, 16, 4));
    assert_eq!(flags, (0..SIDE).map(|y| (27, y)).collect::<Vec<_>>());
    // The same shadow from a small sphere light far along the distant light's line (its
    // probe is the point of its surface facing the wall, which a shadow ray reaches without
    // stopping at the light itself).
    let x = world_x(27.37, 10.0) + 100.0;
    let sphere = format!(
        "[[lights]]\ntype = \"sphere\"\ncenter = [{x}, 0.0, 100.0]\nradius = 0.01\n\
         power = [1000.0, 1000.0, 1000.0]\n"
    );
    let distant = text.find("[[lights]]").expect("a light");
    let end = distant + text[distant..].find("\n\n").expect("its end");
    let text = format!("{}{sphere}{}", &text[..distant], &text[end..]);
    assert!(
        text.contains("sphere") && !text.contains("distant"),
        "{text}"
    );
    let flags = edges(&plan(&text, 16, 4));
    assert_eq!(flags, (0..SIDE).map(|y| (27, y)).collect::<Vec<_>>());
}

/// In the shadow's edge column, 64 edge samples in one pass give the lit fraction of the
/// wall's radiance within 2% (the pixel's Sobol positions are stratified along x); one
/// camera sample gives all of it or none. Pixels wholly lit or shadowed are exact either way.
/// (No global map: the light bounced between the wall and the occluder would blur the step.)
#[test]
fn edge_samples_resolve_a_shadows_edge_inside_a_pixel() {
    let column = 27.37;
    let text = shadow_scene(column);
    let render = |edge: &str| {
        let dir = tempfile::tempdir().unwrap();
        let scene = write_scene(dir.path(), "shadow.toml", &text);
        let out = dir.path().join("shadow.pfm");
        let args = render_args(&[
            path_str(&scene),
            "-o",
            path_str(&out),
            "--threads",
            "2",
            "--edge-samples",
            edge,
            "--global-photons",
            "0",
        ]);
        pipeline::run(&args).unwrap_or_else(|e| panic!("{e}")).image
    };
    // Lit: albedo/π · irradiance · cos 45°.
    let lit = 0.5 / PI * 2.0 * (0.5f64).sqrt();
    // The shaded point is lifted by the ray epsilon towards the light, which moves the
    // shadow's edge that far to the right.
    let epsilon = world(&text).ray_epsilon() as f64;
    let edge = column + epsilon / (world_x(1.0, 10.0) - world_x(0.0, 10.0));
    let resolved = render("64");
    let single = render("0");
    for y in [3, 16, 29] {
        for x in 0..SIDE {
            let fraction = (edge - x as f64).clamp(0.0, 1.0);
            let got = resolved.get(x, y).as_dvec3();
            let want = DVec3::splat(lit * fraction);
            assert!(
                (got - want).abs().max_element() <= 0.02 * lit,
                "pixel ({x}, {y}): {got} vs {want}"
            );
            let one = single.get(x, y).x as f64;
            assert!(
                (one - 0.0).abs() < 1e-6 || (one - lit).abs() < 1e-5 * lit,
                "pixel ({x}, {y}) with one sample: {one}"
            );
        }
    }
}

#[test]
fn too_many_edge_samples_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "s.toml", &shadow_scene(27.37));
    let out = dir.path().join("s.pfm");
    let args = render_args(&[
        path_str(&scene),
        "-o",
        path_str(&out),
        "--edge-samples",
        "5000",
    ]);
    let e = pipeline::run(&args).err().expect("refused");
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("--edge-samples 5000"), "{e}");
}
