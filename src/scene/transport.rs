//! How far light is followed, as a pbrt scene's `Integrator` line asks: pbrt stops every path at
//! `maxdepth` bounces (5 where the line gives none), and its `directlighting` integrator has no
//! light past the first diffuse or glossy surface. dpm's own transport (every path until its
//! flux runs out) stands where a scene says nothing: TOML scenes and pbrt files without an
//! `Integrator` line. Holds the choice only; the renderer applies it.
//!
//! pbrt counts a bounce at every surface with a BSDF, the camera's first hit being bounce 0:
//! a path of at most `maxdepth` such surfaces between the camera and a light. Its `sppm`
//! integrator caps the camera's path and the photons' apart (a visible point at depth below
//! `maxdepth`, a photon stored at most `maxdepth − 1` bounces from its light).

/// pbrt-v3's and pbrt-v4's `maxdepth` where an `Integrator` line gives none.
pub const PBRT_DEFAULT_MAX_DEPTH: u32 = 5;

/// How far light is followed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum Transport {
    /// Every path, until its flux runs out (dpm's own).
    #[default]
    Full,
    /// Paths of at most `max_depth` surfaces from the camera to a light (pbrt's `path`,
    /// `volpath`, `bdpt`, `mlt` and the like).
    Paths { max_depth: u32 },
    /// Camera paths and photon paths capped apart, each at `max_depth` surfaces (pbrt's
    /// `sppm`).
    CameraAndPhotonPaths { max_depth: u32 },
    /// Direct light only, seen through at most `max_depth − 1` mirror and glass bounces
    /// (pbrt's `directlighting` and `whitted`): no photon maps, and glossy lobes see lights
    /// alone.
    Direct { max_depth: u32 },
}

impl Transport {
    /// The cap on surfaces along a path, if any.
    pub fn max_depth(self) -> Option<u32> {
        match self {
            Transport::Full => None,
            Transport::Paths { max_depth }
            | Transport::CameraAndPhotonPaths { max_depth }
            | Transport::Direct { max_depth } => Some(max_depth),
        }
    }

    pub fn is_full(&self) -> bool {
        *self == Transport::Full
    }

    /// Whether an eye path's surface at `depth` (the camera's first hit at 0) is lit at all
    /// (shadow rays and photons); past the cap only emitters seen count.
    #[inline]
    pub fn shades(self, depth: u32) -> bool {
        self.max_depth().is_none_or(|d| depth < d)
    }

    /// Whether a surface at eye depth `depth` reads photons, which have bounced at least once
    /// before it: a path through it is at least two surfaces longer than `depth`, unless
    /// pbrt caps the camera's path on its own.
    #[inline]
    pub fn reads_photons(self, depth: u32) -> bool {
        match self {
            Transport::Full => true,
            Transport::Paths { max_depth } => depth + 2 <= max_depth,
            Transport::CameraAndPhotonPaths { max_depth } => depth < max_depth,
            Transport::Direct { .. } => false,
        }
    }

    /// The most mirror and glass bounces an eye path may follow (`None`: no cap). pbrt's path
    /// tracers see an emitter past `maxdepth` of them; its SPPM camera path and its direct
    /// lighting stop a bounce earlier (their last surface is at depth `maxdepth − 1`).
    pub fn eye_bounces(self) -> Option<u32> {
        match self {
            Transport::Full => None,
            Transport::Paths { max_depth } => Some(max_depth),
            Transport::CameraAndPhotonPaths { max_depth } | Transport::Direct { max_depth } => {
                Some(max_depth.saturating_sub(1))
            }
        }
    }

    /// The most surfaces a photon may have met before the one it is stored on (`None`: no
    /// cap). Exact for pbrt's `sppm`, and for a path integrator's surfaces the camera sees
    /// directly.
    pub fn photon_bounces(self) -> Option<u32> {
        self.max_depth().map(|d| d.saturating_sub(1))
    }

    /// Whether a glossy lobe's sampled ray lights what it meets (pbrt's `directlighting`
    /// counts only the lights it finds).
    #[inline]
    pub fn glossy_sees_surfaces(self) -> bool {
        !matches!(self, Transport::Direct { .. })
    }

    /// One line for `dpm check` and the render's notes.
    pub fn describe(self) -> String {
        match self {
            Transport::Full => "every path until its flux runs out (dpm's own)".into(),
            Transport::Paths { max_depth } => {
                format!("paths of at most {max_depth} surfaces from camera to light")
            }
            Transport::CameraAndPhotonPaths { max_depth } => {
                format!("camera paths and photon paths each of at most {max_depth} surfaces")
            }
            Transport::Direct { max_depth } => format!(
                "direct light only, through at most {} mirror and glass bounces; no photon maps",
                max_depth.saturating_sub(1)
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_caps_count_surfaces_as_pbrt_does() {
        // maxdepth 1: the camera's first hit is lit by shadow rays and nothing else.
        let paths = Transport::Paths { max_depth: 1 };
        assert!(paths.shades(0) && !paths.shades(1));
        assert!(!paths.reads_photons(0));
        assert_eq!(paths.photon_bounces(), Some(0));
        // maxdepth 5: a photon of one bounce lights the first hit, none the fourth.
        let paths = Transport::Paths { max_depth: 5 };
        assert!(paths.reads_photons(3) && !paths.reads_photons(4) && paths.shades(4));
        let sppm = Transport::CameraAndPhotonPaths { max_depth: 5 };
        assert!(sppm.reads_photons(4) && !sppm.shades(5));
        assert_eq!(sppm.photon_bounces(), Some(4));
        assert_eq!(sppm.eye_bounces(), Some(4));
        assert_eq!(paths.eye_bounces(), Some(5));
        assert_eq!(Transport::Direct { max_depth: 1 }.eye_bounces(), Some(0));
        let direct = Transport::Direct { max_depth: 5 };
        assert!(direct.shades(4) && !direct.reads_photons(0) && !direct.glossy_sees_surfaces());
        let full = Transport::Full;
        assert!(full.shades(u32::MAX - 1) && full.reads_photons(1000));
        assert_eq!(full.photon_bounces(), None);
    }
}
