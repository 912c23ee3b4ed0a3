//! Tests of `dpm density`: photon CSV parsing, the built-in distributions, the grid evaluation
//! (orientation, thread-count invariance, a uniform density); the metrics are in
//! `density_metrics.rs`.

use clap::Parser;
use dpm::density::csv::{CsvError, parse_photons};
use dpm::density::grid::{self, Extent, Grid};
use dpm::density::rng::SplitMix64;
use dpm::density::{DensityArgs, DensityError, Distribution, DistributionName, load_photons, run};
use dpm::estimate::{Query, RadianceEstimate, Receiver, Scratch};
use dpm::image_io::read_pfm;
use dpm::photon::{Photon, PhotonMap};
use glam::{DVec2, Vec3};
use indicatif::ProgressBar;
use std::path::Path;

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: DensityArgs,
}

fn args(list: &[&str]) -> DensityArgs {
    Cli::try_parse_from(std::iter::once("density").chain(list.iter().copied()))
        .unwrap()
        .args
}

/// A test-only estimate: the photons within `radius`, divided by the disc's area.
struct DiscCount {
    radius: f32,
}

impl RadianceEstimate for DiscCount {
    fn name(&self) -> &'static str {
        "disc-count"
    }
    fn irradiance(&self, map: &PhotonMap, query: &Query, _scratch: &mut Scratch) -> Vec3 {
        let mut sum = Vec3::ZERO;
        map.tree()
            .for_each_within(query.position, self.radius * self.radius, |slot, _| {
                sum += map.photon(slot).power();
            });
        sum / (std::f32::consts::PI * self.radius * self.radius)
    }
    fn reflected(
        &self,
        map: &PhotonMap,
        query: &Query,
        receiver: &dyn Receiver,
        _scratch: &mut Scratch,
    ) -> Vec3 {
        let mut sum = Vec3::ZERO;
        map.tree()
            .for_each_within(query.position, self.radius * self.radius, |slot, _| {
                let photon = map.photon(slot);
                sum += photon.power() * receiver.bsdf(photon.direction());
            });
        sum / (std::f32::consts::PI * self.radius * self.radius)
    }
}

fn plane_photon(x: f32, y: f32, power: f32) -> Photon {
    Photon::new(
        Vec3::new(x, y, 0.0),
        Vec3::splat(power),
        Vec3::NEG_Z,
        Vec3::Z,
    )
}

fn evaluate(grid: &Grid, photons: Vec<Photon>, radius: f32) -> Vec<Vec3> {
    let n = photons.len() as u64;
    let map = PhotonMap::build(photons, n);
    grid::evaluate(grid, &map, &DiscCount { radius }, &ProgressBar::hidden())
}

// ---- CSV ----

#[test]
fn csv_reads_both_forms_headers_and_comments() {
    let text = "# photons\nx,y,power\n0.5,0.25\n\n 1e-3 , -2 , 3.5 \n";
    let photons = parse_photons(Path::new("p.csv"), text).unwrap();
    assert_eq!(photons.len(), 2);
    assert_eq!(
        (photons[0].x, photons[0].y, photons[0].power),
        (0.5, 0.25, 1.0)
    );
    assert_eq!(
        (photons[1].x, photons[1].y, photons[1].power),
        (1e-3, -2.0, 3.5)
    );
}

fn csv_error(text: &str) -> CsvError {
    parse_photons(Path::new("dir/p.csv"), text).unwrap_err()
}

#[test]
fn csv_errors_name_the_line_and_field() {
    let e = csv_error("0,0\n1,1,1\n0.5,abc\n");
    assert_eq!((e.line, e.field), (3, "y"));
    assert!(e.to_string().starts_with("dir/p.csv:3: field y:"), "{e}");

    let e = csv_error("x,y\n\nnan,0\n");
    assert_eq!((e.line, e.field), (3, "x"));
    assert_eq!(csv_error("0,0,inf\n").field, "power");
    assert_eq!(csv_error("0,0,-1\n").field, "power");
    let e = csv_error("0,0\n1\n");
    assert_eq!((e.line, e.field), (2, "fields"));
    assert_eq!(csv_error("0,0,1,1\n").field, "fields");
    // A header is only a header on the first line with content.
    assert_eq!(csv_error("0,0\nx,y\n").line, 2);
}

