//! The wrapper checked against Embree itself: errors surface, the ray layouts agree with the
//! C compiler's, instances place their scenes, hit filters turn hits down, and curves are met
//! where their geometry says.

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
        let mesh = Arc::new(OwnedMesh::padded(p.to_vec(), vec![[0, 1, 2], [3, 4, 5]]));
        builder
            .add_shared_triangles(mesh, Some(holes.clone()))
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

/// Four collinear control points from (−2, 0, 0) to (2, 0, 0): a straight segment along x, each
/// point with `radius`.
/// A mesh that owns its buffers, as a loaded scene's mesh does.
struct OwnedMesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl OwnedMesh {
    fn padded(mut positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        pad_for_embree(&mut positions);
        Self {
            positions,
            triangles,
        }
    }
}

impl SharedTriangles for OwnedMesh {
    fn positions(&self) -> &Vec<Vec3> {
        &self.positions
    }
    fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
}

/// A bumpy grid of `n` × `n` quads over [0, 1]², two triangles each.
fn bumpy_grid(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let positions = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            Vec3::new(x, y, 0.05 * (7.0 * x).sin() * (5.0 * y).cos())
        })
        .collect();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let triangles = (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .flat_map(|(i, j)| {
            let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            [[a, b, c], [a, c, d]]
        })
        .collect();
    (positions, triangles)
}

#[test]
fn a_mesh_read_in_place_hits_as_its_copy_does_and_lives_as_long_as_the_scene() {
    let device = Device::new().unwrap();
    let (positions, triangles) = bumpy_grid(40);
    let mut copied = device.scene_builder().unwrap();
    copied.add_triangles(&positions, &triangles).unwrap();
    let copied = copied.commit().unwrap();
    assert_eq!(copied.meshes_read_in_place(), 0);

    let mesh = Arc::new(OwnedMesh::padded(positions.clone(), triangles.clone()));
    assert!(padded_for_embree(&mesh.positions));
    let mut shared = device.scene_builder().unwrap();
    shared.add_shared_triangles(mesh.clone(), None).unwrap();
    let shared = shared.commit().unwrap();
    assert_eq!(shared.meshes_read_in_place(), 1);
    assert_eq!(Arc::strong_count(&mesh), 2, "the scene holds the mesh");

    // Without room past the last vertex, the positions are copied and the hits still agree.
    let mut tight = positions.clone();
    tight.shrink_to_fit();
    let tight = Arc::new(OwnedMesh {
        positions: tight,
        triangles: triangles.clone(),
    });
    let in_place = padded_for_embree(&tight.positions);
    let mut fallback = device.scene_builder().unwrap();
    fallback.add_shared_triangles(tight, None).unwrap();
    let fallback = fallback.commit().unwrap();
    assert_eq!(fallback.meshes_read_in_place(), usize::from(in_place));

    let mut hits = 0;
    for k in 0..2000u32 {
        let (x, y) = ((k % 50) as f32 / 49.0, (k / 50) as f32 / 39.0);
        let origin = Vec3::new(x * 1.2 - 0.1, y * 1.2 - 0.1, 1.0);
        let dir = Vec3::new(0.1, -0.05, -1.0).normalize();
        let want = copied.intersect(origin, dir, 0.0, f32::INFINITY);
        for scene in [&shared, &fallback] {
            let got = scene.intersect(origin, dir, 0.0, f32::INFINITY);
            assert_eq!(
                want.map(|h| (h.primitive, h.t)),
                got.map(|h| (h.primitive, h.t))
            );
        }
        hits += usize::from(want.is_some());
    }
    assert!(hits > 1000, "{hits} rays hit the grid");
    drop(shared);
    assert_eq!(
        Arc::strong_count(&mesh),
        1,
        "dropping the scene lets the mesh go"
    );
}

#[test]
fn a_shared_mesh_is_checked_like_a_copied_one() {
    let device = Device::new().unwrap();
    let (mut positions, triangles) = bumpy_grid(4);
    let mut past = triangles.clone();
    past[7][2] = positions.len() as u32;
    let mut builder = device.scene_builder().unwrap();
    let mesh = Arc::new(OwnedMesh::padded(positions.clone(), past));
    let err = builder.add_shared_triangles(mesh, None).unwrap_err();
    assert!(err.message.contains("indexes past 25 vertices"), "{err}");
    positions[3].y = f32::NAN;
    let mesh = Arc::new(OwnedMesh::padded(positions, triangles));
    let err = builder.add_shared_triangles(mesh, None).unwrap_err();
    assert!(err.message.contains("not finite"), "{err}");
    let empty = Arc::new(OwnedMesh::padded(Vec::new(), Vec::new()));
    assert!(builder.add_shared_triangles(empty, None).is_err());
}

