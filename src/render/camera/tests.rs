//! The cameras' rays against closed forms: a thin lens's circle of confusion and its sharp
//! focal plane, orthographic rays that are parallel and span the film's extent, the
//! environment camera's lat-long directions over the whole sphere, the crop's pixel keys, and
//! `sees` for every kind.

use super::RayCamera;
use crate::scene::{Camera, CropWindow, Handedness, Projection, ThinLens};
use glam::Vec3;
use std::f32::consts::PI;

const W: u32 = 64;
const H: u32 = 48;

/// A camera at the origin looking down -z, y up, right-handed (x runs along +x).
fn camera(projection: Projection, lens: ThinLens) -> Camera {
    Camera {
        position: Vec3::ZERO,
        look_at: -Vec3::Z,
        up: Vec3::Y,
        projection,
        lens,
        width: W,
        height: H,
        handedness: Handedness::Right,
        crop: CropWindow::FULL,
    }
}

const PERSPECTIVE: Projection = Projection::Perspective {
    fov_y_degrees: 40.0,
};

/// Where a ray meets the plane `depth` ahead of the camera (z = -depth).
fn at_depth(ray: super::CameraRay, depth: f32) -> Vec3 {
    let t = (-depth - ray.origin.z) / ray.direction.z;
    ray.origin + t * ray.direction
}

/// Lens samples on a fine grid over [0, 1)².
fn lens_grid() -> impl Iterator<Item = (f32, f32)> {
    let n = 24;
    (0..n * n).map(move |i| {
        (
            ((i % n) as f32 + 0.5) / n as f32,
            ((i / n) as f32 + 0.5) / n as f32,
        )
    })
}

/// The largest distance of `points` from their mean.
fn spread(points: &[Vec3]) -> f32 {
    let mean = points.iter().sum::<Vec3>() / points.len() as f32;
    points.iter().map(|p| p.distance(mean)).fold(0.0, f32::max)
}

#[test]
fn a_thin_lens_blurs_a_point_off_the_focal_plane_to_its_circle_of_confusion() {
    let (radius, focus) = (0.1, 4.0);
    let lens = ThinLens {
        radius,
        focal_distance: focus,
    };
    let cam = RayCamera::new(&camera(PERSPECTIVE, lens));
    let (x, y) = (20.3, 31.7);
    for depth in [1.0f32, 2.5, 8.0, 30.0] {
        let hits: Vec<Vec3> = lens_grid()
            .map(|u| at_depth(cam.ray(x, y, u), depth))
            .collect();
        // The rays of one film point pass through its image on the focal plane, so at depth d
        // they cover a disc of radius r |d − f| / f; the grid's outermost ring falls just short.
        let want = radius * (depth - focus).abs() / focus;
        let got = spread(&hits);
        assert!(
            got <= want * 1.0001 && got >= want * 0.97,
            "depth {depth}: spread {got}, circle of confusion radius {want}"
        );
    }
    // In the image: a point at depth d images to a disc of diameter 2r |d − f| / (d f) on the
    // plane one unit deep, in pixels that times (H / 2) / tan(fov / 2). A ray from the lens's
    // rim through a film point that far off the point's pinhole image meets the point.
    let (depth, tan_half) = (12.0f32, 20f32.to_radians().tan());
    let point = Vec3::new(0.0, 0.0, -depth);
    let diameter_px =
        2.0 * radius * (depth - focus).abs() / (depth * focus) * (H as f32 / 2.0) / tan_half;
    // Lens sample (1, 0) is the rim point along +x: a ray from it crosses the axis at the
    // point beyond the focal plane, so it meets the focal plane (its film point) on the +x side.
    let rim = cam.ray(
        W as f32 / 2.0 + diameter_px / 2.0,
        H as f32 / 2.0,
        (1.0, 0.0),
    );
    let miss = (point - rim.origin).cross(rim.direction).length();
    assert!(
        miss < 1e-4 * depth,
        "the rim ray passes {miss} from the point"
    );
}

