//! Progressive series for `dpm tradeoff`: each swept estimate at its default setting (cone
//! k = 400; Epanechnikov and diffusion at 1× the default radius of pass 0's map, K = 0.2) run
//! as a progressive estimate over `passes` passes of fresh photons, with radii shrinking by
//! the render's schedule ([`crate::render::schedule`]), and scored after 1, 2, 4, ... passes
//! (and the last) against cumulative time: error against time as a user buying accuracy with
//! time would see it. Every estimate reads the same pass maps; each is charged the tracing of
//! every pass, its own gradient passes and its own evaluations. Owns the series; must not
//! score or trace itself (the target does).

use super::sweep::{Row, SweepError, Target, UNIT_RADIUS_K};
use crate::estimate::ResolvedEstimator;
use crate::estimate::settings::{EstimatorKind, EstimatorSettings, k_equivalent_radius};
use crate::render::schedule::{Schedule, pass_estimator};
use indicatif::ProgressBar;
use std::time::Instant;

/// One estimate's running series.
struct Series {
    kind: EstimatorKind,
    settings: EstimatorSettings,
    sums: Vec<f64>,
    trace: f64,
    prepare: f64,
    evaluate: f64,
    resolved: Option<ResolvedEstimator>,
}

/// The series of `kinds` over `passes` passes of `count` photons; `bar` counts passes.
pub fn run_progressive(
    kinds: &[EstimatorKind],
    count: usize,
    passes: u64,
    schedule: Schedule,
    target: &mut dyn Target,
    bar: &ProgressBar,
) -> Result<Vec<Row>, SweepError> {
    let name = target.name();
    let mut series: Vec<Series> = kinds
        .iter()
        .map(|&kind| Series {
            kind,
            settings: EstimatorSettings {
                estimator: kind,
                k: UNIT_RADIUS_K,
                ..EstimatorSettings::default()
            },
            sums: Vec::new(),
            trace: 0.0,
            prepare: 0.0,
            evaluate: 0.0,
            resolved: None,
        })
        .collect();
    let mut rows = Vec::new();
    let mut base = None;
    for pass in 0..passes {
        bar.set_message(format!("progressive pass {}/{passes}: tracing", pass + 1));
        let start = Instant::now();
        let mut map = target.photons(count, pass)?;
        let trace = start.elapsed().as_secs_f64();
        let photons = map.len();
        let base = *base.get_or_insert_with(|| k_equivalent_radius(&map, UNIT_RADIUS_K));
        for s in &mut series {
            s.trace += trace;
            let settings = pass_estimator(&s.settings, base, &schedule, pass);
            let start = Instant::now();
            let resolved = settings.resolve(&map)?;
            if let ResolvedEstimator::Diffusion(d) = &resolved {
                d.gradient_pass(&mut map);
            }
            s.prepare += start.elapsed().as_secs_f64();
            let estimate = resolved.into_boxed();
            let start = Instant::now();
            let values = target.evaluate(&map, estimate.as_ref());
            s.evaluate += start.elapsed().as_secs_f64();
            if s.sums.is_empty() {
                s.sums = vec![0.0; values.len()];
                s.resolved = Some(resolved);
            }
            for (sum, v) in s.sums.iter_mut().zip(&values) {
                *sum += v;
            }
            let done = pass + 1;
            if done.is_power_of_two() || done == passes {
                let mean: Vec<f64> = s.sums.iter().map(|v| v / done as f64).collect();
                let first = s.resolved.expect("set on pass 0");
                let (k, radius, gradient_radius, diffusivity) = match (s.kind, first) {
                    (_, ResolvedEstimator::Knn(e)) => (Some(e.k()), None, None, None),
                    (_, ResolvedEstimator::FixedRadius(e)) => (None, Some(e.radius()), None, None),
                    (_, ResolvedEstimator::Diffusion(d)) => (
                        None,
                        Some(d.params().radius),
                        Some(d.params().gradient_radius),
                        Some(d.params().diffusivity),
                    ),
                };
                rows.push(Row {
                    target: name.clone(),
                    estimate: estimate.name(),
                    photons,
                    k,
                    radius,
                    gradient_radius,
                    diffusivity,
                    trace_seconds: s.trace,
                    prepare_seconds: s.prepare,
                    estimate_seconds: s.evaluate,
                    errors: target.score(&mean),
                    passes: Some(done),
                });
            }
        }
        bar.inc(1);
    }
    Ok(rows)
}
