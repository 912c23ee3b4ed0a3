//! Deterministic random numbers and the sampling warps used by light transport. Every photon
//! path and every pixel sample draws from its own generator, seeded from (seed, stream, index),
//! so results never depend on the thread count. Owns numbers, not rays or scenes.

pub mod sobol;

use glam::Vec3;
use std::f32::consts::PI;

/// PCG32 (O'Neill): small, fast, and good enough for Monte Carlo.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Independent streams: photon tracing and eye rays must never share numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    CausticPhotons = 1,
    GlobalPhotons = 2,
    Pixels = 3,
    Distribution = 4,
    /// Keys of the pixels' Owen-scrambled Sobol sequences for light and gather samples.
    EyeSequences = 5,
    /// Emission samples of a pixel (`render::emission`): their Sobol scrambles and PCG streams.
    EmissionSamples = 6,
    /// Pilot caustic paths traced once per render to learn where aimed photons do most good
    /// (`photon::guide`).
    CausticPilots = 7,
}

/// The seed of pass `pass` of a progressive run. Pass 0 keeps the run's own seed, so a one-pass
/// render traces the photons a one-shot render always did; every other pass is a fresh hash of
/// (seed, pass), so pass `i` is the same whatever came before it or wherever it runs.
pub fn pass_seed(seed: u64, pass: u64) -> u64 {
    if pass == 0 {
        seed
    } else {
        splitmix64(seed ^ splitmix64(pass ^ 0x7A55_0000_0000_0000))
    }
}

/// Longest run of one Owen-scrambled Sobol sequence ([`sobol`]); longer runs take
/// a fresh scramble per block of this many.
pub const SOBOL_BLOCK: u64 = 1 << 16;

/// A hash of two numbers, for keys of scrambles.
#[inline]
pub fn mix(a: u64, b: u64) -> u64 {
    splitmix64(a ^ splitmix64(b))
}

/// One camera sample's place in its pixel's low-discrepancy sequences: the pixel's own key
/// (its scramble, so pixels are decorrelated) and the sample's index `pass · spp + sample`
/// (so passes keep stratifying where earlier passes left off).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EyeSequence {
    key: u64,
    index: u64,
}

impl EyeSequence {
    pub fn new(key: u64, index: u64) -> Self {
        Self { key, index }
    }

    /// Pair `j` of the `count` this camera sample draws for `purpose`: point
    /// `index · count + j` of the first two dimensions (a (0,2)-sequence) of the Sobol sequence
    /// scrambled and shuffled for (pixel, purpose). Each purpose has its own scramble (Burley's
    /// padding), so purposes are decorrelated from each other; the `count` pairs of one sample
    /// are consecutive points of one sequence, so they stratify among themselves (an aligned
    /// block of a power-of-two `count` is a (0,m,2)-net) and with those of the other samples
    /// and passes.
    pub fn pair(&self, purpose: u64, count: u32, j: u32) -> (f32, f32) {
        debug_assert!(j < count);
        let i = self.index * count as u64 + j as u64;
        let seed = mix(self.key ^ purpose, i / SOBOL_BLOCK) as u32;
        let [u, v] = sobol::sample_2d((i % SOBOL_BLOCK) as u32, seed);
        (u, v)
    }
}

/// The numbers of one camera path: its own PCG stream, and, for light samples and
/// final-gather directions, the pixel's stratified sequences (see `render::camera`). Every
/// diffuse hit of the path (reflected and refracted branches through glass each reach one) has
/// its own purposes, so the hits' samples are decorrelated too.
#[derive(Clone, Debug)]
pub struct PathSampler {
    pub rng: Rng,
    sequence: Option<EyeSequence>,
    diffuse_hits: u32,
}

/// Purpose keys of [`EyeSequence::pair`]: the kind in the low byte, the light above it, the
/// diffuse hit in the high half.
const PURPOSE_LIGHT: u64 = 1;
const PURPOSE_GATHER: u64 = 2;

