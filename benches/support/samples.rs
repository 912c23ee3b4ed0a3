//! Wall and CPU seconds of criterion's samples, for benches that quote medians of both: on a
//! machine shared with other work, CPU time shows what wall time cannot (whether two threads
//! do more work than one, and what a run would take on two free cores).

use criterion::Bencher;
use rayon::ThreadPool;
use std::cell::RefCell;
use std::time::Instant;

/// Measured samples per benchmark.
pub const SAMPLES: usize = 10;

/// Per-iteration (wall, CPU) seconds of every call criterion makes; the last [`SAMPLES`] are
/// the measured samples (warm-up calls come first, and flat sampling gives one call per
/// sample). CPU time is the whole process's, all threads: on a machine shared with other work
/// it shows whether two threads do more work than one, which wall time cannot.
#[derive(Default)]
pub struct Samples(RefCell<Vec<(f64, f64)>>);

impl Samples {
    pub fn time(&self, b: &mut Bencher, mut f: impl FnMut()) {
        b.iter_custom(|iters| {
            let (start, cpu) = (Instant::now(), cpu_seconds());
            for _ in 0..iters {
                f();
            }
            let elapsed = start.elapsed();
            let per = |t: f64| t / iters as f64;
            self.0
                .borrow_mut()
                .push((per(elapsed.as_secs_f64()), per(cpu_seconds() - cpu)));
            elapsed
        });
    }

    fn median_of(&self, pick: impl Fn(&(f64, f64)) -> f64) -> f64 {
        let all = self.0.borrow();
        let mut last: Vec<f64> = all[all.len().saturating_sub(SAMPLES)..]
            .iter()
            .map(pick)
            .collect();
        last.sort_by(f64::total_cmp);
        match last.len() {
            0 => f64::NAN,
            n if n % 2 == 1 => last[n / 2],
            n => 0.5 * (last[n / 2 - 1] + last[n / 2]),
        }
    }

    /// Median wall seconds.
    pub fn median(&self) -> f64 {
        self.median_of(|s| s.0)
    }

    /// Median CPU seconds (all threads).
    pub fn median_cpu(&self) -> f64 {
        self.median_of(|s| s.1)
    }
}

/// User + system CPU seconds of this process so far (Linux `/proc/self/stat`, in clock ticks
/// of 1/100 s); NaN elsewhere.
pub fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name, which is in parentheses: utime and stime are the 12th
    // and 13th of them.
    let rest = stat.rsplit_once(')').map_or("", |r| r.1);
    let field = |i: usize| {
        rest.split_whitespace()
            .nth(i)
            .and_then(|v| v.parse::<f64>().ok())
    };
    match (field(11), field(12)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

pub fn pool(threads: usize) -> ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon pool")
}
