//! A photon map: photons in kd-tree order, plus the per-photon gradient field when an estimate
//! asks for one. Owns storage and lookup; knows nothing of kernels, Embree or light transport.
//!
//! Memory: a position lives only in the kd-tree (12 bytes, one array per axis), the rest of
//! the photon beside it as [`PhotonAttributes`] (8 bytes), the tree adds its source index (4)
//! and split planes (~0.3): about 24.3 bytes per photon. The [`GradientField`], while a
//! diffusion estimate reads the map, adds 16 per photon (the decoded power and the channel
//! sum as f32 arrays in slot order, which the estimate's leaf scans stream through), 32 per
//! gradient site (every photon, except where sites are thinned) and 256 per leaf of 10–20
//! photons (its box, channel-sum and RGB power moments, shared normal): at most about 90 in all
//! ([`PhotonMap::bytes_per_photon`]), freed with the pass's map.

use super::{KdTree, Photon, PhotonAttributes};
use glam::Vec3;
use rayon::prelude::*;

#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    tree: KdTree,
    /// Power, direction and normal of the photon in each tree slot.
    attributes: Vec<PhotonAttributes>,
    /// The gradients, with the radii they were taken for.
    gradients: Option<GradientField>,
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
    /// Stores gradients taken at every photon (tree order, one per photon) with the gradient
    /// radius they were taken at: every photon is a site of weight 1.
    pub fn set_gradients(&mut self, gradients: &[Vec3], radius: f32) {
        let field = GradientField::new(self, gradients, vec![1.0; self.len()], radius, None);
        self.gradients = Some(field);
    }
    /// Stores a gradient field (see [`GradientField::new`]).
    pub fn set_gradient_field(&mut self, field: GradientField) {
        assert_eq!(field.len(), self.len());
        self.gradients = Some(field);
    }
    pub fn gradients(&self) -> Option<&GradientField> {
        self.gradients.as_ref()
    }
    /// The gradient radius of the stored gradients.
    pub fn gradient_radius(&self) -> Option<f32> {
        self.gradients.as_ref().map(|g| g.radius)
    }
    /// The gradients, if they were taken at exactly `radius` and their sites suit `thinning`
    /// = (smoothing radius, sites per disc): thinned for exactly that, or not thinned at all
    /// (which suits every thinning; `None` asks for that). A progressive render shrinks the
    /// radii from pass to pass, and an estimate must never read a field made for others.
    pub fn gradients_at(
        &self,
        radius: f32,
        thinning: Option<(f32, f64)>,
    ) -> Option<&GradientField> {
        match &self.gradients {
            Some(g)
                if g.with_gradients
                    && g.radius == radius
                    && (g.thinned_for.is_none() || g.thinned_for == thinning) =>
            {
                Some(g)
            }
            _ => None,
        }
    }
    /// The field's powers, leaf normals and leaf moments, with or without gradients (they do
    /// not depend on a radius): what a kernel shaped elsewhere sums.
    pub fn leaf_sums(&self) -> Option<&GradientField> {
        self.gradients.as_ref()
    }
    /// Heap bytes held per photon: the tree, the attributes and the gradients if present.
    pub fn bytes_per_photon(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let bytes = self.tree.heap_bytes()
            + self.attributes.capacity() * size_of::<PhotonAttributes>()
            + self.gradients.as_ref().map_or(0, GradientField::heap_bytes);
        bytes as f64 / self.len() as f64
    }
}

/// The gradient pass's result in the form the diffusion estimate scans. Per slot, the
/// photon's power, decoded, one f32 array per channel, so a leaf's run of slots is a straight
/// loop. The sites (photons with a gradient; see `estimate::diffusion::sites`) apart, in slot
/// order, each leaf's a contiguous run: position, gradient and weight (the photons a site
/// stands for), so the structure tensor's scan touches sites only. Per leaf, the normal all
/// of its photons share, if they share one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GradientField {
    radius: f32,
    /// The (smoothing radius, sites per disc) the sites were thinned for; `None`: every
    /// photon is a site.
    thinned_for: Option<(f32, f64)>,
    power: [Vec<f32>; 3],
    /// Sites: position, gradient, weight, each one array per component.
    site_position: [Vec<f32>; 3],
    site_gradient: [Vec<f32>; 3],
    site_weight: Vec<f32>,
    /// Each photon's channel sum (three times its scalar power) over `power_scale`, in slot
    /// order.
    channel_sum: Vec<f32>,
    power_scale: f64,
    /// The site gradients are stored over this.
    gradient_scale: f64,
    site_slot: Vec<u32>,
    /// The sites of leaf `j` are `leaf_sites[j]..leaf_sites[j + 1]`.
    leaf_sites: Vec<u32>,
    leaf_normals: Vec<Option<Vec3>>,
    /// Per leaf, the moments of its channel sums about its box's centre.
    leaf_moments: Vec<LeafMoments>,
    photons: usize,
    /// Whether the sites' gradients were taken: a field without them holds only what a
    /// kernel sums (powers, leaf normals and moments), for a map that another map shapes.
    with_gradients: bool,
}

