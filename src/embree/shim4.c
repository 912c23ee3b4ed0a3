/* dpm's C shim over Embree 4 (compiled by `cc` in build.rs against the Embree 4.2.0 headers
 * shipped in the embree4-sys crate, the same headers its bindings come from).
 *
 * `rtcInitIntersectArguments` and `rtcInitOccludedArguments` are inline in the headers, with no
 * symbol in the library, and the argument structs depend on the build's configuration
 * (RTC_MIN_WIDTH). So the arguments are made here, by the C compiler reading the real headers,
 * and never cross into Rust: Rust passes the ray (laid out by bindgen from the same headers) and
 * the scene. No ray query context is passed (`context = NULL`, Embree then uses its own), so
 * `rtcInitRayQueryContext` and `struct RTCRayQueryContext` are not needed.
 *
 * The library dpm links is Embree 4.4.0 (the embreex wheel), the headers are 4.2.0. Checked in
 * the v4.4.0 sources (include/embree4/rtcore_ray.h, rtcore_scene.h, rtcore_common.h):
 * - `RTCRay` is unchanged (12 four-byte fields, 48 bytes, 16-aligned);
 * - `RTCHit` gains `instPrimID[RTC_MAX_INSTANCE_LEVEL_COUNT]` when the library is built with
 *   instance arrays (EMBREE_GEOMETRY_INSTANCE_ARRAY, on by default in 4.4; the wheel's library
 *   has them: it accepts RTC_GEOMETRY_TYPE_INSTANCE_ARRAY). Then `RTCHit` is 36 bytes, padded
 *   to 48 by RTC_ALIGN(16), and `RTCRayHit` 96, where the 4.2 headers (and so the Rust
 *   bindings) give 32 and 80: Embree 4.4 writes `hit.instPrimID[0]` at byte 80, just past a
 *   4.2 `RTCRayHit`. So the ray is traced here in a copy with room for 4.4's layout
 *   (`struct dpm_rayhit_room`), and only the 4.2 fields are copied back;
 * - `RTCIntersectArguments` and `RTCOccludedArguments` are unchanged; both end with
 *   `minWidthDistanceFactor` only when built with EMBREE_MIN_WIDTH (off by default). In case the
 *   library was built with it, the arguments below sit in a zeroed struct with room to spare, so
 *   that field would read 0 (min-width off) rather than stack garbage;
 * - `RTCRayQueryContext` gains `instPrimID` the same way; dpm does not pass one.
 * tests/embree.rs's analytic hits, run on this backend, are the final word. */
#include <embree4/rtcore.h>
#include "shim_common.h"

/* A 4.2 `RTCRayHit` followed by room for the fields a 4.4 library may write after it. */
struct dpm_rayhit_room {
    struct RTCRayHit rayhit;
    unsigned int reserve[4 * RTC_MAX_INSTANCE_LEVEL_COUNT];
};
_Static_assert(sizeof(struct dpm_rayhit_room) >= 96, "room for Embree 4.4's RTCRayHit");
_Static_assert(offsetof(struct dpm_rayhit_room, rayhit) == 0, "the ray comes first");

struct dpm_intersect_arguments {
    struct RTCIntersectArguments arguments;
    float reserve[4];
};

struct dpm_occluded_arguments {
    struct RTCOccludedArguments arguments;
    float reserve[4];
};

void dpm_rtc_intersect1(RTCScene scene, struct RTCRayHit *rayhit)
{
    struct dpm_intersect_arguments args = {0};
    struct dpm_rayhit_room room = {0};
    rtcInitIntersectArguments(&args.arguments);
    room.rayhit = *rayhit;
    rtcIntersect1(scene, &room.rayhit, &args.arguments);
    *rayhit = room.rayhit;
}

void dpm_rtc_occluded1(RTCScene scene, struct RTCRay *ray)
{
    struct dpm_occluded_arguments args = {0};
    rtcInitOccludedArguments(&args.arguments);
    rtcOccluded1(scene, ray, &args.arguments);
}
