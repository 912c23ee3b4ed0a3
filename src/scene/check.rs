//! `dpm check SCENE`: reads a scene (TOML or pbrt) without rendering and reports every
//! error, warning and note it meets, then what would be mapped. Owns the recovery that lets
//! one run name more than the first error; must not build a world or trace.
//!
//! Loading stops at its first error. To go on, the pbrt directive the error lies in is set
//! aside (commented out in an in-memory copy of its file, from its first line up to the next
//! directive) and the scene is read again, up to [`MAX_ERRORS`] times. An error inside a
//! mesh or image file, or in a TOML scene (whose parse cannot resume), ends the list.

use super::files::{Disk, SceneFiles};
use super::{LoadOptions, LoadReport, SceneDescription, SceneError, Shape, load_from};
use crate::scene::Light;
use std::collections::HashMap;
use std::fmt::Write;
use std::io;
use std::path::{Path, PathBuf};

/// Errors past this many are not looked for.
pub const MAX_ERRORS: usize = 20;

/// What checking a scene found.
#[derive(Debug, Default)]
pub struct CheckReport {
    pub errors: Vec<SceneError>,
    /// The warnings and notes of the last reading (with the erroneous directives set aside).
    pub report: LoadReport,
    /// What would be rendered, when the scene has no error.
    pub scene: Option<SceneDescription>,
    /// Whether more errors may follow the last one listed.
    pub stopped_early: bool,
}

/// The disk, with some files' text replaced.
struct Patched {
    changed: HashMap<PathBuf, Vec<u8>>,
}

impl SceneFiles for Patched {
    fn read(&self, path: &Path) -> io::Result<Vec<u8>> {
        match self.changed.get(&Disk.identity(path)) {
            Some(bytes) => Ok(bytes.clone()),
            None => Disk.read(path),
        }
    }

    fn is_dir(&self, path: &Path) -> bool {
        Disk.is_dir(path)
    }

    fn identity(&self, path: &Path) -> PathBuf {
        Disk.identity(path)
    }
}

/// Checks the scene at `path`.
pub fn check(path: &Path, options: &LoadOptions) -> CheckReport {
    let mut out = read_on(path, options);
    // Found in the order loading meets them (lights before shapes): listed by place, the
    // whole-scene ones (which may follow from directives set aside) last.
    out.errors.sort_by_key(|e| {
        let whole_scene = e.message.starts_with("the scene has no");
        (whole_scene, e.file.clone(), e.line, e.column)
    });
    out
}

fn read_on(path: &Path, options: &LoadOptions) -> CheckReport {
    let is_pbrt = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pbrt"));
    let mut files = Patched {
        changed: HashMap::new(),
    };
    let mut out = CheckReport::default();
    loop {
        match load_from(path, &files, options) {
            Ok((scene, report)) => {
                out.report = report;
                if out.errors.is_empty() {
                    out.scene = Some(scene);
                }
                return out;
            }
            Err(e) => {
                let resumable = is_pbrt && out.errors.len() + 1 < MAX_ERRORS;
                let patched = resumable && set_aside(&mut files, &e);
                let repeated = out.errors.last() == Some(&e);
                if !repeated {
                    out.errors.push(e);
                }
                if !patched || repeated {
                    out.stopped_early = true;
                    return out;
                }
            }
        }
    }
}

/// Comments out the directive `e` points into; false when it cannot (no line, not a pbrt
/// file, or nothing left to set aside).
fn set_aside(files: &mut Patched, e: &SceneError) -> bool {
    let Some(line) = e.line else { return false };
    // About the whole scene, not one directive: setting one aside cannot help.
    if e.message.starts_with("the scene has no") {
        return false;
    }
    if !e
        .file
        .extension()
        .is_some_and(|x| x.eq_ignore_ascii_case("pbrt"))
    {
        return false;
    }
    let key = Disk.identity(&e.file);
    let Ok(bytes) = files.read(&e.file) else {
        return false;
    };
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if line == 0 || line > lines.len() {
        return false;
    }
    let starts_directive = |l: &str| {
        l.trim_start()
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_uppercase())
    };
    let mut first = line - 1;
    while first > 0 && !starts_directive(&lines[first]) {
        first -= 1;
    }
    let mut last = line;
    while last < lines.len() && !starts_directive(&lines[last]) {
        last += 1;
    }
    let mut changed = false;
    for l in &mut lines[first..last] {
        if !l.trim_start().starts_with('#') && !l.trim().is_empty() {
            l.insert(0, '#');
            changed = true;
        }
    }
    if changed {
        files
            .changed
            .insert(key, (lines.join("\n") + "\n").into_bytes());
    }
    changed
}

