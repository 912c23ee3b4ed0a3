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

/* Hit filters: a geometry whose hits Rust may turn down (alpha cut-outs). The geometry's user
 * data is a `struct dpm_hit_filter`, dpm's own (Rust's `#[repr(C)] FilterSlot`), whose
 * `accept` is a Rust function. The RTCRayN/RTCHitN accessors are C++ only, so the SOA packets
 * are read by their documented layout: ray org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z,
 * time, tfar; hit Ng_x, Ng_y, Ng_z, u, v, primID (the same in Embree 3 and 4). */
struct dpm_candidate {
    unsigned int primitive;
    float u, v;
    float origin[3];
    float dir[3];
    float t;
    int occlusion;
};

struct dpm_hit_filter {
    int (*accept)(void *filter, const struct dpm_candidate *candidate);
};

static void dpm_filter(const struct RTCFilterFunctionNArguments *args, int occlusion)
{
    struct dpm_hit_filter *filter = (struct dpm_hit_filter *)args->geometryUserPtr;
    const unsigned int n = args->N;
    const float *ray = (const float *)args->ray;
    const float *hit = (const float *)args->hit;
    for (unsigned int i = 0; i < n; i++) {
        if (args->valid[i] != -1)
            continue;
        struct dpm_candidate c;
        c.primitive = ((const unsigned int *)hit)[5 * n + i];
        c.u = hit[3 * n + i];
        c.v = hit[4 * n + i];
        for (int k = 0; k < 3; k++) {
            c.origin[k] = ray[k * n + i];
            c.dir[k] = ray[(4 + k) * n + i];
        }
        c.t = ray[8 * n + i];
        c.occlusion = occlusion;
        if (!filter->accept(filter, &c))
            args->valid[i] = 0;
    }
}

static void dpm_intersect_filter(const struct RTCFilterFunctionNArguments *args)
{
    dpm_filter(args, 0);
}

static void dpm_occluded_filter(const struct RTCFilterFunctionNArguments *args)
{
    dpm_filter(args, 1);
}

/* Before the geometry is committed. */
void dpm_rtc_set_hit_filter(RTCGeometry geometry, struct dpm_hit_filter *filter)
{
    rtcSetGeometryUserData(geometry, filter);
    rtcSetGeometryIntersectFilterFunction(geometry, dpm_intersect_filter);
    rtcSetGeometryOccludedFilterFunction(geometry, dpm_occluded_filter);
}
