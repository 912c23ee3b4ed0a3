//! What one pilot ray learns ([`Pilot`]: its chains' last rays, the objects they met, the
//! first diffuse hit's normal and light probes), and what a pixel's five pilots decide
//! together: whether it samples its emission apart ([`sees_emission`]) and whether it holds
//! an edge ([`holds_edge`]). Owns those decisions; must not trace rays.

use crate::world::BoundingSphere;
use glam::Vec3;

/// How far beyond the pilots' own spread a light may lie and still flag the pixel: the
/// directions across a pixel curve between its pilots on a curved mirror.
pub(super) const SPREAD_MARGIN: f32 = 1.5;
/// Normals of one object further apart than this (cos 30°) across a pixel make an edge.
const CREASE_COS: f32 = 0.866;

/// Which branch of a pilot's chains a ray is on: the reflected (0) and refracted (1) choices
/// at each bounce so far, and how many, so that the same branch of neighbouring pilots can be
/// compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct BranchCode(pub(super) u64);

impl BranchCode {
    pub(super) const ROOT: BranchCode = BranchCode(1);

    /// The branch one bounce on, `choice` 0 or 1 (a leading 1 bit keeps depths apart; past
    /// 63 bounces codes wrap, which only makes two branches look alike).
    pub(super) fn then(self, choice: u64) -> BranchCode {
        BranchCode(self.0.wrapping_shl(1) | choice)
    }
}

/// The last ray of one branch of a pilot's chains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct LastRay {
    pub(super) code: BranchCode,
    pub(super) origin: Vec3,
    pub(super) direction: Vec3,
    /// How near it passes a light's bounding sphere ([`gap_to_sphere`]: at most the angle in
    /// radians; negative inside the sphere; infinite without visible lights).
    pub(super) light_gap: f32,
    /// Which of the visible spheres that gap is to (`u32::MAX`: none).
    pub(super) light: u32,
}

/// What one pilot ray learns.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Pilot {
    /// The chains' last rays, one per branch followed to its end.
    pub(super) last_rays: Vec<LastRay>,
    /// Last rays that meet a light, or leave the scene under an image environment.
    pub(super) emitting: u32,
    /// The chains were too many to follow.
    pub(super) tangled: bool,
    /// The objects met along the chains, in order, hashed.
    pub(super) shape: ShapeHash,
    /// The shading normal at the first diffuse hit.
    pub(super) normal: Option<Vec3>,
    /// The light probes visible from the first diffuse hit, one bit each.
    pub(super) visible: u64,
}

impl Default for Pilot {
    fn default() -> Self {
        Self {
            last_rays: Vec::new(),
            emitting: 0,
            tangled: false,
            shape: ShapeHash(0xCBF2_9CE4_8422_2325),
            normal: None,
            visible: 0,
        }
    }
}

/// FNV-1a over the objects a pilot's chains meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct ShapeHash(u64);

impl ShapeHash {
    pub(super) fn add(&mut self, word: u64) {
        for byte in word.to_le_bytes() {
            self.0 = (self.0 ^ byte as u64).wrapping_mul(0x100_0000_01B3);
        }
    }
}

/// How near the ray from `o` along unit `d` passes `sphere`: `sin θ − sin α` for a sphere
/// in front, θ the angle between `d` and the sphere's centre and α its angular radius, which
/// is never more than the angle `θ − α` between the ray and the sphere's silhouette (so a
/// test against an angle errs towards flagging), without an inverse sine or cosine per
/// sphere; `1 − sin α` for a sphere behind (at least a right angle away), −1 inside it.
pub(super) fn gap_to_sphere(o: Vec3, d: Vec3, sphere: &BoundingSphere) -> f32 {
    let to = sphere.center - o;
    let dist = to.length();
    if dist <= sphere.radius {
        return -1.0;
    }
    let sin_radius = sphere.radius / dist;
    if d.dot(to) <= 0.0 {
        return 1.0 - sin_radius;
    }
    d.cross(to).length() / dist - sin_radius
}

/// Whether a pixel with these pilots (its centre and corners) samples its emitted light
/// apart. Yes where the chains were too many to follow. No where every last ray of every
/// pilot meets a light (the pixel lies inside the light's image: each camera sample sees it,
/// no lottery). Yes where some last ray meets a light (its image's edge crosses the pixel).
/// Otherwise yes where a light lies within the pixel's spread of a last ray, with a margin:
/// an image smaller than the pilots' spacing may lie between them. The spread of a branch is
/// the widest angle between the last rays of that branch across the five pilots; a branch
/// that some pilot lacks (a silhouette or a total reflection's edge inside the pixel) takes
/// the widest angle between any two last rays of the pixel.
pub(super) fn sees_emission(pilots: &[&Pilot; 5]) -> bool {
    if pilots.iter().any(|p| p.tangled) {
        return true;
    }
    if pilots
        .iter()
        .all(|p| !p.last_rays.is_empty() && p.emitting as usize == p.last_rays.len())
    {
        return false;
    }
    if pilots.iter().any(|p| p.emitting > 0) {
        return true;
    }
    let rays = || pilots.iter().flat_map(|p| p.last_rays.iter());
    let gap = rays().map(|r| r.light_gap).fold(f32::INFINITY, f32::min);
    if !gap.is_finite() {
        return false;
    }
    // The pixel's widest angle bounds every branch's spread: most pixels stop here.
    let whole = widest(rays());
    rays().any(|ray| ray.light_gap <= SPREAD_MARGIN * whole && near_light(pilots, ray, whole))
}

/// Whether a light lies within `ray`'s branch's spread across the pixel (`pilots`), with the
/// margin: the widest angle between that branch's last rays, or `whole`, the pixel's widest
/// between any two, where some pilot lacks the branch (a silhouette or a total reflection's
/// edge inside the pixel).
pub(super) fn near_light(pilots: &[&Pilot; 5], ray: &LastRay, whole: f32) -> bool {
    let matched = (pilots.iter()).all(|p| p.last_rays.iter().any(|r| r.code == ray.code));
    let spread = if matched {
        let rays = pilots.iter().flat_map(|p| p.last_rays.iter());
        widest(rays.filter(|r| r.code == ray.code))
    } else {
        whole
    };
    ray.light_gap <= SPREAD_MARGIN * spread
}

/// The widest angle between two of the rays' directions (one inverse cosine, of the smallest
/// dot product).
pub(super) fn widest<'a>(rays: impl Iterator<Item = &'a LastRay> + Clone) -> f32 {
    let mut least = 1.0f32;
    for (i, a) in rays.clone().enumerate() {
        for b in rays.clone().skip(i + 1) {
            least = least.min(a.direction.dot(b.direction));
        }
    }
    least.clamp(-1.0, 1.0).acos()
}

/// Whether a pixel with these pilots holds an edge: their chains meet other objects, or their
/// first diffuse hits see other light probes or turn normals more than 30° apart.
pub(super) fn holds_edge(pilots: &[&Pilot; 5]) -> bool {
    let first = pilots[0];
    pilots.iter().any(|p| {
        p.tangled
            || p.shape != first.shape
            || p.visible != first.visible
            || match (p.normal, first.normal) {
                (Some(a), Some(b)) => a.dot(b) < CREASE_COS,
                (None, None) => false,
                _ => true,
            }
    })
}
