//! `dpm tradeoff` and `dpm reference`: the Pareto front against brute force, the plot's SVG,
//! a quick sweep's CSV (columns, timing sums, errors falling with more photons), the reference
//! cache (reused when nothing changed, remade when the scene file changes) and bad flags
//! (exit 2, naming the flag).

mod reliability_support;

use dpm::tradeoff::pareto::pareto_front;
use dpm::tradeoff::svg::{Series, plot};
use proptest::prelude::*;
use reliability_support::*;
use std::collections::HashMap;
use std::path::Path;

/// The front by definition: points no other point beats on both coordinates.
fn brute_force_front(points: &[(f64, f64)]) -> Vec<usize> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    (0..points.len())
        .filter(|&i| finite(&points[i]))
        .filter(|&i| {
            let (t, e) = points[i];
            !points
                .iter()
                .filter(|p| finite(p))
                .any(|&(tj, ej)| tj <= t && ej <= e && (tj < t || ej < e))
        })
        .collect()
}

proptest! {
    #[test]
    fn pareto_front_matches_brute_force(
        // Small integers make ties in time, in error and whole duplicates common.
        coarse in prop::collection::vec((0u8..8, 0u8..8), 0..40),
        fine in prop::collection::vec((0.0f64..100.0, 0.0f64..1.0), 0..40),
    ) {
        for points in [
            coarse.iter().map(|&(t, e)| (t as f64, e as f64)).collect::<Vec<_>>(),
            fine.clone(),
        ] {
            let front = pareto_front(&points);
            let mut sorted = front.clone();
            sorted.sort_unstable();
            prop_assert_eq!(sorted, brute_force_front(&points));
            // In time order, a front's errors fall (or stay, for duplicates).
            for pair in front.windows(2) {
                let (a, b) = (points[pair[0]], points[pair[1]]);
                prop_assert!(a.0 <= b.0 && a.1 >= b.1, "{:?} then {:?}", a, b);
            }
        }
    }
}

/// Checks that every tag is closed in order, attributes are quoted and no bare `&` or `<`
/// appears in text: enough of XML well-formedness for what the plot writes.
fn assert_well_formed(svg: &str) {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = svg;
    while let Some(open) = rest.find('<') {
        let text = &rest[..open];
        assert!(!text.contains('>'), "stray > in text {text:?}");
        for (i, _) in text.match_indices('&') {
            let entity = &text[i..];
            assert!(
                ["&amp;", "&lt;", "&gt;", "&quot;"]
                    .iter()
                    .any(|e| entity.starts_with(e)),
                "bare & in {text:?}"
            );
        }
        let close = rest[open..].find('>').expect("unclosed tag") + open;
        let tag = &rest[open + 1..close];
        assert!(!tag.contains('<'), "< inside tag {tag:?}");
        assert_eq!(
            tag.matches('"').count() % 2,
            0,
            "unbalanced quotes in {tag:?}"
        );
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.trim()),
                "mismatched </{name}>"
            );
        } else if !tag.ends_with('/') {
            let name = tag.split_whitespace().next().expect("tag name");
            stack.push(name.to_string());
        }
        rest = &rest[close + 1..];
    }
    assert!(rest.trim().is_empty(), "text after the root: {rest:?}");
    assert!(stack.is_empty(), "unclosed {stack:?}");
}

/// The `data-estimate` names of the plot's front polylines.
fn fronts_in(svg: &str) -> Vec<String> {
    svg.lines()
        .filter(|l| l.contains("<polyline class=\"front\""))
        .map(|l| {
            let start = l.find("data-estimate=\"").unwrap() + "data-estimate=\"".len();
            l[start..start + l[start..].find('"').unwrap()].to_string()
        })
        .collect()
}

#[test]
fn plot_is_well_formed_with_one_front_per_series() {
    let series = vec![
        Series {
            name: "cone".into(),
            points: vec![(0.5, 0.3), (1.0, 0.2), (2.0, 0.25)],
            front: vec![0, 1],
        },
        Series {
            name: "a & <b>".into(),
            points: vec![(0.1, 0.5), (10.0, 0.1)],
            front: vec![0, 1],
        },
        Series {
            name: "diffusion".into(),
            points: vec![(3.0, f64::NAN), (4.0, 0.05)],
            front: vec![1],
        },
    ];
    let svg = plot("title with <angle> & amp", "seconds", "RMSE", &series);
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
    assert_well_formed(&svg);
    assert_eq!(fronts_in(&svg), ["cone", "a &amp; &lt;b&gt;", "diffusion"]);
    assert!(!svg.contains("NaN") && !svg.contains("inf"), "{svg}");
    // Front polylines hold one point per front member.
    let cone = svg
        .lines()
        .find(|l| l.contains("front\" data-estimate=\"cone\""))
        .unwrap();
    let points = &cone[cone.find("points=\"").unwrap() + 8..];
    assert_eq!(points[..points.find('"').unwrap()].split(' ').count(), 2);
}

