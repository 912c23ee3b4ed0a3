//! Scale invariance: the same scene in units 1e-4 and 1e5 times as large (camera, light,
//! geometry; the point light's power times s², so the irradiance is unchanged) renders the
//! same picture as at scale 1: relative RMSE below 2%, for the diffusion estimate (whose
//! radius and diffusivity are derived from the photon map and dimensionless) and a k-NN one.

mod reliability_support;

use reliability_support::*;
use std::path::Path;

fn render(scene: &Path, output: &Path, estimator: &str) {
    let out = dpm([
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "--estimator".as_ref(),
        estimator.as_ref(),
        "--seed".as_ref(),
        "3".as_ref(),
        "--spp".as_ref(),
        "2".as_ref(),
        "--caustic-photons".as_ref(),
        "3000".as_ref(),
        "--global-photons".as_ref(),
        "2000".as_ref(),
        "--final-gather".as_ref(),
        "2".as_ref(),
        "--global-k".as_ref(),
        "20".as_ref(),
        "--k".as_ref(),
        "30".as_ref(),
    ]);
    assert_succeeds(&out, &scene.display().to_string());
}

/// RMSE of `b` against `a`, relative to the RMS of `a`.
fn relative_rmse(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len());
    let (mut err, mut norm) = (0.0f64, 0.0f64);
    for (&x, &y) in a.iter().zip(b) {
        err += (x as f64 - y as f64).powi(2);
        norm += (x as f64).powi(2);
    }
    (err / norm).sqrt()
}

fn check(estimator: &str) {
    let dir = tempfile::tempdir().unwrap();
    let image = |s: f64| {
        let scene = write_scene(
            dir.path(),
            &format!("{s:e}.toml"),
            &caustic_scene(s, 40, 30),
        );
        let output = dir.path().join(format!("{s:e}.pfm"));
        render(&scene, &output, estimator);
        pfm_pixels(&output).2
    };
    let reference = image(1.0);
    assert!(reference.iter().any(|&v| v > 0.0), "black image at scale 1");
    let mut failures = Vec::new();
    for s in [1e-4, 1e5] {
        let scaled = image(s);
        let e = relative_rmse(&reference, &scaled);
        eprintln!("{estimator}: scale {s:e}: relative RMSE {:.4}%", 100.0 * e);
        if e.is_nan() || e >= 0.02 {
            failures.push(format!("scale {s:e}: relative RMSE {:.3}%", 100.0 * e));
        }
    }
    assert!(failures.is_empty(), "{estimator}: {}", failures.join("; "));
}

#[test]
fn diffusion_estimate_is_scale_invariant() {
    check("diffusion");
}

#[test]
fn cone_estimate_is_scale_invariant() {
    check("cone");
}

/// Zero-area triangles are dropped at load and slivers (tiny but not zero area) go to Embree:
/// the render succeeds at every scale with finite pixels.
#[test]
fn degenerate_and_sliver_triangles_render_safely_at_every_scale() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo("tests/fixtures/meshes/degenerate.obj"),
        dir.path().join("degenerate.obj"),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("sliver.obj"),
        "v 0 0 0\nv 1 0 0\nv 0.5 0.00001 0\nv 0.5 0.5 1e-7\nf 1 2 3\nf 1 2 4\n",
    )
    .unwrap();
    for s in [1e-4, 1.0, 1e5] {
        let objects = format!(
            "\n[[objects]]\ntype = \"mesh\"\nfile = \"degenerate.obj\"\nmaterial = \"floor\"\n\
             scale = {s:e}\ntranslate = [{t:e}, {t:e}, 0.0]\n\n\
             [[objects]]\ntype = \"mesh\"\nfile = \"sliver.obj\"\nmaterial = \"chrome\"\n\
             scale = {s:e}\ntranslate = [{u:e}, {t:e}, 0.0]\n",
            t = 0.5 * s,
            u = -1.5 * s,
        );
        let scene = write_scene(
            dir.path(),
            &format!("{s:e}.toml"),
            &(caustic_scene(s, 16, 12) + &objects),
        );
        let output = dir.path().join(format!("{s:e}.pfm"));
        render(&scene, &output, "diffusion");
        let (_, _, pixels) = pfm_pixels(&output);
        assert!(pixels.iter().all(|v| v.is_finite()), "scale {s:e}");
        assert!(pixels.iter().any(|&v| v > 0.0), "scale {s:e}: black");
    }
}
