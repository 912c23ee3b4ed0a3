//! PROVISIONAL: estimator flags and one fixed-radius Epanechnikov estimate, standing in for the
//! estimate module's `EstimatorSettings` until that lands; then this file goes. Owns nothing
//! that outlives the merge.

use crate::estimate::{Query, RadianceEstimate, Scratch};
use crate::photon::PhotonMap;
use glam::Vec3;

#[derive(Clone, Debug, clap::Args)]
pub struct EstimatorSettings {
    /// Radiance estimate.
    #[arg(long, default_value = "epanechnikov")]
    pub estimator: String,
    /// Photons per k-nearest estimate.
    #[arg(long, default_value_t = 400)]
    pub k: usize,
    /// Support radius of the fixed-radius estimates.
    #[arg(long, default_value_t = 0.02)]
    pub radius: f32,
    /// Diffusivity coefficient K.
    #[arg(long, default_value_t = 0.2)]
    pub diffusivity: f32,
    /// Steepness α of the diffusivity function.
    #[arg(long, default_value_t = 1.0)]
    pub alpha: f32,
}

impl EstimatorSettings {
    pub fn build(&self, _map: &PhotonMap) -> Result<Box<dyn RadianceEstimate>, String> {
        match self.estimator.as_str() {
            "epanechnikov" => Ok(Box::new(Epanechnikov {
                radius: self.radius,
            })),
            other => Err(format!("unknown estimator {other:?}")),
        }
    }
}

struct Epanechnikov {
    radius: f32,
}

impl RadianceEstimate for Epanechnikov {
    fn name(&self) -> &'static str {
        "epanechnikov"
    }
    fn irradiance(&self, map: &PhotonMap, query: &Query, _scratch: &mut Scratch) -> Vec3 {
        let r2 = self.radius * self.radius;
        let mut sum = Vec3::ZERO;
        map.tree().for_each_within(query.position, r2, |slot, d2| {
            sum += (1.0 - d2 / r2) * map.photon(slot).power();
        });
        sum * (2.0 / (std::f32::consts::PI * r2))
    }
}
