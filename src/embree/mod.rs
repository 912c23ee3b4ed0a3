//! The only door to Embree, and the only code in dpm that touches raw pointers: a thin safe
//! wrapper that owns the device, error reporting, building an immutable scene from triangle
//! meshes (copied, or read where their owner holds them: `triangles.rs`), spheres, cubic
//! Bézier curves (`curves.rs`) and instances of other committed scenes (one level, as pbrt's
//! object instancing allows), hit filters that let a geometry turn down
//! hits (alpha cut-outs), single-ray closest-hit and occlusion queries, the Embree version in use,
//! and the rayon pools (flush-to-zero, a bounded thread count) that trace rays. It runs on one of
//! two backends, side by side in this folder and chosen at build time: Embree 3 (`embree3.rs` +
//! `shim3.c`, the default) or Embree 4 (`embree4.rs` + `shim4.c`, feature `embree4`). Each backend
//! file only names its bindings' types and constants; everything that differs in how a ray is
//! cast lives in its C shim, which `cc` compiles against the real headers, so no Embree struct
//! is re-typed in Rust. Nothing outside this folder knows which backend it runs on. It knows
//! nothing of materials, lights or photons, and must not: it never reads a scene description.

mod curves;
mod filters;
mod threads;
mod triangles;
mod version;

pub use curves::{CurveKind, FLAT_CURVE_QUADS};
use filters::FilterSlot;
pub use filters::{Candidate, HitFilter};
pub use threads::{
    MAX_THREADS, ThreadPoolError, enable_flush_to_zero, flush_to_zero_enabled, thread_pool,
};
pub use triangles::{SharedTriangles, pad_for_embree, padded_for_embree};
pub use version::{BACKEND, Version, header_version, version, version_string};

#[cfg(not(feature = "embree4"))]
#[path = "embree3.rs"]
mod backend;
#[cfg(feature = "embree4")]
#[path = "embree4.rs"]
mod backend;

use backend::bindings as sys;
use glam::Vec3;
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::fmt;
use std::sync::{Arc, Mutex};

/// dpm's C shim (`shim3.c` / `shim4.c` with `shim_common.h`), built by `build.rs`.
mod shim {
    use super::sys::{RTCDevice, RTCGeometry, RTCRay, RTCRayHit, RTCScene};
    use std::ffi::{c_char, c_int, c_long, c_void};

    /// Where the shim forwards Embree's error callback; `struct dpm_error_sink` in C.
    #[repr(C)]
    pub struct ErrorSink {
        pub record: unsafe extern "C" fn(*mut c_void, c_int, *const c_char),
    }

    unsafe extern "C" {
        /// `rtcIntersect1` with a fresh incoherent context (3) or arguments (4).
        pub fn dpm_rtc_intersect1(scene: RTCScene, rayhit: *mut RTCRayHit);
        /// `rtcOccluded1` likewise.
        pub fn dpm_rtc_occluded1(scene: RTCScene, ray: *mut RTCRay);
        pub fn dpm_rtc_set_error_sink(device: RTCDevice, sink: *mut ErrorSink);
        pub fn dpm_rtc_get_device_error(device: RTCDevice) -> c_int;
        pub fn dpm_rtc_library_version(device: RTCDevice) -> c_long;
        pub fn dpm_rtc_header_version() -> c_int;
        /// Sets `filter` as the geometry's user data and its intersect and occluded filters.
        pub fn dpm_rtc_set_hit_filter(geometry: RTCGeometry, filter: *mut c_void);
        #[cfg(test)]
        pub fn dpm_rtc_sizeof_ray() -> usize;
        #[cfg(test)]
        pub fn dpm_rtc_sizeof_rayhit() -> usize;
        #[cfg(test)]
        pub fn dpm_rtc_alignof_rayhit() -> usize;
        #[cfg(test)]
        pub fn dpm_rtc_offsetof_hit() -> usize;
    }
}

/// An error reported by Embree (or by this wrapper before a call would reach Embree).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("Embree error {code}: {message}")]
pub struct EmbreeError {
    pub code: ErrorCode,
    pub message: String,
}

/// Embree's error codes, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorCode {
    Unknown,
    InvalidArgument,
    InvalidOperation,
    OutOfMemory,
    UnsupportedCpu,
    Cancelled,
    /// Caught by this wrapper before calling Embree.
    Wrapper,
}

