//! The only door to Embree: a thin safe wrapper over the Embree 3 bindings. It owns the device,
//! error reporting, building an immutable scene from triangle meshes and spheres, and single-ray
//! closest-hit and occlusion queries. Every Embree-3-specific call lives in this folder, so that
//! an Embree 4 backend can sit beside it. It knows nothing of materials, lights or photons.

mod sys;

use glam::Vec3;
use std::ffi::{CStr, CString, c_void};
use std::fmt;
use std::sync::{Arc, Mutex};

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
    fn from_raw(code: sys::RTCError) -> Option<Self> {
        Some(match code {
            sys::RTC_ERROR_NONE => return None,
            sys::RTC_ERROR_INVALID_ARGUMENT => Self::InvalidArgument,
            sys::RTC_ERROR_INVALID_OPERATION => Self::InvalidOperation,
            sys::RTC_ERROR_OUT_OF_MEMORY => Self::OutOfMemory,
            sys::RTC_ERROR_UNSUPPORTED_CPU => Self::UnsupportedCpu,
            sys::RTC_ERROR_CANCELLED => Self::Cancelled,
            _ => Self::Unknown,
        })
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
#[derive(Default)]
struct ErrorSlot(Mutex<Option<EmbreeError>>);

unsafe extern "C" fn record_error(user: *mut c_void, code: sys::RTCError, message: *const i8) {
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
        let mut guard = slot.0.lock().unwrap_or_else(|p| p.into_inner());
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
        let code = unsafe { sys::rtcGetDeviceError(self.raw) };
        let recorded = self
            .errors
            .0
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
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            let code = ErrorCode::from_raw(code).unwrap_or(ErrorCode::Unknown);
            return Err(EmbreeError {
                code,
                message: "rtcNewDevice failed".into(),
            });
        }
        let errors = Box::new(ErrorSlot::default());
        let user = &*errors as *const ErrorSlot as *mut c_void;
        // SAFETY: `user` points into the box kept alive by `DeviceInner` for the device's life.
        unsafe { sys::rtcSetDeviceErrorFunction(raw, Some(record_error), user) };
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

    /// Adds a triangle mesh. Indices must be in range and positions finite.
    pub fn add_triangles(
        &mut self,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<GeometryId, EmbreeError> {
        if triangles.is_empty() {
            return Err(wrapper_error("a triangle mesh needs at least one triangle"));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(wrapper_error("a mesh vertex is not finite"));
        }
        let n = positions.len();
        if let Some(t) = triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= n))
        {
            return Err(wrapper_error(format!(
                "triangle {t:?} indexes past {n} vertices"
            )));
        }
        let device = self.device.clone();
        self.attach(sys::RTC_GEOMETRY_TYPE_TRIANGLE, |g| {
            let vertices = new_buffer::<[f32; 3]>(
                &device,
                g,
                sys::RTC_BUFFER_TYPE_VERTEX,
                sys::RTC_FORMAT_FLOAT3,
                n,
            )?;
            for (dst, p) in vertices.iter_mut().zip(positions) {
                *dst = p.to_array();
            }
            let indices = new_buffer::<[u32; 3]>(
                &device,
                g,
                sys::RTC_BUFFER_TYPE_INDEX,
                sys::RTC_FORMAT_UINT3,
                triangles.len(),
            )?;
            indices.copy_from_slice(triangles);
            Ok(())
        })
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
        self.attach(sys::RTC_GEOMETRY_TYPE_SPHERE_POINT, |g| {
            let points = new_buffer::<[f32; 4]>(
                &device,
                g,
                sys::RTC_BUFFER_TYPE_VERTEX,
                sys::RTC_FORMAT_FLOAT4,
                spheres.len(),
            )?;
            for (dst, (c, r)) in points.iter_mut().zip(spheres) {
                *dst = [c.x, c.y, c.z, *r];
            }
            Ok(())
        })
    }

    /// Builds the acceleration structure. The result cannot be changed.
    pub fn commit(mut self) -> Result<Scene, EmbreeError> {
        let raw = self.raw.take().expect("scene is present until commit");
        // SAFETY: live scene; from here on it is only read.
        unsafe {
            sys::rtcSetSceneFlags(raw, sys::RTC_SCENE_FLAG_ROBUST);
            sys::rtcSetSceneBuildQuality(raw, sys::RTC_BUILD_QUALITY_HIGH);
            sys::rtcCommitScene(raw);
        }
        let scene = Scene {
            device: self.device.clone(),
            raw,
            geometries: self.geometries,
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
    pub geometry: GeometryId,
    pub primitive: u32,
    /// Barycentric coordinates of the hit (triangles: weights of vertices 1 and 2).
    pub u: f32,
    pub v: f32,
    /// Geometric normal, unnormalised, as Embree reports it.
    pub normal: Vec3,
}

fn context() -> sys::RTCIntersectContext {
    // `rtcInitIntersectContext` is inline in the header, without a symbol: do what it does.
    let mut ctx = sys::RTCIntersectContext {
        flags: sys::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
        filter: None,
        ..Default::default()
    };
    ctx.instID.fill(INVALID_ID);
    ctx
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
    pub fn geometry_count(&self) -> u32 {
        self.geometries
    }

    /// The closest hit with `t` in `[tnear, tfar]`, if any.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> Option<Hit> {
        let mut ctx = context();
        let mut rayhit = sys::RTCRayHit {
            ray: raw_ray(origin, dir, tnear, tfar),
            hit: sys::RTCHit {
                geomID: INVALID_ID,
                ..Default::default()
            },
        };
        // SAFETY: committed scene; `ctx` and `rayhit` are valid, aligned and live for the call.
        unsafe { sys::rtcIntersect1(self.raw, &mut ctx, &mut rayhit) };
        let h = rayhit.hit;
        (h.geomID != INVALID_ID).then(|| Hit {
            t: rayhit.ray.tfar,
            geometry: h.geomID,
            primitive: h.primID,
            u: h.u,
            v: h.v,
            normal: Vec3::new(h.Ng_x, h.Ng_y, h.Ng_z),
        })
    }

    /// Whether anything lies along the ray with `t` in `[tnear, tfar]`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> bool {
        let mut ctx = context();
        let mut ray = raw_ray(origin, dir, tnear, tfar);
        // SAFETY: as in `intersect`.
        unsafe { sys::rtcOccluded1(self.raw, &mut ctx, &mut ray) };
        // Embree sets tfar to -inf when the ray is occluded.
        ray.tfar == f32::NEG_INFINITY
    }
}

