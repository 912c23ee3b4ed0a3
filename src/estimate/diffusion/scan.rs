//! The diffusion estimate's leaf scans: the analysis sums (the structure tensor over the
//! gradient sites within `ρ`, the isotropic Epanechnikov sums over the photons within `r`) and
//! the anisotropic kernel's sum, over runs of kd-tree leaves whose photons lie on the query's
//! surface, eight f32 lanes at a time over the [`GradientField`]'s columns. Leaves wholly inside
//! a disc add their moments; leaves that miss the kernel's ellipsoid are skipped. Owns the
//! loops; must not decide the kernel's shape (the estimate in [`super`] does).

use super::super::classic::{PhotonReader, power_of};
use super::Query;
use super::tensor;
use crate::photon::PhotonMap;
use crate::photon::map::{GradientField, LeafMoments};
use glam::{DVec3, Vec3};
use multiversion::multiversion;

/// The squared radii of one query's scans, and their inverses, in f32 for the leaf loops.
pub(super) struct ScanRadii {
    pub r2: f32,
    pub rho2: f32,
    pub inv_r2: f32,
    pub inv_rho2: f32,
}

/// What the analysis sums over the photons on the query's surface: the structure tensor's
/// weighted world-space outer products (xx, xy, xz, yy, yz, zz) and their weight, and within
/// `r` the Epanechnikov sums of the channel sum and its square (without the kernel's
/// constant) and the count.
#[derive(Default)]
pub(super) struct AnalysisSums {
    pub structure: [f64; 6],
    pub structure_weight: f64,
    pub isotropic: f64,
    pub second_moment: f64,
    /// Photons within `r`.
    pub inside: f64,
}

impl AnalysisSums {
    /// Adds a run of leaves whose photons all agree with the query's normal: its sites (every
    /// photon, but where sites are thinned: then each stands for its weight's worth) to the
    /// structure tensor, its photons to the isotropic sums, eight lanes at a time over the
    /// field's arrays (f32 within a run, f64 across runs, all in the field's scaled units).
    #[inline]
    pub fn scan_run(
        &mut self,
        tree: &crate::photon::KdTree,
        field: &GradientField,
        q: Vec3,
        run: &LeafRun,
        radii: &ScanRadii,
    ) {
        let sites = field.leaf_site_range(run.leaves.start).start
            ..field.leaf_site_range(run.leaves.end - 1).end;
        self.scan_sites(field, q, sites, radii);
        // Leaves wholly inside the disc add their moments; the others are scanned.
        run.parts(field, |part| match part {
            Part::Leaf(m) => {
                let far = (q - m.lower).abs().max((m.upper - q).abs());
                let inside = far.length_squared() < radii.r2 * INSIDE_MARGIN;
                if inside {
                    self.add_moments(m, q, radii);
                }
                inside
            }
            Part::Slots(slots) => {
                self.scan_isotropic(tree, field, q, slots, radii);
                true
            }
        });
    }

    /// Adds a leaf that lies wholly within `r` of `q` to the isotropic sums from its moments.
    #[inline]
    fn add_moments(&mut self, m: &LeafMoments, q: Vec3, radii: &ScanRadii) {
        // 1 − d²/r² with d² = |u|² + 2 u·e + |e|², e = c − q.
        let e = (m.centre - q).as_dvec3();
        let inv_r2 = 1.0 / radii.r2 as f64;
        let base = 1.0 - e.length_squared() * inv_r2;
        let sum =
            |(s0, s1, s2): (f64, glam::DVec3, f64)| s0 * base - (2.0 * e.dot(s1) + s2) * inv_r2;
        self.isotropic += sum(m.phi);
        self.second_moment += sum(m.phi2);
        self.inside += m.count as f64;
    }

    /// The isotropic sums over the photons of `slots` within `r`, eight lanes at a time.
    #[inline]
    fn scan_isotropic(
        &mut self,
        tree: &crate::photon::KdTree,
        field: &GradientField,
        q: Vec3,
        slots: std::ops::Range<usize>,
        radii: &ScanRadii,
    ) {
        let (xs, ys, zs) = tree.coordinates();
        let phi = field.channel_sums();
        let Some(end) = lane_end(&slots, xs.len()) else {
            for s in slots {
                self.add_isotropic((tree.point(s) - q).length_squared(), phi[s], radii);
            }
            return;
        };
        let s = slots.start..end;
        let columns = [
            groups(&xs[s.clone()]),
            groups(&ys[s.clone()]),
            groups(&zs[s.clone()]),
        ];
        let (iso, second, inside) = isotropic_lanes(
            columns,
            groups(&phi[s]),
            slots.len(),
            q,
            radii.r2,
            radii.inv_r2,
        );
        self.isotropic += total(iso);
        self.second_moment += total(second);
        self.inside += inside.iter().sum::<u32>() as f64;
    }