#[test]
fn a_bad_photon_file_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.csv");
    std::fs::write(&path, "0.1,0.2\n0.3,,1\n").unwrap();
    let out = dir.path().join("o.pfm");
    let a = args(&[
        "--photons",
        path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    match load_photons(&a) {
        Err(DensityError::Csv(e)) => {
            assert_eq!(
                (e.line, e.field, e.path.as_path()),
                (2, "y", path.as_path())
            )
        }
        other => panic!("{:?}", other.err()),
    }
    std::fs::write(&path, "# nothing\n").unwrap();
    assert!(matches!(load_photons(&a), Err(DensityError::NoPhotons(_))));
    let missing = args(&["--photons", "/nonexistent/p.csv", "-o", "o.pfm"]);
    assert!(matches!(
        load_photons(&missing),
        Err(DensityError::Read { .. })
    ));
}

#[test]
fn flags_are_validated() {
    let parse =
        |l: &[&str]| Cli::try_parse_from(std::iter::once("density").chain(l.iter().copied()));
    assert!(
        parse(&["-o", "a.png"]).is_err(),
        "needs photons or a distribution"
    );
    assert!(parse(&["--photons", "p", "--distribution", "second", "-o", "a.png"]).is_err());
    assert!(parse(&["--photons", "p", "--truth", "t.png", "-o", "a.png"]).is_err());
    assert!(
        parse(&[
            "--distribution",
            "second",
            "--extent",
            "0,0,1",
            "-o",
            "a.png"
        ])
        .is_err()
    );
    assert!(
        parse(&[
            "--distribution",
            "second",
            "--extent",
            "1,0,0,1",
            "-o",
            "a.png"
        ])
        .is_err()
    );
    assert!(parse(&["--distribution", "second", "--width", "0", "-o", "a.png"]).is_err());
    let a = parse(&[
        "--distribution",
        "second",
        "--extent",
        "-1,-2,3,4",
        "-o",
        "a.png",
    ])
    .unwrap()
    .args;
    assert_eq!(
        a.extent,
        Extent {
            x0: -1.0,
            y0: -2.0,
            x1: 3.0,
            y1: 4.0
        }
    );
}

// ---- distributions ----

/// Photons per cell on a coarse grid against the integral of the exact density (chi-square).
#[test]
fn constructed_photon_counts_follow_the_known_density() {
    for name in [DistributionName::Constructed, DistributionName::Second] {
        let count = 200_000;
        let d = Distribution::new(name, count);
        assert_eq!(d.count(), count);
        let photons = d.photons(11);
        let cells = 16;
        let mut observed = vec![0u64; cells * cells];
        for p in &photons {
            let q = p.position();
            assert!(q.x >= 0.0 && q.x <= 1.0 && q.y >= 0.0 && q.y <= 1.0 && q.z == 0.0);
            let (i, j) = (
                ((q.x * cells as f32) as usize).min(cells - 1),
                ((q.y * cells as f32) as usize).min(cells - 1),
            );
            observed[j * cells + i] += 1;
        }
        // Expected counts by a 64×64 midpoint rule per cell.
        let sub = 64;
        let h = 1.0 / (cells * sub) as f64;
        let mut chi2 = 0.0;
        for j in 0..cells {
            for i in 0..cells {
                let mut expected = 0.0;
                for a in 0..sub {
                    for b in 0..sub {
                        let p = DVec2::new(
                            ((i * sub + a) as f64 + 0.5) * h,
                            ((j * sub + b) as f64 + 0.5) * h,
                        );
                        expected += d.photon_density(p) * h * h;
                    }
                }
                let o = observed[j * cells + i] as f64;
                chi2 += (o - expected).powi(2) / expected;
            }
        }
        // 255 degrees of freedom: mean 255, standard deviation 22.6. Allow 5 standard deviations
        // (the midpoint rule's own error near edges is well inside that).
        assert!(chi2 < 255.0 + 5.0 * 22.6, "{name:?}: chi-square {chi2}");
        assert!(
            chi2 > 255.0 - 5.0 * 22.6,
            "{name:?}: chi-square {chi2} is too good to be random"
        );
    }
}

#[test]
fn each_shape_holds_its_share_of_photons() {
    let d = Distribution::new(DistributionName::Constructed, 100_000);
    let photons = d.photons(3);
    let bg = d.counts[0] as f64;
    for (k, shape) in d.layout.shapes.iter().enumerate() {
        let inside = photons
            .iter()
            .filter(|p| {
                shape.profile(DVec2::new(p.position().x as f64, p.position().y as f64)) > 0.0
            })
            .count() as f64;
        // Area where the profile is positive: the mass for uniform shapes, twice it for the
        // ridge's tent.
        let area = if matches!(shape, dpm::density::shapes::Shape::Ridge(_)) {
            2.0 * shape.mass()
        } else {
            shape.mass()
        };
        let expected = d.counts[k + 1] as f64 + bg * area;
        let sigma = (bg * area * (1.0 - area)).sqrt();
        assert!(
            (inside - expected).abs() < 5.0 * sigma + 2.0,
            "shape {k}: {inside} vs {expected} ± {sigma}"
        );
    }
}

#[test]
fn photons_depend_on_the_seed_only() {
    let d = Distribution::new(DistributionName::Second, 5000);
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let one = pool(1).install(|| d.photons(9));
    let two = pool(2).install(|| d.photons(9));
    assert_eq!(one, two);
    assert_ne!(one, d.photons(10));
}

// ---- the grid ----

#[test]
fn a_uniform_density_is_estimated_within_statistical_error() {
    let n = 20_000;
    let mut rng = SplitMix64::new(42);
    let photons: Vec<Photon> = (0..n)
        .map(|_| plane_photon(rng.next_f64() as f32, rng.next_f64() as f32, 2.0))
        .collect();
    let grid = Grid {
        width: 16,
        height: 16,
        extent: Extent {
            x0: 0.1,
            y0: 0.1,
            x1: 0.9,
            y1: 0.9,
        },
    };
    let radius = 0.05;
    let values = evaluate(&grid, photons, radius);
    let truth = 2.0 * n as f64;
    // A disc of radius 0.05 holds about 157 photons: 8% noise a pixel.
    let sigma = truth / (n as f64 * std::f64::consts::PI * 0.05 * 0.05).sqrt();
    let mean = values.iter().map(|v| v.x as f64).sum::<f64>() / values.len() as f64;
    for v in &values {
        assert!((v.x as f64 - truth).abs() < 5.0 * sigma, "{v} vs {truth}");
    }
    // Pixels 0.05 apart share some photons: about 64 independent discs in the grid.
    assert!(
        (mean - truth).abs() < 5.0 * sigma / 8.0,
        "{mean} vs {truth}"
    );
}

#[test]
fn row_zero_is_the_top() {
    // Photons only in the top-left quarter of the extent [0, 2] × [0, 2].
    let photons: Vec<Photon> = (0..400)
        .map(|i| {
            plane_photon(
                0.1 + 0.04 * (i % 20) as f32,
                1.1 + 0.04 * (i / 20) as f32,
                1.0,
            )
        })
        .collect();
    let grid = Grid {
        width: 4,
        height: 6,
        extent: Extent {
            x0: 0.0,
            y0: 0.0,
            x1: 2.0,
            y1: 2.0,
        },
    };
    let values = evaluate(&grid, photons, 0.2);
    for row in 0..6 {
        for col in 0..4 {
            let lit = values[row * 4 + col].x > 0.0;
            assert_eq!(lit, row < 3 && col < 2, "row {row} col {col}");
        }
    }
    assert!((grid.centre(0, 0) - DVec2::new(0.25, 2.0 - 1.0 / 6.0)).length() < 1e-12);
}

#[test]
fn the_command_writes_row_zero_at_the_top() {
    let dir = tempfile::tempdir().unwrap();
    let photons = dir.path().join("p.csv");
    // A cluster near the top-right corner of the unit square.
    let lines: String = (0..50)
        .map(|i| format!("{},{}\n", 0.8 + 0.002 * i as f32, 0.9))
        .collect();
    std::fs::write(&photons, lines).unwrap();
    let out = dir.path().join("o.pfm");
    let csv = dir.path().join("g.csv");
    let a = args(&[
        "--photons",
        photons.to_str().unwrap(),
        "--width",
        "4",
        "--height",
        "4",
        "--estimator",
        "epanechnikov",
        "--radius",
        "0.1",
        "-o",
        out.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let report = run(&a).unwrap();
    assert_eq!((report.photons, report.metrics), (50, None));
    let image = read_pfm(&out).unwrap();
    assert!(image.get(3, 0).x > 0.0, "top right is lit");
    assert_eq!(image.get(0, 3).x, 0.0, "bottom left is dark");
    let text = std::fs::read_to_string(&csv).unwrap();
    let first: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(&first[..4], &["0", "0", "0.125", "0.875"]);
    let top_right: Vec<&str> = text.lines().nth(4).unwrap().split(',').collect();
    assert_eq!(top_right[1], "3");
    assert!(top_right[4].parse::<f64>().unwrap() > 0.0);
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let go = |threads: usize| {
        let out = dir.path().join(format!("t{threads}.pfm"));
        let a = args(&[
            "--distribution",
            "constructed",
            "--count",
            "3000",
            "--width",
            "24",
            "--height",
            "16",
            "--radius",
            "0.08",
            "-o",
            out.to_str().unwrap(),
        ]);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let report = pool.install(|| run(&a)).unwrap();
        (std::fs::read(&out).unwrap(), report.metrics)
    };
    let (one, two) = (go(1), go(2));
    assert_eq!(one.0, two.0, "images differ");
    assert_eq!(one.1, two.1, "metrics differ");
    assert!(one.1.is_some());
}

// ---- through the command, with the real estimates ----

/// Writes `n` uniformly random photons of power 2 on the unit square as CSV.
fn uniform_photon_file(dir: &Path, n: usize) -> std::path::PathBuf {
    let mut rng = SplitMix64::new(8);
    let text: String = (0..n)
        .map(|_| format!("{},{},2\n", rng.next_f64(), rng.next_f64()))
        .collect();
    let path = dir.join("uniform.csv");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn every_estimate_of_a_uniform_density_is_its_density() {
    let dir = tempfile::tempdir().unwrap();
    let n = 20_000;
    let photons = uniform_photon_file(dir.path(), n);
    let out = dir.path().join("u.pfm");
    for estimator in ["simple", "cone", "gaussian", "epanechnikov", "diffusion"] {
        let a = args(&[
            "--photons",
            photons.to_str().unwrap(),
            "--extent",
            "0.2,0.2,0.8,0.8",
            "--width",
            "8",
            "--height",
            "8",
            "--estimator",
            estimator,
            "--k",
            "200",
            "--radius",
            "0.06",
            "-o",
            out.to_str().unwrap(),
        ]);
        run(&a).unwrap();
        let image = read_pfm(&out).unwrap();
        let truth = 2.0 * n as f64;
        let mean = image.pixels.iter().map(|p| p.x as f64).sum::<f64>() / 64.0;
        // About 200 photons an estimate (7% noise), 64 pixels sharing some of them.
        assert!(
            (mean / truth - 1.0).abs() < 0.04,
            "{estimator}: {mean} vs {truth}"
        );
        for p in &image.pixels {
            assert!((p.x as f64 / truth - 1.0).abs() < 0.4, "{estimator}: {p}");
        }
    }
}

#[test]
fn the_kernel_field_needs_the_diffusion_estimate_and_shows_edges() {
    // Photons jittered on lattices over [0.2, 0.8]² (one a cell, so little noise), four times
    // denser left of x = 0.5 than right of it: one vertical edge. Exact lattices would fool the
    // gradient pass (photons at exactly its radius fall in or out by rounding, one side at a
    // time), and Poisson noise with this few photons would squeeze the kernel everywhere.
    let dir = tempfile::tempdir().unwrap();
    let mut rng = SplitMix64::new(1);
    let mut text = String::new();
    for (x0, spacing) in [(0.2, 0.0025f64), (0.5, 0.005)] {
        let n = (0.3 / spacing).round() as usize;
        for i in 0..n {
            for j in 0..2 * n {
                let (x, y) = (i as f64 + rng.next_f64(), j as f64 + rng.next_f64());
                text += &format!("{},{}\n", x0 + x * spacing, 0.2 + y * spacing);
            }
        }
    }
    let photons = dir.path().join("step.csv");
    std::fs::write(&photons, text).unwrap();
    let out = dir.path().join("e.pfm");
    let field = dir.path().join("k.pfm");
    let with = |estimator: &'static str| {
        args(&[
            "--photons",
            photons.to_str().unwrap(),
            "--extent",
            "0.3,0.3,0.7,0.7",
            "--width",
            "16",
            "--height",
            "16",
            "--radius",
            "0.05",
            "--estimator",
            estimator,
            "--kernel-field",
            field.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
    };
    let err = run(&with("epanechnikov")).unwrap_err();
    assert!(
        matches!(err, DensityError::KernelFieldNeedsDiffusion(_)),
        "{err}"
    );
    assert!(!field.exists());

    run(&with("diffusion")).unwrap();
    let image = read_pfm(&field).unwrap();
    let grid = Grid {
        width: 16,
        height: 16,
        extent: "0.3,0.3,0.7,0.7".parse().unwrap(),
    };
    for i in 0..grid.len() {
        let distance = (grid.centre_of(i).x - 0.5).abs();
        let p = image.pixels[i];
        if distance < 0.03 {
            // Squeezed across a vertical edge: bright cyan (the long axis is vertical).
            assert!(
                p.max_element() > 0.5 && p.x < 0.05 * p.y && (p.y - p.z).abs() < 0.05 * p.y,
                "{i}: {p}"
            );
        } else if distance > 0.1 {
            assert!(p.max_element() < 0.1, "{i}: {p}");
        }
    }
}
