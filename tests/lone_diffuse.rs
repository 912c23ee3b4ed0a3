//! A scene's one diffuse object lights itself through its mirrors and glass (light → floor →
//! mirror → floor): dpm builds a global map for it by default, and aims the photons' diffuse
//! bounces at the mirrors and glass, since a bounce that misses them leaves the scene. Checked
//! by twins: the floor in one piece renders as the floor cut in two (two diffuse objects,
//! whose global map has always been built, drawn by the cosine alone); and aimed bounces
//! store the same flux as cosine-drawn ones, and so does a map cut short by a path limit.

mod support;

use dpm::image_metrics::channel_mean;
use dpm::photon::tracer::{MapKind, trace_map, trace_map_within};
use dpm::world::World;

/// A floor under a point light and a mirror ceiling: the floor sees itself in the ceiling.
fn floor_and_mirror(floor: &str) -> String {
    format!(
        "LookAt 0 1.2 -2.5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n\
         Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24\nWorldBegin\n\
         LightSource \"point\" \"point from\" [-0.3 1.5 0] \"rgb I\" [4 4 4]\n\
         AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.8 0.8 0.8]\n{floor}AttributeEnd\n\
         AttributeBegin\nMaterial \"mirror\" \"rgb Kr\" [1 1 1]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-1.5 2 -1.5  1.5 2 -1.5  1.5 2 1.5  -1.5 2 1.5]\nAttributeEnd\n"
    )
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
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let out = dir.join(format!("{name}.pfm"));
    let mut args = vec![
        support::path_str(&path),
        "-o",
        support::path_str(&out),
        "--threads",
        "2",
        "--passes",
        "8",
    ];
    args.extend_from_slice(extra);
    let outcome = dpm::render::pipeline::run(&support::render_args(&args)).unwrap();
    mean(&outcome.image)
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
                let (map, counts) = trace_map_within(&world, kind, 50_000, max_paths, seed, &bar);
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
