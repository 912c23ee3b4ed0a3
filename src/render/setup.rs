//! What a render decides once, before its first pass: the scene loaded into an Embree world,
//! the settings every pass shares and the film header they imply, where this run's passes
//! start (pass 0, `--first-pass`, or the end of a `--resume`d film, with pass 0's base radii),
//! and the pixel plan of the pilot rays. Owns those decisions; the passes themselves are
//! [`super::pass_loop`]'s, and nothing here traces photons except the pass-0 maps a late start
//! needs for its radii and pass 0's global map where a lone diffuse object may not light
//! itself at all.

use super::args::{
    DEFAULT_GLOBAL_PHOTONS, DEFAULT_LONE_GLOBAL_PATHS, DEFAULT_LONE_GLOBAL_PHOTONS,
    DEFAULT_RADIUS_K, RenderArgs,
};
use super::camera::RayCamera;
use super::film::{Film, FilmHeader};
use super::film_file;
use super::memory_budget::check_memory;
use super::pass::{BaseRadii, PassMaps, RenderSettings, trace_pass_maps, wanted_maps};
use super::pilots::PixelPlan;
use super::pipeline::{RenderError, pass_limit};
use super::schedule::{MAX_PASSES, PhotonGrowth, Schedule};
use crate::estimate::settings::EstimatorKind;
use crate::image_io::ImageFormat;
use crate::photon::store::{self, MapInfo};
use crate::photon::tracer::MapKind;
use crate::scene;
use crate::timing::PhaseTimes;
use crate::world::World;
use crate::world::lights::sampler::{LightSampler, SAMPLE_EVERY_LIGHT_MAX};
use std::path::Path;

/// Loads the scene (at `--resolution` if given, the vertical field of view or orthographic view
/// height kept, and the crop window's fractions of the film), reports what
/// loading repaired, and builds its Embree world; returns it with the scene's fingerprint.
pub fn load_world(args: &RenderArgs, times: &mut PhaseTimes) -> Result<(World, u64), RenderError> {
    let (mut description, report) = times.time("load scene", || {
        let options = scene::LoadOptions {
            strict: args.strict,
            pbrt_default_integrator: args.pbrt_default_integrator,
        };
        scene::load_with_options(&args.scene, &options)
    })?;
    if args.full_transport {
        description.transport = scene::Transport::Full;
    }
    if let Some((width, height)) = args.resolution {
        description.camera.width = width;
        description.camera.height = height;
        if matches!(description.camera.image_size(), (0, _) | (_, 0)) {
            return Err(RenderError::Invalid(format!(
                "--resolution {width}x{height}: the scene's crop window holds no whole pixel of that film"
            )));
        }
    }
    report_load(args, &report, times);
    let scene_hash = store::scene_fingerprint(&description);
    let world = times.time("build Embree scene", || {
        World::with_glossy_min_alpha(description, args.glossy_min_alpha)
    })?;
    let in_place = world.meshes_read_in_place() as u64;
    if in_place > 0 {
        times.add_counts("build Embree scene", &[("meshes read in place", in_place)]);
    }
    Ok((world, scene_hash))
}

/// What loading repaired or suspects: warnings on stderr, dropped triangles in the table.
fn report_load(args: &RenderArgs, report: &scene::LoadReport, times: &mut PhaseTimes) {
    let scene = args.scene.display().to_string();
    for warning in &report.warnings {
        // pbrt warnings already begin with their file:line:column.
        if warning.starts_with(&scene) {
            eprintln!("warning: {warning}");
        } else {
            eprintln!("warning: {scene}: {warning}");
        }
    }
    for note in &report.notes {
        eprintln!("note: {note}");
    }
    if report.degenerate_triangles_dropped > 0 {
        let dropped = report.degenerate_triangles_dropped as u64;
        times.add_counts("load scene", &[("zero-area triangles dropped", dropped)]);
    }
}

/// The settings every pass of this render shares, and what the film records of them.
pub struct Wiring {
    pub settings: RenderSettings,
    /// The photon maps each pass traces.
    pub wanted: Vec<MapInfo>,
    pub schedule: Schedule,
    pub scene_hash: u64,
    /// Whether the film accumulates the diffusion kernel's field.
    pub kernel_field: bool,
}

