//! The error of an image against a reference, as every figure in this project quotes it: the
//! relative MSE over the RGB channel means. Shared by the render's per-pass report and the
//! density and trade-off experiments, so it sits below all three. Owns the arithmetic only; it
//! must not read files, render or know what the images show.

use crate::image_io::Image;
use glam::Vec3;

/// The mean of the RGB channels: the scalar the metrics and the CSV files use.
pub fn channel_mean(p: Vec3) -> f64 {
    (p.x as f64 + p.y as f64 + p.z as f64) / 3.0
}

/// Relative MSE: the mean over pixels of (e − r)² / (r² + ε²), ε = 0.1 × the mean of the
/// reference, so pixels the reference leaves dark still count (light leaking into them is an
/// error) without dividing by zero.
pub fn relative_mse(estimate: &[f64], reference: &[f64]) -> f64 {
    assert_eq!(estimate.len(), reference.len());
    let n = reference.len().max(1) as f64;
    let eps = 0.1 * reference.iter().sum::<f64>() / n;
    let eps2 = (eps * eps).max(f64::MIN_POSITIVE);
    estimate
        .iter()
        .zip(reference)
        .map(|(e, r)| (e - r).powi(2) / (r * r + eps2))
        .sum::<f64>()
        / n
}

/// [`relative_mse`] of `image` against `reference` over their pixels' channel means.
pub fn image_relative_mse(image: &Image, reference: &Image) -> f64 {
    let means = |i: &Image| -> Vec<f64> { i.pixels.iter().map(|p| channel_mean(*p)).collect() };
    relative_mse(&means(image), &means(reference))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_mse_is_scale_free() {
        let r = [1.0, 2.0, 0.0, 4.0];
        let e = [1.5, 1.0, 0.2, 4.0];
        let scaled = |v: &[f64]| v.iter().map(|x| x * 1000.0).collect::<Vec<_>>();
        let a = relative_mse(&e, &r);
        let b = relative_mse(&scaled(&e), &scaled(&r));
        assert!((a - b).abs() < 1e-12 * a.max(1.0), "{a} vs {b}");
    }

    #[test]
    fn relative_mse_of_a_known_pair() {
        // ε = 0.1 × mean(r) = 0.05: (0.5² / (1 + ε²) + 0.1² / ε²) / 2.
        let (e, r) = ([1.5, 0.1], [1.0, 0.0]);
        let expected = (0.25 / 1.0025 + 0.01 / 0.0025) / 2.0;
        assert!((relative_mse(&e, &r) - expected).abs() < 1e-12);
        let image = |v: [f32; 2]| Image {
            width: 2,
            height: 1,
            pixels: v.iter().map(|&x| Vec3::splat(x)).collect(),
        };
        let got = image_relative_mse(&image([1.5, 0.1]), &image([1.0, 0.0]));
        assert!((got - expected).abs() < 1e-6, "{got}");
    }
}
