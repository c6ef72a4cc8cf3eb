/* Counts the rays Mitsuba 3 traces: an LD_PRELOAD library that stands in
 * for Embree's rtcIntersect16 and rtcOccluded16 (the calls llvm_ad_rgb makes
 * on AVX-512 machines), counts each call's active lanes, and forwards the
 * call to the Embree that Mitsuba's wheel ships. benches/mitsuba_rays.sh
 * builds it and prints rays per sample beside vkpt's own counts, so the two
 * renderers' path lengths can be compared (the same estimator traces the
 * same number of extension rays per sample).
 *
 * EMBREE_LIB (a compile-time string): the path of Mitsuba's libembree3.so.
 */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>

#include <atomic>

/* Mitsuba's wheel builds Embree's API into namespace mitsuba, so the symbols
 * to stand in for carry C++ names with these (opaque) argument types. */
namespace mitsuba {
struct RTCSceneTy;
struct RTCIntersectContext;
struct RTCRayHit16;
struct RTCRay16;
}  // namespace mitsuba

using Intersect16 = void (*)(const int *, mitsuba::RTCSceneTy *, mitsuba::RTCIntersectContext *,
                             mitsuba::RTCRayHit16 *);
using Occluded16 = void (*)(const int *, mitsuba::RTCSceneTy *, mitsuba::RTCIntersectContext *,
                            mitsuba::RTCRay16 *);

static std::atomic<unsigned long long> extension_rays{0}, shadow_rays{0};

/* Embree's own function: loaded explicitly, since Python opens Mitsuba's
 * libraries locally and RTLD_NEXT would not see them. */
static void *embree(const char *symbol) {
    void *lib = dlopen(EMBREE_LIB, RTLD_NOW);
    void *f = lib ? dlsym(lib, symbol) : nullptr;
    if (!f) {
        fprintf(stderr, "count_rays: %s not found in %s\n", symbol, EMBREE_LIB);
        abort();
    }
    return f;
}

static unsigned active_lanes(const int *valid) {
    unsigned n = 0;
    for (int i = 0; i < 16; i++) n += valid[i] != 0;
    return n;
}

namespace mitsuba {
void rtcIntersect16(const int *valid, RTCSceneTy *scene, RTCIntersectContext *context,
                    RTCRayHit16 *rays) {
    static Intersect16 real = (Intersect16)embree(
        "_ZN7mitsuba14rtcIntersect16EPKiPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_11RTCRayHit16E");
    extension_rays += active_lanes(valid);
    real(valid, scene, context, rays);
}

void rtcOccluded16(const int *valid, RTCSceneTy *scene, RTCIntersectContext *context,
                   RTCRay16 *rays) {
    static Occluded16 real = (Occluded16)embree(
        "_ZN7mitsuba13rtcOccluded16EPKiPNS_10RTCSceneTyEPNS_19RTCIntersectContextEPNS_8RTCRay16E");
    shadow_rays += active_lanes(valid);
    real(valid, scene, context, rays);
}
}  // namespace mitsuba

__attribute__((destructor)) static void report() {
    printf("mitsuba rays: %llu extension, %llu shadow\n", extension_rays.load(), shadow_rays.load());
}
