//! The constructed-distribution target of `dpm tradeoff`: photons drawn from a built-in
//! distribution with an exact density (`dpm density`'s), estimates evaluated on its grid, and
//! errors from `dpm density`'s metrics (edge band and flat regions as that command defines
//! them). Owns only the glue; it must not define regions, draw photons or evaluate kernels
//! itself, and must not write files.

use super::sweep::{Errors, SweepError, Target};
use crate::density::{self, Distribution, DistributionName, Grid, Metrics, Regions, Truth};
use crate::estimate::RadianceEstimate;
use crate::image_metrics::relative_mse;
use crate::photon::PhotonMap;

/// `dpm density`'s default region widths (world units): the edge band's half width and the
/// margin left out at the border.
pub const BAND: f64 = 0.04;
pub const MARGIN: f64 = 0.05;

pub struct ConstructedTarget {
    pub name: DistributionName,
    pub grid: Grid,
    pub seed: u64,
    truth: Option<(Truth, Regions)>,
}

impl ConstructedTarget {
    pub fn new(name: DistributionName, grid: Grid, seed: u64) -> Self {
        Self {
            name,
            grid,
            seed,
            truth: None,
        }
    }
}

impl Target for ConstructedTarget {
    fn name(&self) -> String {
        format!("{:?}", self.name).to_lowercase()
    }

    fn photons(&mut self, count: usize, pass: u64) -> Result<PhotonMap, SweepError> {
        let distribution = Distribution::new(self.name, count as u64);
        if self.truth.is_none() {
            // The density and the regions do not depend on the count.
            let widths = density::RegionWidths {
                band: BAND,
                margin: MARGIN,
            };
            let regions = density::regions(&distribution, &self.grid, widths);
            self.truth = Some((distribution.truth_on(&self.grid), regions));
        }
        let photons = distribution.photons(crate::sampling::pass_seed(self.seed, pass));
        let emitted = photons.len() as u64;
        Ok(PhotonMap::build(photons, emitted))
    }

    fn evaluate(&self, map: &PhotonMap, estimate: &dyn RadianceEstimate) -> Vec<f64> {
        let hidden = indicatif::ProgressBar::hidden();
        density::grid::evaluate(&self.grid, map, estimate, &hidden)
            .into_iter()
            .map(crate::image_metrics::channel_mean)
            .collect()
    }

    fn score(&self, values: &[f64]) -> Errors {
        let (truth, regions) = self.truth.as_ref().expect("photons() runs before score()");
        let m = Metrics::new(values, truth, regions);
        Errors {
            rmse: m.rmse,
            relative_mse: relative_mse(values, &truth.centre),
            edge_band_rmse: m.edge_band_rmse,
            flat_noise: m.flat_noise,
        }
    }
}
