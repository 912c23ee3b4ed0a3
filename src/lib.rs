//! `dpm`: diffusion based photon mapping (Schjøth, Olsen, Sparring) on Embree 3, or on Embree 4
//! with the `embree4` feature.
//!
//! The crate reads top to bottom as the data flows:
//! scene description → Embree → media → photon tracing → photon map → radiance estimate → render (a
//! loop of independent passes into a film) → image.
//! Each stage is one module; each module's opening paragraph says what it owns and what it
//! must not touch.

pub mod bsdf;
pub mod density;
pub mod embree;
pub mod estimate;
pub mod image_io;
pub mod image_metrics;
pub mod interrupt;
pub mod media;
pub mod optics;
pub mod photon;
pub mod render;
pub mod resident_memory;
pub mod sampling;
pub mod scene;
pub mod spectrum;
pub mod timing;
pub mod tradeoff;
pub mod world;
