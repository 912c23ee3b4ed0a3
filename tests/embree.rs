//! Rays against a triangle and a sphere, compared with analytic hits, on whichever Embree
//! backend the build has (Embree 3 by default, Embree 4 with `--features embree4`).

use dpm::embree::{Device, Scene};
use glam::Vec3;

const INF: f32 = f32::INFINITY;

/// The triangle (0,0,0), (1,0,0), (0,1,0) in the plane z = 0.
fn triangle_scene() -> Scene {
    let device = Device::new().unwrap();
    let mut b = device.scene_builder().unwrap();
    let id = b
        .add_triangles(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[[0, 1, 2]])
        .unwrap();
    assert_eq!(id, 0);
    b.commit().unwrap()
}

/// A sphere of radius 2 centred at (1, 2, 3), after a triangle far away (so its id is 1).
fn sphere_scene() -> Scene {
    let device = Device::new().unwrap();
    let mut b = device.scene_builder().unwrap();
    let far = Vec3::splat(100.0);
    b.add_triangles(&[far, far + Vec3::X, far + Vec3::Y], &[[0, 1, 2]])
        .unwrap();
    assert_eq!(
        b.add_spheres(&[(Vec3::new(1.0, 2.0, 3.0), 2.0)]).unwrap(),
        1
    );
    b.commit().unwrap()
}

#[test]
fn triangle_hit_inside_matches_the_plane_intersection() {
    let s = triangle_scene();
    let o = Vec3::new(0.25, 0.5, 3.0);
    let d = Vec3::new(0.0, 0.0, -2.0); // unnormalised: t is in units of |d|
    let h = s.intersect(o, d, 0.0, INF).expect("hit");
    assert!((h.t - 1.5).abs() < 1e-6);
    assert_eq!((h.geometry, h.primitive), (0, 0));
    // Barycentrics weight vertex 1 (u) and vertex 2 (v): p = u*X + v*Y.
    assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
    let n = h.normal.normalize();
    assert!(n.cross(Vec3::Z).length() < 1e-6, "normal {n}");
}

#[test]
fn triangle_misses_outside_and_behind() {
    let s = triangle_scene();
    assert!(
        s.intersect(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z, 0.0, INF)
            .is_none()
    );
    assert!(
        s.intersect(Vec3::new(-0.1, 0.5, 1.0), -Vec3::Z, 0.0, INF)
            .is_none()
    );
    // The triangle lies behind the origin.
    assert!(
        s.intersect(Vec3::new(0.2, 0.2, 1.0), Vec3::Z, 0.0, INF)
            .is_none()
    );
    assert!(!s.occluded(Vec3::new(0.2, 0.2, 1.0), Vec3::Z, 0.0, INF));
    // Parallel to the plane (grazing): no hit.
    assert!(
        s.intersect(Vec3::new(-1.0, 0.2, 0.0), Vec3::X, 0.0, INF)
            .is_none()
    );
}

#[test]
fn triangle_edge_hit_is_found() {
    let s = triangle_scene();
    // Slightly inside the hypotenuse x + y = 1 and the edge y = 0.
    let h = s
        .intersect(Vec3::new(0.5, 0.4999, 1.0), -Vec3::Z, 0.0, INF)
        .expect("hit");
    assert!((h.t - 1.0).abs() < 1e-6);
    let h = s
        .intersect(Vec3::new(0.5, 1e-5, 1.0), -Vec3::Z, 0.0, INF)
        .expect("hit");
    assert!((h.t - 1.0).abs() < 1e-6);
}

#[test]
fn tnear_and_tfar_bound_the_hit() {
    let s = triangle_scene();
    let o = Vec3::new(0.2, 0.2, 1.0);
    assert!(s.intersect(o, -Vec3::Z, 0.0, 0.999).is_none());
    assert!(s.intersect(o, -Vec3::Z, 1.001, INF).is_none());
    assert!(s.intersect(o, -Vec3::Z, 0.999, 1.001).is_some());
    assert!(!s.occluded(o, -Vec3::Z, 0.0, 0.999));
    assert!(s.occluded(o, -Vec3::Z, 0.0, 1.001));
}

