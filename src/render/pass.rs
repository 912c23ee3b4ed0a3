//! One pass of a progressive render, start to end: trace this pass's photon maps from its own
//! random streams, resolve the estimates at this pass's radii (the diffusion estimate's
//! gradient pass timed as its own phase, and so are the irradiance tables a final gather or a
//! sparse shown global map reads), shade fresh pixel samples into a [`PassImage`], and drop
//! the maps. A pass depends only on the scene, the [`RenderSettings`], the base radii, the
//! seed and its index, so any pass can run anywhere and in any order. Owns the per-pass
//! wiring; must not accumulate passes (the [`super::film`] does) or read the command line.
//!
//! Progressive radii. Pass `i` scales every radius by [`Schedule::radius_scale`], the caustic
//! estimate's also by the square root of its map's growth ([`Schedule::caustic_radius_scale`]):
//! the fixed-radius estimates (Epanechnikov, diffusion: `r`, `r_g` and `ρ` together) from their
//! pass-0 radius; the k-NN estimates (simple, cone, Gaussian, and the global map's constant
//! kernel) keep pass 0 as the one-shot estimate, and from pass 1 on cap their search at the
//! scaled base radius (`--radius`, else the k-equivalent radius of pass 0's map). Once the cap
//! is below the k-th photon's distance everywhere they are fixed-radius estimates with a
//! shrinking radius too, so every estimate converges; the k-NN ones only after that point.
//!
//! Normalisation: each pass's maps carry their own emitted count, so each pass is an
//! estimate of the whole image on its own and the film averages passes with equal weights.

use super::camera::{PassSamples, RayCamera};
use super::emission::emitted_mean;
use super::film::{KERNEL_CHANNELS, PassImage, RGB_LAYERS};
use super::integrator::Emission;
use super::integrator::{EstimatedMap, Indirect, Integrator, Radiance};
use super::kernel_probe::KernelProbe;
use super::light_images::Aim;
use super::pilots::PixelPlan;
use super::schedule::{PhotonGrowth, Schedule, pass_estimator};
use crate::estimate::beam::shaping::{VolumeDiffusion, shape_kernels};
use crate::estimate::classic::KnnEstimate;
use crate::estimate::diffusion::shaped::ShapedBy;
use crate::estimate::kernel::RadialKernel;
use crate::estimate::precomputed::{
    PrecomputedIrradiance, SHOWN_TABLE_QUERIES_PER_PHOTON, ShownIrradiance,
};
use crate::estimate::settings::k_equivalent_radius;
use crate::estimate::{
    EstimateError, EstimatorSettings, RadianceEstimate, ResolvedEstimator, Scratch,
};
use crate::photon::PhotonMap;
use crate::photon::tracer::{MapKind, TraceCounts, trace_map_within};
use crate::photon::volume::{VolumeMap, VolumeMaps, VolumePhoton};
use crate::sampling::PathSampler;
use crate::scene::Transport;
use crate::timing::{PhaseTimes, progress};
use crate::world::World;
use indicatif::ProgressBar;
use rayon::prelude::*;
use std::time::Instant;