impl ErrorCode {
    /// `None` for `RTC_ERROR_NONE`; codes this wrapper does not list are `Unknown`.
    fn from_raw(code: c_int) -> Option<Self> {
        if code == backend::ERROR_NONE {
            return None;
        }
        let known = backend::ERRORS.iter().find(|(raw, _)| *raw == code);
        Some(known.map_or(Self::Unknown, |(_, name)| *name))
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = match self {
            Self::Unknown => "RTC_ERROR_UNKNOWN",
            Self::InvalidArgument => "RTC_ERROR_INVALID_ARGUMENT",
            Self::InvalidOperation => "RTC_ERROR_INVALID_OPERATION",
            Self::OutOfMemory => "RTC_ERROR_OUT_OF_MEMORY",
            Self::UnsupportedCpu => "RTC_ERROR_UNSUPPORTED_CPU",
            Self::Cancelled => "RTC_ERROR_CANCELLED",
            Self::Wrapper => "invalid input",
        };
        f.write_str(name)
    }
}

fn wrapper_error(message: impl Into<String>) -> EmbreeError {
    EmbreeError {
        code: ErrorCode::Wrapper,
        message: message.into(),
    }
}

/// The first error Embree reported since the last check. The callback writes it; `check` takes it.
/// `sink` comes first so that the shim, given a pointer to the slot, sees a `dpm_error_sink`.
#[repr(C)]
struct ErrorSlot {
    sink: shim::ErrorSink,
    first: Mutex<Option<EmbreeError>>,
}

impl ErrorSlot {
    fn new() -> Self {
        Self {
            sink: shim::ErrorSink {
                record: record_error,
            },
            first: Mutex::new(None),
        }
    }
}

unsafe extern "C" fn record_error(user: *mut c_void, code: c_int, message: *const c_char) {
    // SAFETY: `user` is the `ErrorSlot` owned by the device's `DeviceInner`, which outlives the
    // device handle (it is dropped only after `rtcReleaseDevice`).
    let slot = unsafe { &*(user as *const ErrorSlot) };
    let message = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string valid for the duration of the call.
        unsafe { CStr::from_ptr(message) }
            .to_string_lossy()
            .into_owned()
    };
    if let Some(code) = ErrorCode::from_raw(code) {
        let mut guard = slot.first.lock().unwrap_or_else(|p| p.into_inner());
        guard.get_or_insert(EmbreeError { code, message });
    }
}

struct DeviceInner {
    raw: sys::RTCDevice,
    errors: Box<ErrorSlot>,
}

// SAFETY: an Embree device is thread-safe; the error slot is behind a mutex.
unsafe impl Send for DeviceInner {}
unsafe impl Sync for DeviceInner {}

impl DeviceInner {
    /// Turns any error Embree reported since the last check into `Err`.
    fn check(&self) -> Result<(), EmbreeError> {
        // Always read (and so clear) Embree's per-thread code, even when the callback has the
        // message, or a stale code would fail the next check.
        // SAFETY: `raw` is a live device.
        let code = unsafe { shim::dpm_rtc_get_device_error(self.raw) };
        let recorded = self
            .errors
            .first
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        match (recorded, ErrorCode::from_raw(code)) {
            (Some(e), _) => Err(e),
            (None, Some(code)) => Err(EmbreeError {
                code,
                message: String::new(),
            }),
            (None, None) => Ok(()),
        }
    }
}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: the last owner releases the device; scenes hold an `Arc` so none outlives it.
        unsafe { sys::rtcReleaseDevice(self.raw) };
    }
}

/// An Embree device. Cheap to clone (shared).
#[derive(Clone)]
pub struct Device {
    inner: Arc<DeviceInner>,
}

impl Device {
    pub fn new() -> Result<Self, EmbreeError> {
        Self::with_config("")
    }

