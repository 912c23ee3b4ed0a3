//! `dpm render`'s flags and their defaults: the one place a reader looks up what a flag
//! means. Owns parsing the command line into [`RenderArgs`]; checking the values together is
//! [`super::pipeline::validate`], running them is [`super::pipeline`].

use super::schedule::DEFAULT_ALPHA;
use crate::estimate::EstimatorFlags;
use crate::estimate::precomputed::DEFAULT_STRIDE;
use std::path::PathBuf;

/// `dpm render --help`'s headings, in the order a user meets the choices. `-h` shows the
/// flags most renders set; `--help` shows every flag with its default.
pub mod headings {
    pub const OUTPUT: &str = "Output and progress";
    pub const PASSES: &str = "Progressive passes and films";
    pub const PHOTONS: &str = "Photons";
    pub use crate::estimate::flags::headings::{ESTIMATE, KERNEL};
    pub const EYE: &str = "Eye pass and sampling";
    pub const DIAGNOSTICS: &str = "Photon files and diagnostics";
}

#[derive(Clone, Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene file: dpm's TOML, or a pbrt-v3/v4 scene by the `.pbrt` extension (see
    /// docs/scene-format.md).
    pub scene: PathBuf,

    /// Output image: .png, .exr or .pfm (default: the scene's name with .png).
    ///
    /// The format follows the extension: .png (tone-mapped sRGB), .exr (linear float RGB, with
    /// direct, caustic and indirect layers and, with the diffusion estimate, the kernel
    /// field), .pfm (linear float RGB). Rewritten atomically as passes complete.
    #[arg(short, long, value_name = "IMAGE", help_heading = headings::OUTPUT)]
    pub output: Option<PathBuf>,

    /// Render at WIDTHxHEIGHT pixels instead of the scene's resolution.
    ///
    /// E.g. 1280x720. The vertical field of view stays the scene's `fov_y`, so a wider image
    /// sees more at the sides. A film remembers its resolution: --resume and `dpm merge`
    /// refuse another.
    #[arg(long, value_name = "WxH", value_parser = parse_resolution, allow_hyphen_values = true,
          help_heading = headings::OUTPUT)]
    pub resolution: Option<(u32, u32)>,

    /// Exposure in stops for PNG output (linear formats are written unscaled).
    #[arg(long, value_name = "STOPS", default_value_t = 0.0, allow_negative_numbers = true,
          help_heading = headings::OUTPUT)]
    pub exposure: f32,

    /// Worker threads (0: one per core); the image does not depend on it.
    #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true,
          help_heading = headings::OUTPUT)]
    pub threads: usize,

    /// Seed of every random number (photon paths and pixel samples of every pass).
    #[arg(long, value_name = "S", default_value_t = 1, allow_negative_numbers = true,
          help_heading = headings::OUTPUT)]
    pub seed: u64,

    /// Refuse a pbrt material dpm can only approximate instead of mapping it with a warning.
    ///
    /// Oren–Nayar `matte` (rendered as Lambert), pbrt-v4's `coatedconductor` and coated layers
    /// with a scattering medium, a `mix` of colour-varying amount: without --strict dpm renders
    /// its approximation and says so once.
    #[arg(long, help_heading = headings::OUTPUT)]
    pub strict: bool,

    /// A reference image (.pfm or .exr) to report the error against after every pass.
    ///
    /// Same resolution as the render; the relative MSE shows in the progress bar and --stats.
    #[arg(long, value_name = "IMAGE", help_heading = headings::OUTPUT)]
    pub reference: Option<PathBuf>,

    /// Progressive passes to render (default 8).
    ///
    /// Each traces fresh photons, shrinks every radius by r²(i+1) = r²(i)·(i+α)/(i+1) and
    /// renders fresh pixel samples; the image is their mean, and converges as passes
    /// accumulate. Default: 8 (1 with --save-photons or --load-photons; with --time, as many
    /// as the budget holds).
    #[arg(long, value_name = "N", allow_negative_numbers = true, help_heading = headings::PASSES)]
    pub passes: Option<u64>,

    /// Wall-clock budget: passes run while the next one fits in it.
    ///
    /// The next pass is predicted from the mean pass time so far; the first pass always runs.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true,
          help_heading = headings::PASSES)]
    pub time: Option<f64>,

    /// Save the film (every pass's per-pixel sums) to FILE after every pass.
    ///
    /// Written atomically, with the scene's hash, seed and settings: `--resume FILE`
    /// continues it, `dpm merge` combines it with films of other pass ranges.
    #[arg(long, value_name = "FILE", help_heading = headings::PASSES)]
    pub film: Option<PathBuf>,

    /// Continue the film in FILE (same scene, seed and settings).
    ///
    /// Passes start where it ends. It is rewritten there unless --film names another file.
    #[arg(long, value_name = "FILE", help_heading = headings::PASSES)]
    pub resume: Option<PathBuf>,

    /// Index of the first pass, to render a range apart for `dpm merge`.
    ///
    /// Passes are the same whichever run renders them, so ranges rendered on other runs or
    /// machines merge into the image one run would have made.
    #[arg(long, value_name = "I", default_value_t = 0, allow_negative_numbers = true,
          help_heading = headings::PASSES, hide_short_help = true)]
    pub first_pass: u64,

    /// α of the progressive radius reduction, in (0, 1) (Knaus and Zwicker: 2/3).
    #[arg(long, value_name = "A", default_value_t = DEFAULT_ALPHA, allow_negative_numbers = true,
          help_heading = headings::PASSES, hide_short_help = true)]
    pub ppm_alpha: f64,

    /// Rewrite -o (and --film) at most every this many seconds (0: after every pass)
    /// [default: after pass 0, then whenever writing has cost at most 2% of the time since].
    ///
    /// The last pass is always written, and so are the complete passes of an interrupted
    /// render. By default a rewrite waits until 50 times what the previous one took has
    /// passed: a caustic-glass EXR with its layers takes about 45 ms, and rewritten after
    /// every one-second pass it took 6% of a 30 s render.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true,
          help_heading = headings::PASSES, hide_short_help = true)]
    pub write_every: Option<f64>,

    /// Photons stored in each pass's caustic map (0: no caustics).
    ///
    /// Light → mirror/glass+ → diffuse paths are emitted until this many are stored. Only
    /// built when the scene has a mirror or glass object.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_CAUSTIC_PHOTONS,
          allow_negative_numbers = true, help_heading = headings::PHOTONS)]
    pub caustic_photons: usize,

    /// The most caustic photons a late pass stores (at most --caustic-photons: every pass the
    /// same).
    ///
    /// Pass i stores --caustic-photons · i / --caustic-growth-from, within these two counts,
    /// and its caustic radii shrink by the square root of its count over --caustic-photons, so
    /// its kernels hold as many photons as before, only tighter. Short renders keep cheap
    /// passes; long ones, whose error is mostly the kernels' blur, buy photons, which cost
    /// little beside the eye pass (docs/guide.md, "Choosing settings").
    #[arg(long, value_name = "N", default_value_t = DEFAULT_CAUSTIC_PHOTONS_MAX,
          help_heading = headings::PHOTONS, hide_short_help = true)]
    pub caustic_photons_max: u64,

    /// The last pass at --caustic-photons before the count grows (0: it never grows; see
    /// --caustic-photons-max).
    #[arg(long, value_name = "PASS", default_value_t = DEFAULT_CAUSTIC_GROWTH_FROM,
          help_heading = headings::PHOTONS, hide_short_help = true)]
    pub caustic_growth_from: u64,

    /// Photons stored in each pass's global map (indirect diffuse light).
    ///
    /// Default: 300000 when the scene has two or more diffuse objects (so diffuse light can
    /// bounce between them); 10000 when it has one and mirrors or glass (its light comes back
    /// to it through them: a dim share, each photon of which costs many paths), or 0 when pass
    /// 0's map, traced once before the passes, stores nothing (a floor under an upright mirror
    /// cannot light itself); else 0 (no global map: a lone plane cannot light itself).
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          help_heading = headings::PHOTONS)]
    pub global_photons: Option<usize>,

    /// Paths a pass may emit for its global map (0: until --global-photons are stored, at
    /// most 64 paths a photon and at least 1000000).
    ///
    /// Default: 100000 where the global map serves one diffuse object lit through its mirrors
    /// and glass and --global-photons is not given (most of such a map's paths store nothing:
    /// light that leaves an open floor leaves the scene, so filling 10000 photons took a
    /// million paths, a third of the torus knot's pass; with 30000 the sparse map's wide
    /// discs, reaching past the floor's edges, darkened a test floor's light by 1.5%), else 0. The map's flux is over the paths emitted,
    /// so a short map is right, only noisier.
    #[arg(long, value_name = "N", allow_negative_numbers = true,
          help_heading = headings::PHOTONS, hide_short_help = true)]
    pub global_paths: Option<u64>,

    /// Treat an open scene as a closed one: no probe, global photons bounce by the cosine
    /// alone and the global map keeps its size.
    ///
    /// By default a scene whose global paths mostly leave it aims half its global bounces at
    /// its objects and sizes its global map by its share of the image (docs/guide.md, "Open
    /// scenes").
    #[arg(long, help_heading = headings::PHOTONS, hide_short_help = true)]
    pub no_open_scene: bool,

    /// Pilot caustic paths traced once per render to aim the caustic photons (0: off).
    ///
    /// At most 128 per cell of the lights' cones, 64 cells a cone: they learn where each
    /// point, spot or sphere light's aimed caustic photons do most good, and every pass then
    /// draws more photons towards the dim parts of a caustic and fewer towards its bright
    /// peak, directly lit floor and misses, each carrying the flux its density gives it
    /// (unbiased; at most 2.5× an unguided photon's). 0: photons spread uniformly over the
    /// cones towards mirrors and glass.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_GUIDE_PATHS,
          allow_negative_numbers = true, help_heading = headings::PHOTONS, hide_short_help = true)]
    pub guide_paths: u64,

    #[command(flatten)]
    pub estimate: EstimatorFlags,

    /// Camera samples per pixel in each pass.
    ///
    /// Stratified within the pixel across samples and passes (one Owen-scrambled Sobol
    /// sequence per pixel).
    #[arg(long, value_name = "N", default_value_t = 1, allow_negative_numbers = true,
          help_heading = headings::EYE)]
    pub spp: u32,

    /// Mirror and glass bounces followed from the eye.
    ///
    /// A pbrt scene's `Integrator` `maxdepth` lowers it further.
    #[arg(long, value_name = "N", default_value_t = 10, allow_negative_numbers = true,
          help_heading = headings::EYE, hide_short_help = true)]
    pub max_depth: u32,

    /// Follow light as dpm does, whatever a pbrt scene's `Integrator` line says.
    ///
    /// By default dpm models the line: paths end at its `maxdepth` (5 where it gives none)
    /// as pbrt counts bounces, and `directlighting` builds no photon maps. Without an
    /// `Integrator` line, and in TOML scenes, every path goes on until its flux runs out.
    #[arg(long, help_heading = headings::EYE)]
    pub full_transport: bool,

    /// Render a pbrt scene that has no `Integrator` line as pbrt does: `path`, maxdepth 5.
    ///
    /// Without it such a scene gets dpm's own transport, as a TOML scene does. With it dpm
    /// renders what pbrt's own image of the file shows (`scripts/pbrt-fidelity.py` sets it).
    #[arg(long, conflicts_with = "full_transport", help_heading = headings::EYE)]
    pub pbrt_default_integrator: bool,

    /// Shadow rays per area light and per environment at each diffuse eye hit.
    ///
    /// Stratified and averaged, for sphere, quad and mesh lights and the environment; a
    /// point, spot or distant light takes one.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_LIGHT_SAMPLES,
          allow_negative_numbers = true, help_heading = headings::EYE, hide_short_help = true)]
    pub light_samples: u32,

    /// Bounded lights up to which each diffuse eye hit samples every light.
    ///
    /// Past it a hit draws `--light-samples` lights from a light tree, by what each can give
    /// it (power, distance, facing), so its cost no longer grows with the lights. Lights at
    /// infinity are sampled at every hit either way.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_EVERY_LIGHT_MAX,
          help_heading = headings::EYE, hide_short_help = true)]
    pub every_light_max: usize,

    /// Glass hits along an eye path that follow both the reflected and the refracted ray.
    ///
    /// Both are weighted by the Fresnel reflectance; past them a path follows one, chosen
    /// with that probability. Splitting every hit costs up to 2^depth rays a pixel through
    /// thick glass for detail a few more passes average in anyway; 0 is pure sampling, 1000
    /// splits every hit (the Whitted tracer).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_GLASS_SPLIT_DEPTH,
          help_heading = headings::EYE, hide_short_help = true)]
    pub glass_split_depth: u32,

    /// Samples per pass of the lights seen through mirrors and glass, where pilots see them.
    ///
    /// The lights, their images in glass and mirrors, and the environment are sampled apart
    /// in each pixel where a pilot ray meets a light, mirror or glass first; those pixels'
    /// camera samples leave that light out. A light's image through glass is often smaller
    /// than a pixel, and a camera sample's rare hit of it is the largest error of a few
    /// passes: these samples are rays only, so many cost little. A constant environment flags
    /// no pixel (every ray that leaves sees it alike: camera samples, whose glass splits, count
    /// it exactly). 0: camera samples count it themselves.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_EMISSION_SAMPLES,
          help_heading = headings::EYE, hide_short_help = true)]
    pub emission_samples: u32,

    /// Spread every emission sample across its pixel: seek no light images.
    ///
    /// By default the pilots of a pixel that samples its emission apart seek, by Newton's
    /// method along their own mirror and glass chains, the points of the pixel where a light's
    /// centre is seen, and half of its emission samples aim at the images there, weighed
    /// against the spread half by the balance heuristic (the same expectation).
    #[arg(long, help_heading = headings::EYE, hide_short_help = true)]
    pub no_light_images: bool,

    /// Camera samples per pass in the pixels that hold an edge.
    ///
    /// An edge pixel is one whose pilot rays (its centre and corners, traced once per
    /// render) see other objects, other chains through mirrors and glass, normals turned
    /// more than 30°, or a light point that one sees and another does not (a shadow's edge).
    /// A pixel's value there is the mean of a step across it, which one sample a pass
    /// resolves slowly. 0: edge pixels take --spp like the rest (so does any N below it).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_EDGE_SAMPLES,
          help_heading = headings::EYE, hide_short_help = true)]
    pub edge_samples: u32,

    /// Microfacet reflection at least this rough (Trowbridge–Reitz α) reads photons.
    ///
    /// A rough glossy lobe weighs each photon by its BSDF (so it shows a caustic that only
    /// photons find, one lit by a point light) and sends its gather rays by sampling itself;
    /// a smoother lobe is sampled and followed like a mirror, and light that focuses through
    /// it reaches the caustic map. Below about 0.1 a lobe is too narrow for the photons of
    /// one estimate (docs/materials.md, "The glossy threshold"); a value above every
    /// roughness in the scene (e.g. 100) follows every glossy lobe.
    #[arg(long, value_name = "ALPHA", default_value_t = crate::bsdf::ESTIMATED_MIN_ALPHA,
          help_heading = headings::EYE, hide_short_help = true)]
    pub glossy_min_alpha: f32,

    /// Final-gather rays per diffuse eye hit for indirect light (0: the global map directly).
    ///
    /// With 0, over progressive passes the global map's blotches average out and its corner
    /// darkening shrinks with the radius; it reached every error sooner than 1 or 4 gather
    /// rays did (docs/guide.md, "Choosing settings").
    #[arg(long, value_name = "N", default_value_t = 0, allow_negative_numbers = true,
          help_heading = headings::EYE, hide_short_help = true)]
    pub final_gather: u32,

    /// Photons per global-map estimate (constant kernel, k-th photon left out).
    #[arg(long, value_name = "K", default_value_t = 100, allow_negative_numbers = true,
          help_heading = headings::EYE, hide_short_help = true)]
    pub global_k: usize,

    /// Neighbours that set each volume photon's radius in the beam radiance estimate (scenes
    /// with participating media).
    #[arg(long, value_name = "K", default_value_t = DEFAULT_VOLUME_K, allow_negative_numbers = true,
          help_heading = headings::EYE, hide_short_help = true)]
    pub volume_k: usize,

    /// Contrast K of the volumetric caustics' diffusion kernel (0: round kernels).
    ///
    /// Each volume photon of a volumetric caustic takes an ellipsoid for its kernel, thin
    /// across the sheets and filaments of its neighbourhood and long along them: the paper's
    /// kernel in 3-D, where a direction whose relative density change over the kernel's radius
    /// exceeds K is squeezed. Measured on scenes/fog-caustic-cone.pbrt (BENCHMARKS.md, "Light
    /// in media"). Volume photons of multiple scattering keep round kernels.
    #[arg(long, value_name = "K", default_value_t = DEFAULT_VOLUME_CONTRAST,
          help_heading = headings::EYE, hide_short_help = true)]
    pub volume_contrast: f64,

    /// With final gathering, precompute irradiance at one global photon in N (0: no tables).
    ///
    /// Christensen's precomputed irradiance: once per pass at one photon in N of the global
    /// map, and a gather ray reads the nearest such point whose normal agrees instead of
    /// running its own estimate. Without final gathering, a sparse global map (more than 16
    /// pixels a photon) is read through a table of its photons. 0 runs a k-NN estimate per
    /// gather ray or eye hit.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_STRIDE, allow_negative_numbers = true,
          help_heading = headings::EYE, hide_short_help = true)]
    pub irradiance_stride: usize,

    /// Also write the diffusion kernel's shape at each pixel (the paper's Figure 2b).
    ///
    /// At each pixel's first diffuse hit: hue = edge direction, brightness = 1 − λ2,
    /// averaged over passes. Needs --estimator diffusion.
    #[arg(long, value_name = "IMAGE", help_heading = headings::DIAGNOSTICS)]
    pub kernel_field: Option<PathBuf>,

    /// Write the per-phase times, counts and per-pass errors as JSON.
    #[arg(long, value_name = "FILE", help_heading = headings::DIAGNOSTICS)]
    pub stats: Option<PathBuf>,

    /// Save pass 0's photon maps to FILE right after tracing.
    ///
    /// A versioned binary with a checksum, written atomically, so a later one-pass render
    /// can skip tracing with --load-photons.
    #[arg(long, value_name = "FILE", help_heading = headings::DIAGNOSTICS, hide_short_help = true)]
    pub save_photons: Option<PathBuf>,

    /// Load the photon maps from FILE (made by --save-photons) instead of tracing them.
    ///
    /// For a one-pass render. The file must come from the same scene (lights, materials,
    /// geometry), --seed and photon counts; the image is then identical to one from freshly
    /// traced maps.
    #[arg(long, value_name = "FILE", help_heading = headings::DIAGNOSTICS, hide_short_help = true)]
    pub load_photons: Option<PathBuf>,
}

