//! The wrapper checked against Embree itself: errors surface, the ray layouts agree with the
//! C compiler's, and instances place their scenes.

use super::*;

#[test]
fn invalid_embree_call_surfaces_as_an_error() {
    let device = Device::new().unwrap();
    let mut builder = device.scene_builder().unwrap();
    // An index buffer in a vertex format: Embree itself refuses it.
    let err = builder
        .attach(backend::TRIANGLE, |g| {
            new_buffer::<[f32; 4]>(&device.inner, g, backend::INDEX, backend::FLOAT4, 1).map(|_| ())
        })
        .unwrap_err();
    assert_ne!(err.code, ErrorCode::Wrapper, "{err}");
    // The device stays usable and the error does not leak into the next call.
    builder.add_spheres(&[(Vec3::ZERO, 1.0)]).unwrap();
    let scene = builder.commit().unwrap();
    assert!(
        scene
            .intersect(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 0.0, f32::INFINITY)
            .is_some()
    );
}

#[test]
fn an_instance_places_its_scene_and_reports_itself_on_a_hit() {
    let device = Device::new().unwrap();
    let mut prototype = device.scene_builder().unwrap();
    prototype.add_spheres(&[(Vec3::ZERO, 1.0)]).unwrap();
    let quad = [
        Vec3::new(-1.0, -1.0, 3.0),
        Vec3::new(1.0, -1.0, 3.0),
        Vec3::new(0.0, 1.0, 3.0),
    ];
    prototype.add_triangles(&quad, &[[0, 1, 2]]).unwrap();
    let prototype = Arc::new(prototype.commit().unwrap());
    let mut top = device.scene_builder().unwrap();
    top.add_spheres(&[(Vec3::new(0.0, 0.0, -10.0), 0.5)])
        .unwrap();
    // Scaled by 2 and moved 5 along +x, twice over at different places.
    let place = |x: f32| {
        glam::Mat4::from_translation(Vec3::new(x, 0.0, 0.0))
            * glam::Mat4::from_scale(Vec3::splat(2.0))
    };
    let first = top.add_instance(&prototype, place(5.0)).unwrap();
    let second = top.add_instance(&prototype, place(-5.0)).unwrap();
    assert_eq!((first, second), (1, 2));
    let scene = top.commit().unwrap();
    drop(prototype);
    for (x, instance) in [(5.0, first), (-5.0, second)] {
        let hit = scene
            .intersect(Vec3::new(x, 0.0, -20.0), Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        // The sphere's near side is at z = −2, 18 along the ray.
        assert!((hit.t - 18.0).abs() < 1e-4, "{hit:?}");
        assert_eq!((hit.instance, hit.geometry), (Some(instance), 0));
        // Past the sphere's far side the ray meets the triangle, at z = 6.
        let hit = scene
            .intersect(Vec3::new(x, 0.0, 2.5), Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert!((hit.t - 3.5).abs() < 1e-4, "{hit:?}");
        assert_eq!(
            (hit.instance, hit.geometry, hit.primitive),
            (Some(instance), 1, 0)
        );
        assert!(!scene.occluded(Vec3::new(x, 0.0, -20.0), Vec3::Z, 0.0, 17.9));
        assert!(scene.occluded(Vec3::new(x, 0.0, -20.0), Vec3::Z, 0.0, 18.1));
    }
    // A hit outside any instance says so.
    let hit = scene
        .intersect(Vec3::new(0.0, 0.0, -20.0), Vec3::Z, 0.0, f32::INFINITY)
        .unwrap();
    assert_eq!((hit.instance, hit.geometry), (None, 0));
    // A transform that is not affine is refused before Embree sees it.
    let mut bad = device.scene_builder().unwrap();
    let inner = Arc::new(device.scene_builder().unwrap().commit().unwrap());
    let mut m = glam::Mat4::IDENTITY;
    m.w_axis.w = 2.0;
    m.x_axis.w = 1.0;
    assert_eq!(
        bad.add_instance(&inner, m).unwrap_err().code,
        ErrorCode::Wrapper
    );
}

#[test]
fn the_rays_rust_allocates_have_the_layout_the_c_compiler_gives_them() {
    // SAFETY: the shim's size queries return constants.
    let c = unsafe {
        (
            shim::dpm_rtc_sizeof_ray(),
            shim::dpm_rtc_sizeof_rayhit(),
            shim::dpm_rtc_alignof_rayhit(),
            shim::dpm_rtc_offsetof_hit(),
        )
    };
    let rust = (
        std::mem::size_of::<sys::RTCRay>(),
        std::mem::size_of::<sys::RTCRayHit>(),
        std::mem::align_of::<sys::RTCRayHit>(),
        std::mem::offset_of!(sys::RTCRayHit, hit),
    );
    assert_eq!(rust, c);
    // Embree 3.13 and the 4.2 headers agree (4.4's larger `RTCHit` is the shim's business).
    assert_eq!(c, (48, 80, 16, 48));
}

/// Turns down every hit on primitive 0 (and, for shadow rays only, primitive 1), recording
/// what it was asked.
struct Holes {
    asked: Mutex<Vec<Candidate>>,
}

impl HitFilter for Holes {
    fn accept(&self, c: &Candidate) -> bool {
        self.asked.lock().unwrap().push(*c);
        !(c.primitive == 0 || (c.primitive == 1 && c.is_occlusion()))
    }
}

#[test]
fn a_hit_filter_turns_hits_down_for_closest_hits_and_occlusion_and_through_instances() {
    let device = Device::new().unwrap();
    // Two triangles facing −z: primitive 0 at z = 1, primitive 1 at z = 2; a sphere behind.
    let p = [
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(3.0, -1.0, 1.0),
        Vec3::new(-1.0, 3.0, 1.0),
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(3.0, -1.0, 2.0),
        Vec3::new(-1.0, 3.0, 2.0),
    ];
    let holes = Arc::new(Holes {
        asked: Mutex::new(Vec::new()),
    });
    let build = |builder: &mut SceneBuilder| {
        builder
            .add_filtered_triangles(&p, &[[0, 1, 2], [3, 4, 5]], holes.clone())
            .unwrap();
        builder
            .add_spheres(&[(Vec3::new(0.0, 0.0, 10.0), 1.0)])
            .unwrap();
    };
    let mut flat = device.scene_builder().unwrap();
    build(&mut flat);
    let flat = flat.commit().unwrap();
    let mut prototype = device.scene_builder().unwrap();
    build(&mut prototype);
    let prototype = Arc::new(prototype.commit().unwrap());
    let mut top = device.scene_builder().unwrap();
    let shift = Vec3::new(0.0, 0.0, 100.0);
    top.add_instance(&prototype, glam::Mat4::from_translation(shift))
        .unwrap();
    let placed = top.commit().unwrap();
    drop(prototype);
    for (scene, offset) in [(&flat, Vec3::ZERO), (&placed, shift)] {
        let origin = Vec3::new(0.0, 0.0, -5.0) + offset;
        // The closest hit skips primitive 0 and stops at primitive 1.
        let hit = scene
            .intersect(origin, Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert_eq!((hit.geometry, hit.primitive), (0, 1), "{hit:?}");
        assert!((hit.t - 7.0).abs() < 1e-4, "{hit:?}");
        // A shadow ray passes both triangles and is stopped by the sphere only.
        assert!(!scene.occluded(origin, Vec3::Z, 0.0, 13.0));
        assert!(scene.occluded(origin, Vec3::Z, 0.0, 15.5));
    }
    // The filter saw the hits at their barycentrics, in the instanced scene's own space.
    let asked = holes.asked.lock().unwrap();
    let on_first = (asked.iter())
        .find(|c| c.primitive == 0 && !c.is_occlusion())
        .unwrap();
    assert!((on_first.t - 6.0).abs() < 1e-4, "{on_first:?}");
    assert!((on_first.u - 0.25).abs() < 1e-5 && (on_first.v - 0.25).abs() < 1e-5);
    assert!(
        asked
            .iter()
            .any(|c| c.origin().z < -4.0 && c.origin().z > -6.0)
    );
    assert!(
        asked
            .iter()
            .all(|c| c.origin().z < 0.0 && c.dir() == Vec3::Z)
    );
}
