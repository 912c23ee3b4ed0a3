//! Interruption: a render stopped by Ctrl-C (or by `dpm::interrupt::request`) before, during
//! photon tracing or during the eye pass returns `Interrupted` (exit code 130, "interrupted;
//! OUT was not written"), leaves an earlier output file byte for byte as it was, and leaves no
//! temporary file behind. The in-process cases share the process-wide flag, so they run one
//! after another inside one test. Every interruption waits for the stage it is meant to land
//! in to start (`dpm::timing::watch_phases` in process, the binary's `started:` lines), never
//! for a guessed duration, so a loaded machine only makes the tests slower.

mod reliability_support;

use clap::Parser;
use dpm::render::pipeline::{self, RenderArgs, RenderError};
use dpm::{interrupt, timing};
use reliability_support::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: RenderArgs,
}

fn args(scene: &Path, output: &Path, extra: &[&str]) -> RenderArgs {
    let mut all = vec![
        "dpm".to_string(),
        scene.display().to_string(),
        "-o".into(),
        output.display().to_string(),
    ];
    all.extend(extra.iter().map(|s| s.to_string()));
    if !extra
        .iter()
        .any(|a| ["--passes", "--save-photons"].contains(a))
    {
        all.extend(["--passes".to_string(), "1".to_string()]);
    }
    Cli::parse_from(all).args
}

/// Files in `dir` other than `keep` (a temporary file left behind would show up here).
fn strays(dir: &Path, keep: &[&Path]) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !keep.contains(&p.as_path()))
        .collect()
}

/// Runs `args`, requesting an interruption as soon as the stage `at` starts (None: before
/// starting); returns the error and how long the render took to stop once asked.
fn interrupted_run(args: &RenderArgs, at: Option<&str>) -> (RenderError, Duration) {
    interrupt::reset();
    let phases = timing::watch_phases();
    let asked = std::sync::Mutex::new(None);
    let done = std::sync::atomic::AtomicBool::new(false);
    let result = std::thread::scope(|s| {
        match at {
            None => {
                *asked.lock().unwrap() = Some(Instant::now());
                interrupt::request();
            }
            Some(stage) => {
                let (asked, done) = (&asked, &done);
                s.spawn(move || {
                    // The timeout only lets this thread see that the render ended without
                    // the stage (the test then fails below); it decides nothing.
                    while !done.load(std::sync::atomic::Ordering::SeqCst) {
                        let Ok(started) = phases.recv_timeout(Duration::from_millis(50)) else {
                            continue;
                        };
                        if started == stage {
                            *asked.lock().unwrap() = Some(Instant::now());
                            interrupt::request();
                            return;
                        }
                    }
                });
            }
        }
        let result = pipeline::run(args);
        done.store(true, std::sync::atomic::Ordering::SeqCst);
        result
    });
    interrupt::reset();
    let asked = asked.into_inner().unwrap();
    match (result, asked) {
        (Err(e), Some(asked)) => (e, asked.elapsed()),
        (Err(e), None) => panic!("the render stopped before {at:?} started: {e}"),
        (Ok(_), _) => panic!("the render finished before the interruption at {at:?}"),
    }
}