    /// Adds the sites `sites` (indices into the field's site arrays) within `ρ` to the
    /// structure tensor, eight lanes at a time.
    #[inline]
    fn scan_sites(
        &mut self,
        field: &GradientField,
        q: Vec3,
        sites: std::ops::Range<usize>,
        radii: &ScanRadii,
    ) {
        let columns = field.site_columns();
        let [xs, ys, zs] = columns.position;
        let Some(end) = lane_end(&sites, xs.len()) else {
            for i in sites {
                self.add_site(field, i, q, radii);
            }
            return;
        };
        let s = sites.start..end;
        let [gx, gy, gz] = columns.gradient;
        let position = [
            groups(&xs[s.clone()]),
            groups(&ys[s.clone()]),
            groups(&zs[s.clone()]),
        ];
        let gradient = [
            groups(&gx[s.clone()]),
            groups(&gy[s.clone()]),
            groups(&gz[s.clone()]),
        ];
        let weight = groups(&columns.weight[s]);
        let (t, tw) = structure_lanes(
            position,
            gradient,
            weight,
            sites.len(),
            q,
            radii.rho2,
            radii.inv_rho2,
        );
        for (acc, v) in self.structure.iter_mut().zip(t) {
            *acc += total(v);
        }
        self.structure_weight += total(tw);
    }

    /// Adds site `i` to the structure tensor if it is within `ρ` of `q`.
    #[inline]
    fn add_site(&mut self, field: &GradientField, i: usize, q: Vec3, radii: &ScanRadii) {
        let c = field.site_columns();
        let [xs, ys, zs] = c.position;
        let [gx, gy, gz] = c.gradient;
        let d2 = (Vec3::new(xs[i], ys[i], zs[i]) - q).length_squared();
        if d2 < radii.rho2 {
            let w = ((1.0 - d2 * radii.inv_rho2) * c.weight[i]) as f64;
            let g = DVec3::new(gx[i] as f64, gy[i] as f64, gz[i] as f64);
            let o = [
                g.x * g.x,
                g.x * g.y,
                g.x * g.z,
                g.y * g.y,
                g.y * g.z,
                g.z * g.z,
            ];
            for (acc, v) in self.structure.iter_mut().zip(o) {
                *acc += w * v;
            }
            self.structure_weight += w;
        }
    }

    /// Adds one photon at squared distance `d2` with channel sum `phi` (scaled) to the
    /// isotropic sums; returns whether it is within `r`.
    #[inline]
    fn add_isotropic(&mut self, d2: f32, phi: f32, radii: &ScanRadii) -> bool {
        if d2 < radii.r2 {
            let e = (1.0 - d2 * radii.inv_r2) as f64;
            let phi = phi as f64;
            self.isotropic += e * phi;
            self.second_moment += e * phi * phi;
            self.inside += 1.0;
            return true;
        }
        false
    }

    /// Adds a leaf that holds several surfaces, testing each photon's normal, and copies the
    /// agreeing photons within `r` to the kernel's inputs.
    pub fn scan_mixed(
        &mut self,
        map: &PhotonMap,
        field: &GradientField,
        query: &Query,
        (leaf, slots): (usize, std::ops::Range<usize>),
        radii: &ScanRadii,
        inputs: &mut Vec<(Vec3, DVec3, u32)>,
    ) {
        let mut reader = PhotonReader::new(query.normal);
        for i in field.leaf_site_range(leaf) {
            if reader.agrees(map.attributes(field.site_slot(i))) {
                self.add_site(field, i, query.position, radii);
            }
        }
        for slot in slots {
            let slot = slot as u32;
            let photon = map.attributes(slot);
            if !reader.agrees(photon) {
                continue;
            }
            let d = map.position(slot) - query.position;
            if self.add_isotropic(
                d.length_squared(),
                field.channel_sums()[slot as usize],
                radii,
            ) {
                inputs.push((d, power_of(photon), slot));
            }
        }
    }
}