impl PathSampler {
    /// A path drawing from `rng`, with stratified pairs from `sequence` (`None`: everything
    /// from `rng`).
    pub fn new(rng: Rng, sequence: Option<EyeSequence>) -> Self {
        Self {
            rng,
            sequence,
            diffuse_hits: 0,
        }
    }

    /// Starts a new diffuse hit of the path; its samples are drawn with the number returned.
    pub fn next_diffuse_hit(&mut self) -> u32 {
        let hit = self.diffuse_hits;
        self.diffuse_hits += 1;
        hit
    }

    fn pair(&mut self, purpose: u64, count: u32, j: u32) -> (f32, f32) {
        match &self.sequence {
            Some(s) => s.pair(splitmix64(purpose), count, j),
            None => self.rng.next_2d(),
        }
    }

    /// Sample `j` of the `count` a diffuse hit `hit` takes of light `light`.
    pub fn light_2d(&mut self, hit: u32, light: usize, j: u32, count: u32) -> (f32, f32) {
        let purpose = PURPOSE_LIGHT | (light as u64 & 0xFF_FFFF) << 8 | (hit as u64) << 32;
        self.pair(purpose, count, j)
    }

    /// Direction numbers of gather ray `j` of `rays` at diffuse hit `hit`.
    pub fn gather_2d(&mut self, hit: u32, j: u32, rays: u32) -> (f32, f32) {
        self.pair(PURPOSE_GATHER | (hit as u64) << 32, rays, j)
    }
}

/// The generators of one stream under one seed, with the per-stream hashing done once: photon
/// tracing seeds a generator per path, millions of times.
#[derive(Clone, Copy, Debug)]
pub struct StreamSeed {
    hashed: u64,
}

impl StreamSeed {
    pub fn new(seed: u64, stream: Stream) -> Self {
        Self {
            hashed: splitmix64(seed ^ splitmix64(stream as u64)),
        }
    }

    /// The same generator as `Rng::for_index(seed, stream, index)`.
    pub fn rng(&self, index: u64) -> Rng {
        Rng::from_hashed(self.hashed, index)
    }
}

impl Rng {
    /// The generator for item `index` of `stream` under `seed`.
    pub fn for_index(seed: u64, stream: Stream, index: u64) -> Self {
        StreamSeed::new(seed, stream).rng(index)
    }

    fn from_hashed(a: u64, index: u64) -> Self {
        let b = splitmix64(a ^ index.wrapping_mul(0xD6E8_FEB8_6659_FD93));
        let mut rng = Self {
            state: 0,
            inc: (splitmix64(b) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(b);
        rng.next_u32();
        rng
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    pub fn next_u64(&mut self) -> u64 {
        (self.next_u32() as u64) << 32 | self.next_u32() as u64
    }

    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    pub fn next_2d(&mut self) -> (f32, f32) {
        (self.next_f32(), self.next_f32())
    }
}

/// An orthonormal basis (t, b, n) around a unit normal (Duff et al. 2017).
#[inline(always)]
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A shading frame: the basis [`basis`] gives around a unit normal, which becomes local z.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Frame {
    pub fn new(n: Vec3) -> Self {
        let (t, b) = basis(n);
        Self { t, b, n }
    }

    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.t + v.y * self.b + v.z * self.n
    }
}

/// `(sin 2πt, cos 2πt)` for `t ≥ 0` (the warps pass `t` in [0, 1)), within 2e-7 of the exact
/// values: a quarter-turn reduction and two short Taylor polynomials on [−π/4, π/4], without
/// the library call that cost photon tracing several percent.
#[inline]
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    debug_assert!(t >= 0.0, "sin_cos_turns takes t >= 0, got {t}");
    let quarters = t * 4.0;
    // Truncation rounds to nearest for non-negative values: k is the nearest quarter turn.
    let k = (quarters + 0.5) as u32;
    let x = (quarters - k as f32) * std::f32::consts::FRAC_PI_2;
    let x2 = x * x;
    // Next terms: x¹¹/11! and x¹²/12!, below 2e-9 on [−π/4, π/4]. Every coefficient is a
    // constant multiplied, none a divisor: `x2 / 9!` was a division at the head of the chain.
    // (The same bits as dividing for all 2²⁴ values `Rng::next_f32` gives, checked.)
    let sin = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let cos = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 - x2 * (1.0 / 3_628_800.0)))));
    // Turned by k quarter turns: (sin, cos), (cos, −sin), (−sin, −cos), (−cos, sin). Chosen
    // by bit masks, not a branch: k is random, and a mispredicted branch per sample stalls the
    // tracer more than the polynomials cost.
    let swap = 0u32.wrapping_sub(k & 1);
    let (s, c) = (sin.to_bits(), cos.to_bits());
    let turned_sin = (s & !swap) | (c & swap);
    let turned_cos = (c & !swap) | (s & swap);
    let sin_sign = (k & 2) << 30;
    let cos_sign = ((k + 1) & 2) << 30;
    (
        f32::from_bits(turned_sin ^ sin_sign),
        f32::from_bits(turned_cos ^ cos_sign),
    )
}

