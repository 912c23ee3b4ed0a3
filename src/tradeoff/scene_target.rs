//! The scene target of `dpm tradeoff` and `dpm reference`: a scene loaded at a reduced
//! resolution, caustic photon maps traced from it, and the caustic contribution of the eye
//! pass rendered with a given map and estimate. Owns that glue only; it uses the render
//! pipeline's public parts (world, tracer, camera, integrator) and must not implement shading,
//! tracing or estimates, nor write files.
//!
//! The caustic contribution is the eye pass's caustic layer (the integrator keeps direct,
//! caustic and indirect light apart): exactly what the caustic estimate adds, seen directly
//! and through mirrors and glass.
//! Indirect diffuse light (the global map) is left out: it does not depend on the caustic
//! estimate and would only add the same time to every run.

use super::scene_metrics::{SceneRegions, scene_errors};
use super::sweep::{Errors, SweepError, Target};
use crate::embree::EmbreeError;
use crate::estimate::RadianceEstimate;
use crate::image_io::Image;
use crate::image_metrics::channel_mean;
use crate::photon::PhotonMap;
use crate::photon::tracer::{MapKind, trace_map};
use crate::render::integrator::{EstimatedMap, Indirect, Integrator};
use crate::render::pass::shade_pass;
use crate::render::{PassSamples, RayCamera};
use crate::scene::{self, SceneError};
use crate::world::World;
use indicatif::ProgressBar;
use std::cell::OnceCell;
use std::path::{Path, PathBuf};

/// Mirror and glass bounces followed from the eye (`dpm render`'s default).
const MAX_DEPTH: u32 = 10;

#[derive(Debug, thiserror::Error)]
pub enum SceneTargetError {
    #[error("{0}")]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Embree(#[from] EmbreeError),
    #[error("{}: the scene has no mirror or glass object, so it has no caustics to measure", .0.display())]
    NoCaustics(PathBuf),
}

pub struct SceneTarget {
    pub path: PathBuf,
    pub world: World,
    pub seed: u64,
    camera: RayCamera,
    /// The eye pass without caustics, made on first use.
    direct: OnceCell<Image>,
    reference: Option<(Vec<f64>, SceneRegions)>,
}

impl SceneTarget {
    /// Loads `path` with its camera set to `width` × `height`.
    pub fn load(path: &Path, width: u32, height: u32, seed: u64) -> Result<Self, SceneTargetError> {
        let mut description = scene::load(path)?;
        description.camera.width = width;
        description.camera.height = height;
        let world = World::new(description)?;
        if !world.has_specular() {
            return Err(SceneTargetError::NoCaustics(path.to_path_buf()));
        }
        let camera = RayCamera::new(&world.description.camera);
        Ok(Self {
            path: path.to_path_buf(),
            world,
            seed,
            camera,
            direct: OnceCell::new(),
            reference: None,
        })
    }

    pub fn width(&self) -> usize {
        self.camera.width()
    }

    pub fn height(&self) -> usize {
        self.camera.height()
    }

    /// A caustic map of `count` stored photons, from pass `pass`'s streams.
    pub fn trace(&self, count: usize, pass: u64, bar: &ProgressBar) -> PhotonMap {
        let seed = crate::sampling::pass_seed(self.seed, pass);
        trace_map(&self.world, MapKind::Caustic, count, seed, bar).0
    }

    /// The eye pass's image and its caustic layer.
    fn eye_pass(&self, caustics: Option<EstimatedMap>) -> (Image, Image) {
        let integrator = Integrator {
            world: &self.world,
            caustics,
            indirect: Indirect::None,
            max_depth: MAX_DEPTH,
            light_samples: 1,
            glass_split_depth: u32::MAX,
            volume: Default::default(),
        };
        // Pass 0's pixel positions for every image: a progressive reference then converges to
        // the image at exactly the points every sweep run samples.
        let samples = PassSamples::new(self.seed, 0, 1);
        let pass = shade_pass(
            &self.camera,
            &integrator,
            &samples,
            None,
            None,
            12,
            &ProgressBar::hidden(),
        );
        (pass.layer(0), pass.layer(2))
    }

    /// The eye pass without caustics (rendered once; call it before timing runs).
    pub fn direct_light(&self) -> &Image {
        self.direct.get_or_init(|| self.eye_pass(None).0)
    }

    /// What the caustic estimate adds to the eye pass (see the module notes).
    pub fn caustic_image(&self, map: &PhotonMap, estimate: &dyn RadianceEstimate) -> Image {
        self.eye_pass(Some(EstimatedMap { map, estimate })).1
    }

    /// Scores later runs against `reference` (the caustic contribution, as from
    /// [`SceneTarget::caustic_image`] at this resolution).
    pub fn set_reference(&mut self, reference: &Image) {
        let values: Vec<f64> = reference.pixels.iter().map(|p| channel_mean(*p)).collect();
        let regions = SceneRegions::from_reference(&values, reference.width, reference.height);
        self.reference = Some((values, regions));
    }

    pub fn regions(&self) -> Option<&SceneRegions> {
        self.reference.as_ref().map(|(_, r)| r)
    }
}

impl Target for SceneTarget {
    fn name(&self) -> String {
        self.path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into())
    }

    fn photons(&mut self, count: usize, pass: u64) -> Result<PhotonMap, SweepError> {
        let map = self.trace(count, pass, &ProgressBar::hidden());
        if map.is_empty() {
            return Err(SweepError::Target(format!(
                "{}: no caustic photons were stored; the lights do not reach a mirror or glass \
                 object followed by a diffuse surface",
                self.path.display()
            )));
        }
        Ok(map)
    }

    fn evaluate(&self, map: &PhotonMap, estimate: &dyn RadianceEstimate) -> Vec<f64> {
        self.caustic_image(map, estimate)
            .pixels
            .iter()
            .map(|p| channel_mean(*p))
            .collect()
    }

    fn score(&self, values: &[f64]) -> Errors {
        let (reference, regions) = self
            .reference
            .as_ref()
            .expect("set_reference() runs before the sweep");
        scene_errors(values, reference, regions)
    }
}
