//! Past one machine (issue 18): deploy/render-shard.sh and deploy/merge-shards.sh, the scripts
//! every Slurm task and Kubernetes pod runs, on 4 shards of 2 passes here. Their films merge
//! to one run of the 8 passes; a lost shard fails the merge naming its passes, and so does a
//! shard killed part way; a rerun writes the same film, byte for byte, and touches no other.
//! Bad settings exit 2 naming the variable. The Slurm script, the Kubernetes Jobs and the
//! container recipe call the same two scripts. (deploy/slurm/test-local-cluster.sh runs the
//! Slurm side on a real Slurm; .ci/run validates the manifests against Kubernetes' schemas.)

mod support;

use dpm::render::film_file;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use support::*;

const TASKS: u64 = 4;
const PASSES_PER_TASK: u64 = 2;
const RENDER_ARGS: &str = "--caustic-photons 20000 --global-photons 10000 --k 50";

/// A shard script with the settings of this test's render.
fn script(name: &str, scene: &Path, films: &Path) -> Command {
    let mut c = Command::new(repo_path(&format!("deploy/{name}")));
    c.env("DPM_BIN", env!("CARGO_BIN_EXE_dpm"))
        .env("DPM_SCENE", scene)
        .env("DPM_FILM_DIR", films)
        .env("DPM_TASKS", TASKS.to_string())
        .env("DPM_PASSES_PER_TASK", PASSES_PER_TASK.to_string())
        .env("DPM_RENDER_ARGS", RENDER_ARGS)
        .env_remove("SLURM_CPUS_PER_TASK")
        .env_remove("DPM_THREADS");
    c
}

fn run(mut c: Command) -> Output {
    c.output().expect("the script runs (bash)")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `c` and checks that it exits 2 and says every fragment on stderr.
fn refused(c: Command, fragments: &[&str]) {
    let o = run(c);
    let text = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    for f in fragments {
        assert!(text.contains(f), "{text:?} lacks {f:?}");
    }
}

struct Render {
    dir: tempfile::TempDir,
    scene: PathBuf,
    films: PathBuf,
}

impl Render {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let scene = write_scene(dir.path(), "box.toml", &cornell_point_light(40, 30));
        let films = dir.path().join("films");
        std::fs::create_dir(&films).unwrap();
        Self { dir, scene, films }
    }

    fn script(&self, name: &str) -> Command {
        script(name, &self.scene, &self.films)
    }

    fn shard(&self, index: u64) -> Command {
        let mut c = self.script("render-shard.sh");
        c.arg(index.to_string());
        c
    }

    fn film(&self, index: u64) -> PathBuf {
        self.films.join(format!("shard-{index}.film"))
    }

    fn render_shard(&self, index: u64) {
        let o = run(self.shard(index));
        assert!(o.status.success(), "shard {index}: {}", stderr(&o));
    }
}

#[test]
fn shards_merge_to_one_run_and_a_lost_or_killed_shard_is_named_and_rerendered_identically() {
    let r = Render::new();
    for i in 0..TASKS {
        r.render_shard(i);
    }
    let first: Vec<Vec<u8>> = (0..TASKS)
        .map(|i| std::fs::read(r.film(i)).unwrap())
        .collect();
    let shard = film_file::read(&r.film(2)).unwrap();
    assert_eq!(shard.passes().ranges(), &[(4, 6)]);

    // Lost: the merge fails, naming the shard and its passes.
    std::fs::remove_file(r.film(2)).unwrap();
    refused(
        r.script("merge-shards.sh"),
        &[
            "shard-2.film is missing: rerun shard 2 (passes 4-5)",
            "--expect 8: passes 4-5 are missing (2 of 8)",
        ],
    );
    assert!(!r.films.join("merged.film").exists());

    // Killed part way: the rerun is killed as soon as its film first appears (after pass 4;
    // films are written atomically, so the film is whole or absent, never torn).
    let mut child = r.shard(2).stderr(Stdio::null()).spawn().unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    while !r.film(2).exists() && child.try_wait().unwrap().is_none() {
        assert!(Instant::now() < deadline, "shard 2 wrote no film in 120 s");
        std::thread::sleep(Duration::from_millis(1));
    }
    // exec in the script: this kills dpm itself.
    let _ = child.kill();
    child.wait().unwrap();
    let partial = film_file::read(&r.film(2)).expect("a killed shard leaves a whole film");
    if partial.passes().ranges() == [(4, 5)] {
        refused(r.script("merge-shards.sh"), &["pass 5 is missing (1 of 8)"]);
        eprintln!("killed after pass 4: the merge named pass 5");
    } else {
        // The kill came after the last write; the race is the machine's, not dpm's.
        assert_eq!(partial.passes().ranges(), &[(4, 6)]);
    }
    for i in [0, 1, 3] {
        assert_eq!(std::fs::read(r.film(i)).unwrap(), first[i as usize], "{i}");
    }

    // Rerun: the same film, byte for byte; then the merge passes.
    r.render_shard(2);
    assert_eq!(std::fs::read(r.film(2)).unwrap(), first[2]);
    let o = run(r.script("merge-shards.sh"));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("8 passes (0-7)"), "{}", stderr(&o));
    assert!(r.films.join("merged.exr").is_file());
    let merged = film_file::read(&r.films.join("merged.film")).unwrap();

    // One machine, the same 8 passes, with the scripts' flags (EXR output, as the shards).
    let whole = r.dir.path().join("whole.film");
    let mut args = vec![
        "render".to_string(),
        path_str(&r.scene).into(),
        "--passes".into(),
        "8".into(),
        "-o".into(),
        path_str(&r.dir.path().join("whole.exr")).into(),
        "--film".into(),
        path_str(&whole).into(),
    ];
    args.extend(RENDER_ARGS.split(' ').map(String::from));
    let o = Command::new(env!("CARGO_BIN_EXE_dpm"))
        .args(&args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let whole = film_file::read(&whole).unwrap();
    assert_eq!(merged.header, whole.header);
    assert_eq!(merged.passes().ranges(), &[(0, 8)]);
    let diff = max_relative_difference(whole.sums(), merged.sums());
    assert!(diff <= 1e-6, "merged shards differ from one run by {diff}");
}