/// What every pass of one render uses: the film records it, and merging compares it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub struct RenderSettings {
    /// Photons stored in each pass's caustic map (0: no caustic map).
    pub caustic_photons: usize,
    /// Photons stored in each pass's global map (0: no global map).
    pub global_photons: usize,
    /// Paths each pass may emit for its global map (0: the tracer's own limit). Left out of
    /// the file when 0, so films that had no such limit keep their bytes.
    #[serde(default, skip_serializing_if = "no_path_limit")]
    pub global_paths: u64,
    /// `--no-open-scene`: no open-scene probe. Left out of the file when false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub no_open_scene: bool,
    /// Camera samples per pixel in each pass.
    pub spp: u32,
    pub max_depth: u32,
    /// Final-gather rays per diffuse eye hit (0: the global map shown directly).
    pub final_gather: u32,
    pub global_k: usize,
    /// Neighbours that set a volume photon's radius. Left out of the file at its default,
    /// so films of scenes without media keep their bytes.
    #[serde(
        default = "default_volume_k",
        skip_serializing_if = "is_default_volume_k"
    )]
    pub volume_k: usize,
    /// The contrast `K` of the volumetric caustics' diffusion kernel (`--volume-contrast`);
    /// none: round kernels. Left out of the file when none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume_contrast: Option<f64>,
    /// Irradiance precomputed at every n-th global photon for final gathering (0: a k-NN
    /// estimate per gather ray).
    pub irradiance_stride: usize,
    /// Shadow rays per area light at each diffuse eye hit.
    pub light_samples: u32,
    /// Bounded lights up to which each diffuse eye hit samples every light; past it they are
    /// drawn from the light tree. Left out of the file at its default, so films keep their
    /// bytes.
    #[serde(
        default = "default_every_light_max",
        skip_serializing_if = "is_default_every_light_max"
    )]
    pub every_light_max: usize,
    /// Glass hits below this depth follow both the reflected and the refracted ray; deeper
    /// ones follow one, chosen by the Fresnel reflectance.
    #[serde(default = "split_everywhere")]
    pub glass_split_depth: u32,
    /// Samples of the light seen along mirror and glass chains per pass in each pixel that
    /// sees a light, mirror or glass first (`render::emission`); 0: camera samples count it.
    /// Films written before it existed counted it in their camera samples.
    #[serde(default)]
    pub emission_samples: u32,
    /// Whether half of those samples aim at the light images found in a pixel
    /// (`render::light_images`). Films written before it existed spread them all.
    #[serde(default)]
    pub light_images: bool,
    /// Camera samples per pass in the pixels whose pilot rays find an edge
    /// (`render::pilots`); 0: they take `spp` like the rest. Films written before it existed
    /// took `spp` everywhere.
    #[serde(default)]
    pub edge_samples: u32,
    /// Pilot paths of the caustic guide learnt once per render (`photon::guide`); 0: photons
    /// spread uniformly over their cones. Films written before it existed were unguided.
    #[serde(default)]
    pub guide_paths: u64,
    /// Microfacet reflection at least this rough reads photons (`bsdf::Part::Estimated`).
    /// Films written before it existed followed every glossy lobe.
    #[serde(default = "follow_every_glossy_lobe")]
    pub glossy_min_alpha: f32,
    /// `α` of the progressive radius reduction.
    pub alpha: f64,
    /// How the caustic map's count grows with the passes. Films written before it existed
    /// stored the same count in every pass.
    #[serde(default = "no_growth", skip_serializing_if = "PhotonGrowth::is_none")]
    pub caustic_growth: PhotonGrowth,
    pub estimator: EstimatorSettings,
    /// How far light is followed (a pbrt scene's `Integrator` line). Left out of the file
    /// when dpm's own, so films that had no cap keep their bytes.
    #[serde(default, skip_serializing_if = "Transport::is_full")]
    pub transport: Transport,
}

fn default_volume_k() -> usize {
    super::args::DEFAULT_VOLUME_K
}

fn is_default_volume_k(k: &usize) -> bool {
    *k == super::args::DEFAULT_VOLUME_K
}

fn default_every_light_max() -> usize {
    super::args::DEFAULT_EVERY_LIGHT_MAX
}

fn is_default_every_light_max(n: &usize) -> bool {
    *n == super::args::DEFAULT_EVERY_LIGHT_MAX
}

fn no_growth() -> PhotonGrowth {
    PhotonGrowth::NONE
}

fn no_path_limit(paths: &u64) -> bool {
    *paths == 0
}

/// Films written before `glass-split-depth` existed split at every glass hit.
fn split_everywhere() -> u32 {
    u32::MAX
}

/// Films written before `glossy-min-alpha` existed followed every glossy lobe.
fn follow_every_glossy_lobe() -> f32 {
    f32::MAX
}