/// The CSV as header names and rows of cells.
fn read_csv(path: &Path) -> (Vec<String>, Vec<HashMap<String, String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{l}");
            header
                .iter()
                .cloned()
                .zip(cells.iter().map(|c| c.to_string()))
                .collect()
        })
        .collect();
    (header, rows)
}

fn number(row: &HashMap<String, String>, column: &str) -> f64 {
    row[column]
        .parse()
        .unwrap_or_else(|_| panic!("{column} = {:?}", row[column]))
}

#[test]
fn quick_constructed_sweep_writes_consistent_rows() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg) = (dir.path().join("c.csv"), dir.path().join("c.svg"));
    let out = dpm([
        "tradeoff".as_ref(),
        "--quick".as_ref(),
        "--csv".as_ref(),
        csv.as_os_str(),
        "--svg".as_ref(),
        svg.as_os_str(),
    ]);
    assert_succeeds(&out, "dpm tradeoff --quick");
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("| estimate | photons |"), "{table}");

    let (header, rows) = read_csv(&csv);
    let expected = [
        "target",
        "estimate",
        "photons",
        "k",
        "radius",
        "gradient_radius",
        "diffusivity",
        "trace_seconds",
        "prepare_seconds",
        "estimate_seconds",
        "total_seconds",
        "rmse",
        "relative_mse",
        "edge_band_rmse",
        "flat_noise",
        "passes",
    ];
    assert_eq!(header, expected);
    // Quick preset: 2 counts × (2 cone k + 1 Epanechnikov radius + 1 diffusion radius × 1 K).
    assert_eq!(rows.len(), 8);
    for r in &rows {
        assert_eq!(r["target"], "constructed");
        let phases = ["trace_seconds", "prepare_seconds", "estimate_seconds"];
        let sum: f64 = phases.iter().map(|c| number(r, c)).sum();
        assert!((number(r, "total_seconds") - sum).abs() < 1e-5, "{r:?}");
        for c in ["rmse", "relative_mse", "edge_band_rmse", "flat_noise"] {
            let v = number(r, c);
            assert!(v.is_finite() && v >= 0.0, "{c} = {v}");
        }
        match r["estimate"].as_str() {
            "cone" => assert!(number(r, "k") >= 2.0 && r["radius"].is_empty()),
            "epanechnikov" => assert!(number(r, "radius") > 0.0 && r["k"].is_empty()),
            "diffusion" => {
                assert!(
                    number(r, "prepare_seconds") > 0.0,
                    "the gradient pass is timed"
                );
                assert!(number(r, "gradient_radius") > 0.0 && number(r, "diffusivity") >= 0.0);
            }
            other => panic!("unexpected estimate {other}"),
        }
        if r["estimate"] != "diffusion" {
            assert_eq!(number(r, "prepare_seconds"), 0.0);
        }
    }
    // Each count's map is traced once: every run of a count shares its trace time.
    let mut trace: HashMap<&str, f64> = HashMap::new();
    for r in &rows {
        let t = *trace
            .entry(r["photons"].as_str())
            .or_insert(number(r, "trace_seconds"));
        assert_eq!(t, number(r, "trace_seconds"));
    }
    // 8× the photons: the same setting (same k, or the same multiple of the default radius)
    // must not get worse. Deterministic seeds; the smallest margin measured was 9% (cone k=20 RMSE).
    let setting =
        |r: &HashMap<String, String>| format!("{} {} {}", r["estimate"], r["k"], r["diffusivity"]);
    for few in rows.iter().filter(|r| r["photons"] == "5000") {
        let many = rows
            .iter()
            .find(|r| r["photons"] == "40000" && setting(r) == setting(few))
            .unwrap();
        for c in ["rmse", "edge_band_rmse"] {
            assert!(
                number(many, c) <= number(few, c),
                "{} {c}: {} photons {} vs {} photons {}",
                setting(few),
                few["photons"],
                few[c],
                many["photons"],
                many[c]
            );
        }
    }
    let svg = std::fs::read_to_string(&svg).unwrap();
    assert_well_formed(&svg);
    assert_eq!(fronts_in(&svg), ["cone", "epanechnikov", "diffusion"]);
}

