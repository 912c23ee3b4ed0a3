//! Phase timing and progress: every long stage shows an indicatif bar (on a terminal; elsewhere,
//! a log line when it starts) and records its wall time and counts, printed at the end as a
//! table and written as JSON with `--stats`. A program embedding dpm (or a test) can
//! [`watch_phases`] to learn when each stage starts. Owns reporting only; it never changes what
//! is computed.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

#[derive(Clone, Debug, Serialize)]
pub struct Phase {
    pub name: String,
    pub seconds: f64,
    /// Named counts (photons emitted, stored, pixels, ...).
    pub counts: Vec<(String, u64)>,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct PhaseTimes {
    pub phases: Vec<Phase>,
}

impl PhaseTimes {
    pub fn new() -> Self {
        Self::default()
    }

    /// Runs `f` as a phase named `name`, recording its wall time.
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.record(name, start.elapsed(), &[]);
        out
    }

    pub fn record(&mut self, name: &str, elapsed: Duration, counts: &[(&str, u64)]) {
        self.phases.push(Phase {
            name: name.to_string(),
            seconds: elapsed.as_secs_f64(),
            counts: counts.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
        });
    }

    /// Adds `elapsed` and `counts` to the phase called `name` (made when missing): the phases
    /// of a progressive render's passes add up into one row each.
    pub fn accumulate(&mut self, name: &str, elapsed: Duration, counts: &[(&str, u64)]) {
        let Some(p) = self.phases.iter_mut().find(|p| p.name == name) else {
            return self.record(name, elapsed, counts);
        };
        p.seconds += elapsed.as_secs_f64();
        for (k, v) in counts {
            match p.counts.iter_mut().find(|(name, _)| name == k) {
                Some((_, total)) => *total += v,
                None => p.counts.push((k.to_string(), *v)),
            }
        }
    }

    /// Adds counts to the most recent phase called `name`.
    pub fn add_counts(&mut self, name: &str, counts: &[(&str, u64)]) {
        if let Some(p) = self.phases.iter_mut().rev().find(|p| p.name == name) {
            p.counts
                .extend(counts.iter().map(|(k, v)| (k.to_string(), *v)));
        }
    }

    pub fn seconds(&self, name: &str) -> f64 {
        self.phases
            .iter()
            .filter(|p| p.name == name)
            .map(|p| p.seconds)
            .sum()
    }

    pub fn total_seconds(&self) -> f64 {
        self.phases.iter().map(|p| p.seconds).sum()
    }

    /// The per-phase table printed at the end of a run.
    pub fn table(&self) -> String {
        let total = self.total_seconds().max(1e-12);
        let mut out = format!("{:<22} {:>10} {:>7}  counts\n", "phase", "seconds", "share");
        for p in &self.phases {
            let counts: Vec<String> = p.counts.iter().map(|(k, v)| format!("{k}={v}")).collect();
            out += &format!(
                "{:<22} {:>10.3} {:>6.1}%  {}\n",
                p.name,
                p.seconds,
                100.0 * p.seconds / total,
                counts.join(" ")
            );
        }
        out += &format!(
            "{:<22} {:>10.3} {:>6.1}%\n",
            "total",
            self.total_seconds(),
            100.0
        );
        out
    }
}

/// A progress bar on stderr for `len` units of work. Off a terminal (a log file, a batch
/// job) the bar stays hidden and one line says the stage started instead.
pub fn progress(len: u64, what: &str) -> ProgressBar {
    announce(what);
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        bar.set_draw_target(ProgressDrawTarget::hidden());
        eprintln!("started: {what} ({len})");
    }
    let style = ProgressStyle::with_template(
        "{msg:>18} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar())
    .progress_chars("=> ");
    bar.set_style(style);
    bar.set_message(what.to_string());
    bar
}

static WATCHERS: Mutex<Vec<Sender<String>>> = Mutex::new(Vec::new());

/// A channel that receives the name of every stage with a progress bar ("caustic photons",
/// "render", ...) as it starts, in this process, until the receiver is dropped.
pub fn watch_phases() -> Receiver<String> {
    let (send, receive) = channel();
    WATCHERS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(send);
    receive
}

fn announce(what: &str) {
    let mut watchers = WATCHERS.lock().unwrap_or_else(|e| e.into_inner());
    watchers.retain(|w| w.send(what.to_string()).is_ok());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_lists_every_phase_and_the_total() {
        let mut t = PhaseTimes::new();
        t.record(
            "photon tracing",
            Duration::from_millis(1500),
            &[("stored", 10)],
        );
        t.record("render", Duration::from_millis(500), &[]);
        let table = t.table();
        assert!(table.contains("photon tracing") && table.contains("stored=10"));
        assert!(table.contains("75.0%") && table.contains("25.0%"));
        assert!((t.total_seconds() - 2.0).abs() < 1e-9);
        assert!((t.seconds("render") - 0.5).abs() < 1e-9);
        t.accumulate("render", Duration::from_millis(250), &[("pixels", 4)]);
        t.accumulate("render", Duration::from_millis(250), &[("pixels", 6)]);
        assert_eq!(t.phases.len(), 2);
        assert!((t.seconds("render") - 1.0).abs() < 1e-9);
        assert_eq!(t.phases[1].counts, vec![("pixels".to_string(), 10)]);
    }

    #[test]
    fn watchers_hear_each_stage_start_until_they_leave() {
        let first = watch_phases();
        let second = watch_phases();
        progress(3, "stage one").finish_and_clear();
        drop(second);
        progress(3, "stage two").finish_and_clear();
        // Other tests may start stages of their own at the same time.
        let heard: Vec<String> = first.try_iter().collect();
        let one = heard.iter().position(|w| w == "stage one");
        let two = heard.iter().position(|w| w == "stage two");
        assert!(
            one.is_some_and(|one| two.is_some_and(|two| one < two)),
            "{heard:?}"
        );
    }
}
