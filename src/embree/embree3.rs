//! The Embree 3 backend (the default): Debian 12's Embree 3.13, with bindings that bindgen
//! generates from `/usr/include/embree3` in `build.rs`. It only names the bindings' types,
//! functions and constants for `mod.rs`; the calls are made there and in `shim3.c`.

pub(super) mod bindings {
    #![allow(
        non_upper_case_globals,
        non_camel_case_types,
        non_snake_case,
        dead_code,
        unsafe_op_in_unsafe_fn,
        clippy::all
    )]
    include!(concat!(env!("OUT_DIR"), "/embree3.rs"));
}

use super::ErrorCode;
use bindings as b;
use std::ffi::c_int;

pub(super) const NAME: &str = "Embree 3";

pub(super) const TRIANGLE: b::RTCGeometryType = b::RTC_GEOMETRY_TYPE_TRIANGLE;
pub(super) const SPHERE_POINT: b::RTCGeometryType = b::RTC_GEOMETRY_TYPE_SPHERE_POINT;
pub(super) const INSTANCE: b::RTCGeometryType = b::RTC_GEOMETRY_TYPE_INSTANCE;
pub(super) const FLAT_BEZIER_CURVE: b::RTCGeometryType = b::RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE;
pub(super) const ROUND_BEZIER_CURVE: b::RTCGeometryType = b::RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE;
pub(super) const NORMAL_ORIENTED_BEZIER_CURVE: b::RTCGeometryType =
    b::RTC_GEOMETRY_TYPE_NORMAL_ORIENTED_BEZIER_CURVE;
pub(super) const VERTEX: b::RTCBufferType = b::RTC_BUFFER_TYPE_VERTEX;
pub(super) const INDEX: b::RTCBufferType = b::RTC_BUFFER_TYPE_INDEX;
pub(super) const NORMAL: b::RTCBufferType = b::RTC_BUFFER_TYPE_NORMAL;
pub(super) const FLOAT3: b::RTCFormat = b::RTC_FORMAT_FLOAT3;
pub(super) const FLOAT4: b::RTCFormat = b::RTC_FORMAT_FLOAT4;
pub(super) const UINT: b::RTCFormat = b::RTC_FORMAT_UINT;
pub(super) const UINT3: b::RTCFormat = b::RTC_FORMAT_UINT3;
pub(super) const FLOAT3X4_COLUMN_MAJOR: b::RTCFormat = b::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR;

/// Embree's error codes as the shim hands them over (`int`), by name; `RTC_ERROR_NONE` is 0.
pub(super) const ERROR_NONE: c_int = b::RTC_ERROR_NONE as c_int;
pub(super) const ERRORS: [(c_int, ErrorCode); 6] = [
    (b::RTC_ERROR_UNKNOWN as c_int, ErrorCode::Unknown),
    (
        b::RTC_ERROR_INVALID_ARGUMENT as c_int,
        ErrorCode::InvalidArgument,
    ),
    (
        b::RTC_ERROR_INVALID_OPERATION as c_int,
        ErrorCode::InvalidOperation,
    ),
    (b::RTC_ERROR_OUT_OF_MEMORY as c_int, ErrorCode::OutOfMemory),
    (
        b::RTC_ERROR_UNSUPPORTED_CPU as c_int,
        ErrorCode::UnsupportedCpu,
    ),
    (b::RTC_ERROR_CANCELLED as c_int, ErrorCode::Cancelled),
];

/// Robust traversal (no cracks between triangles) and a high-quality build.
///
/// # Safety
/// `scene` is a live scene that has not been committed yet.
pub(super) unsafe fn set_scene_quality(scene: b::RTCScene) {
    // SAFETY: the caller's promise.
    unsafe {
        b::rtcSetSceneFlags(scene, b::RTC_SCENE_FLAG_ROBUST);
        b::rtcSetSceneBuildQuality(scene, b::RTC_BUILD_QUALITY_HIGH);
    }
}
