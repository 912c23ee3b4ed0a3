//! Owen-scrambled Sobol points in the first four dimensions (Burley 2020, "Practical
//! Hash-based Owen Scrambling"), exactly the numbers the `sobol_burley` crate's `sample_4d`
//! gives for dimension set 0, at about a third of its cost. Camera samples and light samples
//! draw one point each, tens of millions a render, so the crate's bit-by-bit walk over the
//! index's direction vectors was 6.5% of a metal-ring render.
//!
//! Why a table is exact: a bit-reversed Sobol value is the XOR of the direction vectors of the
//! index bits that are set (linear over GF(2)), and the crate reads only the top 16 bits of the
//! shuffled, reversed index (its sequences are 2¹⁶ long). So per dimension two tables of 256,
//! one per byte of those 16 bits, give the value with one XOR. The shuffle and the scrambles
//! are the crate's own functions. Owns those numbers; must not decide which index or seed a
//! sample uses (`sampling::EyeSequence`, `render::camera::samples`).

use sobol_burley::parts::{hash, owen_scramble_rev, sobol_rev, u32_to_f32_norm};
use std::sync::LazyLock;

/// Per dimension, the reversed Sobol value of each high byte and each low byte of the top 16
/// bits of a reversed index.
static BYTE_TABLES: LazyLock<[[[u32; 256]; 2]; 4]> = LazyLock::new(|| {
    std::array::from_fn(|dimension| {
        std::array::from_fn(|half| {
            let shift = if half == 0 { 24 } else { 16 };
            std::array::from_fn(|byte| sobol_rev((byte as u32) << shift, dimension as u32))
        })
    })
});

/// The crate's per-dimension scramble keys of dimension set 0.
const DIMENSION_KEYS: [u32; 4] = [0x912f69ba, 0x174f18ab, 0x691e72ca, 0xb40cc1b8];

/// Point `index` (< 2¹⁶) of the sequence scrambled and shuffled by `seed`, dimensions 0–3:
/// `sobol_burley::sample_4d(index, 0, seed)`.
#[inline]
pub fn sample_4d(index: u32, seed: u32) -> [f32; 4] {
    Point::new(index, seed).dimensions()
}

/// Dimensions 0 and 1 of [`sample_4d`], without the other two.
#[inline]
pub fn sample_2d(index: u32, seed: u32) -> [f32; 2] {
    Point::new(index, seed).dimensions()
}

/// A shuffled index, ready to give any of the first four dimensions.
struct Point {
    high: usize,
    low: usize,
    seed: u32,
}

impl Point {
    #[inline(always)]
    fn new(index: u32, seed: u32) -> Self {
        debug_assert!(index < 1 << 16, "a Sobol sequence here is 2^16 points long");
        let shuffled = owen_scramble_rev(index.reverse_bits(), hash(seed ^ 0x79c68e4a));
        Self {
            high: (shuffled >> 24) as usize,
            low: ((shuffled >> 16) & 0xff) as usize,
            // The crate multiplies the seed so that structured seeds do not cancel.
            seed: seed.wrapping_mul(0x9c8f2d3b),
        }
    }

    #[inline(always)]
    fn dimensions<const N: usize>(&self) -> [f32; N] {
        let tables = &*BYTE_TABLES;
        std::array::from_fn(|d| {
            let sobol = tables[d][0][self.high] ^ tables[d][1][self.low];
            let scrambled = owen_scramble_rev(sobol, hash(self.seed ^ DIMENSION_KEYS[d]));
            u32_to_f32_norm(scrambled.reverse_bits())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_point_is_the_crates_to_the_bit() {
        let mut rng = super::super::Rng::for_index(1, super::super::Stream::Distribution, 0);
        let mut next = || rng.next_u32();
        let edges = [0, 1, 2, 255, 256, 4095, 32_768, 65_534, 65_535];
        for i in 0..200_000 {
            let index = if i < edges.len() {
                edges[i]
            } else {
                next() & 0xffff
            };
            let seed = if i % 7 == 0 { i as u32 } else { next() };
            let ours = sample_4d(index, seed).map(f32::to_bits);
            let crates = sobol_burley::sample_4d(index, 0, seed).map(f32::to_bits);
            assert_eq!(ours, crates, "index {index}, seed {seed:#x}");
            assert_eq!(sample_2d(index, seed).map(f32::to_bits), [ours[0], ours[1]]);
        }
    }
}
