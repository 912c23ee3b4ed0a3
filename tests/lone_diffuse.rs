//! A scene's one diffuse object lights itself through its mirrors and glass (light → floor →
//! mirror → floor): dpm builds a global map for it by default, and aims the photons' diffuse
//! bounces at the mirrors and glass, since a bounce that misses them leaves the scene. Checked
//! by twins: the floor in one piece renders as the floor cut in two (two diffuse objects,
//! whose global map has always been built, drawn by the cosine alone); and aimed bounces
//! store the same flux as cosine-drawn ones, and so does a map cut short by a path limit.
//! Where the floor cannot light itself (a mirror standing upright on it) pass 0's map, traced
//! once, stores nothing and no pass traces one, which changes no byte of the image; where the
//! map is sparse it is read through its table and keeps the image's mean.

mod support;

use dpm::image_metrics::channel_mean;
use dpm::photon::tracer::{MapKind, trace_map, trace_map_within};
use dpm::world::World;

/// A floor under a point light and a mirror ceiling: the floor sees itself in the ceiling.
fn floor_and_mirror(floor: &str) -> String {
    floor_and_mirror_at(floor, 32, 24)
}

fn floor_and_mirror_at(floor: &str, width: u32, height: u32) -> String {
    format!(
        "LookAt 0 1.2 -2.5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n\
         Film \"image\" \"integer xresolution\" {width} \"integer yresolution\" {height}\n\
         WorldBegin\n\
         LightSource \"point\" \"point from\" [-0.3 1.5 0] \"rgb I\" [4 4 4]\n\
         AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.8 0.8 0.8]\n{floor}AttributeEnd\n\
         AttributeBegin\nMaterial \"mirror\" \"rgb Kr\" [1 1 1]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-1.5 2 -1.5  1.5 2 -1.5  1.5 2 1.5  -1.5 2 1.5]\nAttributeEnd\n"
    )
}

/// A floor with a mirror standing upright on it: a vertical mirror keeps a ray's upward slope,
/// so light leaving the floor never comes back to it.
fn floor_and_standing_mirror() -> String {
    "LookAt 0 1.2 -2.5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n\
     Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24\nWorldBegin\n\
     LightSource \"point\" \"point from\" [-0.3 1.5 -0.5] \"rgb I\" [4 4 4]\n\
     AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.8 0.8 0.8]\n"
        .to_string()
        + WHOLE
        + "AttributeEnd\nAttributeBegin\nMaterial \"mirror\" \"rgb Kr\" [1 1 1]\n\
     Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
     \"point P\" [-0.8 0 0.3  0.8 0 0.3  0.8 0.6 0.3  -0.8 0.6 0.3]\nAttributeEnd\n"
}

const WHOLE: &str = "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
    \"point P\" [-1 0 -1  -1 0 1  1 0 1  1 0 -1]\n";
const HALVES: &str = "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
    \"point P\" [-1 0 -1  -1 0 1  0 0 1  0 0 -1]\n\
    Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
    \"point P\" [0 0 -1  0 0 1  1 0 1  1 0 -1]\n";

fn mean(image: &dpm::image_io::Image) -> f64 {
    image.pixels.iter().map(|p| channel_mean(*p)).sum::<f64>() / image.pixels.len() as f64
}

/// The image mean of `text` rendered by dpm's defaults but for the pass count, plus `extra`.
fn render_mean(dir: &std::path::Path, name: &str, text: &str, extra: &[&str]) -> f64 {
    mean(&render(dir, name, text, extra).image)
}

fn render(
    dir: &std::path::Path,
    name: &str,
    text: &str,
    extra: &[&str],
) -> dpm::render::pipeline::RenderOutcome {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let out = dir.join(format!("{name}.pfm"));
    let mut args = vec![
        support::path_str(&path),
        "-o",
        support::path_str(&out),
        "--passes",
        "8",
    ];
    if !extra.contains(&"--threads") {
        args.extend_from_slice(&["--threads", "2"]);
    }
    args.extend_from_slice(extra);
    dpm::render::pipeline::run(&support::render_args(&args)).unwrap()
}

#[test]
fn a_sparse_shown_map_is_read_through_its_table_and_keeps_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 19,200 pixels over 1,000 photons: sparse enough for the table (more than 16 a photon).
    let scene = floor_and_mirror_at(WHOLE, 160, 120);
    let sparse = ["--global-photons", "1000", "--caustic-photons", "0"];
    let table = render(d, "table.pbrt", &scene, &sparse);
    let per_hit = render(
        d,
        "per-hit.pbrt",
        &scene,
        &[&sparse[..], &["--irradiance-stride", "0"]].concat(),
    );
    let tabled = |o: &dpm::render::pipeline::RenderOutcome| {
        o.times
            .phases
            .iter()
            .any(|p| p.name == "precompute irradiance")
    };
    assert!(tabled(&table) && !tabled(&per_hit));
    // Same photons, same eye samples: only the indirect light's reading differs, by about a
    // tenth of its noise. Without the global map the image is 5% darker (the test above), so
    // a table that lost or doubled part of it would show.
    let (a, b) = (mean(&table.image), mean(&per_hit.image));
    eprintln!("image mean with the table {a:.5}, estimated at every hit {b:.5}");
    assert!((a / b - 1.0).abs() < 0.003, "{a} vs {b}");
    assert_ne!(table.image, per_hit.image, "the table was not read");
    // The table, like the map, is the same on any thread count.
    let one = render(
        d,
        "one-thread.pbrt",
        &scene,
        &[&sparse[..], &["--threads", "1"]].concat(),
    );
    assert!(
        one.image == table.image,
        "1 and 2 threads made different images"
    );
    // A dense map (more photons than a sixteenth of the pixels) keeps its own estimate.
    let dense = render(
        d,
        "dense.pbrt",
        &scene,
        &["--global-photons", "2000", "--caustic-photons", "0"],
    );
    assert!(!tabled(&dense));
}

