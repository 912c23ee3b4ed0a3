/* The part of dpm's C shim that is the same on both backends; included by shim3.c and shim4.c
 * after their backend's rtcore.h.
 *
 * Errors: Embree hands out `enum RTCError`, and a Rust enum that receives a value it does not
 * list (Embree 4.4 added RTC_ERROR_LEVEL_ZERO_RAYTRACING_SUPPORT_MISSING, unknown to the 4.2
 * bindings) would be undefined behaviour, so error codes reach Rust only as `int`, converted
 * here. The error callback goes to `sink->record`, a Rust function; `struct dpm_error_sink` is
 * dpm's own (Rust's `#[repr(C)] ErrorSink` in src/embree/mod.rs), not Embree's. */
#include <stddef.h>

struct dpm_error_sink {
    void (*record)(void *sink, int code, const char *message);
};

static void dpm_forward_error(void *user, enum RTCError code, const char *message)
{
    struct dpm_error_sink *sink = (struct dpm_error_sink *)user;
    sink->record(user, (int)code, message);
}

void dpm_rtc_set_error_sink(RTCDevice device, struct dpm_error_sink *sink)
{
    rtcSetDeviceErrorFunction(device, dpm_forward_error, sink);
}

int dpm_rtc_get_device_error(RTCDevice device) { return (int)rtcGetDeviceError(device); }

/* RTC_DEVICE_PROPERTY_VERSION of the library actually loaded, e.g. 40400. */
long dpm_rtc_library_version(RTCDevice device)
{
    return (long)rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION);
}

/* The version of the headers this was compiled against (the library's may differ). */
int dpm_rtc_header_version(void) { return RTC_VERSION; }

/* The headers' view of the structs Rust allocates, for a test against bindgen's. */
size_t dpm_rtc_sizeof_ray(void) { return sizeof(struct RTCRay); }
size_t dpm_rtc_sizeof_rayhit(void) { return sizeof(struct RTCRayHit); }
size_t dpm_rtc_alignof_rayhit(void) { return _Alignof(struct RTCRayHit); }
size_t dpm_rtc_offsetof_hit(void) { return offsetof(struct RTCRayHit, hit); }
