//! Unit tests of the photon-map file format.
use super::*;
use glam::Vec3;

fn photon(i: u32) -> Photon {
    // Repeated coordinates on purpose: ties must not change the rebuilt tree.
    let f = |k: u32| ((i * k) % 7) as f32 * 0.25;
    Photon::new(
        Vec3::new(f(3), f(5), (i % 3) as f32),
        Vec3::new(0.001 * (i % 11 + 1) as f32, 0.002, 0.003),
        Vec3::new(0.3, -1.0, 0.1).normalize(),
        Vec3::Y,
    )
}

fn map(n: u32, emitted: u64) -> PhotonMap {
    PhotonMap::build((0..n).map(photon).collect(), emitted)
}

const CAUSTIC: MapInfo = MapInfo {
    kind: MapKind::Caustic,
    target: 500,
    guide: 0,
};
const GLOBAL: MapInfo = MapInfo {
    kind: MapKind::Global { with_direct: true },
    target: 300,
    guide: 0,
};

/// A file with a 500-photon caustic map and a 300-photon global map.
fn sample_file(dir: &Path) -> (PathBuf, PhotonMap, PhotonMap) {
    let path = dir.join("maps.photons");
    let (c, g) = (map(500, 9000), map(300, 1234));
    let size = write(&path, 42, 7, &[(CAUSTIC, &c), (GLOBAL, &g)]).unwrap();
    assert_eq!(size, std::fs::metadata(&path).unwrap().len());
    assert_eq!(size, 32 + 2 * 32 + 800 * 20 + 8);
    (path, c, g)
}

fn same_map(a: &PhotonMap, b: &PhotonMap) {
    assert!(a.photons().eq(b.photons()));
    assert_eq!(a.emitted, b.emitted);
    for s in 0..a.len() {
        assert_eq!(a.tree().source_index(s), b.tree().source_index(s));
    }
}

#[test]
fn store_round_trip_rebuilds_the_same_maps() {
    let dir = tempfile::tempdir().unwrap();
    let (path, c, g) = sample_file(dir.path());
    let mut file = read(&path).unwrap();
    assert_eq!((file.scene, file.seed), (42, 7));
    assert_eq!(file.maps.len(), 2);
    assert_eq!(file.maps[0].info, CAUSTIC);
    assert_eq!(file.maps[1].info, GLOBAL);
    file.check_fits(42, 7, &[CAUSTIC, GLOBAL]).unwrap();
    same_map(&file.take(MapKind::Caustic).unwrap(), &c);
    same_map(&file.take(GLOBAL.kind).unwrap(), &g);
    assert!(file.take(MapKind::Caustic).is_none());
}

#[test]
fn store_empty_and_mapless_files_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("none.photons");
    write(&path, 1, 2, &[]).unwrap();
    let file = read(&path).unwrap();
    assert!(file.maps.is_empty());
    write(&path, 1, 2, &[(CAUSTIC, &PhotonMap::build(Vec::new(), 0))]).unwrap();
    let file = read(&path).unwrap();
    assert!(file.maps[0].map.is_empty());
}

#[test]
fn store_photon_bytes_are_little_endian_field_by_field() {
    let p = Photon::new(Vec3::new(1.0, -2.0, 0.5), Vec3::ONE, Vec3::Z, Vec3::Y);
    let b = p.to_le_bytes();
    assert_eq!(b[0..4], 1.0f32.to_le_bytes());
    assert_eq!(b[4..8], (-2.0f32).to_le_bytes());
    assert_eq!(b[8..12], 0.5f32.to_le_bytes());
    assert_eq!(Photon::from_le_bytes(b), p);
}

#[test]
fn store_refuses_truncated_files() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ..) = sample_file(dir.path());
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.photons");
    for len in [
        0,
        3,
        8,
        11,
        12,
        31,
        32,
        63,
        96,
        97,
        1000,
        bytes.len() - 8,
        bytes.len() - 1,
    ] {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        match read(&cut) {
            Err(StoreError::Truncated {
                path,
                expected,
                actual,
            }) => {
                assert_eq!(path, cut);
                assert_eq!(actual, len as u64);
                assert!(expected > actual);
            }
            other => panic!("cut at {len}: {other:?}"),
        }
    }
    let e = read(&cut).unwrap_err().to_string();
    assert!(e.contains("cut.photons") && e.contains("truncated"), "{e}");
}

#[test]
fn store_refuses_foreign_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("image.png");
    for bytes in [
        &b"\x89PNG\r\n\x1a\n0000000000000000000000000000000000000000"[..],
        b"PF\n2 2\n-1.0\n",
        b"X",
        b"DPMPHMAQ and more",
    ] {
        std::fs::write(&path, bytes).unwrap();
        let e = read(&path).unwrap_err();
        assert!(matches!(e, StoreError::Foreign { .. }), "{e:?}");
        assert!(e.to_string().contains("image.png"), "{e}");
        assert!(e.to_string().contains("not a dpm photon map"), "{e}");
    }
}

