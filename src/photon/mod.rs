//! Photons: the compact record ([`record`]), the pure-Rust kd-tree ([`kdtree`]) and the photon
//! map that pairs them ([`map`]). Photon *tracing* lives in [`tracer`], and what a render's
//! pilot paths learn about where to send caustic photons in [`guide`]; nothing here calls
//! Embree except through [`crate::world`].

mod bsdf_scatter;
mod emitter;
pub mod guide;
pub mod kdtree;
pub mod map;
mod medium_scatter;
mod path;
pub mod record;
pub mod store;
pub mod traced;
pub mod tracer;
pub mod volume;

pub use kdtree::{KdTree, Neighbours};
pub use map::PhotonMap;
pub use record::{EncodedDirections, Photon, PhotonAttributes};