#[test]
fn sphere_hit_from_outside_is_the_near_root() {
    let s = sphere_scene();
    let c = Vec3::new(1.0, 2.0, 3.0);
    let o = c + Vec3::new(0.0, 0.0, -10.0);
    let h = s.intersect(o, Vec3::Z, 0.0, INF).expect("hit");
    assert!((h.t - 8.0).abs() < 1e-4, "t = {}", h.t);
    assert_eq!((h.geometry, h.primitive), (1, 0));
    let n = h.normal.normalize();
    assert!((n - -Vec3::Z).length() < 1e-3, "normal {n}");
    // Off-centre: the root of |o + t d − c|² = r² for a ray at offset 1.2 from the centre.
    let o = c + Vec3::new(1.2, 0.0, -10.0);
    let h = s.intersect(o, Vec3::Z, 0.0, INF).expect("hit");
    let expected = 10.0 - (4.0f32 - 1.44).sqrt();
    assert!((h.t - expected).abs() < 1e-4, "t = {} want {expected}", h.t);
    let p = o + h.t * Vec3::Z;
    assert!((h.normal.normalize() - (p - c).normalize()).length() < 1e-3);
}

#[test]
fn sphere_hit_from_inside_is_the_far_root() {
    let s = sphere_scene();
    let c = Vec3::new(1.0, 2.0, 3.0);
    let h = s.intersect(c, Vec3::X, 0.0, INF).expect("hit from inside");
    assert!((h.t - 2.0).abs() < 1e-4, "t = {}", h.t);
    // Starting past the near root (tnear beyond it) also finds the far one.
    let o = c + Vec3::new(-10.0, 0.0, 0.0);
    let h = s.intersect(o, Vec3::X, 9.0, INF).expect("far root");
    assert!((h.t - 12.0).abs() < 1e-4, "t = {}", h.t);
}

#[test]
fn sphere_misses_behind_and_beside() {
    let s = sphere_scene();
    let c = Vec3::new(1.0, 2.0, 3.0);
    assert!(
        s.intersect(c + Vec3::new(0.0, 0.0, 5.0), Vec3::Z, 0.0, INF)
            .is_none()
    );
    assert!(
        s.intersect(c + Vec3::new(2.01, 0.0, -5.0), Vec3::Z, 0.0, INF)
            .is_none()
    );
    // Grazing just inside the silhouette still hits, near t = 5.
    let h = s
        .intersect(c + Vec3::new(1.999, 0.0, -5.0), Vec3::Z, 0.0, INF)
        .expect("graze");
    assert!((h.t - 5.0).abs() < 0.1, "t = {}", h.t);
}

#[test]
fn bad_geometry_is_refused_before_embree() {
    let device = Device::new().unwrap();
    let mut b = device.scene_builder().unwrap();
    assert!(b.add_triangles(&[Vec3::ZERO], &[[0, 1, 2]]).is_err());
    assert!(
        b.add_triangles(&[Vec3::NAN, Vec3::X, Vec3::Y], &[[0, 1, 2]])
            .is_err()
    );
    assert!(b.add_triangles(&[], &[]).is_err());
    assert!(b.add_spheres(&[(Vec3::ZERO, -1.0)]).is_err());
    assert!(b.add_spheres(&[(Vec3::ZERO, f32::NAN)]).is_err());
    // The builder is still usable and ids stay dense.
    assert_eq!(b.add_spheres(&[(Vec3::ZERO, 1.0)]).unwrap(), 0);
    assert_eq!(b.commit().unwrap().geometry_count(), 1);
}

#[test]
fn committed_scene_is_shared_across_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Scene>();
    let s = std::sync::Arc::new(sphere_scene());
    let hits: Vec<bool> = (0..4)
        .map(|i| {
            let s = s.clone();
            std::thread::spawn(move || {
                let o = Vec3::new(1.0, 2.0, -10.0 - i as f32);
                s.intersect(o, Vec3::Z, 0.0, INF).is_some()
            })
        })
        .map(|h| h.join().unwrap())
        .collect();
    assert!(hits.iter().all(|&h| h));
}

#[test]
fn the_reported_version_matches_the_backend() {
    let version = dpm::embree::version().unwrap();
    let text = version.to_string();
    if cfg!(feature = "embree4") {
        assert!(text.starts_with("Embree 4."), "{text}");
        assert_eq!(dpm::embree::BACKEND, "Embree 4");
    } else {
        assert!(text.starts_with("Embree 3."), "{text}");
        assert_eq!(dpm::embree::BACKEND, "Embree 3");
    }
    assert_eq!(dpm::embree::version_string(), text);
    // A second device reports the same library.
    assert_eq!(Device::new().unwrap().version(), version);
}