/// Sets flush-to-zero and denormals-are-zero on the calling thread, as Embree asks of every
/// thread that traces rays.
pub fn enable_flush_to_zero() {
    #[cfg(target_arch = "x86_64")]
    {
        let mut csr: u32 = 0;
        // SAFETY: reads and writes this thread's MXCSR; FTZ (bit 15) and DAZ (bit 6) only change
        // how denormals are treated.
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack));
            csr |= (1 << 15) | (1 << 6);
            std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack));
        }
    }
}

/// Whether flush-to-zero and denormals-are-zero are set on the calling thread.
pub fn flush_to_zero_enabled() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        let mut csr: u32 = 0;
        // SAFETY: reads this thread's MXCSR.
        unsafe { std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack)) };
        csr & ((1 << 15) | (1 << 6)) == (1 << 15) | (1 << 6)
    }
    #[cfg(not(target_arch = "x86_64"))]
    true
}

/// A rayon pool whose workers all run with flush-to-zero set. `threads = 0` means all cores.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| enable_flush_to_zero())
        .build()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_embree_call_surfaces_as_an_error() {
        let device = Device::new().unwrap();
        let mut builder = device.scene_builder().unwrap();
        // An index buffer in a vertex format: Embree itself refuses it.
        let err = builder
            .attach(sys::RTC_GEOMETRY_TYPE_TRIANGLE, |g| {
                new_buffer::<[f32; 4]>(
                    &device.inner,
                    g,
                    sys::RTC_BUFFER_TYPE_INDEX,
                    sys::RTC_FORMAT_FLOAT4,
                    1,
                )
                .map(|_| ())
            })
            .unwrap_err();
        assert_ne!(err.code, ErrorCode::Wrapper, "{err}");
        // The device stays usable and the error does not leak into the next call.
        builder.add_spheres(&[(Vec3::ZERO, 1.0)]).unwrap();
        let scene = builder.commit().unwrap();
        assert!(
            scene
                .intersect(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 0.0, f32::INFINITY)
                .is_some()
        );
    }

    #[test]
    fn flush_to_zero_is_set_on_every_pool_worker() {
        let pool = thread_pool(2).unwrap();
        let all = pool.broadcast(|_| flush_to_zero_enabled());
        assert!(all.iter().all(|&b| b));
    }
}
