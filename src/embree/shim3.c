/* dpm's C shim over Embree 3 (compiled by `cc` in build.rs against /usr/include/embree3).
 *
 * Embree 3's `rtcInitIntersectContext` is inline in its header and has no symbol in the
 * library, and `struct RTCIntersectContext` depends on the header's configuration
 * (RTC_MAX_INSTANCE_LEVEL_COUNT). So the context is made here, by the C compiler reading the real
 * header, and never crosses into Rust: Rust passes the ray (laid out by bindgen from the same
 * header) and the scene, nothing else. */
#include <embree3/rtcore.h>
#include "shim_common.h"

void dpm_rtc_intersect1(RTCScene scene, struct RTCRayHit *rayhit)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect1(scene, &context, rayhit);
}

void dpm_rtc_occluded1(RTCScene scene, struct RTCRay *ray)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcOccluded1(scene, &context, ray);
}