impl CheckReport {
    /// Whether the scene would render.
    pub fn renders(&self) -> bool {
        self.errors.is_empty()
    }

    /// The report as `dpm check` prints it.
    pub fn text(&self) -> String {
        let mut s = String::new();
        for e in &self.errors {
            let _ = writeln!(s, "error: {e}");
        }
        if self.stopped_early && !self.errors.is_empty() {
            let _ = writeln!(
                s,
                "(further errors, if any, were not looked for past this one)"
            );
        }
        for w in &self.report.warnings {
            let _ = writeln!(s, "warning: {w}");
        }
        for n in &self.report.notes {
            let _ = writeln!(s, "note: {n}");
        }
        match &self.scene {
            Some(scene) => {
                for medium in &scene.media.media {
                    let _ = writeln!(s, "note: {}", medium.describe());
                }
                let _ = writeln!(s, "summary: renders: {}", summary(scene));
            }
            None => {
                let _ = writeln!(
                    s,
                    "summary: refused: {} error(s), {} warning(s)",
                    self.errors.len(),
                    self.report.warnings.len()
                );
            }
        }
        s
    }
}

/// What a scene holds, in a line.
fn summary(scene: &SceneDescription) -> String {
    let mut kinds: Vec<(&str, usize)> = Vec::new();
    let mut count = |name| match kinds.iter_mut().find(|(k, _)| *k == name) {
        Some((_, n)) => *n += 1,
        None => kinds.push((name, 1)),
    };
    for light in &scene.lights {
        count(match light {
            Light::Point { .. } => "point",
            Light::Sphere { .. } => "sphere",
            Light::Quad { .. } => "quad",
            Light::Spot { .. } => "spot",
            Light::Distant { .. } => "distant",
            Light::Environment { .. } => "environment",
            Light::EnvironmentMap(_) => "environment image",
            Light::Mesh { .. } => "mesh",
        });
    }
    let lights: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let triangles = |shapes: &[Shape]| -> usize {
        (shapes.iter())
            .map(|s| match s {
                Shape::Sphere { .. } | Shape::Curves(_) => 0,
                Shape::Triangles(m) => m.triangles.len(),
            })
            .sum()
    };
    let segments = |shapes: &[Shape]| -> usize {
        (shapes.iter())
            .map(|s| match s {
                Shape::Curves(c) => c.segment_count(),
                Shape::Sphere { .. } | Shape::Triangles(_) => 0,
            })
            .sum()
    };
    let placed = |count: &dyn Fn(&[Shape]) -> usize| -> usize {
        (scene.instances.iter())
            .map(|i| count(&scene.prototypes[i.prototype as usize].shapes))
            .sum()
    };
    // Curve segments are named only in scenes that have some.
    let curves = |count: usize| match count {
        0 => String::new(),
        n => format!(", {n} curve segments"),
    };
    format!(
        "{}x{}; lights: {}; {} shapes ({} triangles{}), {} materials; {} objects placed {} times ({} triangles{} placed)",
        scene.camera.width,
        scene.camera.height,
        lights.join(", "),
        scene.shapes.len(),
        triangles(&scene.shapes),
        curves(segments(&scene.shapes)),
        scene.materials.len(),
        scene.prototypes.len(),
        scene.instances.len(),
        placed(&triangles),
        curves(placed(&segments)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_erroneous_directive_is_listed_and_a_good_scene_is_summarised() {
        let dir = tempfile::tempdir().unwrap();
        let bad = dir.path().join("bad.pbrt");
        std::fs::write(
            &bad,
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
             LightSource \"point\" \"rgb I\" [1 1 1]\n\
             Shape \"sphere\" \"float radius\" -1\n\
             Material \"velvet\"\n\
             Shape \"sphere\"\n\
             LightSource \"goniometric\"\n",
        )
        .unwrap();
        let report = check(&bad, &LoadOptions::default());
        let lines: Vec<_> = report.errors.iter().map(|e| e.line).collect();
        assert_eq!(lines, [Some(5), Some(6), Some(8)], "{}", report.text());
        assert!(!report.renders() && report.scene.is_none());
        assert!(report.text().contains("summary: refused: 3 error(s)"));
        let good = dir.path().join("good.pbrt");
        std::fs::write(
            &good,
            "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
             LightSource \"point\" \"rgb I\" [1 1 1]\nShape \"sphere\"\n",
        )
        .unwrap();
        let report = check(&good, &LoadOptions::default());
        assert!(report.renders(), "{}", report.text());
        assert!(
            report.text().contains("lights: 1 point; 1 shapes"),
            "{}",
            report.text()
        );
    }
}