fn straight_segment(radius: f32) -> [[f32; 4]; 4] {
    [-2.0, -2.0 / 3.0, 2.0 / 3.0, 2.0].map(|x| [x, 0.0, 0.0, radius])
}

/// A scene of one curve geometry: the straight segment of radius 0.5 (normals +z for a
/// normal-oriented one).
fn one_curve(device: &Device, kind: CurveKind) -> Scene {
    let mut builder = device.scene_builder().unwrap();
    let normals = [Vec3::Z; 4];
    let normals = (kind == CurveKind::NormalOriented).then_some(&normals[..]);
    builder
        .add_curves(kind, &straight_segment(0.5), &[0], normals)
        .unwrap();
    builder.commit().unwrap()
}

#[test]
fn a_ray_through_a_round_curve_s_axis_meets_it_a_radius_short_of_the_axis() {
    let device = Device::new().unwrap();
    let scene = one_curve(&device, CurveKind::Round);
    let hit = |o: Vec3, d: Vec3| scene.intersect(o, d, 0.0, f32::INFINITY);
    // Through the axis at x = 0.5: the tube's side at z = −0.5, 4.5 along the ray.
    let h = hit(Vec3::new(0.5, 0.0, -5.0), Vec3::Z).unwrap();
    assert!((h.t - 4.5).abs() < 1e-4, "{h:?}");
    assert_eq!((h.geometry, h.primitive, h.instance), (0, 0, None));
    assert!((h.u - 0.625).abs() < 1e-4, "{h:?}");
    // The normal is the surface's, outward (towards the ray's origin).
    assert!(h.normal.normalize().dot(-Vec3::Z) > 0.9999, "{h:?}");
    // Off the axis by 0.4: the circle of radius 0.5 is 0.3 deep there.
    let h = hit(Vec3::new(-1.0, 0.4, -5.0), Vec3::Z).unwrap();
    assert!((h.t - 4.7).abs() < 1e-4, "{h:?}");
    let n = h.normal.normalize();
    assert!((n - Vec3::new(0.0, 0.8, -0.6)).length() < 1e-3, "{h:?}");
    // Beside it, and past its end, rays miss; from inside, the tube is met on its way out.
    assert!(hit(Vec3::new(0.5, 0.55, -5.0), Vec3::Z).is_none());
    assert!(hit(Vec3::new(2.2, 0.0, -5.0), Vec3::Z).is_none());
    assert!(!scene.occluded(Vec3::new(0.5, 0.55, -5.0), Vec3::Z, 0.0, f32::INFINITY));
    let h = hit(Vec3::new(0.5, 0.0, 0.0), Vec3::Y).unwrap();
    assert!(
        (h.t - 0.5).abs() < 1e-4 && h.normal.dot(Vec3::Y) > 0.0,
        "{h:?}"
    );
}

#[test]
fn a_flat_curve_faces_every_ray_and_reports_its_tangent() {
    let device = Device::new().unwrap();
    let scene = one_curve(&device, CurveKind::Flat);
    let centre = Vec3::new(0.3, 0.0, 0.0);
    // Rays at the axis from all round it (and slanted along it) meet the band at the axis.
    for k in 0..12 {
        let angle = k as f32 * std::f32::consts::TAU / 12.0;
        let across = Vec3::new(0.0, angle.cos(), angle.sin());
        for slant in [0.0, 0.5] {
            let d = (-across + Vec3::new(slant, 0.0, 0.0)).normalize();
            let o = centre - 5.0 * d;
            let h = scene.intersect(o, d, 0.0, f32::INFINITY);
            let h = h.unwrap_or_else(|| panic!("missed from {o}"));
            assert!((h.t - 5.0).abs() < 1e-3, "{h:?} from {o}");
            assert!(h.normal.normalize().dot(Vec3::X) > 0.9999, "{h:?}");
            // Within the radius of the axis the band is there; beyond it, not.
            let side = across.cross(Vec3::X).normalize();
            let near = scene.intersect(o + 0.45 * side, d, 0.0, f32::INFINITY);
            assert!(near.is_some_and(|h| h.v.abs() > 0.85), "{near:?}");
            assert!(
                scene
                    .intersect(o + 0.55 * side, d, 0.0, f32::INFINITY)
                    .is_none()
            );
        }
    }
}

