//! The command-line layer of the estimator settings: one `clap::Args` struct, flattened into
//! `dpm render`, `dpm density` and `dpm tradeoff`, with each flag's help. It only turns flags
//! into [`EstimatorSettings`]; validation and construction live in [`super::settings`]. Must
//! not hold anything a film records that the plain settings do not.

use super::diffusion::shaped::HistoryPhotons;
use super::diffusion::{Crossings, DiffusionKernel, DiffusivityUnits};
use super::settings::{EstimatorKind, EstimatorSettings, PAPER_K};

/// The help headings these flags stand under.
pub mod headings {
    pub const ESTIMATE: &str = "Caustic estimate";
    pub const KERNEL: &str = "Diffusion kernel";
}

/// Radiance-estimate flags, shared by `dpm render`, `dpm density` and their progressive runs.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct EstimatorFlags {
    /// Radiance estimate: `diffusion` is the paper's method, `cone` (k = 400) its baseline.
    ///
    /// `simple`, `gaussian` (k-NN) and `epanechnikov` (fixed radius) are the other classic
    /// estimates. Every k-NN estimate leaves the k-th photon out of its sum, so all of them
    /// are unbiased on a uniform density.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Diffusion,
          help_heading = headings::ESTIMATE)]
    pub estimator: EstimatorKind,

    /// Photons per k-NN estimate (default 400); sets the default --radius of the others.
    ///
    /// For the k-NN estimates the k-th photon sets the radius and is left out, so k ≥ 2;
    /// 400 is the paper's cone-filter setting, the baseline the diffusion estimate is
    /// compared with. For the fixed-radius estimates it sets the default --radius (a disc of
    /// about k photons where photons typically are): 400 in `dpm density`, 100 in `dpm
    /// render`, whose caustics' error at a render's budget was mostly the blur of their
    /// bright folds (docs/guide.md, "Choosing settings"). The diffusion estimate's flat
    /// regions are quieter with more (see --diffusivity).
    #[arg(long, allow_negative_numbers = true, help_heading = headings::ESTIMATE)]
    pub k: Option<usize>,

    /// Support radius of the fixed-radius estimates (epanechnikov, diffusion), scene units.
    ///
    /// For the k-NN estimates it caps the search instead (default: no cap). Default for the
    /// fixed-radius estimates: the k-equivalent radius, the median over up to 256 photons
    /// spread through the map of the distance to their k-th nearest other photon, so a disc
    /// holds about k photons where photons typically are.
    #[arg(long, value_name = "R", allow_negative_numbers = true,
          help_heading = headings::ESTIMATE)]
    pub radius: Option<f32>,

    /// Slope constant of the cone filter (≥ 1; the weight is 1 − d/(slope·r)).
    ///
    /// 1.1 is Jensen's suggestion; leaving the k-th photon out keeps every slope unbiased.
    #[arg(long, value_name = "SLOPE", default_value_t = 1.1, allow_negative_numbers = true,
          help_heading = headings::ESTIMATE, hide_short_help = true)]
    pub cone_slope: f64,

    /// Radius of the gradient pass (Eq. 6); default radius/2.
    ///
    /// Small enough that thin lines still show in the gradient (with radius itself they
    /// vanished in the design notes' experiment), large enough to keep the gradient's noise
    /// down.
    #[arg(long, value_name = "R", allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub gradient_radius: Option<f32>,

    /// Radius over which the structure tensor is averaged; default radius.
    ///
    /// With the default, one search serves both the tensor and the estimate.
    #[arg(long, value_name = "R", allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub smoothing_radius: Option<f32>,

    /// Diffusivity K (Eq. 9): the edge contrast above which the kernel narrows across it.
    ///
    /// K ≥ 0; 0 narrows it wherever there is any gradient, inf keeps it round. In
    /// dimensionless units 0.2 means the irradiance changes by about √0.2 ≈ 45% of itself
    /// over one radius; 0.2 kept edges and thin lines best in the design notes' experiment.
    /// Noise alone reaches a contrast of about 64/N with N photons per disc (gradient radius
    /// r/2), so flat regions stay round, with noise within ~1.1× of the isotropic estimate,
    /// for N ≳ 1000; at N = 400 expect ~1.4×: raise --k or --radius, or K, if flat regions
    /// look noisy.
    #[arg(long, value_name = "K", default_value_t = 0.2, allow_negative_numbers = true,
          help_heading = headings::KERNEL)]
    pub diffusivity: f64,

    /// Units of --diffusivity: relative edge contrast, or the paper's absolute μ1.
    ///
    /// `dimensionless` compares K with μ1·r²/L̂² (L̂: the isotropic estimate at the point),
    /// which does not change with light power or scene scale, so one K serves every scene;
    /// `absolute` compares it with μ1 in (W m⁻³)², as in the paper, where K must be retuned
    /// whenever the power or the scale changes.
    #[arg(long, value_enum, default_value_t = DiffusivityUnits::Dimensionless,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub k_units: DiffusivityUnits,

    /// Steepness α > 0 of the diffusivity λ2 = 1/(1 + (contrast/K)^(1+α)).
    ///
    /// 1 gives a gradual transition between flat regions and edges.
    #[arg(long, value_name = "A", default_value_t = 1.0, allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub alpha: f64,

    /// Eigenvalue λ3 of the diffusion tensor along the surface normal, in (0, 1].
    ///
    /// The kernel reaches r·√λ3 off the tangent plane. 0.1 is the paper's value (a disc
    /// rather than a sphere, to limit bias in corners).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub lambda3: f64,

    /// Lower bound of λ2, in (0, 1]: the kernel is at least r·√floor wide across an edge.
    ///
    /// 0.01 (a tenth of the radius) sharpened edges most in the design notes' experiment;
    /// 0.05 lost a third of the gain there; without a bound the kernel degenerates to a
    /// segment.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub lambda2_floor: f64,

    /// Photon noise removed from the structure tensor, in gradient-noise variances.
    ///
    /// μ1 is reduced by this many times the gradient variance that photon noise alone would
    /// give (computed from the photons' Σ Φ² around the point). 0 is the paper's raw μ1,
    /// which reads noise as structure and squeezes the kernel wherever photons are sparse
    /// (wormy flat regions); 2 removes the noise's mean and its typical fluctuation after
    /// smoothing, and leaves edges, whose μ1 is far above it, untouched.
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub noise_floor: f64,

    /// Fewest photons the diffusion kernel should hold (0: no bound).
    ///
    /// The ellipse holds about N·√(λ1 λ2) of the N photons in its disc, so λ1 λ2 is kept at
    /// least (m/N)²: a kernel squeezed onto a few photons is shaped by their own noise, a bias
    /// that averaging passes does not remove. Where discs hold few photons (a progressive
    /// render's late passes, dim regions) the kernel turns round, and the estimate stays
    /// consistent. 8 lowered every error of progressive diffusion at the default radius on
    /// the constructed distribution (BENCHMARKS.md); 16 and 32 blurred edges in late passes.
    #[arg(long, value_name = "M", default_value_t = 8.0, allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub min_kernel_photons: f64,

    /// Gradient sites the smoothing disc keeps at least (0: every photon gets a gradient).
    ///
    /// Where a disc would hold more than twice this many photons (a concentrated caustic,
    /// or a radius far above the photon spacing) the gradient pass takes gradients at one
    /// photon in m only, each standing for m, so its cost follows what the structure tensor
    /// needs rather than the photon pile-up. 512 moved no error of the constructed
    /// distribution's table by more than 1% (256: the flat-region noise of the absolute-K
    /// rows by 3.6%; BENCHMARKS.md).
    #[arg(long, value_name = "M", default_value_t = 512.0, allow_negative_numbers = true,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub gradient_sites: f64,

    /// Kernel shape at the Mahalanobis distance: epanechnikov (the paper's) or gaussian.
    ///
    /// Epanechnikov is the paper's choice and the cheapest; gaussian is Jensen's shape,
    /// exactly normalised.
    #[arg(long, value_enum, default_value_t = DiffusionKernel::Epanechnikov,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub kernel: DiffusionKernel,

    /// What the kernel does where filaments cross or fold: shrink, or keep its length.
    ///
    /// Where the structure tensor's minor eigenvalue is large too (no single edge direction),
    /// `shrink` sets λ1 from it as λ2 is set from the major one, so the kernel shrinks along
    /// both axes, down to the photons it should hold (--min-kernel-photons); `keep` is the
    /// paper's λ1 = 1.
    #[arg(long, value_enum, default_value_t = Crossings::Shrink,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub crossings: Crossings,

    /// Earlier passes whose photons shape a progressive pass's diffusion kernels (0: its own).
    ///
    /// The structure tensor, and so each kernel's direction and squeeze, is taken on the
    /// photons of the N passes before (traced again where a run starts past pass 0, so a pass
    /// is the same wherever it runs), at the pass's own radii; the density is still the
    /// pass's own photons. The shape is then independent of the photons it spreads (a kernel
    /// shaped by its own photons loses 0.3–0.6% of a caustic's energy); `--history-photons`
    /// says how many of the N passes' photons it is drawn from, and so kept (110 bytes a kept
    /// photon). 0 is the paper's own-pass tensor.
    #[arg(long, value_name = "N", default_value_t = super::settings::DEFAULT_TENSOR_HISTORY,
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub tensor_history: u32,

    /// Which photons of the tensor history shape the kernels: one pass's worth, or all.
    ///
    /// `one-pass` keeps one photon in N of each of the N earlier passes (more of the first
    /// ones, which shape the passes right after them with fewer beside them; each pass shapes
    /// on one pass's photons of them): the shapes cost about what a pass's own would and are
    /// independent of the photons they spread, which keeps a caustic's energy. `all` shapes
    /// on every photon of the N passes: steadier gradients, sharper faint edges (the
    /// constructed distribution's edge error after 16 passes 0.84× instead of 0.99×), at N
    /// times the gradient pass and the tensor's scan per pixel, which over a few seconds costs
    /// more than it gains on the torus knot and the metal ring (BENCHMARKS.md, "A structure
    /// tensor across passes").
    #[arg(long, value_enum, value_name = "PHOTONS", default_value = "one-pass",
          help_heading = headings::KERNEL, hide_short_help = true)]
    pub history_photons: HistoryPhotons,

    /// Cut each kernel at the edge the tensor history's photons show (needs --tensor-history).
    ///
    /// Where the kernel is squeezed (λ2 < 0.9), a step in the history photons' density across
    /// the edge is fitted within the kernel's disc (its normal turned up to 0.3 rad from X2;
    /// a second step inside makes a strip); the estimate is then the round kernel on the
    /// query's side only, divided by its share there. The constructed distribution's edge
    /// error after 16 passes falls to 0.60× the own-pass tensor's with `--history-photons
    /// all`; on caustics that are not steps (the metal ring's cusp) it costs time and error
    /// (BENCHMARKS.md, "A structure tensor across passes").
    #[arg(long, help_heading = headings::KERNEL, hide_short_help = true)]
    pub edge_cut: bool,
}