/// Consecutive leaves, one surface each, that agree with a query's normal: the leaves and
/// their slots.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LeafRun {
    pub leaves: std::ops::Range<usize>,
    pub slots: std::ops::Range<usize>,
}

/// What [`LeafRun::parts`] hands out: a leaf to take whole (or not), or slots to scan.
pub(super) enum Part<'a> {
    Leaf(&'a LeafMoments),
    Slots(std::ops::Range<usize>),
}

impl LeafRun {
    /// Offers each leaf to `f` as [`Part::Leaf`] (`f` returns whether it dealt with the leaf
    /// whole), then hands it the slots of the leaves it did not take, neighbouring ones merged
    /// into one range, as [`Part::Slots`].
    fn parts(&self, field: &GradientField, mut f: impl FnMut(Part<'_>) -> bool) {
        let mut pending: Option<std::ops::Range<usize>> = None;
        let mut slot = self.slots.start;
        for leaf in self.leaves.clone() {
            let m = field.leaf_moments(leaf);
            let slots = slot..slot + m.count as usize;
            slot = slots.end;
            if f(Part::Leaf(m)) {
                continue;
            }
            pending = match pending {
                Some(p) if p.end == slots.start => Some(p.start..slots.end),
                Some(p) => {
                    f(Part::Slots(p));
                    Some(slots)
                }
                None => Some(slots),
            };
        }
        if let Some(p) = pending {
            f(Part::Slots(p));
        }
    }
}

/// The sum of a lane accumulator's lanes, in f64.
#[inline(always)]
fn total(a: Lanes) -> f64 {
    (((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]))) as f64
}

/// A leaf is wholly inside a disc when its box's far corner is inside by this relative margin
/// (so that no photon rounds to the rim's other side).
const INSIDE_MARGIN: f32 = 1.0 - 1e-5;

/// Lanes of the leaf scans: eight f32, one AVX register (two SSE ones where there is no AVX2:
/// the same arithmetic lane by lane, so the same sums bit for bit on every machine).
const LANES: usize = 8;

type Lanes = [f32; LANES];

/// The isotropic scan's lanes over the first `n` photons of whole lane groups: the sums of
/// `(1 − d²/r²) φ` and `(1 − d²/r²) φ²` over the photons within `r`, and their count.
#[multiversion(targets("x86_64+avx+avx2"))]
fn isotropic_lanes(
    [xs, ys, zs]: [&[Lanes]; 3],
    phi: &[Lanes],
    n: usize,
    q: Vec3,
    r2: f32,
    inv_r2: f32,
) -> (Lanes, Lanes, [u32; LANES]) {
    let (mut iso, mut second, mut inside) = ([0.0f32; LANES], [0.0f32; LANES], [0u32; LANES]);
    for c in 0..xs.len() {
        let (x4, y4, z4, p4) = (xs[c], ys[c], zs[c], phi[c]);
        for lane in 0..LANES {
            let (dx, dy, dz) = (x4[lane] - q.x, y4[lane] - q.y, z4[lane] - q.z);
            let d2 = dx * dx + dy * dy + dz * dz;
            let within = (c * LANES + lane < n) & (d2 < r2);
            let ep = masked(1.0 - d2 * inv_r2, within) * p4[lane];
            iso[lane] += ep;
            second[lane] += ep * p4[lane];
            inside[lane] += u32::from(within);
        }
    }
    (iso, second, inside)
}

/// The structure tensor's lanes over the first `n` sites of whole lane groups: the sums of
/// `(1 − d²/ρ²) w g gᵀ` (xx, xy, xz, yy, yz, zz) and of the weights, over the sites within `ρ`.
#[multiversion(targets("x86_64+avx+avx2"))]
fn structure_lanes(
    [xs, ys, zs]: [&[Lanes]; 3],
    [gx, gy, gz]: [&[Lanes]; 3],
    gw: &[Lanes],
    n: usize,
    q: Vec3,
    rho2: f32,
    inv_rho2: f32,
) -> ([Lanes; 6], Lanes) {
    let mut t = [[0.0f32; LANES]; 6];
    let mut tw = [0.0f32; LANES];
    for c in 0..xs.len() {
        let (x4, y4, z4) = (xs[c], ys[c], zs[c]);
        let (gx4, gy4, gz4, gw4) = (gx[c], gy[c], gz[c], gw[c]);
        for lane in 0..LANES {
            let (dx, dy, dz) = (x4[lane] - q.x, y4[lane] - q.y, z4[lane] - q.z);
            let d2 = dx * dx + dy * dy + dz * dz;
            let keep = (c * LANES + lane < n) & (d2 < rho2);
            let w = masked((1.0 - d2 * inv_rho2) * gw4[lane], keep);
            let (x, y, z) = (gx4[lane], gy4[lane], gz4[lane]);
            let (wx, wy) = (w * x, w * y);
            t[0][lane] += wx * x;
            t[1][lane] += wx * y;
            t[2][lane] += wx * z;
            t[3][lane] += wy * y;
            t[4][lane] += wy * z;
            t[5][lane] += w * z * z;
            tw[lane] += w;
        }
    }
    (t, tw)
}