/// Uniform direction on the unit sphere.
#[inline(always)]
pub fn uniform_sphere(u: (f32, f32)) -> Vec3 {
    let z = 1.0 - 2.0 * u.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin, cos) = sin_cos_turns(u.1);
    Vec3::new(r * cos, r * sin, z)
}

/// Uniform point in the unit disc (pdf 1/π).
#[inline(always)]
pub fn uniform_disc(u: (f32, f32)) -> (f32, f32) {
    let r = u.0.sqrt();
    let (sin, cos) = sin_cos_turns(u.1);
    (r * cos, r * sin)
}

/// Cosine-weighted direction around the unit normal `n` (pdf cosθ/π).
#[inline(always)]
pub fn cosine_hemisphere(n: Vec3, u: (f32, f32)) -> Vec3 {
    cosine_hemisphere_in(basis(n), n, u)
}

/// [`cosine_hemisphere`] with the tangents `(t, b)` of `n` from [`basis`] already worked out
/// (a quad light's normal is the same for every photon).
#[inline(always)]
pub fn cosine_hemisphere_in((t, b): (Vec3, Vec3), n: Vec3, u: (f32, f32)) -> Vec3 {
    let r = u.0.sqrt();
    let (sin, cos) = sin_cos_turns(u.1);
    let z = (1.0 - u.0).max(0.0).sqrt();
    // Unit to within a few ulps without normalising: r² + z² = 1 in an orthonormal frame.
    t * (r * cos) + b * (r * sin) + n * z
}

/// Uniform direction in the cone around unit `axis` with half-angle cosine `cos_max`
/// (pdf 1 / (2π (1 − cos_max))).
#[inline(always)]
pub fn uniform_cone(axis: Vec3, cos_max: f32, u: (f32, f32)) -> Vec3 {
    ConeFrame::new(axis, cos_max).sample(u)
}

/// A cone of directions around a unit axis with its frame built once, for drawing many
/// directions from one cone (a light aimed at a fixed target draws millions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeFrame {
    t: Vec3,
    b: Vec3,
    axis: Vec3,
    cos_max: f32,
}

impl ConeFrame {
    #[inline(always)]
    pub fn new(axis: Vec3, cos_max: f32) -> Self {
        let (t, b) = basis(axis);
        Self {
            t,
            b,
            axis,
            cos_max,
        }
    }

