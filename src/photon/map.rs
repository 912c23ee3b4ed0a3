//! A photon map: photons in kd-tree order, plus the per-photon gradient when an estimate asks
//! for one. Owns storage and lookup; knows nothing of kernels, Embree or light transport.
//!
//! Memory: a position lives only in the kd-tree (12 bytes, one array per axis), the rest of
//! the photon beside it as [`PhotonAttributes`] (8 bytes), the tree adds its source index (4)
//! and split planes (~0.3), and the gradient, when present, is three 16-bit mantissas under a
//! shared exponent (7, [`PackedGradients`]): about 24.3 bytes per photon, 31.3 with the
//! gradient ([`PhotonMap::bytes_per_photon`]).

use super::{KdTree, Photon, PhotonAttributes};
use glam::Vec3;
use rayon::prelude::*;

#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    tree: KdTree,
    /// Power, direction and normal of the photon in each tree slot.
    attributes: Vec<PhotonAttributes>,
    /// The gradients and the gradient radius they were taken at.
    gradients: Option<(PackedGradients, f32)>,
    /// Photon paths emitted from the lights to fill this map (for reporting and scaling).
    pub emitted: u64,
}

impl PhotonMap {
    pub fn build(photons: Vec<Photon>, emitted: u64) -> Self {
        let positions: Vec<Vec3> = photons.iter().map(Photon::position).collect();
        Self::from_sources(positions, |i| photons[i].attributes(), emitted)
    }

    /// The map of the photons at `positions`, the attributes of photon `i` given by
    /// `attributes_of(i)`, asked for in the tree's order.
    pub fn from_sources(
        positions: Vec<Vec3>,
        attributes_of: impl Fn(usize) -> PhotonAttributes + Sync,
        emitted: u64,
    ) -> Self {
        let tree = KdTree::build(&positions);
        drop(positions);
        let mut attributes = Vec::new();
        (0..tree.len())
            .into_par_iter()
            .map(|s| attributes_of(tree.source_index(s) as usize))
            .collect_into_vec(&mut attributes);
        Self {
            tree,
            attributes,
            gradients: None,
            emitted,
        }
    }
    pub fn len(&self) -> usize {
        self.attributes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.attributes.is_empty()
    }
    pub fn tree(&self) -> &KdTree {
        &self.tree
    }
    /// The photon in tree slot `slot` (slot `s` of a query result).
    #[inline]
    pub fn photon(&self, slot: u32) -> Photon {
        Photon::from_parts(
            self.tree.point(slot as usize),
            self.attributes[slot as usize],
        )
    }
    /// Everything but the position of the photon in `slot`: cheaper than [`PhotonMap::photon`]
    /// when the query already knows the distance.
    #[inline]
    pub fn attributes(&self, slot: u32) -> &PhotonAttributes {
        &self.attributes[slot as usize]
    }
    #[inline]
    pub fn position(&self, slot: u32) -> Vec3 {
        self.tree.point(slot as usize)
    }
    /// Photons in tree order.
    pub fn photons(&self) -> impl ExactSizeIterator<Item = Photon> + '_ {
        (0..self.len() as u32).map(|s| self.photon(s))
    }
    /// Total stored power.
    pub fn total_power(&self) -> Vec3 {
        self.attributes.iter().map(PhotonAttributes::power).sum()
    }
    /// Stores the gradients (tree order, one per photon), packed to 7 bytes each, with the
    /// gradient radius they were taken at: a progressive render shrinks that radius from pass
    /// to pass, and an estimate must never read gradients of another radius.
    pub fn set_gradients(&mut self, gradients: &[Vec3], radius: f32) {
        assert_eq!(gradients.len(), self.len());
        self.gradients = Some((PackedGradients::pack(gradients), radius));
    }
    pub fn gradients(&self) -> Option<&PackedGradients> {
        self.gradients.as_ref().map(|(g, _)| g)
    }
    /// The gradient radius of the stored gradients.
    pub fn gradient_radius(&self) -> Option<f32> {
        self.gradients.as_ref().map(|(_, r)| *r)
    }
    /// The gradients, if they were taken at exactly `radius`.
    pub fn gradients_at(&self, radius: f32) -> Option<&PackedGradients> {
        match &self.gradients {
            Some((g, r)) if *r == radius => Some(g),
            _ => None,
        }
    }
    /// Heap bytes held per photon: the tree, the attributes and the gradients if present.
    pub fn bytes_per_photon(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let bytes = self.tree.heap_bytes()
            + self.attributes.capacity() * size_of::<PhotonAttributes>()
            + self.gradients.as_ref().map_or(0, |(g, _)| g.heap_bytes());
        bytes as f64 / self.len() as f64
    }
}

/// Gradients in 7 bytes each: three signed 16-bit mantissas under one exponent per photon
/// (like RGBE, with signs). Every component is kept within 2⁻¹⁵ of the photon's largest one
/// (about 3·10⁻⁵), and each photon has its own exponent, so maps whose powers span any range
/// keep all of their gradients; only magnitudes below 2⁻¹²⁸ (under f32's normal range) read
/// back as zero.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PackedGradients {
    packed: Vec<[u8; 7]>,
}

