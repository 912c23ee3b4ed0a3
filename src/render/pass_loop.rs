//! The pass loop: from a run's first pass, one [`super::pass`] after another into the
//! [`Film`], while `--passes` or the `--time` budget allows (a pass whose predicted time, the
//! mean of this run's pass times, would overrun the budget is not started, though the first
//! always runs), with a progress bar over the passes, each pass's line in the report (its time
//! and, with `--reference`, the film's error after it), and `-o`/`--film` rewritten as passes
//! complete (after pass 0, then as often as costs at most 2% of the render, or every
//! `--write-every` seconds; the last write is the caller's). Ctrl-C ends the pass in flight
//! unfinished; the film keeps the complete ones. Owns the order of passes and when they are
//! written; must not decide what a pass computes.

use super::args::RenderArgs;
use super::camera::RayCamera;
use super::film::Film;
use super::pass::{PassContext, PassReport};
use super::photon_files::{load_maps, save_maps};
use super::pilots::PixelPlan;
use super::pipeline::{PassRecord, RenderError, write_outputs};
use super::schedule::MAX_PASSES;
use super::setup::{Start, Wiring};
use super::tensor_history::TensorHistory;
use crate::estimate::EstimatorKind;
use crate::image_io::Image;
use crate::image_metrics::image_relative_mse;
use crate::timing::{PhaseTimes, progress};
use crate::world::World;
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Everything the passes of one run share.
pub struct PassLoop<'a> {
    pub args: &'a RenderArgs,
    pub world: &'a World,
    pub wiring: &'a Wiring,
    pub camera: RayCamera,
    pub plan: &'a PixelPlan,
    pub reference: Option<Image>,
    pub output: &'a Path,
    pub film_path: Option<PathBuf>,
    /// When the run started: the budget counts from here, loading included.
    pub run_start: Instant,
    /// Told of every pass as it lands.
    pub observer: Option<super::pipeline::PassObserver<'a>>,
}

/// What the loop leaves: the film (None if no pass began one) and the report of the passes.
pub struct LoopOutcome {
    pub film: Option<Film>,
    pub records: Vec<PassRecord>,
    pub last_report: Option<PassReport>,
    pub saved_photons: Option<PathBuf>,
    pub budget_note: Option<String>,
    pub interrupted: bool,
}

impl PassLoop<'_> {
    pub fn run(&self, start: Start, times: &mut PhaseTimes) -> Result<LoopOutcome, RenderError> {
        let args = self.args;
        let Start {
            film,
            first,
            mut radii,
        } = start;
        let mut out = LoopOutcome {
            film,
            records: Vec::new(),
            last_report: None,
            saved_photons: None,
            budget_note: None,
            interrupted: false,
        };
        let last = (first + super::pipeline::pass_limit(self.args)).min(MAX_PASSES);
        let bar = self.bar(first, last);
        let mut last_write: Option<LastWrite> = None;
        let settings = &self.wiring.settings;
        let mut history = TensorHistory::new(
            match settings.estimator.estimator {
                EstimatorKind::Diffusion => settings.estimator.tensor_history,
                _ => 0,
            },
            settings.estimator.history_photons,
        );
        for pass in first..last {
            if self.budget_spent(&out.records) {
                break;
            }
            let pass_start = Instant::now();
            let maps = if pass == 0 && args.load_photons.is_some() {
                load_maps(args, self.wiring.scene_hash, &self.wiring.wanted, times)?
            } else {
                let wiring = self.wiring;
                let schedule = &wiring.schedule;
                super::pass::trace_pass_maps(self.world, &wiring.settings, schedule, pass, times)
            };
            if crate::interrupt::requested() {
                out.interrupted = true;
                break;
            }
            if pass == 0
                && let Some(path) = &args.save_photons
            {
                let (hash, wanted) = (self.wiring.scene_hash, &self.wiring.wanted);
                save_maps(path, hash, args.seed, wanted, &maps, times)?;
                out.saved_photons = Some(path.clone());
            }
            // Pass 0's maps resolve the base radii; later passes only scale them.
            let radii = match radii {
                Some(r) => r,
                None => *radii.insert(super::pass::BaseRadii::resolve(
                    &self.wiring.settings,
                    &maps,
                )?),
            };
            let film = out
                .film
                .get_or_insert_with(|| Film::new(self.wiring.header(args, self.world, radii)));
            let context = PassContext {
                world: self.world,
                camera: self.camera,
                plan: self.plan,
                settings: &self.wiring.settings,
                radii,
                schedule: self.wiring.schedule,
                kernel_field: self.wiring.kernel_field,
            };
            history.fill_before(pass, self.world, settings, &self.wiring.schedule, times);
            let analysis = history.analysis_map();
            if let Some((map, _)) = &maps.caustic {
                history.record(pass, map);
            }
            let Some(report) = context.run(pass, maps, analysis, times)? else {
                out.interrupted = true;
                break;
            };
            film.add_pass(pass, &report.image)
                .expect("a pass's image fits its film and is new to it");
            let seconds = pass_start.elapsed().as_secs_f64();
            out.records.push(PassRecord {
                pass,
                seconds,
                elapsed: self.run_start.elapsed().as_secs_f64(),
                relative_mse: self
                    .reference
                    .as_ref()
                    .map(|r| image_relative_mse(&film.image(), r)),
            });
            if let (Some(observer), Some(record)) = (self.observer, out.records.last()) {
                observer(record, film);
            }
            out.last_report = Some(report);
            if pass == first && args.time.is_some_and(|t| self.elapsed() > t) {
                out.budget_note = Some(format!(
                    "the --time budget ({:.1} s) is shorter than one pass ({seconds:.1} s); one pass ran",
                    args.time.unwrap_or_default()
                ));
            }
            match self.budget_bar() {
                Some(_) => bar.set_position(self.run_start.elapsed().as_secs()),
                None => bar.inc(1),
            }
            bar.set_message(pass_message(film, &out.records, &out.last_report));
            let since = last_write.map(|w| (w.end.elapsed(), w.took));
            if pass + 1 < last && write_due(args.write_every, since) {
                let start = Instant::now();
                write_outputs(args, self.output, self.film_path.as_deref(), film, times)?;
                last_write = Some(LastWrite {
                    end: Instant::now(),
                    took: start.elapsed(),
                });
            }
        }
        bar.finish_and_clear();
        Ok(out)
    }

    fn elapsed(&self) -> f64 {
        self.run_start.elapsed().as_secs_f64()
    }

    /// With a budget and no pass count, the bar counts seconds of the budget.
    fn budget_bar(&self) -> Option<f64> {
        self.args.time.filter(|_| self.args.passes.is_none())
    }

    fn bar(&self, first: u64, last: u64) -> ProgressBar {
        match self.budget_bar() {
            Some(t) => progress(t.ceil() as u64, "seconds of budget"),
            None => progress(last - first, "passes"),
        }
    }

    /// Whether the next pass, predicted to take the mean of this run's passes, would overrun
    /// the budget. The first pass always runs.
    fn budget_spent(&self, records: &[PassRecord]) -> bool {
        let Some(budget) = self.args.time.filter(|_| !records.is_empty()) else {
            return false;
        };
        let mean = records.iter().map(|r| r.seconds).sum::<f64>() / records.len() as f64;
        self.elapsed() + mean > budget
    }
}

