//! Shared by the reliability tests (cli_errors, determinism, scale, interrupt): running the
//! built `dpm` binary and writing small scenes into temporary folders.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// `dpm ARGS`, run to completion.
pub fn dpm<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    // One pass for a render unless the test names its passes: these tests check one pass.
    let mut args: Vec<std::ffi::OsString> =
        args.into_iter().map(|a| a.as_ref().to_owned()).collect();
    let named = ["--passes", "--time", "--save-photons", "--load-photons"];
    if args.first().is_some_and(|a| a == "render")
        && !args.iter().any(|a| named.iter().any(|n| a == n))
    {
        args.extend(["--passes".into(), "1".into()]);
    }
    Command::new(env!("CARGO_BIN_EXE_dpm"))
        .args(args)
        .output()
        .expect("the dpm binary runs")
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Asserts exit code `code`, no panic, and stderr containing every fragment.
pub fn assert_fails(out: &Output, code: i32, fragments: &[&str], what: &str) {
    let err = stderr(out);
    assert_eq!(
        out.status.code(),
        Some(code),
        "{what}: exit status; stderr:\n{err}"
    );
    assert!(!err.contains("panicked"), "{what}: panicked:\n{err}");
    for f in fragments {
        assert!(err.contains(f), "{what}: stderr lacks {f:?}:\n{err}");
    }
}

pub fn assert_succeeds(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: exit {:?}\n{}",
        out.status.code(),
        stderr(out)
    );
}

/// A small caustic scene in scene units scaled by `s`: a point light (power scaled by s², so
/// irradiance is unchanged) over a glass sphere and a mirror sphere standing on a diffuse
/// floor in front of a diffuse back wall. Point lights only: they have no geometry of their own.
pub fn caustic_scene(s: f64, width: u32, height: u32) -> String {
    let v = |x: f64, y: f64, z: f64| format!("[{:e}, {:e}, {:e}]", x * s, y * s, z * s);
    format!(
        "[camera]\nposition = {}\nlook_at = {}\nup = [0.0, 1.0, 0.0]\nfov_y = 40.0\n\
         resolution = [{width}, {height}]\n\n\
         [[lights]]\ntype = \"point\"\nposition = {}\npower = [{p:e}, {p:e}, {p:e}]\n\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = [0.7, 0.7, 0.7]\n\n\
         [materials.wall]\ntype = \"diffuse\"\nalbedo = [0.5, 0.6, 0.4]\n\n\
         [materials.glass]\ntype = \"glass\"\nior = 1.5\n\n\
         [materials.chrome]\ntype = \"mirror\"\n\n\
         [[objects]]\ntype = \"quad\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nmaterial = \"floor\"\n\n\
         [[objects]]\ntype = \"quad\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nmaterial = \"wall\"\n\n\
         [[objects]]\ntype = \"sphere\"\ncenter = {}\nradius = {:e}\nmaterial = \"glass\"\n\n\
         [[objects]]\ntype = \"sphere\"\ncenter = {}\nradius = {:e}\nmaterial = \"chrome\"\n",
        v(0.0, 2.2, 3.2),
        v(0.0, 0.3, 0.0),
        v(0.6, 2.0, 0.4),
        v(-2.0, 0.0, -1.5),
        v(0.0, 0.0, 3.5),
        v(4.0, 0.0, 0.0),
        v(-2.0, 0.0, -1.5),
        v(4.0, 0.0, 0.0),
        v(0.0, 2.5, 0.0),
        v(0.0, 0.5, 0.0),
        0.45 * s,
        v(-0.9, 0.3, -0.6),
        0.3 * s,
        p = 60.0 * s * s,
    )
}

/// Writes `text` as `name` in `dir`; returns its path.
pub fn write_scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Pixels of a PFM file (RGB triples, bottom row first, as stored).
pub fn pfm_pixels(path: &Path) -> (usize, usize, Vec<f32>) {
    let image = dpm::image_io::read_pfm(path).unwrap_or_else(|e| panic!("{e}"));
    let values = image.pixels.iter().flat_map(|p| p.to_array()).collect();
    (image.width, image.height, values)
}

/// A running `dpm` whose stderr is read line by line as it comes, so a test can wait for the
/// line that says a stage started (`started: render (…)`) instead of guessing how long it takes.
pub struct LoggedRun {
    child: std::process::Child,
    lines: std::sync::mpsc::Receiver<String>,
    seen: Vec<String>,
}

impl LoggedRun {
    pub fn spawn(command: &mut Command) -> Self {
        use std::io::BufRead;
        let mut child = command
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("the dpm binary runs");
        let stderr = child.stderr.take().unwrap();
        let (send, lines) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines() {
                let Ok(line) = line else { break };
                if send.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            child,
            lines,
            seen: Vec::new(),
        }
    }

    /// Waits for the `n`-th line (counting from 1, over the whole run) that starts with
    /// `prefix`; panics, with what it printed, if the process ends first.
    pub fn wait_for_line(&mut self, prefix: &str, n: usize) {
        let count = |seen: &[String]| seen.iter().filter(|l| l.starts_with(prefix)).count();
        while count(&self.seen) < n {
            match self.lines.recv() {
                Ok(line) => self.seen.push(line),
                Err(_) => panic!(
                    "dpm ended before printing {prefix:?} {n} times:\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }

    /// Sends SIGINT, as Ctrl-C does.
    pub fn interrupt(&self) {
        let kill = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
    }

    /// Waits for the process to end; its whole stderr is in the output.
    pub fn finish(mut self) -> Output {
        let status = self.child.wait().unwrap();
        self.seen.extend(self.lines.iter());
        Output {
            status,
            stdout: Vec::new(),
            stderr: self.seen.join("\n").into_bytes(),
        }
    }
}