#[test]
fn a_lone_floor_lights_itself_through_a_mirror_as_a_floor_in_two_pieces_does() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let one = render_mean(d, "one.pbrt", &floor_and_mirror(WHOLE), &[]);
    // Two diffuse objects: a global map by the cosine, of a size that keeps the test short.
    let two = render_mean(
        d,
        "two.pbrt",
        &floor_and_mirror(HALVES),
        &["--global-photons", "30000"],
    );
    let none = render_mean(
        d,
        "none.pbrt",
        &floor_and_mirror(WHOLE),
        &["--global-photons", "0"],
    );
    eprintln!("one piece {one:.5}, two pieces {two:.5}, no global map {none:.5}");
    assert!((one / two - 1.0).abs() < 0.01, "{one} vs {two}");
    // The light the floor sends itself is a share worth checking for.
    assert!(one / none > 1.05, "{one} vs {none}");
}

fn phase<'a>(
    outcome: &'a dpm::render::pipeline::RenderOutcome,
    name: &str,
) -> Option<&'a dpm::timing::Phase> {
    outcome.times.phases.iter().find(|p| p.name == name)
}

#[test]
fn a_lone_floor_that_cannot_light_itself_traces_no_global_map() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let standing = render(d, "standing.pbrt", &floor_and_standing_mirror(), &[]);
    let probe = phase(&standing, "probe global map").expect("a lone floor is probed");
    assert!(probe.counts.iter().any(|(k, v)| k == "stored" && *v == 0));
    assert!(phase(&standing, "trace global photons").is_none());
    // Traced every pass all the same, the empty map changes nothing: the same bytes.
    let traced = render(
        d,
        "traced.pbrt",
        &floor_and_standing_mirror(),
        &["--global-photons", "10000", "--global-paths", "100000"],
    );
    assert!(phase(&traced, "probe global map").is_none());
    let global = phase(&traced, "trace global photons").expect("given, it is traced");
    assert!(global.counts.iter().any(|(k, v)| k == "stored" && *v == 0));
    assert!(standing.image == traced.image, "the images differ");
    // Under a mirror ceiling the floor does light itself: the probe finds photons and every
    // pass traces its map.
    let ceiling = render(d, "ceiling.pbrt", &floor_and_mirror(WHOLE), &[]);
    assert!(phase(&ceiling, "trace global photons").is_some());
}

#[test]
fn aimed_diffuse_bounces_store_the_flux_cosine_drawn_ones_do() {
    let (description, _) = support::pbrt::loads(&floor_and_mirror(WHOLE));
    let mut world = World::new(description).unwrap();
    assert!(
        world.diffuse_bounce_aim > 0.0,
        "a lone floor beside a mirror aims"
    );
    let kind = MapKind::Global { with_direct: false };
    let bar = indicatif::ProgressBar::hidden();
    let flux = |world: &World, seed: u64| {
        let (map, _) = trace_map(world, kind, 50_000, seed, &bar);
        (0..map.len() as u32)
            .map(|s| channel_mean(map.attributes(s).power()) as f64)
            .sum::<f64>()
    };
    let aimed = flux(&world, 1) + flux(&world, 2);
    world.diffuse_bounce_aim = 0.0;
    let cosine = flux(&world, 1) + flux(&world, 2);
    eprintln!("stored flux: aimed {aimed:.5}, cosine {cosine:.5}");
    assert!((aimed / cosine - 1.0).abs() < 0.01, "{aimed} vs {cosine}");
}

#[test]
fn a_global_map_cut_short_by_its_path_limit_stores_the_same_flux() {
    let (description, _) = support::pbrt::loads(&floor_and_mirror(WHOLE));
    let world = World::new(description).unwrap();
    let kind = MapKind::Global { with_direct: false };
    let bar = indicatif::ProgressBar::hidden();
    let flux = |max_paths: Option<u64>| {
        (1..=8)
            .map(|seed| {
                let (map, _, counts) =
                    trace_map_within(&world, kind, 50_000, max_paths, seed, &bar);
                if let Some(limit) = max_paths {
                    assert_eq!(counts.emitted, limit, "the limit binds");
                    assert!(map.len() < 50_000);
                }
                (0..map.len() as u32)
                    .map(|s| channel_mean(map.attributes(s).power()) as f64)
                    .sum::<f64>()
            })
            .sum::<f64>()
    };
    // A path can store many photons (floor, ceiling mirror, floor, ...): one seed's flux over
    // 100,000 paths varies by about 3%.
    let (full, short) = (flux(None), flux(Some(100_000)));
    eprintln!("stored flux: full {full:.5}, 100,000 paths {short:.5}");
    assert!((short / full - 1.0).abs() < 0.02, "{short} vs {full}");
}