impl Wiring {
    /// Wires the flags to the scene: the settings, the caustic guide (learnt here, once), the
    /// maps and the up-front memory check.
    pub fn new(
        args: &RenderArgs,
        world: &mut World,
        scene_hash: u64,
        output: &Path,
        times: &mut PhaseTimes,
    ) -> Result<Self, RenderError> {
        let mut settings = render_settings(args, world);
        drop_an_empty_lone_global_map(&mut settings, args, world, times);
        super::global_budget::size_for_an_open_scene(&mut settings, args, world, times);
        if settings.every_light_max != SAMPLE_EVERY_LIGHT_MAX {
            world.light_sampler =
                LightSampler::with_limit(&world.light_sources, settings.every_light_max);
        }
        super::caustic_guide::learn(world, &settings, args.seed, times);
        let wanted = wanted_maps(&settings, world);
        // The caustic map is largest in the last pass this run may render (a resumed film's
        // first pass is not known yet).
        let last_pass = match args.resume {
            Some(_) => MAX_PASSES,
            None => (args.first_pass + pass_limit(args))
                .min(MAX_PASSES)
                .saturating_sub(1),
        };
        check_memory(
            &settings.estimator,
            world,
            &wanted,
            &settings.caustic_growth,
            last_pass,
        )?;
        // The kernel field needs the diffusion estimate and a caustic map to steer it.
        let kernel_field = settings.estimator.estimator == EstimatorKind::Diffusion
            && wanted.iter().any(|w| w.kind == MapKind::Caustic)
            && (args.kernel_field.is_some()
                || ImageFormat::from_path(output).ok() == Some(ImageFormat::Exr));
        Ok(Self {
            schedule: Schedule::new(settings.alpha, args.seed)
                .with_growth(settings.caustic_growth, settings.caustic_photons as u64),
            settings,
            wanted,
            scene_hash,
            kernel_field,
        })
    }

    /// The film header of this render once pass 0's base radii are known.
    pub fn header(&self, args: &RenderArgs, world: &World, radii: BaseRadii) -> FilmHeader {
        let (width, height) = world.description.camera.image_size();
        FilmHeader {
            scene_file: args.scene.display().to_string(),
            scene_hash: self.scene_hash,
            seed: args.seed,
            width: width as usize,
            height: height as usize,
            settings: self.settings.clone(),
            radii,
            kernel_field: self.kernel_field,
            response: world.description.response,
        }
    }

    /// Where this run's passes start.
    pub fn start(
        &self,
        args: &RenderArgs,
        world: &World,
        times: &mut PhaseTimes,
    ) -> Result<Start, RenderError> {
        let mut start = Start {
            film: None,
            first: args.first_pass,
            radii: None,
        };
        if let Some(path) = &args.resume {
            let resumed = times.time("read film", || film_file::read(path))?;
            let probe = self.header(args, world, resumed.header.radii);
            if let Some(field) = resumed.header.first_difference(&probe) {
                return Err(RenderError::Invalid(format!(
                    "--resume {}: the film and this render differ in {field}; it cannot be continued",
                    path.display()
                )));
            }
            start.first = resumed.passes().end();
            start.radii = Some(resumed.header.radii);
            start.film = Some(resumed);
        } else if start.first > 0 {
            start.radii = Some(self.pass_zero_radii(world, times)?);
        }
        Ok(start)
    }

    /// Pass 0's radii for a run that starts later: given ones need no maps, derived ones need
    /// pass 0's, traced once.
    fn pass_zero_radii(
        &self,
        world: &World,
        times: &mut PhaseTimes,
    ) -> Result<BaseRadii, RenderError> {
        let given = self.settings.estimator.radius.is_some()
            || !self.wanted.iter().any(|w| w.kind == MapKind::Caustic);
        let global = self
            .wanted
            .iter()
            .any(|w| matches!(w.kind, MapKind::Global { .. }));
        let maps = if given && !global {
            PassMaps::default()
        } else {
            trace_pass_maps(world, &self.settings, &self.schedule, 0, times)
        };
        Ok(BaseRadii::resolve(&self.settings, &maps)?)
    }
}

/// Where a run's passes start: the film it continues (none yet for a fresh render: its header
/// needs pass 0's radii), its first pass, and pass 0's radii when already known.
pub struct Start {
    pub film: Option<Film>,
    pub first: u64,
    pub radii: Option<BaseRadii>,
}