/// The normal every photon of each leaf shares (leaves in order from the first), if they
/// share one: a scan of a one-surface leaf tests the normal once.
pub fn leaf_normals(map: &PhotonMap) -> Vec<Option<Vec3>> {
    let tree = map.tree();
    (tree.leaf_base()..tree.node_end())
        .into_par_iter()
        .with_min_len(256)
        .map(|leaf| {
            let mut codes = tree
                .node_slots(leaf)
                .map(|s| map.attributes(s as u32).normal_code());
            let first = codes.next()?;
            codes
                .all(|c| c == first)
                .then(|| super::record::decode_octahedral(first.to_be_bytes()))
        })
        .collect()
}

/// A leaf's tight box and the moments of its photons' channel sums `φ` (in the field's scaled
/// units) about the box's centre `c`, with `u = x − c`: enough to add the Epanechnikov sums
/// `Σ (1 − d²/r²) φ` and `Σ (1 − d²/r²) φ²` of a leaf that lies wholly inside a disc at once,
/// since `d² = |u|² + 2 u·(c − q) + |c − q|²`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LeafMoments {
    pub lower: Vec3,
    pub upper: Vec3,
    pub centre: Vec3,
    pub count: u32,
    /// `Σ φ`, `Σ φ u`, `Σ φ |u|²`.
    pub phi: (f64, glam::DVec3, f64),
    /// `Σ φ²`, `Σ φ² u`, `Σ φ² |u|²`.
    pub phi2: (f64, glam::DVec3, f64),
    /// The RGB powers' moments, for the anisotropic kernel.
    pub power: PowerMoments,
}

/// A leaf's RGB photon powers (the field's power columns) about its box's centre, `u = x − c`:
/// `Σ Φ`, `Σ Φ u_j` and `Σ Φ u_i u_j`. Enough to add `Σ (1 − dᵀMd) Φ` for any quadratic form
/// `M` (the diffusion kernel's ellipsoid) over a leaf that lies wholly inside it, at once.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PowerMoments {
    pub sum: Vec3,
    /// `Σ Φ u_x`, `Σ Φ u_y`, `Σ Φ u_z`.
    pub first: [Vec3; 3],
    /// `Σ Φ u_i u_j` for (i, j) = xx, xy, xz, yy, yz, zz.
    pub second: [Vec3; 6],
}

