//! The render stage, shaped as a pass loop. [`pipeline`] is the command line around it: it
//! checks the flags, lets [`setup`] load the world and decide once what every pass shares
//! (settings, the caustic guide [`caustic_guide`], the memory check [`memory_budget`], where
//! the passes start, the pilot rays' pixel plan [`pilots`]), runs the [`pass_loop`] and writes
//! the result. A render is a sequence of independent passes ([`schedule`] says what pass `i`
//! draws and at which radii); each pass ([`pass`]) traces its own photon maps (or reads pass
//! 0's from a file, [`photon_files`]), prepares its estimates, shades fresh camera samples
//! ([`camera`]) through the [`integrator`], with the light seen along mirror and glass chains
//! sampled apart in the pixels that need it ([`emission`]) and, for the kernel-field layer, the
//! diffusion kernel's shape at each pixel ([`kernel_probe`]), and drops its maps; the [`film`]
//! accumulates the passes' images and is what gets written ([`output`], [`film_file`]) and
//! merged ([`merge`]). Owns pixels, sample placement and accumulation; must not parse scenes
//! or store photons.

pub mod args;
mod bsdf_shading;
pub mod camera;
pub mod caustic_guide;
mod direct_light;
pub mod emission;
pub mod film;
pub mod film_file;
mod gather;
mod global_budget;
pub mod integrator;
pub mod kernel_probe;
pub mod light_images;
pub mod memory_budget;
pub mod merge;
pub mod output;
pub mod pass;
pub mod pass_loop;
pub mod photon_files;
pub mod pilots;
pub mod pipeline;
pub mod schedule;
pub mod setup;
pub mod tensor_history;
pub mod volume_shading;

pub use camera::{PassSamples, RayCamera};
pub use film::{Film, PassImage};
