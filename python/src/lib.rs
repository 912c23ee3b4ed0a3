//! dpm from Python: `dpm.render` returns the image as a NumPy array, `dpm.check` the
//! diagnostics as records. Settings are `dpm render`'s flags by their long names, parsed by
//! the same clap definitions, so Python is refused what the command line is. Renders run with
//! the GIL released. Must not render differently from the command line: it calls the same
//! pipeline with the same arguments.

use clap::Parser;
use dpm::render::args::RenderArgs;
use dpm::render::pipeline::{self, RenderError};
use numpy::{PyArray3, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

pyo3::create_exception!(_dpm, SceneError, pyo3::exceptions::PyException);

/// `dpm render`'s arguments, parsed as the command line parses them.
#[derive(Parser)]
#[command(name = "dpm render")]
struct Cli {
    #[command(flatten)]
    args: RenderArgs,
}

/// The command line for `scene` and the keyword settings: `caustic_photons=200000` becomes
/// `--caustic-photons 200000`, `True` a bare flag, `False` and `None` nothing.
fn command_line(scene: &str, settings: &Bound<'_, PyDict>) -> PyResult<Vec<String>> {
    let mut argv = vec!["dpm render".to_string(), scene.to_string()];
    for (key, value) in settings.iter() {
        let flag = format!("--{}", key.extract::<String>()?.replace('_', "-"));
        if value.is_none() {
            continue;
        }
        if let Ok(on) = value.extract::<bool>() {
            if on {
                argv.push(flag);
            }
            continue;
        }
        argv.push(flag);
        argv.push(value.str()?.to_string());
    }
    Ok(argv)
}

/// `dpm density`'s arguments, parsed as the command line parses them.
#[derive(Parser)]
#[command(name = "dpm density")]
struct DensityCli {
    #[command(flatten)]
    args: dpm::density::DensityArgs,
}

fn parse(argv: Vec<String>) -> PyResult<RenderArgs> {
    Cli::try_parse_from(argv)
        .map(|cli| cli.args)
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

fn to_python(error: RenderError) -> PyErr {
    match error {
        RenderError::Scene(e) => {
            let text = e.to_string();
            let line = e.line;
            let column = e.column;
            let file = e.file.display().to_string();
            Python::attach(|py| {
                let err = SceneError::new_err(text);
                let value = err.value(py);
                let _ = value.setattr("file", file);
                let _ = value.setattr("line", line);
                let _ = value.setattr("column", column);
                err
            })
        }
        other if other.exit_code() == 2 => PyValueError::new_err(other.to_string()),
        other => pyo3::exceptions::PyRuntimeError::new_err(other.to_string()),
    }
}

/// Renders `scene` and returns its image, linear RGB, as a float32 array of shape (H, W, 3).
///
/// Keyword settings are `dpm render`'s flags by their long names with `_` for `-`
/// (`caustic_photons=200000`, `estimator="cone"`); they are checked as the command line checks
/// them. The image equals the one `dpm render` writes for the same settings and seed.
#[pyfunction]
#[pyo3(signature = (scene, **settings))]
fn render<'py>(
    py: Python<'py>,
    scene: PathBuf,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (args, folder) = render_args(py, &scene, settings)?;
    let (outcome, mut stopped) = run_interruptibly(py, &args);
    let _ = std::fs::remove_dir_all(&folder);
    let outcome = match (outcome, stopped.take()) {
        (Ok(outcome), signal) => {
            stopped = signal;
            outcome
        }
        // Stopped before any pass was complete.
        (Err(_), Some(signal)) => return Err(signal),
        (Err(e), None) => return Err(to_python(e)),
    };
    let image = array(py, &outcome.image)?;
    if let Some(signal) = stopped {
        // Stopped at the end of a pass: the passes completed come with the interrupt.
        signal.value(py).setattr("image", image)?;
        signal.value(py).setattr("passes", outcome.passes.len())?;
        return Err(signal);
    }
    Ok(image)
}

/// `dpm render`'s arguments for `settings` (`resolution=(w, h)` as `--resolution WxH`),
/// writing its file into a fresh folder: the image comes back in memory, and the caller
/// removes the folder.
fn render_args(
    py: Python<'_>,
    scene: &std::path::Path,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<(RenderArgs, PathBuf)> {
    let named = match settings {
        Some(settings) => settings.copy()?,
        None => PyDict::new(py),
    };
    if let Some(size) = named.get_item("resolution")?
        && let Ok((w, h)) = size.extract::<(u32, u32)>()
    {
        named.set_item("resolution", format!("{w}x{h}"))?;
    }
    let folder = tempfile_folder()?;
    named.set_item("output", folder.join("image.pfm").display().to_string())?;
    let args = command_line(&scene.display().to_string(), &named).and_then(parse);
    if args.is_err() {
        let _ = std::fs::remove_dir_all(&folder);
    }
    Ok((args?, folder))
}

/// Runs the pipeline on another thread with the GIL released, and looks at Python's signals
/// while it runs: a Ctrl-C asks dpm to stop at the end of the current pass, and comes back as
/// the `KeyboardInterrupt` to raise once it has.
fn run_interruptibly(
    py: Python<'_>,
    args: &RenderArgs,
) -> (Result<pipeline::RenderOutcome, RenderError>, Option<PyErr>) {
    let (done, finished) = std::sync::mpsc::channel();
    let finished = std::sync::Mutex::new(finished);
    let mut stopped = None;
    let outcome = std::thread::scope(|scope| {
        let worker = scope.spawn(move || {
            let outcome = pipeline::run(args);
            let _ = done.send(());
            outcome
        });
        loop {
            let waited = py.detach(|| finished.lock().unwrap().recv_timeout(SIGNAL_POLL));
            if !matches!(waited, Err(std::sync::mpsc::RecvTimeoutError::Timeout)) {
                break;
            }
            if stopped.is_none()
                && let Err(signal) = py.check_signals()
            {
                dpm::interrupt::request();
                stopped = Some(signal);
            }
        }
        worker.join().expect("the render thread does not panic")
    });
    dpm::interrupt::reset();
    (outcome, stopped)
}

/// How often a render looks at Python's signals (Ctrl-C).
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// An image as a float32 array of shape (H, W, 3).
fn array<'py>(
    py: Python<'py>,
    image: &dpm::image_io::Image,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let flat: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
    numpy::PyArray1::from_vec(py, flat).reshape([image.height, image.width, 3])
}

/// What a render's thread tells the iterator: a pass landed, or the render ended.
enum Message {
    Pass(f64, dpm::image_io::Image),
    Done(Box<Result<pipeline::RenderOutcome, RenderError>>),
}

/// A render seen pass by pass: iterating it yields the image after each pass (a float32
/// array (H, W, 3)) while the next one renders; `stats` then holds the phase table.
#[pyclass(module = "dpm")]
struct Render {
    messages: std::sync::Mutex<std::sync::mpsc::Receiver<Message>>,
    worker: Option<std::thread::JoinHandle<()>>,
    folder: PathBuf,
    /// Each pass's seconds so far.
    #[pyo3(get)]
    pass_seconds: Vec<f64>,
    stats: Option<Py<PyDict>>,
    stopped: Option<PyErr>,
    /// The film once the render has ended.
    film: Option<dpm::render::film::Film>,
}

#[pymethods]
impl Render {
    /// Starts rendering `scene` (the arguments of [`render`]); iterate to get each pass.
    #[new]
    #[pyo3(signature = (scene, **settings))]
    fn new(py: Python<'_>, scene: PathBuf, settings: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let (args, folder) = render_args(py, &scene, settings)?;
        let (send, messages) = std::sync::mpsc::channel();
        let worker = std::thread::spawn(move || {
            let pass_sender = std::sync::Mutex::new(send.clone());
            let observer = |record: &pipeline::PassRecord, film: &dpm::render::film::Film| {
                let message = Message::Pass(record.seconds, film.image());
                let _ = pass_sender.lock().unwrap().send(message);
            };
            let outcome = pipeline::run_observed(&args, Some(&observer));
            let _ = send.send(Message::Done(Box::new(outcome)));
        });
        Ok(Self {
            messages: std::sync::Mutex::new(messages),
            worker: Some(worker),
            folder,
            pass_seconds: Vec::new(),
            stats: None,
            stopped: None,
            film: None,
        })
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray3<f32>>>> {
        loop {
            let Some(worker) = &self.worker else {
                return Ok(None);
            };
            let _ = worker;
            let received = {
                let messages = &self.messages;
                py.detach(|| messages.lock().unwrap().recv_timeout(SIGNAL_POLL))
            };
            match received {
                Ok(Message::Pass(seconds, image)) => {
                    self.pass_seconds.push(seconds);
                    return array(py, &image).map(Some);
                }
                Ok(Message::Done(outcome)) => {
                    if let Some(worker) = self.worker.take() {
                        let _ = worker.join();
                    }
                    dpm::interrupt::reset();
                    let _ = std::fs::remove_dir_all(&self.folder);
                    let stopped = self.stopped.take();
                    return match (*outcome, stopped) {
                        (Ok(outcome), stopped) => {
                            self.stats = Some(stats(py, &outcome)?.unbind());
                            self.film = Some(outcome.film);
                            match stopped {
                                Some(signal) => Err(signal),
                                None => Ok(None),
                            }
                        }
                        (Err(_), Some(signal)) => Err(signal),
                        (Err(e), None) => Err(to_python(e)),
                    };
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    if self.stopped.is_none()
                        && let Err(signal) = py.check_signals()
                    {
                        dpm::interrupt::request();
                        self.stopped = Some(signal);
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    self.worker = None;
                    return Err(pyo3::exceptions::PyRuntimeError::new_err(
                        "the render thread ended without a result",
                    ));
                }
            }
        }
    }

    /// Writes the film (every pass's per-pixel sums, as `dpm render --film` does) once the
    /// render has ended, for `dpm merge` or `--resume`.
    fn save_film(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let Some(film) = &self.film else {
            return Err(pyo3::exceptions::PyRuntimeError::new_err(
                "the render has not ended: iterate it to the end first",
            ));
        };
        py.detach(|| dpm::render::film_file::write(&path, film))
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The phase table once the render has ended (`None` before): each phase's seconds and
    /// counts, the passes and whether Ctrl-C stopped them.
    #[getter]
    fn stats(&self, py: Python<'_>) -> Option<Py<PyDict>> {
        self.stats.as_ref().map(|s| s.clone_ref(py))
    }
}

/// Merges films (from `save_film` or `dpm render --film`) and returns the merged image as
/// `render` does; `output` and `film` also write the image and the merged film, `expect`
/// requires passes 0 to N−1, all of them (`dpm merge`'s flags).
#[pyfunction]
#[pyo3(signature = (films, *, output=None, film=None, expect=None))]
fn merge<'py>(
    py: Python<'py>,
    films: Vec<PathBuf>,
    output: Option<PathBuf>,
    film: Option<PathBuf>,
    expect: Option<u64>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let folder = tempfile_folder()?;
    let args = dpm::render::merge::MergeArgs {
        films,
        output: output.unwrap_or_else(|| folder.join("merged.pfm")),
        film,
        expect,
        exposure: 0.0,
        kernel_field: None,
    };
    let merged = py.detach(|| dpm::render::merge::run(&args));
    let _ = std::fs::remove_dir_all(&folder);
    let merged = merged.map_err(|e| PyValueError::new_err(e.to_string()))?;
    array(py, &merged.film.image())
}

/// The paper's density experiment (`dpm density`, its flags as keywords: `distribution=`,
/// `count=`, `estimator=`...): returns the estimated density as a float32 array (H, W, 3) and
/// the report (`dpm density --stats`: the metrics against the exact density, the seconds) as
/// a dict.
#[pyfunction]
#[pyo3(signature = (**settings))]
fn density<'py>(
    py: Python<'py>,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyArray3<f32>>, Bound<'py, PyAny>)> {
    let named = match settings {
        Some(settings) => settings.copy()?,
        None => PyDict::new(py),
    };
    let folder = tempfile_folder()?;
    let output = folder.join("density.pfm");
    named.set_item("output", output.display().to_string())?;
    let mut argv = command_line("", &named)?;
    argv.remove(1); // no scene
    argv[0] = "dpm density".into();
    let args = DensityCli::try_parse_from(argv).map(|cli| cli.args);
    let ran = args
        .map_err(|e| PyValueError::new_err(e.to_string()))
        .and_then(|args| {
            let report = py.detach(|| dpm::density::run(&args));
            let report = report.map_err(|e| PyValueError::new_err(e.to_string()))?;
            let image = dpm::image_io::read_image(&output)
                .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
            let json = serde_json::to_string(&report)
                .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
            Ok((image, json))
        });
    let _ = std::fs::remove_dir_all(&folder);
    let (image, json) = ran?;
    let report = py.import("json")?.call_method1("loads", (json,))?;
    Ok((array(py, &image)?, report))
}

/// A finished render's phase table and passes as a dict.
fn stats<'py>(py: Python<'py>, outcome: &pipeline::RenderOutcome) -> PyResult<Bound<'py, PyDict>> {
    let phases = PyDict::new(py);
    for phase in &outcome.times.phases {
        let row = PyDict::new(py);
        row.set_item("seconds", phase.seconds)?;
        for (name, count) in &phase.counts {
            row.set_item(name, count)?;
        }
        phases.set_item(&phase.name, row)?;
    }
    let stats = PyDict::new(py);
    stats.set_item("phases", phases)?;
    stats.set_item("passes", outcome.passes.len())?;
    stats.set_item("seconds", outcome.times.total_seconds())?;
    stats.set_item("interrupted", outcome.interrupted)?;
    stats.set_item("caustic_bytes_per_photon", outcome.caustic_bytes_per_photon)?;
    // The process's, as the command line prints it: this render's unless an earlier one in
    // the same process peaked higher.
    stats.set_item(
        "peak_resident_bytes",
        dpm::resident_memory::peak_resident_bytes(),
    )?;
    Ok(stats)
}

