//! `dpm render` on bad input, through the built binary: every malformed scene in
//! tests/fixtures/bad/, bad parameters, bad output paths and bad photon map files each give
//! exit code 2 and a message naming the file (with line and field) or the flag, never a
//! panic, and never an output file.

mod reliability_support;

use reliability_support::*;
use std::path::{Path, PathBuf};

/// The scene error the library reports, as the binary must print it.
fn library_error(scene: &Path) -> dpm::scene::SceneError {
    match dpm::scene::load(scene) {
        Ok(_) => panic!("{} loads, but it is in bad/", scene.display()),
        Err(e) => e,
    }
}

#[test]
fn every_malformed_scene_exits_2_naming_file_line_and_field() {
    let bad = repo("tests/fixtures/bad");
    let out_dir = tempfile::tempdir().unwrap();
    let output = out_dir.path().join("never.png");
    let mut fixtures: Vec<PathBuf> = std::fs::read_dir(&bad)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    fixtures.sort();
    assert!(fixtures.len() >= 30, "only {} fixtures", fixtures.len());
    let mut failures = Vec::new();
    for scene in &fixtures {
        let name = scene.file_name().unwrap().to_string_lossy().into_owned();
        let out = dpm([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            output.as_os_str(),
        ]);
        let err = stderr(&out);
        let expected = library_error(scene);
        let Some(line) = expected.line else {
            failures.push(format!("{name}: the error names no line: {expected}"));
            continue;
        };
        let located = format!("{}:{line}: {}: ", expected.file.display(), expected.field);
        let problems = [
            (out.status.code() != Some(2), "exit code is not 2"),
            (err.contains("panicked"), "panicked"),
            (
                !err.contains(&format!("error: {expected}")),
                "not the scene error",
            ),
            (!err.contains(&located), "no file:line: field:"),
            (expected.field.is_empty(), "empty field"),
            (output.exists(), "wrote an output"),
        ];
        for (bad, what) in problems {
            if bad {
                failures.push(format!(
                    "{name}: {what} (exit {:?}): {err}",
                    out.status.code()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn missing_unreadable_and_directory_scenes_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("absent.toml");
    let out = dpm(["render".as_ref(), missing.as_os_str()]);
    assert_fails(
        &out,
        2,
        &["absent.toml", "cannot read the scene file"],
        "missing",
    );

    let out = dpm(["render".as_ref(), dir.path().as_os_str()]);
    assert_fails(&out, 2, &["is a directory"], "directory");

    // An OBJ nobody may read (skipped where permissions do not bind, e.g. as root).
    let obj = dir.path().join("locked.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let text = caustic_scene(1.0, 8, 8)
        + "\n[[objects]]\ntype = \"mesh\"\nfile = \"locked.obj\"\nmaterial = \"floor\"\n";
    let scene = write_scene(dir.path(), "locked.toml", &text);
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&obj, std::fs::Permissions::from_mode(0o000)).unwrap();
    if std::fs::File::open(&obj).is_err() {
        let out = dpm(["render".as_ref(), scene.as_os_str()]);
        assert_fails(
            &out,
            2,
            &["locked.toml:", "objects[4].file", "locked.obj"],
            "unreadable",
        );
    }
    std::fs::set_permissions(&obj, std::fs::Permissions::from_mode(0o644)).unwrap();
}

/// A valid scene with caustics, in a temporary folder.
struct Fixture {
    dir: tempfile::TempDir,
    scene: PathBuf,
}

impl Fixture {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let scene = write_scene(dir.path(), "scene.toml", &caustic_scene(1.0, 16, 12));
        Self { dir, scene }
    }
    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
    /// `dpm render scene.toml -o OUT` plus `args`, and cheap settings for the flags that
    /// `args` leaves out.
    fn render(&self, output: &Path, args: &[&str]) -> std::process::Output {
        let mut all: Vec<std::ffi::OsString> = vec!["render".into(), self.scene.clone().into()];
        all.extend(["-o".into(), output.as_os_str().to_owned()]);
        for (flag, value) in [
            ("--caustic-photons", "500"),
            ("--global-photons", "0"),
            ("--k", "20"),
        ] {
            if !args.contains(&flag) {
                all.extend([flag.into(), value.into()]);
            }
        }
        all.extend(args.iter().map(Into::into));
        dpm(all)
    }
}

/// `dpm merge` refuses what is not a film, a missing film, and an output it cannot write,
/// exit 2 naming the file.
#[test]
fn merge_refuses_bad_films_naming_them() {
    let f = Fixture::new();
    let not_a_film = f.path("not.film");
    std::fs::write(&not_a_film, b"PF\n1 1\n-1.0\n000000000000").unwrap();
    let out = f.path("m.png");
    let run = |args: &[&str]| dpm([&["merge"][..], args].concat());
    let cases: &[(&[&str], &[&str])] = &[
        (
            &[not_a_film.to_str().unwrap(), "-o", out.to_str().unwrap()],
            &["not.film", "not a dpm film"],
        ),
        (
            &["/no/such.film", "-o", out.to_str().unwrap()],
            &["/no/such.film"],
        ),
        (
            &[not_a_film.to_str().unwrap(), "-o", "/no/such/dir/m.png"],
            &["/no/such/dir"],
        ),
        (
            &[not_a_film.to_str().unwrap(), "-o", "m.bmp"],
            &["m.bmp", "extension"],
        ),
    ];
    for (args, fragments) in cases {
        let o = run(args);
        assert_fails(&o, 2, fragments, &format!("merge {args:?}"));
        assert!(!out.exists());
    }
}

#[test]
fn bad_parameters_exit_2_naming_the_flag() {
    let f = Fixture::new();
    let output = f.path("out.png");
    #[rustfmt::skip]
    let cases: &[(&[&str], &[&str])] = &[
        (&["--k", "0"], &["--k 0", "at least 2"]),
        (&["--k", "1"], &["--k 1", "at least 2"]),
        (&["--k", "-3"], &["'-3'", "--k"]),
        (&["--radius", "0"], &["--radius 0", "positive"]),
        (&["--radius", "-0.1"], &["--radius -0.1", "positive"]),
        (&["--radius", "NaN"], &["--radius NaN", "positive"]),
        (&["--radius", "inf"], &["--radius inf", "positive"]),
        (&["--gradient-radius", "-1"], &["--gradient-radius -1"]),
        (&["--smoothing-radius", "0"], &["--smoothing-radius 0"]),
        (&["--diffusivity", "-0.2"], &["--diffusivity -0.2"]),
        (&["--diffusivity", "NaN"], &["--diffusivity NaN"]),
        (&["--alpha", "0"], &["--alpha 0"]),
        (&["--lambda3", "0"], &["--lambda3 0"]),
        (&["--lambda2-floor", "2"], &["--lambda2-floor 2"]),
        (&["--cone-slope", "0.5"], &["--cone-slope 0.5"]),
        (&["--global-k", "1"], &["--global-k 1"]),
        (&["--spp", "0"], &["--spp 0"]),
        (&["--light-samples", "0"], &["--light-samples 0", "from 1 to 4096"]),
        (&["--light-samples", "100000"], &["--light-samples 100000", "from 1 to 4096"]),
        (&["--light-samples", "-1"], &["'-1'", "--light-samples"]),
        (&["--irradiance-stride", "1000000"], &["--irradiance-stride 1000000", "0 (off)"]),
        (&["--irradiance-stride", "-4"], &["'-4'", "--irradiance-stride"]),
        (&["--guide-paths", "200000000"], &["--guide-paths 200000000", "0 (off) to 100000000"]),
        (&["--guide-paths", "-1"], &["'-1'", "--guide-paths"]),
        (&["--caustic-photons", "-5"], &["'-5'", "--caustic-photons"]),
        (&["--caustic-photons", "lots"], &["'lots'", "--caustic-photons"]),
        (&["--estimator", "magic"], &["'magic'", "--estimator"]),
        (&["--load-photons", "/no/such/file.photons"], &["--load-photons /no/such/file.photons", "does not exist"]),
        (&["--save-photons", "/no/such/dir/x.photons"], &["--save-photons", "/no/such/dir", "does not exist"]),
        (&["--passes", "0"], &["--passes 0", "at least one pass"]),
        (&["--passes", "-2"], &["'-2'", "--passes"]),
        (&["--time", "0"], &["--time 0", "positive"]),
        (&["--time", "NaN"], &["--time NaN", "positive"]),
        (&["--time", "-5"], &["--time -5", "positive"]),
        (&["--ppm-alpha", "1"], &["--ppm-alpha 1", "(0, 1)"]),
        (&["--ppm-alpha", "0"], &["--ppm-alpha 0", "(0, 1)"]),
        (&["--write-every", "-1"], &["--write-every -1"]),
        (&["--min-kernel-photons", "-1"], &["--min-kernel-photons -1"]),
        (&["--edge-cut", "--tensor-history", "0"], &["--edge-cut with --tensor-history 0", "earlier passes"]),
        (&["--edge-cut", "--kernel", "gaussian"], &["--edge-cut with --kernel gaussian", "epanechnikov"]),
        (&["--edge-cut", "--estimator", "epanechnikov"], &["--edge-cut with --estimator epanechnikov", "diffusion"]),
        (&["--first-pass", "999999", "--passes", "5"], &["--first-pass 999999", "1000000 passes"]),
        (&["--resume", "/no/such/film"], &["--resume /no/such/film", "does not exist"]),
        (&["--passes", "4", "--save-photons", "x.photons"], &["--save-photons", "one pass"]),
        (&["--reference", "/no/such/ref.pfm"], &["--reference /no/such/ref.pfm", "does not exist"]),
        (&["--resolution", "640"], &["'640'", "--resolution", "WIDTHxHEIGHT"]),
        (&["--resolution", "0x480"], &["'0x480'", "--resolution", "at least 1 pixel"]),
        (&["--resolution", "640x0"], &["'640x0'", "--resolution", "at least 1 pixel"]),
        (&["--resolution", "-640x480"], &["'-640x480'", "--resolution", "whole number"]),
        (&["--resolution", "640xlots"], &["'640xlots'", "--resolution", "whole number"]),
        (&["--resolution", "1e3x480"], &["'1e3x480'", "--resolution", "whole number"]),
    ];
    for (args, fragments) in cases {
        let out = f.render(&output, args);
        assert_fails(&out, 2, fragments, &format!("{args:?}"));
        assert!(!output.exists(), "{args:?} wrote an output");
    }
}

#[test]
fn absurd_thread_counts_exit_2_at_once_naming_the_flag() {
    let f = Fixture::new();
    let output = f.path("out.png");
    let start = std::time::Instant::now();
    let out = f.render(&output, &["--threads", "100000"]);
    assert_fails(&out, 2, &["--threads 100000", "1024"], "render --threads");
    assert!(!output.exists());
    let (csv, svg) = (f.path("t.csv"), f.path("t.svg"));
    let out = dpm([
        "tradeoff".as_ref(),
        "--quick".as_ref(),
        "--threads".as_ref(),
        "5000".as_ref(),
        "--csv".as_ref(),
        csv.as_os_str(),
        "--svg".as_ref(),
        svg.as_os_str(),
    ]);
    assert_fails(&out, 2, &["--threads 5000", "1024"], "tradeoff --threads");
    assert!(!csv.exists() && !svg.exists());
    // Refused before any thread is spawned, not after minutes of trying.
    assert!(start.elapsed().as_secs() < 30, "{:?}", start.elapsed());
    // The bound itself is allowed.
    let out = f.render(&output, &["--threads", "1024"]);
    assert_succeeds(&out, "render --threads 1024");
}

#[test]
fn version_names_the_embree_in_use() {
    let out = dpm(["--version"]);
    assert_succeeds(&out, "dpm --version");
    let text = String::from_utf8_lossy(&out.stdout);
    let major = if cfg!(feature = "embree4") { 4 } else { 3 };
    assert!(
        text.starts_with(&format!(
            "dpm {} (Embree {major}.",
            env!("CARGO_PKG_VERSION")
        )),
        "{text}"
    );
    assert!(text.contains(&dpm::embree::version_string()), "{text}");
}

#[test]
fn bad_output_paths_exit_2() {
    let f = Fixture::new();
    #[rustfmt::skip]
    let cases: &[(PathBuf, &[&str])] = &[
        (f.path("no/such/dir/out.png"), &["out.png", "directory", "does not exist"]),
        (f.path("out.bmp"), &["out.bmp", "unknown image extension \"bmp\""]),
        (f.path("out"), &["unknown image extension"]),
        (f.path("out.png.tmp"), &["unknown image extension \"tmp\""]),
    ];
    for (output, fragments) in cases {
        let out = f.render(output, &[]);
        assert_fails(&out, 2, fragments, &output.display().to_string());
        assert!(!output.exists());
    }
    // --save-photons must not overwrite the image it renders.
    let output = f.path("out.pfm");
    let o = output.to_str().unwrap();
    let out = f.render(&output, &["--save-photons", o]);
    assert_fails(
        &out,
        2,
        &["--save-photons", "is also the output image"],
        "same file",
    );
}

#[test]
fn photon_counts_that_cannot_fit_in_memory_are_refused_before_tracing() {
    let f = Fixture::new();
    let output = f.path("out.png");
    for (flag, count) in [
        ("--caustic-photons", "100000000000"),
        ("--global-photons", "18446744073709551615"),
    ] {
        let start = std::time::Instant::now();
        let out = f.render(&output, &[flag, count]);
        assert_fails(
            &out,
            2,
            &[
                &format!("{flag} {count}"),
                "would need about",
                "is available",
                "lower the photon counts",
            ],
            flag,
        );
        assert!(
            start.elapsed().as_secs() < 30,
            "{flag}: refused only after {:?}",
            start.elapsed()
        );
        assert!(!output.exists());
    }
    // A caustic map that only grows that large late in the render is refused up front too,
    // and a render that ends before it grows is not.
    let grown = [
        "--caustic-photons",
        "1000000",
        "--caustic-photons-max",
        "100000000000",
    ];
    let out = f.render(&output, &[&grown[..], &["--passes", "100000"]].concat());
    assert_fails(
        &out,
        2,
        &[
            "--caustic-photons 1000000 (growing to 12499875000 a pass by pass 99999, \
             --caustic-photons-max 100000000000)",
            "would need about",
        ],
        "growth",
    );
    assert!(!output.exists());
    let small = ["--caustic-photons-max", "100000000000", "--passes", "2"];
    assert_succeeds(&f.render(&output, &small), "no growth before pass 9");
    // The image counts too: 4e9 x 4e9 pixels is refused before rendering.
    let huge = caustic_scene(1.0, 4_000_000_000, 4_000_000_000);
    let scene = write_scene(f.dir.path(), "huge.toml", &huge);
    let out = dpm([
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
    ]);
    assert_fails(
        &out,
        2,
        &["a 4000000000x4000000000 image", "would need about"],
        "huge image",
    );
}

#[test]
fn photon_files_save_load_and_refuse_foreign_truncated_corrupt_or_mismatched_ones() {
    let f = Fixture::new();
    let photons = f.path("maps.photons");
    let p = photons.to_str().unwrap();
    let traced = f.path("traced.pfm");
    assert_succeeds(&f.render(&traced, &["--save-photons", p]), "save");
    let loaded = f.path("loaded.pfm");
    let out = f.render(&loaded, &["--load-photons", p]);
    assert_succeeds(&out, "load");
    let err = stderr(&out);
    assert!(
        err.contains("load photons") && !err.contains("trace caustic"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(&traced).unwrap(),
        std::fs::read(&loaded).unwrap()
    );

    // Another view of the same scene may reuse the maps.
    let good = std::fs::read(&photons).unwrap();
    let other = f.path("other.pfm");

    // Made for another render: refused, naming the file and what differs.
    #[rustfmt::skip]
    let mismatches: &[(&[&str], &str)] = &[
        (&["--caustic-photons", "501"], "this render asks for --caustic-photons 501"),
        (&["--seed", "2"], "this render uses --seed 2"),
        (&["--global-photons", "100"], "holds no global map"),
    ];
    for (args, fragment) in mismatches {
        let mut all = vec!["--load-photons", p];
        all.extend_from_slice(args);
        let out = f.render(&other, &all);
        assert_fails(&out, 2, &["maps.photons", fragment], fragment);
    }
    let moved =
        caustic_scene(1.0, 16, 12).replace("power = [6e1, 6e1, 6e1]", "power = [6e1, 6e1, 7e1]");
    assert_ne!(moved, caustic_scene(1.0, 16, 12));
    let moved = write_scene(f.dir.path(), "moved.toml", &moved);
    let out = dpm([
        "render".as_ref(),
        moved.as_os_str(),
        "-o".as_ref(),
        other.as_os_str(),
        "--caustic-photons".as_ref(),
        "500".as_ref(),
        "--global-photons".as_ref(),
        "0".as_ref(),
        "--load-photons".as_ref(),
        photons.as_os_str(),
    ]);
    assert_fails(&out, 2, &["maps.photons", "another scene"], "another scene");

    // Broken files.
    let mut corrupt = good.clone();
    corrupt[200] ^= 1;
    let mut version = good.clone();
    version[8] = 9;
    let cases: &[(&[u8], &[&str])] = &[
        (&good[..good.len() / 2], &["truncated"]),
        (&good[..5], &["truncated"]),
        (b"P3\n1 1\n255\n0 0 0\n", &["not a dpm photon map file"]),
        (&corrupt, &["corrupt", "checksum"]),
        (&version, &["format version 9"]),
    ];
    let broken = f.path("broken.photons");
    for (bytes, fragments) in cases {
        std::fs::write(&broken, bytes).unwrap();
        let out = f.render(&other, &["--load-photons", broken.to_str().unwrap()]);
        let mut all = vec!["broken.photons"];
        all.extend_from_slice(fragments);
        assert_fails(&out, 2, &all, fragments[0]);
        assert!(!other.exists());
    }
    // The good file was never touched.
    assert_eq!(std::fs::read(&photons).unwrap(), good);
}

/// A light sealed inside a closed opaque object is a warning, not an error: with the camera
/// inside too (a closed room) or with glass around the light, there is nothing to say.
#[test]
fn light_inside_a_closed_opaque_object_is_a_warning_not_an_error() {
    let dir = tempfile::tempdir().unwrap();
    // A closed unit cube around the origin, wound outwards.
    let cube = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
                f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\n\
                f 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";
    std::fs::write(dir.path().join("cube.obj"), cube).unwrap();
    let scene = |camera: &str, object: &str| {
        format!(
            "[camera]\nposition = {camera}\nlook_at = [0, 0, 0.1]\nup = [0, 1, 0]\nfov_y = 40\n\
             resolution = [8, 6]\n\n[[lights]]\ntype = \"point\"\nposition = [0.1, 0.2, 0.3]\n\
             power = [10, 10, 10]\n\n[materials.white]\ntype = \"diffuse\"\n\
             albedo = [0.5, 0.5, 0.5]\n\n[materials.glass]\ntype = \"glass\"\nior = 1.5\n\n\
             [[objects]]\n{object}\n"
        )
    };
    let sphere = |m: &str| {
        format!("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.5\nmaterial = \"{m}\"")
    };
    let mesh = |m: &str| format!("type = \"mesh\"\nfile = \"cube.obj\"\nmaterial = \"{m}\"");
    let outside = "[0, 1, 6]";
    let inside = "[0.5, 0.5, -0.5]";
    #[rustfmt::skip]
    let cases = [
        (outside, sphere("white"), Some("inside an opaque sphere")),
        (outside, mesh("white"), Some("inside a closed opaque mesh")),
        (inside, sphere("white"), None),
        (inside, mesh("white"), None),
        (outside, sphere("glass"), None),
        (outside, mesh("glass"), None),
    ];
    let source = dir.path().join("scene.toml");
    for (camera, object, warning) in &cases {
        let (_, report) = dpm::scene::parse(&scene(camera, object), &source).unwrap();
        match warning {
            Some(w) => {
                assert_eq!(report.warnings.len(), 1, "{object}: {:?}", report.warnings);
                assert!(
                    report.warnings[0].contains("lights[0]"),
                    "{:?}",
                    report.warnings
                );
                assert!(report.warnings[0].contains(w), "{:?}", report.warnings);
            }
            None => assert!(
                report.warnings.is_empty(),
                "{camera} {object}: {:?}",
                report.warnings
            ),
        }
    }
    // Through the binary: exit 0, the warning on stderr naming the scene file.
    let path = write_scene(dir.path(), "sealed.toml", &scene(outside, &mesh("white")));
    let output = dir.path().join("sealed.pfm");
    let out = dpm([
        "render".as_ref(),
        path.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
    ]);
    assert_succeeds(&out, "sealed light");
    let err = stderr(&out);
    assert!(
        err.contains("warning: ") && err.contains("sealed.toml: lights[0] is inside"),
        "{err}"
    );
}

#[test]
fn the_shipped_scenes_give_no_warnings() {
    for entry in std::fs::read_dir(repo("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|x| x == "toml") {
            let (_, report) = dpm::scene::load_with_report(&path).unwrap();
            assert!(
                report.warnings.is_empty(),
                "{}: {:?}",
                path.display(),
                report.warnings
            );
        }
    }
}