/// The anisotropic kernel's lanes over the first `n` photons of whole lane groups: the sums of
/// `(1 − y) Φ` (r, g, b) over the photons with `y = Σ (a_i·d)² < 1`.
#[multiversion(targets("x86_64+avx+avx2"))]
fn ellipse_lanes(
    [xs, ys, zs]: [&[Lanes]; 3],
    [pr, pg, pb]: [&[Lanes]; 3],
    n: usize,
    q: Vec3,
    [a1, a2, a3]: [Vec3; 3],
) -> [Lanes; 3] {
    let (mut r, mut g, mut b) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
    for c in 0..xs.len() {
        let (x4, y4, z4) = (xs[c], ys[c], zs[c]);
        let (pr4, pg4, pb4) = (pr[c], pg[c], pb[c]);
        for lane in 0..LANES {
            let (dx, dy, dz) = (x4[lane] - q.x, y4[lane] - q.y, z4[lane] - q.z);
            let u = dx * a1.x + dy * a1.y + dz * a1.z;
            let v = dx * a2.x + dy * a2.y + dz * a2.z;
            let w = dx * a3.x + dy * a3.y + dz * a3.z;
            let y = u * u + v * v + w * w;
            let k = masked(1.0 - y, (c * LANES + lane < n) & (y < 1.0));
            r[lane] += k * pr4[lane];
            g[lane] += k * pg4[lane];
            b[lane] += k * pb4[lane];
        }
    }
    [r, g, b]
}

/// A run rounded to whole lane groups (see [`lane_end`]) as groups.
#[inline(always)]
fn groups(a: &[f32]) -> &[Lanes] {
    a.as_chunks::<LANES>().0
}

/// The end of a run rounded up to whole groups of [`LANES`] (the last group runs on into the
/// next leaf's photons, which a lane mask leaves out), or `None` where that would run off
/// arrays of length `len`.
#[inline]
fn lane_end(slots: &std::ops::Range<usize>, len: usize) -> Option<usize> {
    let end = slots.start + slots.len().div_ceil(LANES) * LANES;
    (end <= len).then_some(end)
}

/// `v` where `keep`, else 0, by bits: a select the compiler would make a branch.
#[inline(always)]
fn masked(v: f32, keep: bool) -> f32 {
    f32::from_bits(v.to_bits() & u32::from(keep).wrapping_neg())
}

/// The Epanechnikov kernel `1 − dᵀD⁻¹d/r²` over runs of slots, in f32 lanes: the metric's
/// three scaled axes, relative to the query.
pub(super) struct EllipseScan {
    a: [Vec3; 3],
    q: Vec3,
    /// The quadratic form `M = Σ a_i a_iᵀ` (xx, xy, xz, yy, yz, zz), for leaf moments.
    m: [f64; 6],
}

/// Where a leaf's box lies against the kernel's ellipsoid.
enum BoxPlace {
    Outside,
    Inside,
    Across,
}

impl EllipseScan {
    pub fn new(metric: &tensor::ScaledMetric, q: Vec3) -> Self {
        let [a1, a2, a3] = metric.axes();
        let m = |i: usize, j: usize| a1[i] * a1[j] + a2[i] * a2[j] + a3[i] * a3[j];
        Self {
            a: [a1, a2, a3].map(|a| a.as_vec3()),
            q,
            m: [m(0, 0), m(0, 1), m(0, 2), m(1, 1), m(1, 2), m(2, 2)],
        }
    }

