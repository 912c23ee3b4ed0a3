//! pbrt's `Integrator` line as dpm applies it: how far light is followed ([`Transport`]), from
//! the integrator's kind and its `maxdepth` (5 where it gives none, as in pbrt-v3 and v4).
//! Its other parameters (SPPM's radius and iterations, a sampler's budget) are dpm's own
//! settings' business and only noted. Owns that reading; must not touch the camera or film.

use super::super::parser::Item;
use super::{Mapper, param_error, value_error};
use crate::scene::{PBRT_DEFAULT_MAX_DEPTH, SceneError, Transport};

/// A cap past which pbrt's paths carry nothing visible and dpm's would only cost.
const MAX_DEPTH_LIMIT: i64 = 1 << 20;

impl Mapper<'_> {
    /// The transport an `Integrator` line asks for; dpm's own where there is none, unless
    /// pbrt's default integrator was asked for (`path`, maxdepth 5).
    pub(super) fn transport(&mut self, integrator: Option<&Item>) -> Result<Transport, SceneError> {
        let Some(item) = integrator else {
            if self.default_integrator {
                let transport = Transport::Paths {
                    max_depth: PBRT_DEFAULT_MAX_DEPTH,
                };
                self.report.notes.push(format!(
                    "no Integrator line: pbrt's default \"path\": {} (--pbrt-default-integrator)",
                    transport.describe()
                ));
                return Ok(transport);
            }
            return Ok(Transport::Full);
        };
        let depth = || -> Result<u32, SceneError> {
            let p = |e| param_error("Integrator", e);
            match item.params.integer("maxdepth").map_err(p)? {
                None => Ok(PBRT_DEFAULT_MAX_DEPTH),
                Some(d) if (0..=MAX_DEPTH_LIMIT).contains(&d) => Ok(d as u32),
                Some(d) => Err(value_error(
                    item,
                    "Integrator",
                    "maxdepth",
                    format!("{d} is not from 0 to {MAX_DEPTH_LIMIT}"),
                )),
            }
        };
        let transport = match item.kind.as_str() {
            "path" | "volpath" | "bdpt" | "mlt" | "lightpath" | "simplepath" | "simplevolpath"
            | "randomwalk" => Transport::Paths {
                max_depth: depth()?,
            },
            "sppm" => Transport::CameraAndPhotonPaths {
                max_depth: depth()?,
            },
            "directlighting" | "whitted" => Transport::Direct {
                max_depth: depth()?,
            },
            other => {
                self.report.notes.push(format!(
                    "{}: Integrator \"{other}\": not a light transport dpm models; dpm's own applies",
                    item.at
                ));
                return Ok(Transport::Full);
            }
        };
        self.report.notes.push(format!(
            "{}: Integrator \"{}\": {} (--full-transport: dpm's own)",
            item.at,
            item.kind,
            transport.describe()
        ));
        Ok(transport)
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::Transport;
    use crate::scene::files::InMemory;
    use std::path::Path;

    fn transport(integrator: &str) -> Result<Transport, String> {
        let text = format!(
            "{integrator}\nCamera \"perspective\"\nWorldBegin\nLightSource \"point\"\n\
             Shape \"sphere\"\nWorldEnd\n"
        );
        let mut files = InMemory::default();
        files.insert("s.pbrt", text);
        crate::scene::load_from(Path::new("s.pbrt"), &files, &Default::default())
            .map(|(s, _)| s.transport)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn each_integrator_caps_as_pbrt_does() {
        assert_eq!(transport(""), Ok(Transport::Full));
        assert_eq!(
            transport("Integrator \"path\""),
            Ok(Transport::Paths { max_depth: 5 })
        );
        assert_eq!(
            transport("Integrator \"bdpt\" \"integer maxdepth\" [ 20 ]"),
            Ok(Transport::Paths { max_depth: 20 })
        );
        assert_eq!(
            transport("Integrator \"sppm\" \"float radius\" .075"),
            Ok(Transport::CameraAndPhotonPaths { max_depth: 5 })
        );
        assert_eq!(
            transport("Integrator \"directlighting\" \"integer maxdepth\" 2"),
            Ok(Transport::Direct { max_depth: 2 })
        );
        assert_eq!(
            transport("Integrator \"ambientocclusion\""),
            Ok(Transport::Full)
        );
        let err = transport("Integrator \"path\" \"integer maxdepth\" -1").unwrap_err();
        assert!(
            err.contains("s.pbrt:1:") && err.contains("maxdepth"),
            "{err}"
        );
    }
}