#[test]
fn store_refuses_other_versions() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ..) = sample_file(dir.path());
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[8..12].copy_from_slice(&2u32.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let e = read(&path).unwrap_err();
    assert!(
        matches!(
            e,
            StoreError::UnsupportedVersion {
                found: 2,
                supported: 1,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("version 2"), "{e}");
}

#[test]
fn store_refuses_corrupt_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ..) = sample_file(dir.path());
    let good = std::fs::read(&path).unwrap();
    // Flip one bit anywhere after the version: header fields, photons or the checksum.
    for at in [13, 17, 29, 40, 100, 5000, good.len() - 9, good.len() - 1] {
        let mut bytes = good.clone();
        bytes[at] ^= 0x10;
        std::fs::write(&path, &bytes).unwrap();
        let e = read(&path).unwrap_err();
        let ok = match &e {
            StoreError::Checksum { .. } => true,
            // A flipped count makes the size disagree with the header.
            StoreError::Truncated { .. } | StoreError::Corrupt { .. } => at < 96,
            _ => false,
        };
        assert!(ok, "flip at {at}: {e:?}");
    }
    let mut bytes = good.clone();
    bytes.push(0);
    std::fs::write(&path, &bytes).unwrap();
    let e = read(&path).unwrap_err();
    assert!(matches!(e, StoreError::Corrupt { .. }), "{e:?}");
    assert!(e.to_string().contains("1 bytes after the end"), "{e}");
}

#[test]
fn store_refuses_missing_files_and_directories() {
    let dir = tempfile::tempdir().unwrap();
    for path in [dir.path().join("absent.photons"), dir.path().to_path_buf()] {
        let e = read(&path).unwrap_err();
        assert!(matches!(e, StoreError::Read { .. }), "{e:?}");
        assert!(e.to_string().contains(&*path.to_string_lossy()), "{e}");
    }
    let e = write(&dir.path().join("no/such/dir/x.photons"), 0, 0, &[]).unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
    assert_eq!(e.exit_code(), 2);
}

#[test]
fn store_refuses_maps_made_for_another_render() {
    let dir = tempfile::tempdir().unwrap();
    let (path, ..) = sample_file(dir.path());
    let file = read(&path).unwrap();
    let global_off = MapInfo {
        kind: MapKind::Global { with_direct: false },
        ..GLOBAL
    };
    let more = MapInfo {
        target: 501,
        ..CAUSTIC
    };
    let guided = MapInfo {
        guide: 50_000,
        ..CAUSTIC
    };
    let cases: &[(u64, u64, &[MapInfo], &str)] = &[
        (43, 7, &[CAUSTIC, GLOBAL], "another scene"),
        (
            42,
            8,
            &[CAUSTIC, GLOBAL],
            "--seed 7, this render uses --seed 8",
        ),
        (
            42,
            7,
            &[more, GLOBAL],
            "--caustic-photons 500, this render asks for --caustic-photons 501",
        ),
        (42, 7, &[CAUSTIC, global_off], "--final-gather"),
        (
            42,
            7,
            &[guided, GLOBAL],
            "--guide-paths 0, this render uses --guide-paths 50000",
        ),
        (42, 7, &[CAUSTIC], "holds a global map"),
        (42, 7, &[GLOBAL], "holds a caustic map"),
    ];
    for &(scene, seed, wanted, fragment) in cases {
        let e = file.check_fits(scene, seed, wanted).unwrap_err();
        assert!(matches!(e, StoreError::Mismatch { .. }), "{e:?}");
        let message = e.to_string();
        assert!(message.contains(fragment), "{message}");
        assert!(message.contains("maps.photons"), "{message}");
    }
    // A guided map keeps its pilot count and fits only a render with the same.
    write(&path, 42, 7, &[(guided, &map(10, 20))]).unwrap();
    let file = read(&path).unwrap();
    assert_eq!(file.maps[0].info, guided);
    file.check_fits(42, 7, &[guided]).unwrap();
    assert!(file.check_fits(42, 7, &[CAUSTIC]).is_err());
    write(&path, 42, 7, &[]).unwrap();
    let e = read(&path)
        .unwrap()
        .check_fits(42, 7, &[CAUSTIC])
        .unwrap_err();
    assert!(e.to_string().contains("holds no caustic map"), "{e}");
}

#[test]
fn store_scene_fingerprint_follows_what_tracing_sees() {
    let text = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\n\
                fov_y = 40\nresolution = [64, 48]\n\n[[lights]]\ntype = \"point\"\n\
                position = [0.0, 3.0, 0.0]\npower = [10, 10, 10]\n\n[materials.white]\n\
                type = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\n[[objects]]\n\
                type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"white\"\n";
    let fp = |t: &str| {
        let (scene, _) = crate::scene::parse(t, Path::new("x.toml")).unwrap();
        scene_fingerprint(&scene)
    };
    let base = fp(text);
    assert_eq!(base, fp(text));
    assert_eq!(
        base,
        fp(&text.replace("resolution = [64, 48]", "resolution = [8, 8]"))
    );
    assert_eq!(base, fp(&text.replace("fov_y = 40", "fov_y = 60")));
    assert_ne!(
        base,
        fp(&text.replace("power = [10, 10, 10]", "power = [10, 10, 11]"))
    );
    assert_ne!(base, fp(&text.replace("radius = 1", "radius = 1.0001")));
    assert_ne!(base, fp(&text.replace("albedo = [0.5,", "albedo = [0.6,")));
}