    /// `Σ (1 − y) Φ` over a run of leaves: the leaves whose box lies outside the ellipsoid's
    /// bounding slab on some axis (most of them where the kernel is squeezed) are skipped,
    /// those wholly inside it (most of them where it is round) add their moments, and the
    /// others are scanned, runs of neighbouring ones together.
    pub fn run(&self, tree: &crate::photon::KdTree, field: &GradientField, run: &LeafRun) -> DVec3 {
        let mut sum = DVec3::ZERO;
        run.parts(field, |part| match part {
            Part::Leaf(m) => match self.place(m.lower, m.upper) {
                BoxPlace::Outside => true,
                BoxPlace::Inside => {
                    sum += self.moments(m);
                    true
                }
                BoxPlace::Across => false,
            },
            Part::Slots(slots) => {
                sum += self.sum(tree, field, slots);
                true
            }
        });
        sum
    }

    /// Where the box lies: outside if on some axis `a_i` its projection lies wholly outside
    /// [−1, 1], inside if the projections' far ends bound `y` below 1 (each with a margin on
    /// the safe side, so that no photon is lost or counted twice by rounding).
    #[inline]
    fn place(&self, lower: Vec3, upper: Vec3) -> BoxPlace {
        let centre = (lower + upper) * 0.5 - self.q;
        let half = (upper - lower) * 0.5;
        let mut far = 0.0;
        for a in &self.a {
            let (mid, reach) = (centre.dot(*a).abs(), half.dot(a.abs()));
            if mid - reach > 1.0 + 1e-4 {
                return BoxPlace::Outside;
            }
            far += (mid + reach) * (mid + reach);
        }
        if far < INSIDE_MARGIN {
            BoxPlace::Inside
        } else {
            BoxPlace::Across
        }
    }

    /// `Σ (1 − y) Φ` over a leaf wholly inside the ellipsoid, from its moments about its
    /// centre `c`: with `e = c − q`, `y = eᵀMe + 2 (Me)·u + uᵀMu`.
    #[inline]
    fn moments(&self, leaf: &LeafMoments) -> DVec3 {
        let m = &self.m;
        let e = (leaf.centre - self.q).as_dvec3();
        let me = DVec3::new(
            m[0] * e.x + m[1] * e.y + m[2] * e.z,
            m[1] * e.x + m[3] * e.y + m[4] * e.z,
            m[2] * e.x + m[4] * e.y + m[5] * e.z,
        );
        let p = &leaf.power;
        let first = p.first.map(|v| v.as_dvec3());
        let second = p.second.map(|v| v.as_dvec3());
        p.sum.as_dvec3() * (1.0 - e.dot(me))
            - 2.0 * (first[0] * me.x + first[1] * me.y + first[2] * me.z)
            - (second[0] * m[0]
                + 2.0 * (second[1] * m[1] + second[2] * m[2] + second[4] * m[4])
                + second[3] * m[3]
                + second[5] * m[5])
    }

    /// `Σ (1 − y) Φ` over the run's photons with `y = dᵀD⁻¹d/r² < 1`, eight lanes at a time.
    #[inline]
    fn sum(
        &self,
        tree: &crate::photon::KdTree,
        field: &GradientField,
        slots: std::ops::Range<usize>,
    ) -> DVec3 {
        let (xs, ys, zs) = tree.coordinates();
        let [pr, pg, pb] = field.power_columns();
        let Some(end) = lane_end(&slots, xs.len()) else {
            let mut sum = DVec3::ZERO;
            for slot in slots {
                let y = self.distance(tree.point(slot) - self.q);
                let k = if y < 1.0 { 1.0 - y } else { 0.0 };
                sum += (k * field.power(slot as u32)).as_dvec3();
            }
            return sum;
        };
        let s = slots.start..end;
        let position = [
            groups(&xs[s.clone()]),
            groups(&ys[s.clone()]),
            groups(&zs[s.clone()]),
        ];
        let power = [
            groups(&pr[s.clone()]),
            groups(&pg[s.clone()]),
            groups(&pb[s]),
        ];
        let [r, g, b] = ellipse_lanes(position, power, slots.len(), self.q, self.a);
        DVec3::new(total(r), total(g), total(b))
    }

    #[inline]
    fn distance(&self, d: Vec3) -> f32 {
        let [a1, a2, a3] = self.a;
        let (u, v, w) = (d.dot(a1), d.dot(a2), d.dot(a3));
        u * u + v * v + w * w
    }
}