/// Stored exponent `e + EXPONENT_BIAS` with the largest component below `2^e`; 0 is a zero
/// gradient.
const EXPONENT_BIAS: i32 = 127;

impl PackedGradients {
    pub fn pack(gradients: &[Vec3]) -> Self {
        Self {
            packed: gradients.iter().map(|&g| pack_one(g)).collect(),
        }
    }
    #[inline]
    pub fn get(&self, slot: u32) -> Vec3 {
        unpack_one(self.packed[slot as usize])
    }
    pub fn len(&self) -> usize {
        self.packed.len()
    }
    pub fn is_empty(&self) -> bool {
        self.packed.is_empty()
    }
    pub fn iter(&self) -> impl ExactSizeIterator<Item = Vec3> + '_ {
        self.packed.iter().map(|&p| unpack_one(p))
    }
    fn heap_bytes(&self) -> usize {
        self.packed.capacity() * size_of::<[u8; 7]>()
    }
}

fn pack_one(g: Vec3) -> [u8; 7] {
    let largest = g.abs().max_element();
    if !g.is_finite() || largest == 0.0 {
        return [0; 7];
    }
    let e = (largest.log2().floor() as i32 + 1).min(128);
    if e + EXPONENT_BIAS < 1 {
        return [0; 7];
    }
    let scale = (2.0f64).powi(15 - e);
    let q = |v: f32| ((v as f64 * scale).round().clamp(-32767.0, 32767.0) as i16).to_le_bytes();
    let (x, y, z) = (q(g.x), q(g.y), q(g.z));
    [
        x[0],
        x[1],
        y[0],
        y[1],
        z[0],
        z[1],
        (e + EXPONENT_BIAS) as u8,
    ]
}

#[inline]
fn unpack_one(p: [u8; 7]) -> Vec3 {
    if p[6] == 0 {
        return Vec3::ZERO;
    }
    // 2^(e − 15) built from its bits: exact and cheaper than powi.
    let e = p[6] as i64 - EXPONENT_BIAS as i64 - 15;
    let step = f64::from_bits(((e + 1023) as u64) << 52);
    let m = |i: usize| i16::from_le_bytes([p[i], p[i + 1]]) as f64 * step;
    Vec3::new(m(0) as f32, m(2) as f32, m(4) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_gradients_keep_fifteen_bits_of_each_photons_largest_component() {
        let mut g = vec![Vec3::new(3.0e12, -1.0, 0.0), Vec3::new(-1e-37, 4e-38, 0.0)];
        for e in -30..=30 {
            let m = 10f32.powi(e);
            g.push(Vec3::new(m, -0.37 * m, 0.001 * m));
            g.push(Vec3::new(-0.999 * m, 0.5 * m, m));
        }
        let packed = PackedGradients::pack(&g);
        for (slot, want) in g.iter().enumerate() {
            let got = packed.get(slot as u32);
            let tolerance = want.abs().max_element() * 2f32.powi(-15);
            assert!(
                (got - *want).abs().max_element() <= tolerance,
                "{want} -> {got}"
            );
        }
        let extreme = [
            Vec3::splat(f32::MAX),
            Vec3::new(f32::NAN, 1.0, 1.0),
            Vec3::ZERO,
        ];
        let extreme = PackedGradients::pack(&extreme);
        assert!(extreme.get(0).is_finite() && extreme.get(0).x > 3.4e38);
        assert_eq!(extreme.get(1), Vec3::ZERO);
        assert_eq!(extreme.get(2), Vec3::ZERO);
        assert_eq!(
            PackedGradients::pack(&[Vec3::splat(1e-39)]).get(0),
            Vec3::ZERO
        );
    }

    #[test]
    fn a_map_holds_at_most_32_bytes_per_photon_with_its_gradient() {
        let photons: Vec<Photon> = (0..10_000)
            .map(|i| {
                let t = i as f32 * 0.618;
                Photon::new(
                    Vec3::new(t.fract(), (t * 0.7).fract(), 0.0),
                    Vec3::ONE,
                    -Vec3::Z,
                    Vec3::Z,
                )
            })
            .collect();
        let mut map = PhotonMap::build(photons.clone(), 10_000);
        let bare = map.bytes_per_photon();
        map.set_gradients(&vec![Vec3::X; map.len()], 1.0);
        let with = map.bytes_per_photon();
        assert!(
            bare < 25.0 && with <= 32.0 && with - bare == 7.0,
            "{bare} {with}"
        );
        let mut got: Vec<Photon> = map.photons().collect();
        let mut want = photons;
        let key = |p: &Photon| p.to_le_bytes();
        got.sort_by_key(key);
        want.sort_by_key(key);
        assert_eq!(got, want);
    }
}
