//! Participating media, the stage between Embree's surfaces and the photon tracer: what light
//! meets between surfaces. Owns the media as pbrt defines them (a homogeneous medium's
//! coefficients, a heterogeneous medium's density grid looked up as pbrt looks it up, the
//! coarse majorant grid over it), the Henyey–Greenstein phase function with pbrt's sign of g,
//! and the two ways along a segment: free flights by delta tracking (where a photon or path
//! scatters next) and transmittance by ratio tracking (what a shadow ray lets through). Must
//! not trace rays against surfaces (a caller gives the segment between two hits), store
//! photons or shade pixels.
//!
//! - [`phase`]: Henyey–Greenstein, evaluated and sampled exactly.
//! - [`homogeneous`]: constant coefficients; closed-form transmittance and pbrt's one-sample
//!   spectral free flight.
//! - [`grid`]: pbrt-v3's `heterogeneous` density (trilinear between voxel centres, zero
//!   outside) and the majorant grid a 3-D DDA walks (pbrt-v4's design: a thin wisp in a mostly
//!   empty grid does not cost the densest voxel's steps).
//! - [`tracking`]: delta and ratio tracking over the majorant segments.
//! - [`equiangular`]: where a small light's single scattering is sampled along a ray.
//! - [`medium`]: one medium whatever its kind, as transport asks of it: transmittance, free
//!   flights and the phase function.

pub mod equiangular;
pub mod grid;
pub mod homogeneous;
pub mod medium;
pub mod phase;
pub mod tracking;

pub use grid::{DensityGrid, MajorantGrid, MajorantSegment};
pub use homogeneous::{FreeFlight, Homogeneous};
pub use medium::Medium;
pub use phase::HenyeyGreenstein;
