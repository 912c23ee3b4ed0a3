//! Photon tracing's shared pieces for the tests: tracing a map on two threads, a lone
//! diffuse plane under one light, the solid angle of a rectangle, and the check of the power a
//! lone plane stores.

use super::*;
use dpm::photon::PhotonMap;
use dpm::photon::tracer::{MapKind, TraceCounts, trace_map};
use dpm::world::World;
use indicatif::ProgressBar;
use std::f64::consts::PI;

/// Traces one map on a pool of two threads.
pub fn trace(world: &World, kind: MapKind, target: usize, seed: u64) -> (PhotonMap, TraceCounts) {
    in_pool(2, || {
        trace_map(world, kind, target, seed, &ProgressBar::hidden())
    })
}

/// The global map with direct photons too: every diffuse hit.
pub const GLOBAL_ALL: MapKind = MapKind::Global { with_direct: true };

/// A diffuse `2 half × 2 half` quad at y = 0 (x, z in [-half, half]), albedo 0.5, under `light`
/// (TOML of one `[[lights]]` entry without its header).
pub fn square_plane_scene(light: &str, half: f64) -> String {
    let (c, e) = (-half, 2.0 * half);
    format!(
        r#"
[camera]
position = [0.0, 2.5, 3.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 45.0
resolution = [16, 12]

[[lights]]
{light}

[materials.grey]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]

[[objects]]
type = "quad"
corner = [{c}, 0.0, {c}]
edge_u = [0.0, 0.0, {e}]
edge_v = [{e}, 0.0, 0.0]
material = "grey"
"#
    )
}

pub const POINT_LIGHT: &str =
    "type = \"point\"\nposition = [0.0, 1.0, 0.0]\npower = [100.0, 100.0, 100.0]";

/// Fraction of an isotropic point source's power that crosses a `2a × 2b` rectangle centred
/// under it at distance `h`: Ω / 4π with Ω = 4 asin(ab / √((a² + h²)(b² + h²))).
pub fn rectangle_fraction(a: f64, b: f64, h: f64) -> f64 {
    4.0 * (a * b / ((a * a + h * h) * (b * b + h * h)).sqrt()).asin() / (4.0 * PI)
}

/// Checks the fraction of paths that store a photon, and the stored power, on a lone plane.
pub fn assert_stored_power(text: &str, phi: f64, fraction: f64, target: usize, tolerance: f64) {
    let world = world(text);
    let (map, counts) = trace(&world, GLOBAL_ALL, target, 5);
    let got = counts.stored as f64 / counts.emitted.max(1) as f64;
    let total = dvec(map.total_power());
    eprintln!("{counts:?}: stored/emitted {got}, stored power {total}");
    assert!(
        rel_err(got, fraction) < tolerance,
        "stored/emitted {got} ({counts:?}) vs the analytic fraction {fraction}"
    );
    assert!(
        rel_err(total.x, phi * fraction) < tolerance + 0.004,
        "stored power {total} vs {}",
        phi * fraction
    );
}