    /// A device with an Embree configuration string (e.g. `"threads=2"`).
    pub fn with_config(config: &str) -> Result<Self, EmbreeError> {
        let config = CString::new(config).map_err(|_| wrapper_error("NUL in device config"))?;
        // SAFETY: `config` is a valid C string for the duration of the call.
        let raw = unsafe { sys::rtcNewDevice(config.as_ptr()) };
        if raw.is_null() {
            // SAFETY: querying the error of a null device is how Embree reports creation failure.
            let code = unsafe { shim::dpm_rtc_get_device_error(std::ptr::null_mut()) };
            let code = ErrorCode::from_raw(code).unwrap_or(ErrorCode::Unknown);
            return Err(EmbreeError {
                code,
                message: "rtcNewDevice failed".into(),
            });
        }
        let errors = Box::new(ErrorSlot::new());
        let sink = &*errors as *const ErrorSlot as *mut shim::ErrorSink;
        // SAFETY: `sink` points to the start of the `#[repr(C)]` slot, a `dpm_error_sink`, in the
        // box that `DeviceInner` keeps alive for the device's life; Embree only passes it back.
        unsafe { shim::dpm_rtc_set_error_sink(raw, sink) };
        let inner = Arc::new(DeviceInner { raw, errors });
        inner.check()?;
        Ok(Self { inner })
    }

    pub fn scene_builder(&self) -> Result<SceneBuilder, EmbreeError> {
        // SAFETY: live device.
        let raw = unsafe { sys::rtcNewScene(self.inner.raw) };
        self.inner.check()?;
        if raw.is_null() {
            return Err(wrapper_error("rtcNewScene returned null"));
        }
        Ok(SceneBuilder {
            device: self.inner.clone(),
            raw: Some(raw),
            geometries: 0,
            instanced: Vec::new(),
            filters: Vec::new(),
            shared: Vec::new(),
            meshes_read_in_place: 0,
        })
    }
}

/// `RTC_INVALID_GEOMETRY_ID` is a cast macro bindgen cannot translate.
const INVALID_ID: u32 = u32::MAX;

/// Index of a geometry in a scene, in the order it was added (0, 1, 2, ...).
pub type GeometryId = u32;

/// A scene under construction. Consumed by [`SceneBuilder::commit`].
pub struct SceneBuilder {
    device: Arc<DeviceInner>,
    raw: Option<sys::RTCScene>,
    geometries: u32,
    /// The scenes this one's instances place, kept alive as long as it is.
    instanced: Vec<Arc<Scene>>,
    /// The hit filters its geometries call, kept alive (and in place) as long as it is.
    #[allow(clippy::vec_box)] // Embree holds their addresses: a Vec alone would move them.
    filters: Vec<Box<FilterSlot>>,
    /// The meshes Embree reads where they lie, kept alive as long as it is.
    shared: Vec<Arc<dyn SharedTriangles>>,
    meshes_read_in_place: usize,
}

impl SceneBuilder {
    fn scene(&self) -> sys::RTCScene {
        self.raw.expect("scene is present until commit")
    }

    /// Creates a geometry, lets `fill` write its buffers, commits and attaches it.
    fn attach(
        &mut self,
        kind: sys::RTCGeometryType,
        fill: impl FnOnce(sys::RTCGeometry) -> Result<(), EmbreeError>,
    ) -> Result<GeometryId, EmbreeError> {
        // SAFETY: live device; the geometry is released below whatever happens.
        let geometry = unsafe { sys::rtcNewGeometry(self.device.raw, kind) };
        self.device.check()?;
        let filled = fill(geometry).and_then(|_| {
            // SAFETY: live geometry with its buffers set.
            unsafe { sys::rtcCommitGeometry(geometry) };
            self.device.check()
        });
        let id = filled.and_then(|_| {
            // SAFETY: live scene and geometry; attaching keeps a reference to the geometry.
            let id = unsafe { sys::rtcAttachGeometry(self.scene(), geometry) };
            self.device.check().map(|_| id)
        });
        // SAFETY: drop our reference; the scene holds its own if attached.
        unsafe { sys::rtcReleaseGeometry(geometry) };
        let id = id?;
        debug_assert_eq!(id, self.geometries);
        self.geometries += 1;
        Ok(id)
    }