/// The radii pass 0 resolves and every later pass scales.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub struct BaseRadii {
    /// The caustic estimate's fixed radius, or its k-NN search cap from pass 1 on.
    pub caustic: Option<f32>,
    /// The global map's k-NN search cap from pass 1 on.
    pub global: Option<f32>,
}

impl BaseRadii {
    /// The base radii from pass 0's maps (the given `--radius` when there is one).
    pub fn resolve(settings: &RenderSettings, maps: &PassMaps) -> Result<BaseRadii, EstimateError> {
        let e = &settings.estimator;
        let caustic = match maps.caustic.as_ref().map(|(m, _)| m) {
            Some(map) if !map.is_empty() => match e.radius {
                Some(r) => Some(r),
                None => {
                    let r = k_equivalent_radius(map, e.k);
                    if r.is_none() && e.estimator.is_fixed_radius() {
                        return Err(EstimateError::DegenerateMap);
                    }
                    r
                }
            },
            _ => e.radius,
        };
        let global = match maps.global.as_ref().map(|(m, _)| m) {
            Some(map) if !map.is_empty() => k_equivalent_radius(map, settings.global_k),
            _ => None,
        };
        Ok(BaseRadii { caustic, global })
    }
}

/// The global map's estimate in pass `pass`.
pub fn global_estimate(
    settings: &RenderSettings,
    radii: &BaseRadii,
    schedule: &Schedule,
    pass: u64,
) -> KnnEstimate {
    let cap = (pass > 0)
        .then(|| radii.global.map(|r| r * schedule.radius_scale(pass)))
        .flatten();
    KnnEstimate::new(RadialKernel::Constant, settings.global_k, cap)
}

/// The largest radius a volume photon takes, relative to the size of the media (the scene's
/// where they are not bounded): a lone photon in an empty stretch of fog would otherwise
/// spread over the whole scene.
const VOLUME_MAX_RADIUS: f32 = 0.05;

/// One pass's photon maps, with what tracing them took.
#[derive(Default)]
pub struct PassMaps {
    pub caustic: Option<(PhotonMap, TraceCounts)>,
    pub global: Option<(PhotonMap, TraceCounts)>,
    /// The photons the caustic and global paths left in media (empty without media).
    pub volume: VolumePhotons,
}

/// A pass's volume photons, before their maps are built.
#[derive(Default)]
pub struct VolumePhotons {
    pub caustic: Vec<VolumePhoton>,
    pub global: Vec<VolumePhoton>,
}

/// The maps a render with `settings` traces in a scene.
pub fn wanted_maps(settings: &RenderSettings, world: &World) -> Vec<crate::photon::store::MapInfo> {
    use crate::photon::store::MapInfo;
    let mut wanted = Vec::new();
    // Without a diffuse surface no caustic photon is ever stored: tracing would only run
    // to its path limit.
    // A medium keeps caustic photons too (a volumetric caustic).
    let receives = world.has_diffuse() || world.media.is_some();
    if world.has_specular() && receives && settings.caustic_photons > 0 {
        wanted.push(MapInfo {
            kind: MapKind::Caustic,
            target: settings.caustic_photons as u64,
            guide: u32::try_from(settings.guide_paths).expect("--guide-paths is checked"),
        });
    }
    if settings.global_photons > 0 {
        wanted.push(MapInfo {
            kind: MapKind::Global {
                with_direct: settings.final_gather > 0,
            },
            target: settings.global_photons as u64,
            guide: 0,
        });
    }
    wanted
}

/// Photons pass `pass` stores in a map the render wants (`info.target` is pass 0's): the
/// caustic map grows by `growth`, the global map keeps its count.
pub fn pass_target(info: &crate::photon::store::MapInfo, growth: &PhotonGrowth, pass: u64) -> u64 {
    match info.kind {
        MapKind::Caustic => growth.photons(info.target, pass),
        MapKind::Global { .. } => info.target,
    }
}

