//! Tests of `dpm density`'s metrics: zero for the truth, a constant error read back as that
//! constant, flat-region noise as the spread of the error, and the built-in truth's regions.

use dpm::density::grid::{Extent, Grid};
use dpm::density::metrics::{LineProbe, Metrics, RegionWidths, Regions};
use dpm::density::{Distribution, DistributionName, Truth};
use glam::DVec2;

fn synthetic() -> (Grid, Truth, Regions) {
    let grid = Grid {
        width: 40,
        height: 40,
        extent: Extent::UNIT,
    };
    let centre: Vec<f64> = grid.map(|p| if p.x < 0.5 { 1.0 } else { 3.0 });
    let truth = Truth {
        pixel_mean: centre.clone(),
        centre,
    };
    let widths = RegionWidths {
        band: 0.1,
        margin: 0.1,
    };
    let line = LineProbe {
        a: DVec2::new(0.5, 0.2),
        b: DVec2::new(0.5, 0.8),
        true_peak: 3.0,
    };
    let regions = Regions::new(
        &grid,
        widths,
        |p| (p.x - 0.5).abs(),
        |_| f64::INFINITY,
        Some(line),
    );
    (grid, truth, regions)
}

#[test]
fn metrics_of_the_truth_are_zero() {
    let (_, truth, regions) = synthetic();
    let m = Metrics::new(&truth.centre, &truth, &regions);
    assert_eq!(
        (
            m.rmse,
            m.interior_rmse,
            m.edge_band_rmse,
            m.flat_noise,
            m.energy_error
        ),
        (0.0, 0.0, 0.0, 0.0, 0.0)
    );
    assert_eq!(m.line_peak, Some(1.0));
    // 32×32 interior pixels (centres 0.1 to 0.9); the band holds 8 columns of them.
    assert_eq!(
        (m.interior_pixels, m.edge_band_pixels, m.flat_pixels),
        (1024, 256, 768)
    );
}

#[test]
fn metrics_of_the_truth_plus_a_constant_are_that_constant() {
    let (_, truth, regions) = synthetic();
    let c = 0.25;
    let shifted: Vec<f64> = truth.centre.iter().map(|t| t + c).collect();
    let m = Metrics::new(&shifted, &truth, &regions);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(
        close(m.rmse, c) && close(m.interior_rmse, c) && close(m.edge_band_rmse, c),
        "{m:?}"
    );
    assert!(close(m.relative_rmse, c / 2.0), "mean truth is 2: {m:?}");
    assert!(m.flat_noise.abs() < 1e-7 && close(m.flat_bias, c), "{m:?}");
    assert!(close(m.energy_error, c / 2.0), "{m:?}");
    assert!(close(m.line_peak.unwrap(), (3.0 + c) / 3.0));
}

#[test]
fn the_flat_noise_is_the_spread_of_the_error() {
    let (_, truth, regions) = synthetic();
    // ± 0.1 in a checkerboard: no bias, standard deviation 0.1.
    let noisy: Vec<f64> = truth
        .centre
        .iter()
        .enumerate()
        .map(|(i, t)| t + if (i + i / 40) % 2 == 0 { 0.1 } else { -0.1 })
        .collect();
    let m = Metrics::new(&noisy, &truth, &regions);
    assert!(
        (m.flat_noise - 0.1).abs() < 1e-9 && m.flat_bias.abs() < 1e-9,
        "{m:?}"
    );
    assert!(m.energy_error.abs() < 1e-9);
}

#[test]
fn the_built_in_truth_is_consistent() {
    let d = Distribution::new(DistributionName::Constructed, 1_000_000);
    let grid = Grid {
        width: 512,
        height: 512,
        extent: Extent::UNIT,
    };
    let truth = d.truth_on(&grid);
    // The pixel means integrate to the total power in the unit square (= count · power).
    let total: f64 = truth.pixel_mean.iter().sum::<f64>() * grid.pixel_area();
    let expected = d.count() as f64 * d.photon_power as f64;
    // 16×16 sub-samples miss up to 1/32 of a pixel at each edge of the thin line, which runs
    // along the pixel grid: about 2e-4 of the total here.
    assert!(
        (total / expected - 1.0).abs() < 5e-4,
        "{total} vs {expected}"
    );
    // The thin line's true peak is the line plus the background.
    let line_row = truth.centre[256 * 512..257 * 512]
        .iter()
        .copied()
        .fold(0.0, f64::max);
    assert!((line_row - d.thin_line_peak()).abs() < 1e-9 * line_row);
}