#[test]
fn bad_settings_exit_2_naming_the_variable() {
    let r = Render::new();
    let mut c = r.shard(0);
    c.env_remove("DPM_SCENE");
    refused(c, &["DPM_SCENE is not set"]);
    refused(
        r.script("render-shard.sh"),
        &["usage: render-shard.sh INDEX"],
    );
    let mut c = r.script("render-shard.sh");
    c.arg("-1");
    refused(c, &["INDEX '-1' is not a shard number"]);
    let mut c = r.shard(0);
    c.env("DPM_PASSES_PER_TASK", "0");
    refused(c, &["DPM_PASSES_PER_TASK '0'"]);
    let mut c = r.shard(0);
    c.env("DPM_FILM_DIR", r.dir.path().join("absent"));
    refused(c, &["DPM_FILM_DIR", "is not a directory"]);
    // dpm's own refusal passes through: a render too long for dpm's pass cap.
    let mut c = r.script("render-shard.sh");
    c.arg("9999999");
    refused(c, &["at most 1000000 passes"]);
    let mut c = r.script("merge-shards.sh");
    c.env("DPM_TASKS", "x");
    refused(c, &["DPM_TASKS 'x'"]);
    refused(
        r.script("merge-shards.sh"),
        &["no shard film", "all 4 are missing"],
    );
    assert!(
        std::fs::read_dir(&r.films).unwrap().next().is_none(),
        "nothing written"
    );
}

/// The batch engines' files run the same two scripts, so what the Slurm test and the test
/// above check is what a pod runs.
#[test]
fn slurm_kubernetes_and_the_image_run_the_same_scripts() {
    let read =
        |p: &str| std::fs::read_to_string(repo_path(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    let holds = |p: &str, fragments: &[&str]| {
        let text = read(p);
        for f in fragments {
            assert!(text.contains(f), "{p} lacks {f}");
        }
    };
    holds(
        "deploy/slurm/render.sbatch",
        &["/render-shard.sh\" \"$SLURM_ARRAY_TASK_ID\""],
    );
    holds("deploy/slurm/merge.sbatch", &["/merge-shards.sh\""]);
    holds(
        "deploy/slurm/submit.sh",
        &["--array=0-$((DPM_TASKS - 1))", "--dependency=afterok:"],
    );
    holds(
        "deploy/kubernetes/render-job.yaml",
        &[
            "completionMode: Indexed",
            "command: [\"/opt/dpm/deploy/render-shard.sh\"]",
            "args: [\"$(JOB_COMPLETION_INDEX)\"]",
            "configMapRef:",
        ],
    );
    holds(
        "deploy/kubernetes/merge-job.yaml",
        &["command: [\"/opt/dpm/deploy/merge-shards.sh\"]"],
    );
    holds(
        "deploy/Dockerfile",
        &[
            "FROM debian:12",
            "libembree-dev",
            "COPY deploy/render-shard.sh deploy/merge-shards.sh deploy/settings.sh /opt/dpm/deploy/",
            "cargo build --release --locked --bin dpm",
        ],
    );
    // The render Job's completions are the merge's DPM_TASKS.
    let value = |p: &str, key: &str| -> String {
        let text = read(p);
        let line = text
            .lines()
            .map(str::trim_start)
            .find(|l| l.starts_with(key))
            .unwrap_or_else(|| panic!("{p}: no {key}"));
        line[key.len()..].trim().trim_matches('"').to_string()
    };
    assert_eq!(
        value("deploy/kubernetes/render-job.yaml", "completions:"),
        value("deploy/kubernetes/settings.yaml", "DPM_TASKS:")
    );
}