#[test]
fn a_point_on_the_focal_plane_stays_sharp() {
    for projection in [PERSPECTIVE, Projection::Orthographic { view_height: 2.0 }] {
        let lens = ThinLens {
            radius: 0.3,
            focal_distance: 6.0,
        };
        let cam = RayCamera::new(&camera(projection, lens));
        let hits: Vec<Vec3> = lens_grid()
            .map(|u| at_depth(cam.ray(11.2, 40.9, u), 6.0))
            .collect();
        assert!(
            spread(&hits) < 1e-5 * 6.0,
            "{projection:?}: {}",
            spread(&hits)
        );
        // And it is where the pinhole ray meets that plane.
        let sharp = at_depth(cam.chief_ray(11.2, 40.9), 6.0);
        assert!(hits[0].distance(sharp) < 1e-5 * 6.0);
    }
}

#[test]
fn without_a_lens_the_lens_sample_changes_nothing() {
    let cam = RayCamera::new(&camera(PERSPECTIVE, ThinLens::PINHOLE));
    for u in lens_grid().step_by(37) {
        assert_eq!(cam.ray(3.5, 7.25, u), cam.chief_ray(3.5, 7.25));
    }
}

#[test]
fn orthographic_rays_are_parallel_and_a_square_spans_its_share_of_the_film() {
    // A film 2 units tall, 64 × 48 pixels: 24 pixels a unit. A 1 × 1 square centred on the
    // axis 5 ahead spans pixel columns 20..44 and rows 12..36.
    let view_height = 2.0;
    let cam = RayCamera::new(&camera(
        Projection::Orthographic { view_height },
        ThinLens::PINHOLE,
    ));
    let mut columns = (u32::MAX, 0);
    let mut rows = (u32::MAX, 0);
    for y in 0..H {
        for x in 0..W {
            let ray = cam.chief_ray(x as f32 + 0.5, y as f32 + 0.5);
            assert_eq!(ray.direction, -Vec3::Z, "parallel to the view");
            assert_eq!(ray.origin.z, 0.0, "from the film plane");
            let p = at_depth(ray, 5.0);
            if p.x.abs() <= 0.5 && p.y.abs() <= 0.5 {
                columns = (columns.0.min(x), columns.1.max(x + 1));
                rows = (rows.0.min(y), rows.1.max(y + 1));
            }
        }
    }
    assert_eq!((columns, rows), ((20, 44), (12, 36)));
    // The film's corners are the extent's: aspect × height wide.
    let corner = cam.chief_ray(0.0, 0.0).origin;
    assert!((corner - Vec3::new(-4.0 / 3.0, 1.0, 0.0)).length() < 1e-6);
}

#[test]
fn the_environment_camera_maps_the_film_to_the_sphere_as_pbrt_v3_does() {
    let cam = RayCamera::new(&camera(Projection::Environment, ThinLens::PINHOLE));
    let (w, h) = (W as f32, H as f32);
    let close = |a: Vec3, b: Vec3| a.distance(b) < 1e-5;
    // θ from the top row (up), φ from the left edge; camera x right, y up, z forward:
    // (sin θ cos φ, cos θ, sin θ sin φ). Forward (-z here) is a quarter of the way across.
    assert!(close(cam.chief_ray(w / 4.0, h / 2.0).direction, -Vec3::Z));
    assert!(close(cam.chief_ray(w / 2.0, h / 2.0).direction, -Vec3::X));
    assert!(close(cam.chief_ray(0.0, h / 2.0).direction, Vec3::X));
    assert!(close(cam.chief_ray(w * 0.75, h / 2.0).direction, Vec3::Z));
    assert!(close(cam.chief_ray(5.0, 0.0).direction, Vec3::Y));
    assert!(close(cam.chief_ray(5.0, h).direction, -Vec3::Y));
    // Every direction is some film point's: invert the mapping for directions spread evenly
    // over the sphere (uniform in φ and cos θ) and shoot them again.
    let n = 40;
    for i in 0..n * n {
        let cos_theta = 1.0 - 2.0 * ((i / n) as f32 + 0.5) / n as f32;
        let phi = 2.0 * PI * ((i % n) as f32 + 0.5) / n as f32;
        let theta = cos_theta.acos();
        let (x, y) = (phi / (2.0 * PI) * w, theta / PI * h);
        let d = cam.chief_ray(x, y).direction;
        // In camera space (x right = +x, y up = +y, z forward = -z).
        let want = Vec3::new(
            theta.sin() * phi.cos(),
            cos_theta,
            -(theta.sin() * phi.sin()),
        );
        assert!(close(d, want), "θ {theta} φ {phi}: {d} vs {want}");
        assert!((d.length() - 1.0).abs() < 1e-6);
    }
    // A row's share of the sphere is its band's 2π (cos θ0 − cos θ1) / 4π: the film is even in
    // θ, so the pixels of the poles' rows hold less of it than the equator's.
    let row_share = |y: f32| {
        let (c0, c1) = (
            cam.chief_ray(0.0, y).direction.y,
            cam.chief_ray(0.0, y + 1.0).direction.y,
        );
        (c0 - c1) / 2.0
    };
    let total: f32 = (0..H).map(|y| row_share(y as f32)).sum();
    assert!(
        (total - 1.0).abs() < 1e-5,
        "rows cover {total} of the sphere"
    );
    let want_equator = ((PI * 23.0 / h).cos() - (PI * 24.0 / h).cos()) / 2.0;
    assert!((row_share(23.0) - want_equator).abs() < 1e-6);
}