/// Traces the maps of pass `pass` (an interruption leaves them empty: check for it).
pub fn trace_pass_maps(
    world: &World,
    settings: &RenderSettings,
    schedule: &Schedule,
    pass: u64,
    times: &mut PhaseTimes,
) -> PassMaps {
    let seed = schedule.seed(pass);
    let mut maps = PassMaps::default();
    for info in wanted_maps(settings, world) {
        let (slot, what) = match info.kind {
            MapKind::Caustic => (&mut maps.caustic, "caustic photons"),
            MapKind::Global { .. } => (&mut maps.global, "global photons"),
        };
        let target = pass_target(&info, &schedule.growth, pass);
        let bar = progress(target, what);
        let start = Instant::now();
        let max_paths = match info.kind {
            MapKind::Global { .. } if settings.global_paths > 0 => Some(settings.global_paths),
            _ => None,
        };
        let (map, volume, counts) =
            trace_map_within(world, info.kind, target as usize, max_paths, seed, &bar);
        match info.kind {
            MapKind::Caustic => maps.volume.caustic = volume,
            MapKind::Global { .. } => maps.volume.global = volume,
        }
        bar.finish_and_clear();
        times.accumulate(
            &format!("trace {what}"),
            start.elapsed(),
            &[("emitted", counts.emitted), ("stored", counts.stored)],
        );
        *slot = Some((map, counts));
        if crate::interrupt::requested() {
            break;
        }
    }
    maps
}

/// What a pass did, beside its image.
pub struct PassReport {
    pub image: PassImage,
    pub caustic: Option<TraceCounts>,
    pub global: Option<TraceCounts>,
    /// The caustic estimate with every number resolved.
    pub estimator: Option<String>,
    pub caustic_bytes_per_photon: Option<f64>,
    /// The volume photon maps' photons and heap bytes (both maps), in a scene with media.
    pub volume_maps: Option<(usize, usize)>,
}

/// The tables a pass's global map is read through (see [`PassContext::irradiance_tables`]).
#[derive(Default)]
struct IrradianceTables {
    gather: Option<PrecomputedIrradiance>,
    shown: Option<ShownIrradiance>,
}

/// Everything a pass needs besides its maps.
pub struct PassContext<'a> {
    pub world: &'a World,
    pub camera: RayCamera,
    pub settings: &'a RenderSettings,
    pub radii: BaseRadii,
    pub schedule: Schedule,
    /// Whether to fill the kernel-field channels (diffusion estimate only).
    pub kernel_field: bool,
    /// How each pixel spends its samples (planned once per render by the pilot rays).
    pub plan: &'a PixelPlan,
}

