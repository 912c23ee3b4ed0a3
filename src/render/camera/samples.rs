//! Where a pixel's samples go: the sample positions of every (seed, pass, pixel, sample).
//! Pixel positions and lens points come from one Owen-scrambled 4-D Sobol sequence per pixel
//! (Burley 2020, the `sobol_burley` crate's numbers from `sampling::sobol`: dimensions 0–1 the
//! position in the pixel, 2–3 the lens), indexed by `pass · spp + sample`: the passes of a
//! progressive run keep stratifying the same pixel and aperture instead of repeating its first
//! sample, and pixels are decorrelated by their own scramble. A pixel is its full-film index
//! ([`super::RayCamera::pixel_key`]). Light samples and final-gather directions come from the
//! pixel's [`EyeSequence`] (one scrambled sequence per pixel and purpose, the same index, `R`
//! consecutive points for `R` samples at a hit). Everything else a path draws comes from a PCG
//! stream keyed by the same four numbers. Owns sample placement; must not shade or accumulate.

use crate::sampling::{EyeSequence, Rng, SOBOL_BLOCK, Stream, StreamSeed, pass_seed};

/// The stratified numbers of one camera sample, and the stream for the rest of its path.
pub struct CameraSample {
    /// Position inside the pixel, each in [0, 1).
    pub jitter: (f32, f32),
    /// Point on the lens, each in [0, 1) (for [`super::RayCamera::ray`]).
    pub lens: (f32, f32),
    /// The path's place in the pixel's light and gather sequences.
    pub sequence: EyeSequence,
    pub rng: Rng,
}

/// One emission sample of a pixel: where in the pixel and on the lens, and the stream for its
/// glass choices.
pub struct EmissionSample {
    pub jitter: (f32, f32),
    pub lens: (f32, f32),
    pub rng: Rng,
}

/// Samples of one pass: `spp` per pixel.
#[derive(Clone, Copy, Debug)]
pub struct PassSamples {
    seed: u64,
    pass: u64,
    spp: u32,
    /// The seed's pixel stream of this pass (the PCG part).
    stream: StreamSeed,
}

impl PassSamples {
    pub fn new(seed: u64, pass: u64, spp: u32) -> Self {
        Self {
            seed,
            pass,
            spp,
            stream: StreamSeed::new(pass_seed(seed, pass), Stream::Pixels),
        }
    }

    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// Emission sample `j` of `count` of pixel `pixel` in this pass: its position inside the
    /// pixel and its lens point, from the pixel's own scrambled Sobol sequence (index
    /// `pass · count + j`, so passes keep stratifying it), and the stream for its glass
    /// choices.
    pub fn emission_sample(&self, pixel: u64, j: u32, count: u32) -> EmissionSample {
        let index = self.pass * count as u64 + j as u64;
        let [x, y, lens_u, lens_v] = self.sobol_point(Stream::EmissionSamples, pixel, index);
        let rng = StreamSeed::new(pass_seed(self.seed, self.pass), Stream::EmissionSamples)
            .rng(pixel * count as u64 + j as u64);
        EmissionSample {
            jitter: (x, y),
            lens: (lens_u, lens_v),
            rng,
        }
    }

    /// Point `index` of pixel `pixel`'s 4-D scrambled Sobol sequence of `stream`. The scramble
    /// depends on the seed and the pixel (and the block of indices), not the pass: one sequence
    /// per pixel.
    fn sobol_point(&self, stream: Stream, pixel: u64, index: u64) -> [f32; 4] {
        let scramble = StreamSeed::new(self.seed, stream)
            .rng(pixel ^ (index / SOBOL_BLOCK).wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .next_u32();
        crate::sampling::sobol::sample_4d((index % SOBOL_BLOCK) as u32, scramble)
    }

    /// Sample `s` (< spp) of pixel `pixel` (full-film row-major index) in this pass.
    pub fn sample(&self, pixel: u64, s: u32) -> CameraSample {
        self.sample_of(pixel, s, self.spp)
    }

    /// Sample `s` (< `count`) of pixel `pixel` where that pixel takes `count` camera samples
    /// a pass (an edge pixel takes more than `spp`, in every pass alike).
    pub fn sample_of(&self, pixel: u64, s: u32, count: u32) -> CameraSample {
        let index = self.pass * count as u64 + s as u64;
        let [x, y, lens_u, lens_v] = self.sobol_point(Stream::Pixels, pixel, index);
        CameraSample {
            jitter: (x, y),
            lens: (lens_u, lens_v),
            sequence: EyeSequence::new(
                StreamSeed::new(self.seed, Stream::EyeSequences)
                    .rng(pixel)
                    .next_u64(),
                index,
            ),
            // Keyed by (pixel, sample), never by a running count: pixels take different counts.
            rng: self.stream.rng(pixel << 32 | s as u64),
        }
    }
}
