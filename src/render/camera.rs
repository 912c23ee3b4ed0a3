//! Where a pixel's samples go: the pinhole camera's primary rays, and the sample positions of
//! every (seed, pass, pixel, sample). Pixel positions come from one Owen-scrambled Sobol
//! sequence per pixel (Burley 2020, the `sobol_burley` crate), indexed by `pass · spp +
//! sample`: the passes of a progressive run keep stratifying the same pixel instead of
//! repeating its first sample, and pixels are decorrelated by their own scramble. Light
//! samples and final-gather directions come from the pixel's [`EyeSequence`] (one scrambled
//! sequence per pixel and purpose, the same index, `R` consecutive points for `R` samples at a
//! hit). Everything else a path draws comes from a PCG stream keyed by the same four numbers.
//! Owns sample placement; must not shade or accumulate.

use crate::sampling::{EyeSequence, Rng, SOBOL_BLOCK, Stream, StreamSeed, pass_seed};
use crate::scene::{Camera, Handedness};
use glam::Vec3;

/// Primary rays of a pinhole camera.
#[derive(Clone, Copy, Debug)]
pub struct PinholeCamera {
    origin: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half: f32,
    width: u32,
    height: u32,
}

impl PinholeCamera {
    pub fn new(c: &Camera) -> Self {
        let forward = (c.look_at - c.position).normalize();
        let right_handed = forward.cross(c.up).normalize();
        let up = right_handed.cross(forward);
        let right = match c.handedness {
            Handedness::Right => right_handed,
            Handedness::Left => -right_handed,
        };
        Self {
            origin: c.position,
            forward,
            right,
            up,
            tan_half: (c.fov_y_degrees.to_radians() * 0.5).tan(),
            width: c.width,
            height: c.height,
        }
    }

    /// The unit direction through image position (`x`, `y`) in pixels, (0, 0) the top-left corner.
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let aspect = self.width as f32 / self.height as f32;
        let u = (2.0 * x / self.width as f32 - 1.0) * self.tan_half * aspect;
        let v = (1.0 - 2.0 * y / self.height as f32) * self.tan_half;
        (self.forward + u * self.right + v * self.up).normalize()
    }

    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Whether `point` lies in the camera's field of view (in front of it, within the image's
    /// bounds; not whether something hides it).
    pub fn sees(&self, point: Vec3) -> bool {
        let d = point - self.origin;
        let depth = d.dot(self.forward);
        let aspect = self.width as f32 / self.height as f32;
        let u = d.dot(self.right) / (depth * self.tan_half * aspect);
        let v = d.dot(self.up) / (depth * self.tan_half);
        // A NaN depth (a point at infinity) fails every comparison.
        depth > 0.0 && u.abs() <= 1.0 && v.abs() <= 1.0
    }

    pub fn width(&self) -> usize {
        self.width as usize
    }

    pub fn height(&self) -> usize {
        self.height as usize
    }
}

/// The stratified numbers of one camera sample, and the stream for the rest of its path.
pub struct CameraSample {
    /// Position inside the pixel, each in [0, 1).
    pub jitter: (f32, f32),
    /// The path's place in the pixel's light and gather sequences.
    pub sequence: EyeSequence,
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
    /// pixel, from the pixel's own scrambled Sobol sequence (index `pass · count + j`, so
    /// passes keep stratifying it), and the stream for its glass choices.
    pub fn emission_sample(&self, pixel: u64, j: u32, count: u32) -> ((f32, f32), Rng) {
        let index = self.pass * count as u64 + j as u64;
        let scramble = StreamSeed::new(self.seed, Stream::EmissionSamples)
            .rng(pixel ^ (index / SOBOL_BLOCK).wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .next_u32();
        let [x, y, _, _] = sobol_burley::sample_4d((index % SOBOL_BLOCK) as u32, 0, scramble);
        let rng = StreamSeed::new(pass_seed(self.seed, self.pass), Stream::EmissionSamples)
            .rng(pixel * count as u64 + j as u64);
        ((x, y), rng)
    }

    /// Sample `s` (< spp) of pixel `pixel` (row-major index) in this pass.
    pub fn sample(&self, pixel: u64, s: u32) -> CameraSample {
        self.sample_of(pixel, s, self.spp)
    }

    /// Sample `s` (< `count`) of pixel `pixel` where that pixel takes `count` camera samples
    /// a pass (an edge pixel takes more than `spp`, in every pass alike).
    pub fn sample_of(&self, pixel: u64, s: u32, count: u32) -> CameraSample {
        let index = self.pass * count as u64 + s as u64;
        // The scramble depends on the seed and the pixel, not the pass: one sequence per pixel.
        let scramble = StreamSeed::new(self.seed, Stream::Pixels)
            .rng(pixel ^ (index / SOBOL_BLOCK).wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .next_u32();
        let [x, y, _, _] = sobol_burley::sample_4d((index % SOBOL_BLOCK) as u32, 0, scramble);
        CameraSample {
            jitter: (x, y),
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
