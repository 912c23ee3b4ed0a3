//! A photon meeting a surface with a BSDF model: left in the map where the model has a lobe
//! read from photons ([`Part::Estimated`]: Lambert, rough reflection), then scattered by those
//! lobes (a diffuse bounce: the path is no longer a caustic one) or by the followed ones
//! (specular or nearly so, as a mirror scatters it), chosen by their weights, with Russian
//! roulette by the sample's weight. Part of the tracer ([`super::tracer`]); must not trace.

use super::path::{LivePath, MapKind, store_photon};
use super::traced::TracedPhoton;
use crate::bsdf::{Bsdf, Part};
use crate::sampling::Frame;
use crate::world::Interaction;
use glam::Vec3;

/// The direction the path goes on in, or `None` where it ends.
pub(super) fn scatter(
    kind: MapKind,
    path: &mut LivePath,
    bsdf: &Bsdf,
    hit: &Interaction,
    d: Vec3,
    ns: Vec3,
    stored: &mut Vec<TracedPhoton>,
) -> Option<Vec3> {
    // The surface's own side, not the ray's: a dielectric knows its inside by it.
    let frame = Frame::new(hit.shading_normal);
    let wo = frame.to_local(-d);
    if bsdf.has(Part::Estimated) {
        store_photon(kind, path, hit.position, d, ns, stored);
    }
    // The estimated lobes or the followed ones (as a mirror is), chosen by their albedos; a
    // caustic path ends where it turns diffuse.
    let estimated = bsdf.weight(wo, Part::Estimated);
    let followed = bsdf.weight(wo, Part::Followed);
    if (estimated + followed).is_nan() || estimated + followed <= 0.0 {
        return None;
    }
    let p_estimated = estimated / (estimated + followed);
    let (part, chosen) = if path.rng.next_f32() < p_estimated {
        (Part::Estimated, p_estimated)
    } else {
        (Part::Followed, 1.0 - p_estimated)
    };
    let ends_caustic = match part {
        Part::Estimated => true,
        _ => path.diffuse_seen,
    };
    if kind == MapKind::Caustic && ends_caustic {
        return None;
    }
    let (u_lobe, u) = (path.rng.next_f32(), path.rng.next_2d());
    let s = bsdf.sample(wo, u_lobe, u, part)?;
    let weight = s.f * (s.wi.z.abs() / (s.pdf * chosen));
    let survive = weight.max_element().min(1.0);
    if survive.is_nan() || survive <= 0.0 || path.rng.next_f32() >= survive {
        return None;
    }
    path.flux *= weight / survive;
    if part == Part::Estimated {
        path.diffuse_seen = true;
    } else {
        path.specular_seen = true;
    }
    Some(frame.to_world(s.wi))
}