impl EstimatorFlags {
    /// The plain settings these flags give, `--k` defaulting to the paper's 400.
    pub fn settings(&self) -> EstimatorSettings {
        self.settings_with_radius_k(PAPER_K)
    }

    /// The plain settings, with `fixed_radius_k` as `--k`'s default for the fixed-radius
    /// estimates (the k-NN ones keep 400).
    pub fn settings_with_radius_k(&self, fixed_radius_k: usize) -> EstimatorSettings {
        let default_k = if self.estimator.is_fixed_radius() {
            fixed_radius_k
        } else {
            PAPER_K
        };
        EstimatorSettings {
            estimator: self.estimator,
            k: self.k.unwrap_or(default_k),
            radius: self.radius,
            cone_slope: self.cone_slope,
            gradient_radius: self.gradient_radius,
            smoothing_radius: self.smoothing_radius,
            diffusivity: self.diffusivity,
            k_units: self.k_units,
            alpha: self.alpha,
            lambda3: self.lambda3,
            lambda2_floor: self.lambda2_floor,
            noise_floor: self.noise_floor,
            min_kernel_photons: self.min_kernel_photons,
            gradient_sites: self.gradient_sites,
            kernel: self.kernel,
            crossings: self.crossings,
            tensor_history: self.tensor_history,
            history_photons: self.history_photons,
            edge_cut: self.edge_cut,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::EstimateError;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        flags: EstimatorFlags,
    }

    fn parse(args: &[&str]) -> EstimatorSettings {
        let mut all = vec!["dpm"];
        all.extend_from_slice(args);
        Cli::try_parse_from(all).expect("parses").flags.settings()
    }

    #[test]
    fn command_line_is_well_formed_and_every_flag_has_help() {
        use clap::CommandFactory;
        let mut cmd = Cli::command();
        cmd.clone().debug_assert();
        let help = cmd.render_long_help().to_string();
        for flag in [
            "--estimator",
            "--k",
            "--radius",
            "--cone-slope",
            "--gradient-radius",
            "--smoothing-radius",
            "--diffusivity",
            "--k-units",
            "--alpha",
            "--lambda3",
            "--lambda2-floor",
            "--kernel",
        ] {
            assert!(help.contains(flag), "{flag} missing from\n{help}");
        }
    }

    #[test]
    fn settings_round_trip_through_toml_infinite_k_included() {
        let s = parse(&[
            "--diffusivity",
            "inf",
            "--radius",
            "0.25",
            "--estimator",
            "cone",
        ]);
        let text = toml::to_string(&s).expect("serialises");
        assert_eq!(
            toml::from_str::<EstimatorSettings>(&text).expect("parses"),
            s
        );
    }

    #[test]
    fn default_matches_the_command_line_defaults() {
        assert_eq!(parse(&[]), EstimatorSettings::default());
    }

    #[test]
    fn flags_parse() {
        let s = parse(&[
            "--estimator",
            "cone",
            "--k",
            "50",
            "--radius",
            "0.5",
            "--cone-slope",
            "2",
            "--k-units",
            "absolute",
            "--kernel",
            "gaussian",
            "--diffusivity",
            "inf",
        ]);
        assert_eq!(s.estimator, EstimatorKind::Cone);
        assert_eq!((s.k, s.radius, s.cone_slope), (50, Some(0.5), 2.0));
        assert_eq!(s.k_units, DiffusivityUnits::Absolute);
        assert_eq!(s.kernel, DiffusionKernel::Gaussian);
        assert_eq!(s.diffusivity, f64::INFINITY);
        assert!(s.validate().is_ok());
    }

    #[test]
    fn bad_values_name_their_flag() {
        let cases: &[(&[&str], &str)] = &[
            (&["--k", "0"], "k"),
            (&["--k", "1"], "k"),
            (&["--radius", "0"], "radius"),
            (&["--radius", "-1"], "radius"),
            (&["--radius", "NaN"], "radius"),
            (&["--radius", "inf"], "radius"),
            (&["--gradient-radius", "0"], "gradient-radius"),
            (&["--smoothing-radius", "-0.1"], "smoothing-radius"),
            (&["--cone-slope", "0.9"], "cone-slope"),
            (&["--diffusivity", "-0.2"], "diffusivity"),
            (&["--diffusivity", "NaN"], "diffusivity"),
            (&["--alpha", "0"], "alpha"),
            (&["--alpha", "-1"], "alpha"),
            (&["--lambda3", "0"], "lambda3"),
            (&["--lambda3", "1.5"], "lambda3"),
            (&["--lambda2-floor", "0"], "lambda2-floor"),
        ];
        for (args, flag) in cases {
            let err = parse(args).validate().expect_err("invalid");
            let EstimateError::InvalidSetting { flag: named, .. } = &err else {
                panic!("{err}")
            };
            assert_eq!(named, flag, "{args:?}");
            assert!(err.to_string().starts_with(&format!("--{flag} ")), "{err}");
        }
        assert!(parse(&["--diffusivity", "0"]).validate().is_ok());
    }
}