/// `dpm reference` with tiny settings; returns stdout.
fn reference(scene: &Path, cache: &Path) -> String {
    let out = dpm([
        "reference".as_ref(),
        scene.as_os_str(),
        "--photons".as_ref(),
        "20000".as_ref(),
        "--width".as_ref(),
        "32".as_ref(),
        "--height".as_ref(),
        "24".as_ref(),
        "--cache-dir".as_ref(),
        cache.as_os_str(),
    ]);
    assert_succeeds(&out, "dpm reference");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The cache file a `dpm reference` line names.
fn cached_file(line: &str) -> std::path::PathBuf {
    let start = line.find(' ').unwrap() + 1;
    let path = line[start..].split_whitespace().nth(1).unwrap();
    std::path::PathBuf::from(path)
}

#[test]
fn reference_is_cached_reused_and_remade_when_the_scene_changes() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let scene = write_scene(dir.path(), "caustic.toml", &caustic_scene(1.0, 32, 24));

    let first = reference(&scene, &cache);
    assert!(first.starts_with("reference: rendered "), "{first}");
    let file = cached_file(&first);
    assert!(
        file.starts_with(&cache) && file.extension().unwrap() == "pfm",
        "{first}"
    );
    // Dated far back, so a rewrite would show whatever the file system's clock resolution.
    let made = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_000_000_000);
    std::fs::File::options()
        .append(true)
        .open(&file)
        .unwrap()
        .set_modified(made)
        .unwrap();
    let (w, h, pixels) = pfm_pixels(&file);
    assert_eq!((w, h), (32, 24));
    assert!(
        pixels.iter().any(|v| *v > 0.0),
        "the reference holds a caustic"
    );

    let second = reference(&scene, &cache);
    assert!(second.starts_with("reference: reused "), "{second}");
    assert_eq!(cached_file(&second), file);
    assert_eq!(std::fs::metadata(&file).unwrap().modified().unwrap(), made);

    // The sweep finds the same cache entry when it asks for the same settings.
    let (csv, svg) = (dir.path().join("s.csv"), dir.path().join("s.svg"));
    let out = dpm([
        "tradeoff".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--quick".as_ref(),
        "--photons".as_ref(),
        "1000".as_ref(),
        "--reference-photons".as_ref(),
        "20000".as_ref(),
        "--width".as_ref(),
        "32".as_ref(),
        "--height".as_ref(),
        "24".as_ref(),
        "--cache-dir".as_ref(),
        cache.as_os_str(),
        "--csv".as_ref(),
        csv.as_os_str(),
        "--svg".as_ref(),
        svg.as_os_str(),
    ]);
    assert_succeeds(&out, "dpm tradeoff --scene");
    assert!(
        stderr(&out).contains("reference: reused"),
        "{}",
        stderr(&out)
    );
    let (_, rows) = read_csv(&csv);
    assert_eq!(rows.len(), 4);
    assert!(
        rows.iter()
            .all(|r| r["target"] == "caustic" && number(r, "rmse") > 0.0)
    );

    // A changed scene file (the light 10% brighter) is a new reference.
    let brighter =
        caustic_scene(1.0, 32, 24).replace("power = [6e1, 6e1, 6e1]", "power = [66, 66, 66]");
    assert_ne!(
        brighter,
        caustic_scene(1.0, 32, 24),
        "the light's power line changed"
    );
    std::fs::write(&scene, brighter).unwrap();
    let third = reference(&scene, &cache);
    assert!(third.starts_with("reference: rendered "), "{third}");
    assert_ne!(cached_file(&third), file);
    assert_eq!(std::fs::metadata(&file).unwrap().modified().unwrap(), made);
}

#[test]
fn bad_flags_exit_2_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("x.csv");
    let svg = dir.path().join("x.svg");
    let outputs = [
        "--csv",
        csv.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ];
    let cases: &[(&[&str], &str)] = &[
        (&["--photons", "0"], "--photons"),
        (&["--photons", "ten"], "--photons"),
        (&["--cone-k", "1"], "--cone-k"),
        (&["--radii=-1"], "--radii"),
        (&["--radii", "0x"], "--radii"),
        (&["--diffusivities", "-0.5"], "--diffusivities"),
        (&["--width", "0"], "--width"),
        (&["--error", "psnr"], "--error"),
        (&["--estimates", "gaussian"], "--estimates"),
        (&["--regions", "r.png"], "--regions"),
        (
            &["--scene", "a.toml", "--distribution", "constructed"],
            "--scene",
        ),
        (&["--csv", "/no/such/dir/x.csv"], "--csv"),
        (&["--svg", "plot.png"], "--svg"),
    ];
    for (args, flag) in cases {
        let mut all = vec!["tradeoff", "--quick"];
        // Explicit outputs unless the case is about them.
        if !args.contains(&"--csv") && !args.contains(&"--svg") {
            all.extend_from_slice(&outputs);
        }
        all.extend_from_slice(args);
        let out = dpm(&all);
        assert_fails(&out, 2, &[flag], &format!("{args:?}"));
        assert!(!csv.exists() && !svg.exists(), "{args:?} wrote output");
    }
    let missing = dir.path().join("missing.toml");
    let out = dpm([
        "tradeoff".as_ref(),
        "--quick".as_ref(),
        "--scene".as_ref(),
        missing.as_os_str(),
        "--csv".as_ref(),
        csv.as_os_str(),
        "--svg".as_ref(),
        svg.as_os_str(),
    ]);
    assert_fails(&out, 2, &["missing.toml"], "missing scene");
    let out = dpm(["reference", "scenes/torus-knot.toml", "--photons", "0"]);
    assert_fails(&out, 2, &["--photons"], "reference --photons 0");
}