impl PassContext<'_> {
    pub fn channels(&self) -> usize {
        3 * RGB_LAYERS.len()
            + if self.kernel_field {
                KERNEL_CHANNELS.len()
            } else {
                0
            }
    }

    /// Runs pass `pass` on its `maps` (consumed: they are freed when it ends). `None` when an
    /// interruption was requested: the pass is incomplete and must be discarded.
    /// `analysis`: the map of the earlier passes' caustic photons that shapes the diffusion
    /// kernels ([`super::tensor_history`]), or `None` for the pass's own.
    pub fn run(
        &self,
        pass: u64,
        maps: PassMaps,
        analysis: Option<PhotonMap>,
        times: &mut PhaseTimes,
    ) -> Result<Option<PassReport>, EstimateError> {
        if crate::interrupt::requested() {
            return Ok(None);
        }
        let PassMaps {
            mut caustic,
            global,
            volume,
        } = maps;
        let volume = self.volume_maps(volume, pass, times);
        let mut estimator = None;
        let mut diffusion = None;
        // The diffusion kernels' shapes come from the earlier passes' photons when there are
        // any (the tensor history), else from this pass's own.
        let mut analysis = analysis.filter(|a| !a.is_empty());
        let resolved = match caustic.as_mut() {
            Some((map, _)) if !map.is_empty() => {
                let settings = pass_estimator(
                    &self.settings.estimator,
                    self.radii.caustic,
                    &self.schedule,
                    pass,
                );
                let resolved = settings.resolve(map)?;
                estimator = Some(resolved.to_string());
                if let ResolvedEstimator::Diffusion(d) = &resolved {
                    let start = Instant::now();
                    // Where the history shapes the kernels the pass's own map is only
                    // summed: its leaf sums, no gradients.
                    let photons = match analysis.as_mut() {
                        Some(a) => {
                            d.gradient_pass(a);
                            crate::estimate::diffusion::shaped::prepare_summed(map);
                            a.len()
                        }
                        None => {
                            d.gradient_pass(map);
                            map.len()
                        }
                    };
                    diffusion = Some(*d);
                    times.accumulate(
                        "gradient pass",
                        start.elapsed(),
                        &[("photons", photons as u64)],
                    );
                }
                Some(resolved)
            }
            _ => None,
        };
        let caustic_estimate: Option<Box<dyn RadianceEstimate + '_>> =
            match (resolved, analysis.as_ref()) {
                (Some(ResolvedEstimator::Diffusion(d)), Some(analysis)) => {
                    Some(Box::new(ShapedBy {
                        estimate: d,
                        analysis,
                    }))
                }
                (resolved, _) => resolved.map(ResolvedEstimator::into_boxed),
            };
        if let (Some(estimate), Some((map, _))) = (&caustic_estimate, caustic.as_mut()) {
            estimate.prepare(map);
        }
        let global_estimate = global_estimate(self.settings, &self.radii, &self.schedule, pass);
        let tables = match &global {
            Some((map, _)) if !map.is_empty() => {
                let tables = self.irradiance_tables(map, &global_estimate, pass, times);
                if crate::interrupt::requested() {
                    return Ok(None);
                }
                tables
            }
            _ => IrradianceTables::default(),
        };
        let integrator = Integrator {
            world: self.world,
            caustics: match (&caustic, &caustic_estimate) {
                (Some((map, _)), Some(e)) => Some(EstimatedMap {
                    map,
                    estimate: e.as_ref(),
                }),
                _ => None,
            },
            indirect: match &global {
                Some((map, _)) if !map.is_empty() => match self.settings.final_gather {
                    0 => Indirect::Visualize {
                        map,
                        estimate: &global_estimate,
                        table: tables.shown.as_ref(),
                    },
                    rays => Indirect::FinalGather {
                        map: EstimatedMap {
                            map,
                            estimate: &global_estimate,
                        },
                        rays,
                        precomputed: tables.gather.as_ref(),
                    },
                },
                _ => Indirect::None,
            },
            max_depth: self.settings.max_depth,
            light_samples: self.settings.light_samples,
            glass_split_depth: self.settings.glass_split_depth,
            volume: VolumeMaps {
                caustic: volume.0.as_ref(),
                global: volume.1.as_ref(),
            },
        };
        let probe = match (&caustic, &diffusion) {
            (Some((map, _)), Some(d)) if self.kernel_field => Some(KernelProbe {
                world: self.world,
                map: analysis.as_ref().unwrap_or(map),
                estimate: d,
            }),
            _ => None,
        };
        let samples = PassSamples::new(self.schedule.seed, pass, self.settings.spp);
        let bar = progress(self.camera.height() as u64, "render");
        let start = Instant::now();
        let image = shade_pass(
            &self.camera,
            &integrator,
            &samples,
            Some(self.plan),
            probe.as_ref(),
            self.channels(),
            &bar,
        );
        bar.finish_and_clear();
        let pixels = (image.width * image.height) as u64;
        times.accumulate(
            "render",
            start.elapsed(),
            &[
                ("pixels", pixels),
                ("spp", self.settings.spp as u64),
                ("emission pixels", self.plan.emission_pixels() as u64),
                ("edge pixels", self.plan.edge_pixels() as u64),
            ],
        );
        if crate::interrupt::requested() {
            return Ok(None);
        }
        Ok(Some(PassReport {
            image,
            caustic: caustic.as_ref().map(|(_, c)| *c),
            global: global.as_ref().map(|(_, c)| *c),
            estimator,
            caustic_bytes_per_photon: caustic.as_ref().map(|(m, _)| m.bytes_per_photon()),
            volume_maps: (volume.0.is_some() || volume.1.is_some()).then(|| {
                let maps = [&volume.0, &volume.1];
                let photons = maps.iter().flat_map(|m| m.iter()).map(|m| m.len()).sum();
                let bytes = maps.iter().flat_map(|m| m.iter()).map(|m| m.bytes()).sum();
                (photons, bytes)
            }),
        }))
    }

    /// The pass's volume photon maps (caustic, global), each photon's radius its
    /// `--volume-k` nearest neighbours' times the pass's radius scale, so that the beam
    /// estimate's 2-D kernels shrink at the rate the surface estimates' do.
    fn volume_maps(
        &self,
        photons: VolumePhotons,
        pass: u64,
        times: &mut PhaseTimes,
    ) -> (Option<VolumeMap>, Option<VolumeMap>) {
        if photons.caustic.is_empty() && photons.global.is_empty() {
            return (None, None);
        }
        let start = Instant::now();
        let count = (photons.caustic.len() + photons.global.len()) as u64;
        let k = self.settings.volume_k;
        // Relative to the media's own size where they are bounded (a cloud under a wide sky).
        let media = self.world.media.as_ref();
        let reach = (media.and_then(|m| m.bounds())).map_or(self.world.scale, |b| 2.0 * b.radius);
        let max_radius = VOLUME_MAX_RADIUS * reach;
        let scale = self.schedule.radius_scale(pass);
        let build = |photons: Vec<VolumePhoton>| {
            (!photons.is_empty()).then(|| VolumeMap::build(photons, k, max_radius, scale))
        };
        let mut maps = (build(photons.caustic), build(photons.global));
        times.accumulate("volume maps", start.elapsed(), &[("photons", count)]);
        // A walk under a subsurface surface is smooth: shaping its photons would only cost.
        let shaped = media.is_some_and(|m| m.has_free_media());
        if let (Some(map), Some(contrast), true) =
            (maps.0.as_mut(), self.settings.volume_contrast, shaped)
        {
            let start = Instant::now();
            let params = VolumeDiffusion {
                contrast,
                ..VolumeDiffusion::default()
            };
            map.set_shapes(shape_kernels(map, scale, &params));
            let photons = [("photons", map.len() as u64)];
            times.accumulate("volume kernels", start.elapsed(), &photons);
        }
        maps
    }

    /// The irradiance tables of the pass's global map, if it is read through one (none with
    /// `--irradiance-stride 0`): for final gathering at one photon in the stride
    /// (Christensen's), and for a map shown directly a [`ShownIrradiance`] when the map is
    /// sparse, the eye pass making more than [`SHOWN_TABLE_QUERIES_PER_PHOTON`] estimates a
    /// photon. The choice depends only on the map and the image size, so a pass makes the
    /// same image wherever it runs.
    fn irradiance_tables(
        &self,
        map: &PhotonMap,
        estimate: &KnnEstimate,
        pass: u64,
        times: &mut PhaseTimes,
    ) -> IrradianceTables {
        let stride = self.settings.irradiance_stride;
        let pixels = self.camera.width() * self.camera.height();
        let mut tables = IrradianceTables::default();
        let count = if stride == 0 {
            return tables;
        } else if self.settings.final_gather > 0 {
            map.len().div_ceil(stride)
        } else if map.len() * SHOWN_TABLE_QUERIES_PER_PHOTON < pixels {
            map.len()
        } else {
            return tables;
        };
        let bar = progress(count as u64, "precompute irradiance");
        let start = Instant::now();
        let points = if self.settings.final_gather > 0 {
            // Lookups search as far as the estimate itself may reach: pass 0's k-equivalent
            // radius, shrinking with the passes like the estimate's cap.
            let reach = self
                .radii
                .global
                .map(|r| r * self.schedule.radius_scale(pass));
            let table = PrecomputedIrradiance::build(map, estimate, stride, reach, &bar);
            let points = table.len();
            tables.gather = Some(table);
            points
        } else {
            let table = ShownIrradiance::build(map, estimate, &bar);
            let points = table.len();
            tables.shown = Some(table);
            points
        };
        bar.finish_and_clear();
        times.accumulate(
            "precompute irradiance",
            start.elapsed(),
            &[("points", points as u64)],
        );
        tables
    }
}