#[test]
fn an_interrupted_render_writes_nothing_and_keeps_the_old_output() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "scene.toml", &caustic_scene(1.0, 1200, 900));
    let output = dir.path().join("out.pfm");
    let earlier = b"an earlier render, not to be touched".to_vec();
    std::fs::write(&output, &earlier).unwrap();
    let photons = dir.path().join("maps.photons");
    let p = photons.to_str().unwrap();

    // (what, extra flags, when, the photon file it must have saved)
    let heavy_trace = ["--caustic-photons", "3000000", "--global-photons", "0"];
    let heavy_render = [
        "--caustic-photons",
        "2000",
        "--global-photons",
        "0",
        "--estimator",
        "simple",
        "--k",
        "20",
        "--spp",
        "16",
    ];
    let cases: Vec<(&str, Vec<&str>, Option<&str>, bool)> = vec![
        ("before starting", vec!["--save-photons", p], None, false),
        (
            "while tracing",
            [&heavy_trace[..], &["--save-photons", p]].concat(),
            Some("caustic photons"),
            false,
        ),
        (
            "while rendering",
            [&heavy_render[..], &["--save-photons", p]].concat(),
            Some("render"),
            true,
        ),
    ];
    for (what, extra, at, saved) in cases {
        let _ = std::fs::remove_file(&photons);
        let (e, elapsed) = interrupted_run(&args(&scene, &output, &extra), at);
        eprintln!("{what}: stopped {elapsed:?} after the request");
        assert!(
            matches!(&e, RenderError::Interrupted { output: o, .. } if *o == output),
            "{what}: {e:?}"
        );
        assert_eq!(e.exit_code(), 130, "{what}");
        let message = e.to_string();
        assert!(
            message.starts_with(&format!(
                "interrupted; {} was not written",
                output.display()
            )),
            "{what}: {message}"
        );
        assert!(
            elapsed < Duration::from_secs(60),
            "{what}: stopped after {elapsed:?}"
        );
        assert_eq!(
            std::fs::read(&output).unwrap(),
            earlier,
            "{what}: output changed"
        );
        assert_eq!(photons.exists(), saved, "{what}: photon file");
        if saved {
            // Maps traced before the interruption are kept, and the message says where.
            assert!(message.contains("maps.photons"), "{message}");
            assert!(dpm::photon::store::read(&photons).is_ok());
        }
        let keep = [output.as_path(), scene.as_path(), photons.as_path()];
        assert!(
            strays(dir.path(), &keep).is_empty(),
            "{what}: {:?}",
            strays(dir.path(), &keep)
        );
    }

    // Cleared, the same render completes.
    let small = write_scene(dir.path(), "small.toml", &caustic_scene(1.0, 8, 6));
    let done = pipeline::run(&args(
        &small,
        &output,
        &["--caustic-photons", "300", "--k", "10"],
    ));
    assert!(done.is_ok(), "{:?}", done.err());
    assert_ne!(std::fs::read(&output).unwrap(), earlier);
}

#[test]
fn ctrl_c_stops_the_binary_with_exit_130_and_keeps_the_old_output() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "scene.toml", &caustic_scene(1.0, 1500, 1000));
    let output = dir.path().join("out.png");
    let earlier = b"an earlier render".to_vec();
    std::fs::write(&output, &earlier).unwrap();
    let mut run = LoggedRun::spawn(
        std::process::Command::new(env!("CARGO_BIN_EXE_dpm"))
            .args([
                "render".as_ref(),
                scene.as_os_str(),
                "-o".as_ref(),
                output.as_os_str(),
            ])
            .args([
                "--caustic-photons",
                "0",
                "--global-photons",
                "0",
                "--spp",
                "64",
            ]),
    );
    run.wait_for_line("started: render ", 1);
    let sent = Instant::now();
    run.interrupt();
    let out = run.finish();
    let stopped = sent.elapsed();
    assert_fails(
        &out,
        130,
        &["interrupted; ", "out.png was not written"],
        "Ctrl-C",
    );
    assert!(
        stopped < Duration::from_secs(30),
        "stopped {stopped:?} after Ctrl-C"
    );
    assert_eq!(std::fs::read(&output).unwrap(), earlier);
    let keep = [output.as_path(), scene.as_path()];
    assert!(
        strays(dir.path(), &keep).is_empty(),
        "{:?}",
        strays(dir.path(), &keep)
    );
}

/// Ctrl-C during a progressive render ends the pass in flight unfinished and keeps every
/// complete one: the output and the film hold them, and the exit code is still 130.
#[test]
fn ctrl_c_during_a_progressive_render_keeps_the_complete_passes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "scene.toml", &caustic_scene(1.0, 200, 150));
    let output = dir.path().join("out.pfm");
    let film = dir.path().join("out.film");
    let mut run = LoggedRun::spawn(
        std::process::Command::new(env!("CARGO_BIN_EXE_dpm"))
            .args([
                "render".as_ref(),
                scene.as_os_str(),
                "-o".as_ref(),
                output.as_os_str(),
            ])
            .args(["--film".as_ref(), film.as_os_str()])
            .args([
                "--caustic-photons",
                "50000",
                "--passes",
                "100000",
                "--spp",
                "4",
            ]),
    );
    // The film is written when a pass completes, before the next pass starts: the second
    // pass's eye pass starting means pass 0 is in the film and pass 1 is in flight.
    run.wait_for_line("started: render ", 2);
    assert!(film.exists(), "no film after the first pass");
    run.interrupt();
    let out = run.finish();
    assert_fails(&out, 130, &["interrupted: the output holds the "], "Ctrl-C");
    let film = dpm::render::film_file::read(&film).expect("a whole film");
    let passes = film.passes().count();
    assert!(
        passes >= 1 && film.passes().ranges() == [(0, passes)],
        "{:?}",
        film.passes()
    );
    assert!(stderr(&out).contains(&format!("holds the {passes} complete pass")));
    let image = dpm::image_io::read_pfm(&output).expect("a whole image");
    assert_eq!(image, film.image());
}