    /// Uniform direction in the cone: the same as [`uniform_cone`] on the same numbers. Unit
    /// length to within a few ulps without normalising: the frame is orthonormal and
    /// sin² + cos² = 1 (the square root and division that normalising costs showed in tracing).
    #[inline(always)]
    pub fn sample(&self, u: (f32, f32)) -> Vec3 {
        let cos_t = 1.0 - u.0 * (1.0 - self.cos_max);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let (sin, cos) = sin_cos_turns(u.1);
        self.t * (sin_t * cos) + self.b * (sin_t * sin) + self.axis * cos_t
    }

    /// The numbers [`ConeFrame::sample`] turns into `direction`, a unit vector in the cone:
    /// its inverse, up to rounding (clamped into [0, 1)² for directions on the rim).
    #[inline(always)]
    pub fn coordinates(&self, direction: Vec3) -> (f32, f32) {
        let (x, y) = self.tangent(direction);
        let turns = y.atan2(x) * (0.5 / PI);
        let u1 = if turns < 0.0 { turns + 1.0 } else { turns };
        let below_one = 1.0 - f32::EPSILON / 2.0;
        (self.first_coordinate(x, y), u1.clamp(0.0, below_one))
    }

    /// `direction` in the frame's tangent plane: (d·t, d·b), at the angle of the turn
    /// [`ConeFrame::sample`] took, of length sin θ.
    #[inline(always)]
    pub fn tangent(&self, direction: Vec3) -> (f32, f32) {
        (direction.dot(self.t), direction.dot(self.b))
    }

    /// The first number [`ConeFrame::sample`] took for a direction whose [`ConeFrame::tangent`]
    /// is (`x`, `y`): its 1 − cos θ over the cone's, in [0, 1).
    #[inline(always)]
    pub fn first_coordinate(&self, x: f32, y: f32) -> f32 {
        let height = 1.0 - self.cos_max;
        // 1 − cos θ from sin² θ: accurate in a cone a hair wide, where 1 − d·axis is rounding.
        let sin2 = x * x + y * y;
        let versine = sin2 / (1.0 + (1.0 - sin2).max(0.0).sqrt());
        let u0 = if height > 0.0 { versine / height } else { 0.0 };
        u0.clamp(0.0, 1.0 - f32::EPSILON / 2.0)
    }

    pub fn axis(&self) -> Vec3 {
        self.axis
    }

    pub fn cos_max(&self) -> f32 {
        self.cos_max
    }

    pub fn solid_angle(&self) -> f32 {
        cone_solid_angle(self.cos_max)
    }
}