/// Glass hits that split an edge pixel's camera paths at most.
const EDGE_GLASS_SPLIT_DEPTH: u32 = 1;

/// Every pixel of one pass, rows in parallel (one row per job: rows of very different cost,
/// a caustic against empty floor, are shared out evenly), each thread with its own scratch.
/// Pixels not yet started when an interruption is requested are left black; the caller must
/// check for it and discard the pass.
pub fn shade_pass(
    camera: &RayCamera,
    integrator: &Integrator,
    samples: &PassSamples,
    plan: Option<&PixelPlan>,
    probe: Option<&KernelProbe>,
    channels: usize,
    progress: &ProgressBar,
) -> PassImage {
    let (w, h) = (camera.width(), camera.height());
    let mut image = PassImage::new(w, h, channels);
    let spp = samples.spp();
    // Edge pixels' many samples each follow one branch past the first glass hit: a split
    // tree per sample multiplied their cost by the tree's size for detail the samples
    // themselves average in.
    let edge_integrator = Integrator {
        glass_split_depth: integrator.glass_split_depth.min(EDGE_GLASS_SPLIT_DEPTH),
        ..*integrator
    };
    let camera_medium = (integrator.world.media.as_ref()).and_then(|m| m.camera());
    image
        .values
        .par_chunks_mut(w * channels)
        .with_max_len(1)
        .enumerate()
        .for_each_init(Scratch::default, |scratch, (y, row)| {
            for (x, px) in row.chunks_mut(channels).enumerate() {
                // Per pixel, not per row: a row through glass can take seconds.
                if crate::interrupt::requested() {
                    return;
                }
                // The plan is the image's; the samples are keyed by the full film's pixel.
                let pixel = y * w + x;
                let key = camera.pixel_key(x, y);
                let (fx, fy) = camera.film_pixel(x, y);
                let (fx, fy) = (fx as f32, fy as f32);
                let apart = plan.filter(|p| p.emission_apart(pixel));
                let counted = if apart.is_some() {
                    Emission::Elsewhere
                } else {
                    Emission::Counted
                };
                let count = plan.map_or(spp, |p| p.camera_samples(pixel, spp));
                let integrator = if count > spp {
                    &edge_integrator
                } else {
                    integrator
                };
                let mut sum = Radiance::default();
                for s in 0..count {
                    let sample = samples.sample_of(key, s, count);
                    let (jx, jy) = sample.jitter;
                    let ray = camera.ray(fx + jx, fy + jy, sample.lens);
                    let mut sampler = PathSampler::new(sample.rng, Some(sample.sequence));
                    sum += integrator.trace(
                        ray.origin,
                        ray.direction,
                        camera_medium,
                        0,
                        counted,
                        &mut sampler,
                        scratch,
                    );
                }
                let mut mean = (1.0 / count.max(1) as f32) * sum;
                if let Some(p) = apart {
                    let n = p.emission_samples();
                    let aim = Aim::new(p.light_images(pixel), n);
                    let at = (0..n).map(|j| samples.emission_sample(key, j, n));
                    let corner = glam::Vec2::new(fx, fy);
                    mean.direct += emitted_mean(integrator, camera, &aim, corner, at);
                }
                for (i, v) in [mean.total(), mean.direct, mean.caustic, mean.indirect]
                    .iter()
                    .enumerate()
                {
                    px[3 * i..3 * i + 3].copy_from_slice(&v.to_array());
                }
                if let Some(p) = probe {
                    let ray = camera.chief_ray(fx + 0.5, fy + 0.5);
                    px[12..16].copy_from_slice(&p.channels(ray.origin, ray.direction, scratch));
                }
            }
            progress.inc(1);
        });
    image
}