/// Drops the default global map of a lone diffuse object that does not light itself: when
/// pass 0's map, traced here, stores nothing from its paths, no pass traces one. A floor
/// under a standing chrome ring is such a case: a vertical mirror keeps a ray's upward slope,
/// so light leaving the floor never comes back to it, and the ring's 100,000 global paths a
/// pass stored nothing for 4% of its pass. The trace is pass 0's own (the same seed), so the
/// decision is the same on every machine, and dropping a map that stays empty changes no
/// pass's image (the caustic photons and camera samples have streams of their own). A map
/// given by `--global-photons` is always traced.
fn drop_an_empty_lone_global_map(
    settings: &mut RenderSettings,
    args: &RenderArgs,
    world: &World,
    times: &mut PhaseTimes,
) {
    if !world.lights_itself_alone() || args.global_photons.is_some() || settings.global_photons == 0
    {
        return;
    }
    let start = std::time::Instant::now();
    let seed = Schedule::new(settings.alpha, args.seed).seed(0);
    let kind = MapKind::Global {
        with_direct: settings.final_gather > 0,
    };
    let paths = (settings.global_paths > 0).then_some(settings.global_paths);
    let bar = indicatif::ProgressBar::hidden();
    let (_, _, counts) = crate::photon::tracer::trace_map_within(
        world,
        kind,
        settings.global_photons,
        paths,
        seed,
        &bar,
    );
    times.record(
        "probe global map",
        start.elapsed(),
        &[("emitted", counts.emitted), ("stored", counts.stored)],
    );
    if counts.stored == 0 {
        settings.global_photons = 0;
        settings.global_paths = 0;
    }
}

/// The settings every pass of this render uses.
fn render_settings(args: &RenderArgs, world: &World) -> RenderSettings {
    let diffuse_objects = world.diffuse_objects();
    let lone = world.lights_itself_alone();
    let transport = world.description.transport;
    let mut settings = RenderSettings {
        caustic_photons: args.caustic_photons,
        // Diffuse light bounces between two diffuse objects, or from one back to itself
        // through its mirrors and glass; a lone plane cannot light itself.
        // A medium scatters light many times over: its volume photons are the global map's.
        global_photons: args.global_photons.unwrap_or(match diffuse_objects {
            _ if world.media.is_some() => DEFAULT_GLOBAL_PHOTONS,
            0 => 0,
            1 if lone => DEFAULT_LONE_GLOBAL_PHOTONS,
            1 => 0,
            _ => DEFAULT_GLOBAL_PHOTONS,
        }),
        global_paths: args.global_paths.unwrap_or(match args.global_photons {
            None if lone => DEFAULT_LONE_GLOBAL_PATHS,
            _ => 0,
        }),
        no_open_scene: args.no_open_scene,
        spp: args.spp,
        max_depth: transport
            .eye_bounces()
            .map_or(args.max_depth, |cap| args.max_depth.min(cap)),
        final_gather: args.final_gather,
        global_k: args.global_k,
        volume_k: args.volume_k,
        // Left out where there are no media, so their films keep their bytes.
        volume_contrast: (world.media.is_some() && args.volume_contrast > 0.0)
            .then_some(args.volume_contrast),
        irradiance_stride: args.irradiance_stride,
        light_samples: args.light_samples,
        every_light_max: args.every_light_max,
        glass_split_depth: args.glass_split_depth,
        emission_samples: args.emission_samples,
        light_images: !args.no_light_images,
        edge_samples: args.edge_samples,
        guide_paths: if args.caustic_photons > 0 {
            args.guide_paths
        } else {
            0
        },
        glossy_min_alpha: args.glossy_min_alpha,
        alpha: args.ppm_alpha,
        caustic_growth: PhotonGrowth::new(
            args.caustic_growth_from,
            args.caustic_photons_max,
            args.caustic_photons as u64,
        ),
        estimator: args.estimate.settings_with_radius_k(DEFAULT_RADIUS_K),
        transport,
    };
    if let scene::Transport::Direct { .. } = transport {
        // pbrt's direct lighting: nothing reaches a diffuse or glossy surface past a bounce.
        settings.caustic_photons = 0;
        settings.global_photons = 0;
        settings.global_paths = 0;
        settings.guide_paths = 0;
    }
    settings
}

/// The pilot rays' plan of every pixel (once per render); None when interrupted.
pub fn survey_pixels(
    camera: &RayCamera,
    world: &World,
    settings: &RenderSettings,
    times: &mut PhaseTimes,
) -> Option<PixelPlan> {
    let plan = times.time("pilot rays", || {
        PixelPlan::survey(
            camera,
            world,
            settings.max_depth,
            settings.emission_samples,
            settings.edge_samples,
            settings.light_images,
        )
    })?;
    times.add_counts(
        "pilot rays",
        &[
            ("emission pixels", plan.emission_pixels() as u64),
            ("aimed", plan.aimed_pixels() as u64),
            ("edge pixels", plan.edge_pixels() as u64),
        ],
    );
    Some(plan)
}
