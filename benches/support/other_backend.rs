//! The trace bench's other Embree backend: builds `examples/embree_rays.rs` with the backend
//! this bench was not built with (`--features embree4` from a default build, none from an
//! Embree 4 one) and drives it over pipes, one timing per request, so that its rounds interleave
//! with the bench's own.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

/// Builds the helper for the other backend; `Err` says why it cannot (Embree 4 not fetched, or
/// the build failed), and the bench then leaves that column out.
pub fn build() -> Result<PathBuf, String> {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut features = Vec::new();
    if !cfg!(feature = "embree4") {
        let dir = std::env::var_os("EMBREE4_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| manifest.join("target/embree4"));
        let library = dir.join("libembree4.so");
        if !library.exists() {
            return Err(format!(
                "Embree 4 is not fetched ({} is missing; run scripts/fetch-embree4.sh)",
                library.display()
            ));
        }
        features = vec!["--features", "embree4"];
    }
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    eprintln!("trace bench: building examples/embree_rays.rs for the other Embree backend");
    let output = Command::new(cargo)
        .current_dir(manifest)
        .args(["build", "--release", "--example", "embree_rays"])
        .args(["--message-format", "json-render-diagnostics"])
        .args(features)
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("could not run cargo: {e}"))?;
    if !output.status.success() {
        return Err(format!("building the helper failed ({})", output.status));
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    stdout
        .lines()
        .filter_map(|line| serde_json::from_str::<serde_json::Value>(line).ok())
        .filter(|m| m["reason"] == "compiler-artifact" && m["target"]["name"] == "embree_rays")
        .find_map(|m| m["executable"].as_str().map(PathBuf::from))
        .ok_or_else(|| "cargo named no embree_rays executable".to_string())
}

/// A running helper with one scene and its ray sets loaded.
pub struct Helper {
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<ChildStdout>,
    /// The Embree it runs on, as it reports it (`Embree 4.4.0`).
    pub version: String,
}

impl Helper {
    pub fn spawn(executable: &Path, scene: &Path, ray_files: &[PathBuf]) -> Result<Self, String> {
        let mut child = Command::new(executable)
            .arg(scene)
            .args(ray_files)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| format!("{}: {e}", executable.display()))?;
        let stdin = child.stdin.take();
        let stdout = BufReader::new(child.stdout.take().ok_or("no helper stdout")?);
        let mut helper = Self {
            child,
            stdin,
            stdout,
            version: String::new(),
        };
        let ready = helper.read_line()?;
        helper.version = ready
            .strip_prefix("ready ")
            .ok_or(format!("helper said {ready:?}"))?
            .to_string();
        Ok(helper)
    }

    fn read_line(&mut self) -> Result<String, String> {
        let mut line = String::new();
        match self.stdout.read_line(&mut line) {
            Ok(0) => Err("the helper stopped".into()),
            Ok(_) => Ok(line.trim_end().to_string()),
            Err(e) => Err(e.to_string()),
        }
    }

    /// Wall-clock and CPU seconds, and the hit count, of closest hits of ray set `set` on
    /// `threads` threads.
    pub fn time(&mut self, set: usize, threads: usize) -> Result<(f64, f64, usize), String> {
        let stdin = self.stdin.as_mut().ok_or("helper closed")?;
        writeln!(stdin, "{set} {threads}")
            .and_then(|_| stdin.flush())
            .map_err(|e| e.to_string())?;
        let line = self.read_line()?;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            [wall, cpu, hits] => match (wall.parse(), cpu.parse(), hits.parse()) {
                (Ok(wall), Ok(cpu), Ok(hits)) => Ok((wall, cpu, hits)),
                _ => Err(format!("helper said {line:?}")),
            },
            _ => Err(format!("helper said {line:?}")),
        }
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        // End of input ends the helper.
        drop(self.stdin.take());
        let _ = self.child.wait();
    }
}