impl RenderArgs {
    /// The per-pass sample counts and the irradiance stride, each within its range; the
    /// error names the flag and the range.
    pub fn check_counts(&self) -> Result<(), String> {
        let counts = [
            (
                "light-samples",
                self.light_samples as usize,
                1,
                MAX_LIGHT_SAMPLES as usize,
            ),
            (
                "emission-samples",
                self.emission_samples as usize,
                0,
                MAX_EMISSION_SAMPLES as usize,
            ),
            (
                "edge-samples",
                self.edge_samples as usize,
                0,
                MAX_EDGE_SAMPLES as usize,
            ),
            (
                "guide-paths",
                usize::try_from(self.guide_paths).unwrap_or(usize::MAX),
                0,
                MAX_GUIDE_PATHS as usize,
            ),
            (
                "irradiance-stride",
                self.irradiance_stride,
                0,
                MAX_IRRADIANCE_STRIDE,
            ),
        ];
        for (flag, value, least, most) in counts {
            if !(least..=most).contains(&value) {
                let from = if least == 0 { "0 (off)" } else { "1" };
                return Err(format!("--{flag} {value}: must be from {from} to {most}"));
            }
        }
        Ok(())
    }
}

/// `--resolution`'s value: two whole numbers >= 1 joined by `x` (`1280x720`).
pub fn parse_resolution(text: &str) -> Result<(u32, u32), String> {
    let wanted = "expected WIDTHxHEIGHT in pixels, e.g. 1280x720";
    let (width, height) = text
        .trim()
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("no `x` between width and height: {wanted}"))?;
    let side = |what: &str, value: &str| match value.trim().parse::<u32>() {
        Ok(0) => Err(format!("the {what} is 0: it must be at least 1 pixel")),
        Ok(pixels) => Ok(pixels),
        Err(_) => Err(format!(
            "the {what} `{value}` is not a whole number of pixels: {wanted}"
        )),
    };
    Ok((side("width", width)?, side("height", height)?))
}