/// A fresh folder under the system's temporary folder.
fn tempfile_folder() -> PyResult<PathBuf> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let name = format!(
        "dpm-python-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    );
    let folder = std::env::temp_dir().join(name);
    std::fs::create_dir_all(&folder)?;
    Ok(folder)
}

/// Reads `scene` without rendering; returns its diagnostics as a list of dicts with `file`,
/// `line`, `column`, `severity` ("error", "warning" or "note") and `message`.
#[pyfunction]
fn check<'py>(py: Python<'py>, scene: PathBuf) -> PyResult<Bound<'py, PyList>> {
    let report = py.detach(|| dpm::scene::check::check(&scene, &Default::default()));
    let records = PyList::empty(py);
    for e in &report.errors {
        let record = PyDict::new(py);
        record.set_item("file", e.file.display().to_string())?;
        record.set_item("line", e.line)?;
        record.set_item("column", e.column)?;
        record.set_item("severity", "error")?;
        record.set_item("message", format!("{}: {}", e.field, e.message))?;
        records.append(record)?;
    }
    for (severity, texts) in [
        ("warning", &report.report.warnings),
        ("note", &report.report.notes),
    ] {
        for text in texts {
            let record = PyDict::new(py);
            record.set_item("file", scene.display().to_string())?;
            record.set_item("line", py.None())?;
            record.set_item("column", py.None())?;
            record.set_item("severity", severity)?;
            record.set_item("message", text)?;
            records.append(record)?;
        }
    }
    Ok(records)
}

#[pymodule]
fn _dpm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_class::<Render>()?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(density, m)?)?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    Ok(())
}