    /// Adds spheres (`RTC_GEOMETRY_TYPE_SPHERE_POINT`): one geometry, primitive `i` is `spheres[i]`.
    pub fn add_spheres(&mut self, spheres: &[(Vec3, f32)]) -> Result<GeometryId, EmbreeError> {
        if spheres.is_empty() {
            return Err(wrapper_error("a sphere geometry needs at least one sphere"));
        }
        if let Some(s) = spheres
            .iter()
            .find(|(c, r)| !c.is_finite() || !r.is_finite() || *r <= 0.0)
        {
            return Err(wrapper_error(format!("invalid sphere {s:?}")));
        }
        let device = self.device.clone();
        self.attach(backend::SPHERE_POINT, |g| {
            let points = new_buffer::<[f32; 4]>(
                &device,
                g,
                backend::VERTEX,
                backend::FLOAT4,
                spheres.len(),
            )?;
            for (dst, (c, r)) in points.iter_mut().zip(spheres) {
                *dst = [c.x, c.y, c.z, *r];
            }
            Ok(())
        })
    }

    /// Adds an instance of the committed scene `prototype`, placed by the affine map
    /// `object_to_world` (its last row must be 0 0 0 1). Hits through it report the
    /// prototype's geometry and primitive, and this geometry's id as [`Hit::instance`].
    pub fn add_instance(
        &mut self,
        prototype: &Arc<Scene>,
        object_to_world: glam::Mat4,
    ) -> Result<GeometryId, EmbreeError> {
        if !Arc::ptr_eq(&prototype.device, &self.device) {
            return Err(wrapper_error(
                "an instance's scene belongs to another device",
            ));
        }
        if !prototype.instanced.is_empty() {
            return Err(wrapper_error("instances nest one level deep only"));
        }
        if !object_to_world.is_finite() || object_to_world.row(3) != glam::Vec4::W {
            return Err(wrapper_error(format!(
                "an instance's transform is not a finite affine map: {object_to_world:?}"
            )));
        }
        if object_to_world.determinant().abs() < 1e-30 {
            return Err(wrapper_error("an instance's transform is singular"));
        }
        // Column-major 3 × 4: the three columns of the linear part, then the translation.
        let mut columns = [0.0f32; 12];
        for (c, column) in columns.chunks_exact_mut(3).enumerate() {
            column.copy_from_slice(&object_to_world.col(c).truncate().to_array());
        }
        let child = prototype.raw;
        let id = self.attach(backend::INSTANCE, |g| {
            // SAFETY: live instance geometry and committed scene; Embree copies the 12 floats.
            unsafe {
                sys::rtcSetGeometryInstancedScene(g, child);
                sys::rtcSetGeometryTransform(
                    g,
                    0,
                    backend::FLOAT3X4_COLUMN_MAJOR,
                    columns.as_ptr() as *const c_void,
                );
            }
            Ok(())
        })?;
        self.instanced.push(Arc::clone(prototype));
        Ok(id)
    }

    /// Builds the acceleration structure. The result cannot be changed.
    pub fn commit(mut self) -> Result<Scene, EmbreeError> {
        let raw = self.raw.take().expect("scene is present until commit");
        // SAFETY: live scene; from here on it is only read.
        unsafe {
            backend::set_scene_quality(raw);
            sys::rtcCommitScene(raw);
        }
        let scene = Scene {
            device: self.device.clone(),
            raw,
            geometries: self.geometries,
            instanced: std::mem::take(&mut self.instanced),
            filters: std::mem::take(&mut self.filters),
            shared: std::mem::take(&mut self.shared),
            meshes_read_in_place: self.meshes_read_in_place,
        };
        scene.device.check()?;
        Ok(scene)
    }
}

impl Drop for SceneBuilder {
    fn drop(&mut self) {
        if let Some(raw) = self.raw.take() {
            // SAFETY: an uncommitted scene we own.
            unsafe { sys::rtcReleaseScene(raw) };
        }
    }
}

/// Asks Embree for a new buffer of `count` elements of `T` and hands it out as a slice.
fn new_buffer<'g, T: Copy>(
    device: &DeviceInner,
    geometry: sys::RTCGeometry,
    kind: sys::RTCBufferType,
    format: sys::RTCFormat,
    count: usize,
) -> Result<&'g mut [T], EmbreeError> {
    let stride = std::mem::size_of::<T>();
    // SAFETY: live geometry; Embree allocates (and pads) `count * stride` bytes it owns.
    let ptr = unsafe { sys::rtcSetNewGeometryBuffer(geometry, kind, 0, format, stride, count) };
    device.check()?;
    if ptr.is_null() {
        return Err(wrapper_error("rtcSetNewGeometryBuffer returned null"));
    }
    // SAFETY: the buffer holds `count` elements of `stride` bytes, aligned to 16, and lives as
    // long as the geometry, which outlives the slice's use inside `attach`.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr as *mut T, count) })
}