/// A leaf's sites for a scan: position, gradient and weight columns.
pub struct SiteColumns<'a> {
    pub position: [&'a [f32]; 3],
    pub gradient: [&'a [f32]; 3],
    pub weight: &'a [f32],
}

/// The power of two at or above `largest` (1 for zero or non-finite), so that values over it
/// are at most 1 and their squares and products stay in f32's range.
fn scale_for(largest: f32) -> f64 {
    if largest > 0.0 && largest.is_finite() {
        2f64.powi((largest as f64).log2().ceil() as i32)
    } else {
        1.0
    }
}

impl GradientField {
    /// The field of `map` without gradients: its powers, leaf normals and leaf moments only
    /// ([`PhotonMap::leaf_sums`]).
    pub fn leaf_sums_of(map: &PhotonMap) -> Self {
        let n = map.len();
        let mut field = Self::new(map, &vec![Vec3::ZERO; n], vec![0.0; n], f32::NAN, None);
        field.with_gradients = false;
        field
    }

    /// The field of `map` with `gradients` and site `weights` (slot order; a site is a photon
    /// of positive weight, and its gradient is kept), taken at gradient radius `radius` on
    /// sites thinned for `thinned_for` = (smoothing radius, sites per disc) (`None`: all
    /// photons, weight 1).
    pub fn new(
        map: &PhotonMap,
        gradients: &[Vec3],
        weights: Vec<f32>,
        radius: f32,
        thinned_for: Option<(f32, f64)>,
    ) -> Self {
        assert_eq!(gradients.len(), map.len());
        assert_eq!(weights.len(), map.len());
        let tree = map.tree();
        let channel = |c: usize| -> Vec<f32> {
            (0..map.len())
                .into_par_iter()
                .with_min_len(4096)
                .map(|s| map.attributes(s as u32).power()[c])
                .collect()
        };
        let mut field = Self {
            radius,
            thinned_for,
            power: [channel(0), channel(1), channel(2)],
            photons: map.len(),
            with_gradients: true,
            ..Self::default()
        };
        // Scales (powers of two, so exact) that keep the f32 scans' squares of powers and
        // gradients inside f32's range whatever the light's power or the scene's size.
        let sites = weights.iter().filter(|&&w| w > 0.0).count();
        let phi3 = |s: usize| {
            let p = map.attributes(s as u32).power();
            p.x + p.y + p.z
        };
        let largest = |f: &dyn Fn(usize) -> f32| {
            (0..map.len())
                .filter(|&s| weights[s] > 0.0)
                .map(f)
                .filter(|v| v.is_finite())
                .fold(0.0f32, f32::max)
        };
        field.power_scale = scale_for(
            (0..map.len())
                .map(phi3)
                .filter(|v| v.is_finite())
                .fold(0.0f32, f32::max),
        );
        field.gradient_scale = scale_for(largest(&|s| gradients[s].abs().max_element()));
        let (ps, gs) = (
            (1.0 / field.power_scale) as f32,
            (1.0 / field.gradient_scale) as f32,
        );
        for c in 0..3 {
            field.site_position[c].reserve_exact(sites);
            field.site_gradient[c].reserve_exact(sites);
        }
        field.site_weight.reserve_exact(sites);
        field.channel_sum = (0..map.len()).map(|s| phi3(s) * ps).collect();
        field.site_slot.reserve_exact(sites);
        field
            .leaf_sites
            .reserve_exact(tree.node_end() - tree.leaf_base() + 1);
        field.leaf_sites.push(0);
        for leaf in tree.leaf_base()..tree.node_end() {
            for s in tree.node_slots(leaf) {
                if weights[s] > 0.0 {
                    let (p, g) = (tree.point(s), gradients[s] * gs);
                    for c in 0..3 {
                        field.site_position[c].push(p[c]);
                        field.site_gradient[c].push(g[c]);
                    }
                    field.site_weight.push(weights[s]);
                    field.site_slot.push(s as u32);
                }
            }
            field.leaf_sites.push(field.site_slot.len() as u32);
        }
        let channel = &field.channel_sum;
        let power = &field.power;
        let field_power = |s: usize| Vec3::new(power[0][s], power[1][s], power[2][s]);
        field.leaf_moments = (tree.leaf_base()..tree.node_end())
            .into_par_iter()
            .with_min_len(256)
            .map(|leaf| {
                let slots = tree.node_slots(leaf);
                let (mut lower, mut upper) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
                for s in slots.clone() {
                    lower = lower.min(tree.point(s));
                    upper = upper.max(tree.point(s));
                }
                let centre = (lower + upper) * 0.5;
                let mut m = LeafMoments {
                    lower,
                    upper,
                    centre,
                    count: slots.len() as u32,
                    ..LeafMoments::default()
                };
                let (mut sum, mut first, mut second) = (
                    glam::DVec3::ZERO,
                    [glam::DVec3::ZERO; 3],
                    [glam::DVec3::ZERO; 6],
                );
                for s in slots {
                    let u = (tree.point(s) - centre).as_dvec3();
                    let (p, u2) = (channel[s] as f64, u.length_squared());
                    m.phi.0 += p;
                    m.phi.1 += u * p;
                    m.phi.2 += u2 * p;
                    m.phi2.0 += p * p;
                    m.phi2.1 += u * (p * p);
                    m.phi2.2 += u2 * p * p;
                    let rgb = field_power(s).as_dvec3();
                    sum += rgb;
                    for (f, uj) in first.iter_mut().zip(u.to_array()) {
                        *f += rgb * uj;
                    }
                    let pairs = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
                    for (acc, (i, j)) in second.iter_mut().zip(pairs) {
                        *acc += rgb * (u[i] * u[j]);
                    }
                }
                m.power = PowerMoments {
                    sum: sum.as_vec3(),
                    first: first.map(|v| v.as_vec3()),
                    second: second.map(|v| v.as_vec3()),
                };
                m
            })
            .collect();
        field.leaf_normals = leaf_normals(map);
        field
    }
    pub fn len(&self) -> usize {
        self.photons
    }
    pub fn is_empty(&self) -> bool {
        self.photons == 0
    }
    /// The gradient radius.
    pub fn radius(&self) -> f32 {
        self.radius
    }
    /// What [`GradientField::channel_sums`] are to be multiplied by.
    pub fn power_scale(&self) -> f64 {
        self.power_scale
    }
    /// What the site columns' gradients are to be multiplied by.
    pub fn gradient_scale(&self) -> f64 {
        self.gradient_scale
    }
    /// Photons with a gradient.
    pub fn sites(&self) -> usize {
        self.site_slot.len()
    }
    /// The gradient of every photon in slot order, zero where there is no site.
    pub fn gradients(&self) -> Vec<Vec3> {
        let mut all = vec![Vec3::ZERO; self.photons];
        for (i, &s) in self.site_slot.iter().enumerate() {
            all[s as usize] = self.site(i).1.as_vec3();
        }
        all
    }
    /// The site weight of every photon in slot order (0 where there is no site).
    pub fn weights(&self) -> Vec<f32> {
        let mut all = vec![0.0; self.photons];
        for (i, &s) in self.site_slot.iter().enumerate() {
            all[s as usize] = self.site_weight[i];
        }
        all
    }
    /// Site `i`: (position, gradient, weight), the gradient at its true scale.
    #[inline]
    pub fn site(&self, i: usize) -> (Vec3, glam::DVec3, f32) {
        let [px, py, pz] = &self.site_position;
        let [gx, gy, gz] = &self.site_gradient;
        (
            Vec3::new(px[i], py[i], pz[i]),
            glam::DVec3::new(gx[i] as f64, gy[i] as f64, gz[i] as f64) * self.gradient_scale,
            self.site_weight[i],
        )
    }
    /// The slot of site `i`.
    #[inline]
    pub fn site_slot(&self, i: usize) -> u32 {
        self.site_slot[i]
    }
    /// The sites of leaf `leaf` (counted from the first leaf), as indices for [`Self::site`].
    #[inline]
    pub fn leaf_site_range(&self, leaf: usize) -> std::ops::Range<usize> {
        self.leaf_sites[leaf] as usize..self.leaf_sites[leaf + 1] as usize
    }
    /// All sites' columns (index them with [`Self::leaf_site_range`]).
    #[inline]
    pub fn site_columns(&self) -> SiteColumns<'_> {
        let [px, py, pz] = &self.site_position;
        let [gx, gy, gz] = &self.site_gradient;
        SiteColumns {
            position: [px, py, pz],
            gradient: [gx, gy, gz],
            weight: &self.site_weight,
        }
    }
    /// Each photon's channel sum over [`GradientField::power_scale`], in slot order.
    #[inline]
    pub fn channel_sums(&self) -> &[f32] {
        &self.channel_sum
    }
    /// The power columns (r, g, b) in slot order.
    #[inline]
    pub fn power_columns(&self) -> [&[f32]; 3] {
        [&self.power[0], &self.power[1], &self.power[2]]
    }
    /// The decoded power of the photon in `slot`.
    #[inline]
    pub fn power(&self, slot: u32) -> Vec3 {
        let s = slot as usize;
        Vec3::new(self.power[0][s], self.power[1][s], self.power[2][s])
    }
    /// The box and channel-sum moments of leaf `leaf` (counted from the first leaf).
    #[inline]
    pub fn leaf_moments(&self, leaf: usize) -> &LeafMoments {
        &self.leaf_moments[leaf]
    }
    /// The normal every photon of leaf `leaf` (counted from the first leaf) shares, if any.
    #[inline]
    pub fn leaf_normal(&self, leaf: usize) -> Option<Vec3> {
        self.leaf_normals[leaf]
    }
    fn heap_bytes(&self) -> usize {
        let floats: usize = self
            .power
            .iter()
            .chain(&self.site_position)
            .chain(&self.site_gradient)
            .map(Vec::capacity)
            .sum();
        (floats + self.site_weight.capacity() + self.channel_sum.capacity()) * size_of::<f32>()
            + (self.site_slot.capacity() + self.leaf_sites.capacity()) * size_of::<u32>()
            + self.leaf_normals.capacity() * size_of::<Option<Vec3>>()
            + self.leaf_moments.capacity() * size_of::<LeafMoments>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_holds_at_most_90_bytes_per_photon_with_its_gradient_field() {
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
        eprintln!("bytes per photon: {bare} bare, {with} with the field");
        assert!(
            bare < 25.0 && with <= 90.0 && with - bare >= 48.0,
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