/// Solid angle of a cone of half-angle cosine `cos_max`.
#[inline(always)]
pub fn cone_solid_angle(cos_max: f32) -> f32 {
    2.0 * PI * (1.0 - cos_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `coordinates` undoes `sample` for cones from a hair's width to a hemisphere: the numbers
    /// come back, and where the cone is so narrow that `sample` itself rounds them (cos θ within
    /// an ulp of 1), they give back the same direction.
    #[test]
    fn cone_coordinates_invert_the_cone_sample() {
        let mut rng = Rng::for_index(3, Stream::Distribution, 0);
        for &cos_max in &[0.999_99f32, 0.99, 0.5, 0.0] {
            let axis = uniform_sphere(rng.next_2d());
            let frame = ConeFrame::new(axis, cos_max);
            let half_angle = cos_max.acos();
            for _ in 0..2000 {
                let u = rng.next_2d();
                let d = frame.sample(u);
                let back = frame.coordinates(d);
                let again = frame.sample(back);
                // The chord, not acos of a dot product a rounding away from 1.
                let apart = (d - again).length();
                assert!(
                    apart < 2e-3 * half_angle + 1e-6,
                    "{cos_max}: {u:?} came back as {back:?}, {apart} rad away"
                );
                if cos_max <= 0.99 {
                    // Turns wrap: 0.999.. and 0.0 are neighbours; at the apex they mean nothing.
                    let turn = (back.1 - u.1).abs().min(1.0 - (back.1 - u.1).abs());
                    assert!((back.0 - u.0).abs() < 1e-4, "{cos_max}: {u:?} -> {back:?}");
                    assert!(turn < 1e-3 || u.0 < 1e-3, "{cos_max}: {u:?} -> {back:?}");
                }
            }
        }
    }

    #[test]
    fn pass_zero_keeps_the_seed_and_other_passes_differ() {
        assert_eq!(pass_seed(7, 0), 7);
        let seeds: std::collections::HashSet<u64> = (0..1000).map(|p| pass_seed(7, p)).collect();
        assert_eq!(seeds.len(), 1000);
        assert_ne!(pass_seed(7, 1), pass_seed(8, 1));
    }

    #[test]
    fn streams_and_indices_are_independent_and_repeatable() {
        let a: Vec<u32> = (0..4)
            .map(|i| Rng::for_index(7, Stream::Pixels, i).next_u32())
            .collect();
        let b: Vec<u32> = (0..4)
            .map(|i| Rng::for_index(7, Stream::Pixels, i).next_u32())
            .collect();
        assert_eq!(a, b);
        let c = Rng::for_index(7, Stream::CausticPhotons, 0).next_u32();
        assert_ne!(a[0], c);
        assert_ne!(a[0], a[1]);
        assert_ne!(Rng::for_index(8, Stream::Pixels, 0).next_u32(), a[0]);
        let seeded = StreamSeed::new(7, Stream::Pixels);
        assert_eq!(seeded.rng(3).next_u32(), a[3]);
    }

    #[test]
    fn sin_cos_turns_matches_the_library_everywhere_in_a_turn() {
        let n = 1 << 20;
        let mut worst = 0.0f64;
        // Every 2^-20 of a turn, the quarter-turn boundaries included, then the top of [0, 1).
        let ts = (0..n).map(|i| i as f32 / n as f32).chain([
            1.0 - f32::EPSILON / 2.0,
            0.125,
            0.375,
            0.625,
            0.875,
        ]);
        for t in ts {
            let (s, c) = sin_cos_turns(t);
            let phi = 2.0 * std::f64::consts::PI * t as f64;
            worst = worst
                .max((s as f64 - phi.sin()).abs())
                .max((c as f64 - phi.cos()).abs());
        }
        assert!(worst < 2e-7, "worst error {worst:e}");
        assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_turns(0.25), (1.0, 0.0));
        assert_eq!(sin_cos_turns(0.5), (0.0, -1.0));
    }

    #[test]
    fn uniform_floats_have_the_right_mean_and_range() {
        let mut rng = Rng::for_index(1, Stream::Pixels, 0);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = rng.next_f32();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.005);
    }

    #[test]
    fn basis_is_orthonormal_for_any_normal() {
        let mut rng = Rng::for_index(3, Stream::Pixels, 0);
        for i in 0..1000 {
            let n = if i == 0 {
                -Vec3::Z
            } else {
                uniform_sphere(rng.next_2d())
            };
            let (t, b) = basis(n);
            assert!((t.length() - 1.0).abs() < 1e-4 && (b.length() - 1.0).abs() < 1e-4);
            assert!(t.dot(b).abs() < 1e-4 && t.dot(n).abs() < 1e-4 && b.dot(n).abs() < 1e-4);
        }
    }

    #[test]
    fn cosine_hemisphere_has_mean_cosine_two_thirds() {
        let mut rng = Rng::for_index(4, Stream::Pixels, 0);
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let m = 200_000;
        let mean: f64 = (0..m)
            .map(|_| {
                let d = cosine_hemisphere(n, rng.next_2d());
                assert!((d.length() - 1.0).abs() < 1e-6, "{d} is not unit");
                d.dot(n) as f64
            })
            .sum::<f64>()
            / m as f64;
        assert!((mean - 2.0 / 3.0).abs() < 0.003, "{mean}");
    }

    /// The variance, over 2000 pixels, of the estimate of `∫ cos²θ · cosθ/π dω = 1/2` from
    /// `rays` cosine-distributed directions each (one hit with `rays` gather rays, or `rays`
    /// passes of one ray with the index continuing), from the pixels' stratified sequences
    /// and from independent numbers.
    fn gather_variance(rays: u32, across_passes: bool, stratified: bool) -> f64 {
        let n = Vec3::new(0.2, 0.3, 0.9).normalize();
        let pixels = 2000u64;
        let seeds = StreamSeed::new(9, Stream::EyeSequences);
        let estimates: Vec<f64> = (0..pixels)
            .map(|pixel| {
                let key = seeds.rng(pixel).next_u64();
                let mut rng = Rng::for_index(9, Stream::Pixels, pixel);
                let mut sum = 0.0;
                for r in 0..rays {
                    let u = if stratified {
                        // One hit's rays, or pass r's only ray (the index continues).
                        let (index, count, j) = if across_passes {
                            (r as u64, 1, 0)
                        } else {
                            (0, rays, r)
                        };
                        let sequence = EyeSequence::new(key, index);
                        let mut sampler = PathSampler::new(rng.clone(), Some(sequence));
                        let hit = sampler.next_diffuse_hit();
                        sampler.gather_2d(hit, j, count)
                    } else {
                        rng.next_2d()
                    };
                    let d = cosine_hemisphere(n, u);
                    sum += (d.dot(n) as f64).powi(2);
                }
                sum / rays as f64
            })
            .collect();
        let mean = estimates.iter().sum::<f64>() / pixels as f64;
        assert!((mean - 0.5).abs() < 0.02, "mean {mean}");
        estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (pixels - 1) as f64
    }

    #[test]
    fn gather_directions_stratify_within_a_hit_and_across_passes() {
        for across_passes in [false, true] {
            let random = gather_variance(16, across_passes, false);
            let stratified = gather_variance(16, across_passes, true);
            // Independent: Var(cos²θ)/16 = (1/3 − 1/4)/16 ≈ 0.0052. A (0,4,2)-net of 16 points
            // brings it down by far more than 4×; independent scrambles would not.
            assert!(
                stratified < random / 8.0,
                "across passes {across_passes}: stratified {stratified:e}, random {random:e}"
            );
        }
    }

    #[test]
    fn purposes_hits_lights_and_pixels_draw_different_numbers() {
        let s = EyeSequence::new(5, 3);
        let mut a = PathSampler::new(Rng::for_index(1, Stream::Pixels, 0), Some(s));
        let draws = [
            a.gather_2d(0, 0, 1),
            a.gather_2d(1, 0, 1),
            a.light_2d(0, 0, 0, 1),
            a.light_2d(0, 1, 0, 1),
            a.light_2d(1, 0, 0, 1),
            PathSampler::new(a.rng.clone(), Some(EyeSequence::new(6, 3))).gather_2d(0, 0, 1),
        ];
        for (i, x) in draws.iter().enumerate() {
            for y in &draws[i + 1..] {
                assert_ne!(x, y);
            }
        }
        // The same numbers again from the same sample: nothing depends on the order drawn.
        let mut b = PathSampler::new(Rng::for_index(1, Stream::Pixels, 0), Some(s));
        assert_eq!(b.light_2d(0, 1, 0, 1), draws[3]);
    }

    #[test]
    fn cone_samples_stay_inside_the_cone() {
        let mut rng = Rng::for_index(5, Stream::Pixels, 0);
        let axis = Vec3::new(1.0, 2.0, -0.5).normalize();
        for cos_max in [0.9, 0.0, -0.7, 1.0 - 1e-6] {
            for _ in 0..10_000 {
                let d = uniform_cone(axis, cos_max, rng.next_2d());
                assert!(d.dot(axis) >= cos_max - 1e-5);
                assert!((d.length() - 1.0).abs() < 1e-6, "{d} is not unit");
            }
        }
        assert!((cone_solid_angle(-1.0) - 4.0 * PI).abs() < 1e-5);
    }
}