/// Most shadow rays per area light a diffuse hit may take (more is a typo, not a setting).
pub const MAX_LIGHT_SAMPLES: u32 = 4096;
/// Largest `--irradiance-stride`: beyond it the table is too sparse to stand for the map.
pub const MAX_IRRADIANCE_STRIDE: usize = 1 << 16;

/// Passes per render by default: chosen by measurement (docs/guide.md, "Choosing settings").
pub const DEFAULT_PASSES: u64 = 8;
/// `--k` of the fixed-radius caustic estimates by default: their radius holds about this
/// many photons where photons typically are (docs/guide.md, "Choosing settings").
pub const DEFAULT_RADIUS_K: usize = 100;
/// Stored caustic photons per pass by default.
pub const DEFAULT_CAUSTIC_PHOTONS: usize = 75_000;
/// The most caustic photons a late pass stores by default (BENCHMARKS.md, "caustic-glass
/// against pbrt-v3's SPPM").
pub const DEFAULT_CAUSTIC_PHOTONS_MAX: u64 = 300_000;
/// The last pass at --caustic-photons by default: a default render (8 passes) ends before it.
pub const DEFAULT_CAUSTIC_GROWTH_FROM: u64 = 8;
/// Stored global photons per pass by default (scenes with two or more diffuse objects).
pub const DEFAULT_GLOBAL_PHOTONS: usize = 300_000;

