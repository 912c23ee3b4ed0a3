//! The global map's path budget: a pass emits at most `GLOBAL_PATHS_PER_PHOTON` paths a
//! wanted photon. Under an open sky the limit binds and the map is left short; in a closed
//! room it never does, so its map (and image) is what an unlimited budget gives.

mod support;

use dpm::render::pass::default_global_paths;
use dpm::render::pipeline::RenderOutcome;

const PHOTONS: u64 = 20_000;

fn render(dir: &std::path::Path, scene: &std::path::Path, extra: &[&str]) -> RenderOutcome {
    let out = dir.join("out.pfm");
    let photons = PHOTONS.to_string();
    let mut args = vec![
        support::path_str(scene),
        "-o",
        support::path_str(&out),
        "--passes",
        "2",
        "--resolution",
        "64x48",
        "--global-photons",
        &photons,
        "--caustic-photons",
        "0",
    ];
    args.extend_from_slice(extra);
    dpm::render::pipeline::run(&support::render_args(&args)).unwrap()
}

/// The emitted and stored counts of the global map's phase.
fn global_counts(outcome: &RenderOutcome) -> (u64, u64) {
    let phase = (outcome.times.phases.iter())
        .find(|p| p.name == "trace global photons")
        .expect("a global map is traced");
    let count = |name: &str| {
        (phase.counts.iter())
            .find(|(k, _)| k == name)
            .map(|(_, v)| *v)
            .unwrap()
    };
    (count("emitted"), count("stored"))
}

#[test]
fn an_open_floor_stops_at_the_path_budget_and_a_closed_room_never_meets_it() {
    let dir = tempfile::tempdir().unwrap();
    // Two matte balls on a floor under a point light, the sky open around them.
    let open = support::write_scene(
        dir.path(),
        "open.pbrt",
        "LookAt 0 3 7  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\n\
         WorldBegin\nLightSource \"point\" \"point from\" [0 4 0] \"rgb I\" [60 60 60]\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"point P\" [-5 0 -5  5 0 -5  5 0 5  -5 0 5] \
         \"integer indices\" [0 2 1 0 3 2]\n\
         AttributeBegin\nTranslate -0.8 0.6 0\nShape \"sphere\" \"float radius\" [0.6]\n\
         AttributeEnd\nAttributeBegin\nTranslate 0.9 0.6 0.3\n\
         Shape \"sphere\" \"float radius\" [0.6]\nAttributeEnd\nWorldEnd\n",
    );
    let budget = 2 * default_global_paths(PHOTONS);
    let (emitted, stored) = global_counts(&render(dir.path(), &open, &[]));
    assert_eq!(emitted, budget, "the open floor's map runs to its budget");
    assert!(stored < 2 * PHOTONS, "and is left short: {stored}");
    // Given a bigger budget, it emits more.
    let more = (4 * budget).to_string();
    let (emitted, _) = global_counts(&render(dir.path(), &open, &["--global-paths", &more]));
    assert!(emitted > budget, "{emitted}");

    let room = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.pbrt");
    let (emitted, stored) = global_counts(&render(dir.path(), &room, &[]));
    assert_eq!(stored, 2 * PHOTONS, "the closed room fills its map");
    assert!(emitted < budget / 2, "well inside the budget: {emitted}");
}