#[test]
fn a_normal_oriented_curve_is_a_band_across_its_normals() {
    let device = Device::new().unwrap();
    let scene = one_curve(&device, CurveKind::NormalOriented);
    let hit = |o: Vec3, d: Vec3| scene.intersect(o, d, 0.0, f32::INFINITY);
    // Normals +z: the band lies in z = 0, from y = −0.5 to 0.5, v from 0 to 1 across it.
    let h = hit(Vec3::new(0.5, 0.4, -5.0), Vec3::Z).unwrap();
    assert!(
        (h.t - 5.0).abs() < 1e-4 && (h.v - 0.9).abs() < 1e-3,
        "{h:?}"
    );
    assert!(h.normal.normalize().dot(Vec3::Z).abs() > 0.9999, "{h:?}");
    assert!(hit(Vec3::new(0.5, 0.6, -5.0), Vec3::Z).is_none());
    // Slanted, it is still met in its plane; edge on, it is not there.
    let d = Vec3::new(0.0, 1.0, 1.0).normalize();
    let h = hit(Vec3::new(0.5, -3.0, -3.0), d).unwrap();
    assert!((h.t - 3.0 * 2f32.sqrt()).abs() < 1e-3, "{h:?}");
    assert!(hit(Vec3::new(0.5, -5.0, 0.2), Vec3::Y).is_none());
}

#[test]
fn curves_hit_through_an_instance_report_the_instance() {
    let device = Device::new().unwrap();
    let prototype = Arc::new(one_curve(&device, CurveKind::Round));
    let mut top = device.scene_builder().unwrap();
    top.add_spheres(&[(Vec3::new(0.0, 0.0, 30.0), 1.0)])
        .unwrap();
    // Twice as large, 3 up.
    let m = glam::Mat4::from_translation(Vec3::new(0.0, 3.0, 0.0))
        * glam::Mat4::from_scale(Vec3::splat(2.0));
    let instance = top.add_instance(&prototype, m).unwrap();
    let scene = top.commit().unwrap();
    let h = scene
        .intersect(Vec3::new(1.0, 3.0, -10.0), Vec3::Z, 0.0, f32::INFINITY)
        .unwrap();
    // The tube (radius 1 now) is met at z = −1.
    assert!((h.t - 9.0).abs() < 1e-3, "{h:?}");
    assert_eq!(
        (h.instance, h.geometry, h.primitive),
        (Some(instance), 0, 0)
    );
    assert!(scene.occluded(Vec3::new(1.0, 3.0, -10.0), Vec3::Z, 0.0, 9.1));
    assert!(!scene.occluded(Vec3::new(1.0, 3.0, -10.0), Vec3::Z, 0.0, 8.9));
    assert!(
        scene
            .intersect(Vec3::new(1.0, 4.2, -10.0), Vec3::Z, 0.0, f32::INFINITY)
            .is_none()
    );
}

#[test]
fn malformed_curves_are_refused_before_embree_sees_them() {
    let device = Device::new().unwrap();
    let mut builder = device.scene_builder().unwrap();
    let good = straight_segment(0.5);
    let mut bad = |kind, points: &[[f32; 4]], first: &[u32], normals: Option<&[Vec3]>| {
        let err = builder
            .add_curves(kind, points, first, normals)
            .unwrap_err();
        assert_eq!(err.code, ErrorCode::Wrapper, "{err}");
        err.message
    };
    let mut not_finite = good;
    not_finite[1][2] = f32::NAN;
    let mut negative = good;
    negative[2][3] = -0.1;
    let flat = CurveKind::Flat;
    assert!(bad(flat, &good, &[], None).contains("at least one segment"));
    assert!(bad(flat, &not_finite, &[0], None).contains("not finite"));
    assert!(bad(flat, &negative, &[0], None).contains("negative radius"));
    assert!(bad(flat, &good, &[1], None).contains("run past 4"));
    assert!(bad(flat, &straight_segment(0.0), &[0], None).contains("no radius"));
    let normals = [Vec3::Z; 4];
    let oriented = CurveKind::NormalOriented;
    assert!(bad(oriented, &good, &[0], None).contains("needs a normal"));
    assert!(bad(oriented, &good, &[0], Some(&normals[..3])).contains("3 curve normals"));
    let zero = [Vec3::Z, Vec3::ZERO, Vec3::Z, Vec3::Z];
    assert!(bad(oriented, &good, &[0], Some(&zero)).contains("zero"));
    assert!(bad(CurveKind::Round, &good, &[0], Some(&normals)).contains("only normal-oriented"));
    // A curve tapering to a point is fine, and the builder is still usable.
    let mut taper = good;
    taper[3][3] = 0.0;
    builder.add_curves(flat, &taper, &[0], None).unwrap();
    builder.commit().unwrap();
}
