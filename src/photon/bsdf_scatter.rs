//! A photon meeting a surface with a BSDF model: left in the map where the model has a
//! Lambert lobe, then scattered by the Lambert lobes (a diffuse bounce) or by the followed ones
//! (glossy or specular, as a mirror scatters it), chosen by their weights, with Russian
//! roulette by the sample's weight. Part of the tracer ([`super::tracer`]); must not trace.

use super::tracer::{LivePath, MapKind, TracedPhoton, store_photon};
use crate::bsdf::{Bsdf, Model, Part};
use crate::sampling::Frame;
use crate::world::Interaction;
use glam::Vec3;

/// The direction the path goes on in, or `None` where it ends.
pub(super) fn scatter(
    kind: MapKind,
    path: &mut LivePath,
    model: &Model,
    hit: &Interaction,
    d: Vec3,
    ns: Vec3,
    stored: &mut Vec<TracedPhoton>,
) -> Option<Vec3> {
    let bsdf = Bsdf::new(model);
    // The surface's own side, not the ray's: a dielectric knows its inside by it.
    let frame = Frame::new(hit.shading_normal);
    let wo = frame.to_local(-d);
    if bsdf.has(Part::Lambert) {
        store_photon(kind, path, hit.position, d, ns, stored);
    }
    // The Lambert lobes (read from photons) or the followed ones (as a mirror is),
    // chosen by their albedos; a caustic path ends where it turns diffuse.
    let lambert = bsdf.weight(wo, Part::Lambert);
    let followed = bsdf.weight(wo, Part::Followed);
    if (lambert + followed).is_nan() || lambert + followed <= 0.0 {
        return None;
    }
    let p_lambert = lambert / (lambert + followed);
    let (part, chosen) = if path.rng.next_f32() < p_lambert {
        (Part::Lambert, p_lambert)
    } else {
        (Part::Followed, 1.0 - p_lambert)
    };
    let ends_caustic = match part {
        Part::Lambert => true,
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
    if part == Part::Lambert {
        path.diffuse_seen = true;
    } else {
        path.specular_seen = true;
    }
    Some(frame.to_world(s.wi))
}
