//! The PLY reader: a mesh comes back with finite positions and normals and every triangle
//! naming vertices the mesh has, or an error that names a header line or an element.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match dpm::scene::ply::parse(data) {
        Ok(mesh) => {
            let n = mesh.positions.len();
            assert!(mesh.positions.iter().all(|p| p.is_finite()));
            if let Some(normals) = &mesh.normals {
                assert_eq!(normals.len(), n);
                assert!(normals.iter().all(|p| p.is_finite()));
            }
            assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
        }
        Err(e) => assert!(!e.field.is_empty() && !e.message.is_empty(), "{e:?}"),
    }
});