/// `--volume-k`: measured on pbrt's cloud scene, where 100 blurred its silhouette.
pub const DEFAULT_VOLUME_K: usize = 30;
/// `--volume-contrast`: on the volumetric caustic of scenes/fog-caustic-cone.pbrt, 0.2 left
/// twice the error of 0.02 in the cone and 0.01 gained 6% more.
pub const DEFAULT_VOLUME_CONTRAST: f64 = 0.02;
/// Stored global photons per pass by default in a scene whose one diffuse object sees itself
/// through mirrors and glass alone (BENCHMARKS.md, "caustic-glass against pbrt-v3").
pub const DEFAULT_LONE_GLOBAL_PHOTONS: usize = 10_000;
/// Paths a pass emits for that lone object's global map at most, by default.
pub const DEFAULT_LONE_GLOBAL_PATHS: u64 = 100_000;
/// Shadow rays per area light at each diffuse eye hit by default (docs/guide.md,
/// "Choosing settings").
pub const DEFAULT_LIGHT_SAMPLES: u32 = 4;
/// Bounded lights up to which every diffuse eye hit samples each by default (docs/guide.md,
/// "Many lights").
pub const DEFAULT_EVERY_LIGHT_MAX: usize = crate::world::lights::sampler::SAMPLE_EVERY_LIGHT_MAX;
/// Glass hits that split an eye path by default (BENCHMARKS.md, "Whole scenes and the defaults").
pub const DEFAULT_GLASS_SPLIT_DEPTH: u32 = 1000;
/// Emission samples per flagged pixel and pass by default (docs/guide.md, "Choosing settings").
pub const DEFAULT_EMISSION_SAMPLES: u32 = 16;
/// Camera samples per pass in edge pixels by default (docs/guide.md, "Choosing settings").
pub const DEFAULT_EDGE_SAMPLES: u32 = 4;