/// When the outputs were last rewritten, and what that took.
#[derive(Clone, Copy)]
struct LastWrite {
    end: Instant,
    took: Duration,
}

/// By default a rewrite waits this many times what the last one took: writing costs at most
/// 1/50 of the render.
pub const WRITE_COST_RATIO: u32 = 50;

/// Whether the outputs are due a rewrite after a pass, given `--write-every` and the time
/// since the last rewrite with what it took (`None`: none yet this run, which is always due).
/// Every `--write-every` seconds where it is given, else once [`WRITE_COST_RATIO`] times the
/// last rewrite has passed.
pub fn write_due(every: Option<f64>, since_last: Option<(Duration, Duration)>) -> bool {
    let Some((since, took)) = since_last else {
        return true;
    };
    match every {
        Some(seconds) => since >= Duration::from_secs_f64(seconds),
        None => since >= took * WRITE_COST_RATIO,
    }
}

/// The pass bar's message: passes held, photons so far, the error so far.
fn pass_message(film: &Film, records: &[PassRecord], last: &Option<PassReport>) -> String {
    let per_pass = last.as_ref().map_or(0, |r| {
        r.caustic.map_or(0, |c| c.stored) + r.global.map_or(0, |c| c.stored)
    });
    let photons = per_pass * records.len() as u64;
    let mut m = format!("{} passes, {photons} photons", film.passes().count());
    if let Some(e) = records.last().and_then(|r| r.relative_mse) {
        m += &format!(", rel. MSE {e:.3e}");
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(v: u64) -> Duration {
        Duration::from_millis(v)
    }

    #[test]
    fn by_default_a_rewrite_waits_fifty_times_what_the_last_took() {
        assert!(write_due(None, None), "the first pass is always written");
        assert!(!write_due(None, Some((ms(499), ms(10)))));
        assert!(write_due(None, Some((ms(500), ms(10)))));
        // A write that takes nothing measurable leaves every pass written.
        assert!(write_due(None, Some((ms(0), ms(0)))));
    }

    #[test]
    fn write_every_counts_seconds_whatever_a_write_took() {
        assert!(
            write_due(Some(0.0), Some((ms(0), ms(900)))),
            "0: after every pass"
        );
        assert!(!write_due(Some(2.0), Some((ms(1_999), ms(1)))));
        assert!(write_due(Some(2.0), Some((ms(2_000), ms(1)))));
        assert!(write_due(Some(2.0), None));
    }
}
