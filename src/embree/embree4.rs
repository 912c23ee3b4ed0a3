//! The Embree 4 backend (feature `embree4`): the `embree4-sys` crate's bindings (bindgen on the
//! Embree 4.2.0 headers it ships), linked with the Embree 4.4.0 library that
//! `scripts/fetch-embree4.sh` fetches. It only names the bindings' types, functions and
//! constants for `mod.rs`; the calls are made there and in `shim4.c` (which also records what was
//! checked of the 4.2 headers against 4.4's).

pub(super) use embree4_sys as bindings;

use super::ErrorCode;
use bindings as b;
use std::ffi::c_int;

pub(super) const NAME: &str = "Embree 4";

pub(super) const TRIANGLE: b::RTCGeometryType = b::RTCGeometryType::TRIANGLE;
pub(super) const SPHERE_POINT: b::RTCGeometryType = b::RTCGeometryType::SPHERE_POINT;
pub(super) const INSTANCE: b::RTCGeometryType = b::RTCGeometryType::INSTANCE;
pub(super) const FLAT_BEZIER_CURVE: b::RTCGeometryType = b::RTCGeometryType::FLAT_BEZIER_CURVE;
pub(super) const ROUND_BEZIER_CURVE: b::RTCGeometryType = b::RTCGeometryType::ROUND_BEZIER_CURVE;
pub(super) const NORMAL_ORIENTED_BEZIER_CURVE: b::RTCGeometryType =
    b::RTCGeometryType::NORMAL_ORIENTED_BEZIER_CURVE;
pub(super) const VERTEX: b::RTCBufferType = b::RTCBufferType::VERTEX;
pub(super) const INDEX: b::RTCBufferType = b::RTCBufferType::INDEX;
pub(super) const NORMAL: b::RTCBufferType = b::RTCBufferType::NORMAL;
pub(super) const FLOAT3: b::RTCFormat = b::RTCFormat::FLOAT3;
pub(super) const FLOAT4: b::RTCFormat = b::RTCFormat::FLOAT4;
pub(super) const UINT: b::RTCFormat = b::RTCFormat::UINT;
pub(super) const UINT3: b::RTCFormat = b::RTCFormat::UINT3;
pub(super) const FLOAT3X4_COLUMN_MAJOR: b::RTCFormat = b::RTCFormat::FLOAT3X4_COLUMN_MAJOR;

/// Embree's error codes as the shim hands them over (`int`), by name; `RTC_ERROR_NONE` is 0.
pub(super) const ERROR_NONE: c_int = b::RTCError::NONE as c_int;
pub(super) const ERRORS: [(c_int, ErrorCode); 6] = [
    (b::RTCError::UNKNOWN as c_int, ErrorCode::Unknown),
    (
        b::RTCError::INVALID_ARGUMENT as c_int,
        ErrorCode::InvalidArgument,
    ),
    (
        b::RTCError::INVALID_OPERATION as c_int,
        ErrorCode::InvalidOperation,
    ),
    (b::RTCError::OUT_OF_MEMORY as c_int, ErrorCode::OutOfMemory),
    (
        b::RTCError::UNSUPPORTED_CPU as c_int,
        ErrorCode::UnsupportedCpu,
    ),
    (b::RTCError::CANCELLED as c_int, ErrorCode::Cancelled),
];

/// Robust traversal (no cracks between triangles) and a high-quality build.
///
/// # Safety
/// `scene` is a live scene that has not been committed yet.
pub(super) unsafe fn set_scene_quality(scene: b::RTCScene) {
    // SAFETY: the caller's promise.
    unsafe {
        b::rtcSetSceneFlags(scene, b::RTCSceneFlags::ROBUST);
        b::rtcSetSceneBuildQuality(scene, b::RTCBuildQuality::HIGH);
    }
}