/// Pilot paths of the caustic guide: about 100 a cone cell of a light aimed at eight targets.
pub const DEFAULT_GUIDE_PATHS: u64 = 50_000;

/// More pilot paths than this would take longer than the passes they guide.
pub const MAX_GUIDE_PATHS: u64 = 100_000_000;
/// Most camera samples an edge pixel may take per pass (more is a typo, not a setting).
pub const MAX_EDGE_SAMPLES: u32 = 4096;
/// Most emission samples a pixel may take per pass (more is a typo, not a setting).
pub const MAX_EMISSION_SAMPLES: u32 = 65_536;

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{CommandFactory, Parser};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: RenderArgs,
    }

    const HEADINGS: [&str; 7] = [
        headings::OUTPUT,
        headings::PASSES,
        headings::PHOTONS,
        headings::ESTIMATE,
        headings::KERNEL,
        headings::EYE,
        headings::DIAGNOSTICS,
    ];

    /// Every flag stands under one of the headings, which `--help` shows in reading order;
    /// `-h` keeps the common flags and drops the rest.
    #[test]
    fn help_groups_every_flag_under_a_heading() {
        let mut cmd = Cli::command();
        cmd.build();
        cmd.clone().debug_assert();
        for arg in cmd.get_arguments() {
            if arg.is_positional() || ["help"].contains(&arg.get_id().as_str()) {
                continue;
            }
            let heading = arg.get_help_heading();
            assert!(
                heading.is_some_and(|h| HEADINGS.contains(&h)),
                "--{} stands under {heading:?}",
                arg.get_id()
            );
        }
        let long = cmd.clone().render_long_help().to_string();
        let at = |text: &str, h: &str| text.find(&format!("\n{h}:\n"));
        let places: Vec<usize> = HEADINGS
            .iter()
            .map(|h| at(&long, h).unwrap_or_else(|| panic!("{h} missing from --help")))
            .collect();
        assert!(places.is_sorted(), "headings out of order: {places:?}");

        let short = cmd.render_help().to_string();
        for flag in [
            "--output",
            "--passes",
            "--time",
            "--film",
            "--resume",
            "--estimator",
        ] {
            assert!(short.contains(flag), "{flag} missing from -h");
        }
        for flag in ["--glass-split-depth", "--noise-floor", "--load-photons"] {
            assert!(!short.contains(flag), "{flag} in -h");
            assert!(long.contains(flag), "{flag} missing from --help");
        }
        assert!(short.lines().count() * 3 < long.lines().count() * 2);
    }

    /// `--help` names the default of every flag that has a fixed one.
    #[test]
    fn long_help_shows_every_fixed_default() {
        let cmd = Cli::command();
        let long = cmd.clone().render_long_help().to_string();
        for arg in cmd.get_arguments() {
            if let Some(default) = arg.get_default_values().first() {
                let shown = format!("[default: {}]", default.to_string_lossy());
                let flag = format!("--{}", arg.get_long().unwrap());
                let from = long.find(&format!("{flag} ")).expect("flag listed");
                let entry = &long[from..];
                let end = entry[1..].find("\n      --").map_or(entry.len(), |e| e + 1);
                assert!(entry[..end].contains(&shown), "{flag}'s {shown} missing");
            }
        }
    }
}
