//! Hit filters: what a geometry's Embree intersect and occluded filter functions ask Rust, the
//! candidate hit as the C shim (`shim_common.h`) lays it out, and the slot a filtered
//! geometry's user data points at. Owns that C-facing layout; must not know what a filter
//! decides (alpha cut-outs live in the world).

use glam::Vec3;
use std::ffi::{c_int, c_void};
use std::sync::Arc;

/// A hit Embree has found and a [`HitFilter`] may turn down: `struct dpm_candidate` in C.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    pub primitive: u32,
    /// Barycentric coordinates, as in [`Hit`].
    pub u: f32,
    pub v: f32,
    /// The ray, in the space of the scene that holds the geometry (an instanced scene's own).
    origin: [f32; 3],
    dir: [f32; 3],
    /// Distance along the ray, in units of `dir`'s length.
    pub t: f32,
    occlusion: c_int,
}

impl Candidate {
    pub fn origin(&self) -> Vec3 {
        Vec3::from_array(self.origin)
    }

    pub fn dir(&self) -> Vec3 {
        Vec3::from_array(self.dir)
    }

    /// Whether an occlusion query asks (a shadow ray), not a closest-hit one.
    pub fn is_occlusion(&self) -> bool {
        self.occlusion != 0
    }

    /// A candidate as Embree would pass it, for testing filters.
    pub fn new(primitive: u32, u: f32, v: f32, origin: Vec3, dir: Vec3, occlusion: bool) -> Self {
        Self {
            primitive,
            u,
            v,
            origin: origin.to_array(),
            dir: dir.to_array(),
            t: 1.0,
            occlusion: c_int::from(occlusion),
        }
    }
}

/// Decides, hit by hit, whether a geometry is there (an alpha cut-out). Embree calls it from
/// the tracing threads, inside a query: it must be cheap and must not trace rays.
pub trait HitFilter: Send + Sync {
    fn accept(&self, candidate: &Candidate) -> bool;
}

/// What a filtered geometry's user data points at: `struct dpm_hit_filter` in C, then the
/// filter itself.
#[repr(C)]
pub(super) struct FilterSlot {
    pub(super) accept: unsafe extern "C" fn(*mut c_void, *const Candidate) -> c_int,
    pub(super) filter: Arc<dyn HitFilter>,
}

impl FilterSlot {
    /// A slot for `filter`, boxed so that its address, Embree's user data for the geometry
    /// (returned beside it), stays put while the scene that keeps it lives.
    pub(super) fn boxed(filter: Arc<dyn HitFilter>) -> (Box<Self>, *mut c_void) {
        let mut slot = Box::new(FilterSlot {
            accept: accept_candidate,
            filter,
        });
        let user = &mut *slot as *mut FilterSlot as *mut c_void;
        (slot, user)
    }
}

pub(super) unsafe extern "C" fn accept_candidate(
    slot: *mut c_void,
    candidate: *const Candidate,
) -> c_int {
    // SAFETY: `slot` is the geometry's user data, a `FilterSlot` its scene keeps in place;
    // `candidate` is the shim's, live for the call.
    let (slot, candidate) = unsafe { (&*(slot as *const FilterSlot), &*candidate) };
    // A panic must not unwind into Embree: the hit then stands.
    let accept = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        slot.filter.accept(candidate)
    }));
    c_int::from(accept.unwrap_or(true))
}
