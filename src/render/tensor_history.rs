//! The tensor history of a progressive render: the caustic photons of the passes before the
//! one running, up to `--tensor-history` of them, from which that pass's diffusion kernels take
//! their shapes (`estimate::diffusion::shaped`: one pass's worth of them by default, or all,
//! `--history-photons`). A pass's photons depend only on the seed and its index, so a run that
//! starts past pass 0 (a resumed film, a range rendered apart) traces the passes before it
//! again and renders the same pass as one run would. Owns which passes are kept and the map
//! they make; must not shade.

use super::pass::{RenderSettings, pass_target, wanted_maps};
use super::schedule::Schedule;
use crate::estimate::diffusion::shaped::{HistoryPhotons, history_map};
use crate::photon::tracer::{MapKind, trace_map};
use crate::photon::{Photon, PhotonMap};
use crate::timing::{PhaseTimes, progress};
use crate::world::World;
use std::collections::VecDeque;
use std::time::Instant;

/// The caustic photons of the latest passes, oldest first.
pub struct TensorHistory {
    depth: u64,
    /// Which of a pass's photons are kept.
    photons: HistoryPhotons,
    passes: VecDeque<(u64, Vec<Photon>)>,
}

impl TensorHistory {
    /// A history of `depth` passes (0: none is kept; each pass shapes its own kernels),
    /// keeping `photons` of each.
    pub fn new(depth: u32, photons: HistoryPhotons) -> Self {
        Self {
            depth: u64::from(depth),
            photons,
            passes: VecDeque::new(),
        }
    }

    /// Makes sure the passes before `pass` that the history keeps are there, tracing the
    /// caustic maps of those it lacks (a run that starts past pass 0).
    pub fn fill_before(
        &mut self,
        pass: u64,
        world: &World,
        settings: &RenderSettings,
        schedule: &Schedule,
        times: &mut PhaseTimes,
    ) {
        let from = pass.saturating_sub(self.depth);
        self.passes.retain(|(p, _)| (from..pass).contains(p));
        let Some(info) =
            (wanted_maps(settings, world).into_iter()).find(|info| info.kind == MapKind::Caustic)
        else {
            return;
        };
        for earlier in from..pass {
            if self.passes.iter().any(|(p, _)| *p == earlier) {
                continue;
            }
            let target = pass_target(&info, &schedule.growth, earlier);
            let bar = progress(target, "caustic photons of an earlier pass");
            let start = Instant::now();
            let (map, counts) = trace_map(
                world,
                info.kind,
                target as usize,
                schedule.seed(earlier),
                &bar,
            );
            bar.finish_and_clear();
            times.accumulate(
                "trace tensor history",
                start.elapsed(),
                &[("emitted", counts.emitted), ("stored", counts.stored)],
            );
            if crate::interrupt::requested() {
                return;
            }
            let at = self.passes.partition_point(|(p, _)| *p < earlier);
            let kept = (self.photons).kept(earlier, self.depth, map.photons());
            self.passes.insert(at, (earlier, kept));
        }
    }

    /// Keeps pass `pass`'s caustic photons for the passes after it.
    pub fn record(&mut self, pass: u64, map: &PhotonMap) {
        if self.depth == 0 {
            return;
        }
        let kept = (self.photons).kept(pass, self.depth, map.photons());
        self.passes.push_back((pass, kept));
        while self.passes.len() as u64 > self.depth {
            self.passes.pop_front();
        }
    }

    /// The map the kernels of the next pass take their shapes from
    /// ([`history_map`]). `None` while nothing is kept.
    pub fn analysis_map(&self) -> Option<PhotonMap> {
        let kept: Vec<(u64, &[Photon])> = (self.passes.iter())
            .map(|(pass, photons)| (*pass, photons.as_slice()))
            .collect();
        history_map(&kept, self.depth, self.photons)
    }
}