/// A committed, immutable scene. Tracing is thread-safe, so it is `Send + Sync`.
pub struct Scene {
    device: Arc<DeviceInner>,
    raw: sys::RTCScene,
    geometries: u32,
    /// The scenes this one's instances place (released after this one).
    instanced: Vec<Arc<Scene>>,
    /// The hit filters its geometries call: only held, and dropped after the scene is released.
    #[allow(dead_code, clippy::vec_box)] // as in SceneBuilder
    filters: Vec<Box<FilterSlot>>,
    /// The meshes Embree reads where they lie: only held, and dropped after the scene is.
    #[allow(dead_code)]
    shared: Vec<Arc<dyn SharedTriangles>>,
    meshes_read_in_place: usize,
}

// SAFETY: a committed Embree scene may be traced from any number of threads; nothing mutates it.
unsafe impl Send for Scene {}
unsafe impl Sync for Scene {}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: we own this reference.
        unsafe { sys::rtcReleaseScene(self.raw) };
    }
}

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray in units of `dir`'s length.
    pub t: f32,
    /// The geometry hit: in the top-level scene, or in the instanced scene when `instance`
    /// is set.
    pub geometry: GeometryId,
    pub primitive: u32,
    /// The instance geometry (of the top-level scene) the hit went through, if any.
    pub instance: Option<GeometryId>,
    /// Where on the primitive the hit lies: for triangles the barycentric weights of
    /// vertices 1 and 2; for curves the parameter along the segment (0 to 1) and the place
    /// across it ([`CurveKind`] says in what range).
    pub u: f32,
    pub v: f32,
    /// Geometric normal, unnormalised, as Embree reports it (in the instanced scene's space for
    /// a hit through an instance); for a flat curve, its tangent.
    pub normal: Vec3,
}

fn raw_ray(origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> sys::RTCRay {
    sys::RTCRay {
        org_x: origin.x,
        org_y: origin.y,
        org_z: origin.z,
        tnear,
        dir_x: dir.x,
        dir_y: dir.y,
        dir_z: dir.z,
        time: 0.0,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl Scene {
    /// How many of its triangle meshes Embree reads where they lie (not copied).
    pub fn meshes_read_in_place(&self) -> usize {
        self.meshes_read_in_place
    }

    pub fn geometry_count(&self) -> u32 {
        self.geometries
    }

    /// The closest hit with `t` in `[tnear, tfar]`, if any.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> Option<Hit> {
        let mut rayhit = sys::RTCRayHit {
            ray: raw_ray(origin, dir, tnear, tfar),
            hit: sys::RTCHit {
                geomID: INVALID_ID,
                instID: [INVALID_ID; 1],
                ..Default::default()
            },
        };
        // SAFETY: committed scene; `rayhit` is valid, aligned and live for the call (the shim
        // makes the context or arguments).
        unsafe { shim::dpm_rtc_intersect1(self.raw, &mut rayhit) };
        let h = rayhit.hit;
        (h.geomID != INVALID_ID).then(|| Hit {
            t: rayhit.ray.tfar,
            geometry: h.geomID,
            primitive: h.primID,
            instance: (h.instID[0] != INVALID_ID).then_some(h.instID[0]),
            u: h.u,
            v: h.v,
            normal: Vec3::new(h.Ng_x, h.Ng_y, h.Ng_z),
        })
    }

    /// Whether anything lies along the ray with `t` in `[tnear, tfar]`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> bool {
        let mut ray = raw_ray(origin, dir, tnear, tfar);
        // SAFETY: as in `intersect`.
        unsafe { shim::dpm_rtc_occluded1(self.raw, &mut ray) };
        // Embree sets tfar to -inf when the ray is occluded.
        ray.tfar == f32::NEG_INFINITY
    }
}

#[cfg(test)]
mod tests;