#[test]
fn a_crop_keys_its_pixels_by_the_full_film() {
    let mut c = camera(PERSPECTIVE, ThinLens::PINHOLE);
    c.crop = CropWindow {
        x: [0.25, 0.5],
        y: [0.1, 0.9],
    };
    let cam = RayCamera::new(&c);
    // pbrt's rounding: ceil(64 · 0.25) = 16 .. 32, ceil(48 · 0.1) = 5 .. ceil(43.2) = 44.
    assert_eq!((cam.width(), cam.height()), (16, 39));
    assert_eq!(cam.film_size(), (64, 48));
    assert_eq!(cam.film_pixel(0, 0), (16, 5));
    assert_eq!(cam.pixel_key(3, 2), (7 * 64 + 19) as u64);
    let full = RayCamera::new(&camera(PERSPECTIVE, ThinLens::PINHOLE));
    assert_eq!(full.pixel_key(19, 7), cam.pixel_key(3, 2));
}

#[test]
fn sees_answers_for_each_kind() {
    let pinhole = RayCamera::new(&camera(PERSPECTIVE, ThinLens::PINHOLE));
    let tan_half = 20f32.to_radians().tan();
    // Just inside and just outside the top edge at depth 10; behind the camera.
    let top = 10.0 * tan_half;
    assert!(pinhole.sees(Vec3::new(0.0, top * 0.99, -10.0)));
    assert!(!pinhole.sees(Vec3::new(0.0, top * 1.02, -10.0)));
    assert!(!pinhole.sees(Vec3::new(0.0, 0.0, 10.0)));
    // A lens focused at 2 blurs the point at depth 10 over r |1/f − 1/d| = 0.2 at unit depth.
    let blurred = RayCamera::new(&camera(
        PERSPECTIVE,
        ThinLens {
            radius: 0.5,
            focal_distance: 2.0,
        },
    ));
    assert!(blurred.sees(Vec3::new(0.0, 10.0 * (tan_half + 0.19), -10.0)));
    assert!(!blurred.sees(Vec3::new(0.0, 10.0 * (tan_half + 0.21), -10.0)));
    let ortho = RayCamera::new(&camera(
        Projection::Orthographic { view_height: 2.0 },
        ThinLens::PINHOLE,
    ));
    assert!(ortho.sees(Vec3::new(1.3, -0.99, -50.0)));
    assert!(!ortho.sees(Vec3::new(1.4, 0.0, -50.0)));
    assert!(!ortho.sees(Vec3::new(0.0, 0.0, 1.0)));
    let environment = RayCamera::new(&camera(Projection::Environment, ThinLens::PINHOLE));
    for p in [Vec3::Z, -Vec3::Z, Vec3::new(3.0, -7.0, 0.1)] {
        assert!(environment.sees(p));
    }
}
