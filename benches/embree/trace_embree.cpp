/* Embree's traversal on the rays of `cargo bench --bench traversal`, for
 * comparison with vkpt's own CPU traversal (benches/embree_traversal.sh).
 *
 * Mitsuba 3's llvm_ad_rgb traces with Embree: one rtcIntersectN call per
 * packet of N lanes of its vectorized kernel (16 with AVX-512, 8 with AVX2).
 * This program times Embree's single-ray call and its 4-, 8- and 16-ray
 * packets on the same triangles and rays vkpt traces, on every core, and
 * checks each packet width finds the same hits as vkpt (distance within
 * 1e-4 relative).
 *
 *   trace_embree TRIS RAYS HITS RUNS THREADS
 *
 * TRIS: little-endian f32, 9 per triangle (v0, v1, v2). RAYS: 8 per ray
 * (origin, t_max, direction, 0). HITS: vkpt's distance per ray, negative
 * for a miss.
 */
#include <embree3/rtcore.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Mitsuba's wheel builds Embree's API into namespace mitsuba (C++ names). */
RTC_NAMESPACE_USE

static float *read_floats(const char *path, size_t per_item, size_t *items) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "cannot open %s\n", path);
        exit(1);
    }
    fseek(f, 0, SEEK_END);
    long bytes = ftell(f);
    fseek(f, 0, SEEK_SET);
    *items = (size_t)bytes / (4 * per_item);
    float *data = (float *)malloc((size_t)bytes);
    if (!data || fread(data, 1, (size_t)bytes, f) != (size_t)bytes) {
        fprintf(stderr, "cannot read %s\n", path);
        exit(1);
    }
    fclose(f);
    return data;
}

static RTCScene scene;
static const float *rays;
static float *found; /* Embree's distance per ray, negative for a miss */

struct job {
    size_t begin, end;
    int width;
};

static void trace_one(size_t i) {
    const float *r = rays + 8 * i;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    rh.ray.org_x = r[0];
    rh.ray.org_y = r[1];
    rh.ray.org_z = r[2];
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = r[3];
    rh.ray.dir_x = r[4];
    rh.ray.dir_y = r[5];
    rh.ray.dir_z = r[6];
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &ctx, &rh);
    found[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1.0f : rh.ray.tfar;
}

/* One packet of W rays starting at ray `begin` (lanes past `end` off). */
#define PACKET(W, TYPE, CALL)                                                  \
    static void trace_##W(size_t begin, size_t end) {                          \
        struct RTCIntersectContext ctx;                                        \
        rtcInitIntersectContext(&ctx);                                         \
        TYPE rh;                                                               \
        int valid[W];                                                          \
        for (int k = 0; k < W; k++) {                                          \
            size_t i = begin + (size_t)k;                                      \
            valid[k] = i < end ? -1 : 0;                                       \
            const float *r = rays + 8 * (i < end ? i : begin);                 \
            rh.ray.org_x[k] = r[0];                                            \
            rh.ray.org_y[k] = r[1];                                            \
            rh.ray.org_z[k] = r[2];                                            \
            rh.ray.tnear[k] = 0.0f;                                            \
            rh.ray.tfar[k] = r[3];                                             \
            rh.ray.dir_x[k] = r[4];                                            \
            rh.ray.dir_y[k] = r[5];                                            \
            rh.ray.dir_z[k] = r[6];                                            \
            rh.ray.time[k] = 0.0f;                                             \
            rh.ray.mask[k] = 0xffffffffu;                                      \
            rh.ray.id[k] = 0;                                                  \
            rh.ray.flags[k] = 0;                                               \
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                        \
            rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;                     \
        }                                                                      \
        CALL(valid, scene, &ctx, &rh);                                         \
        for (int k = 0; k < W && begin + (size_t)k < end; k++)                 \
            found[begin + (size_t)k] = rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID \
                                           ? -1.0f                             \
                                           : rh.ray.tfar[k];                   \
    }
PACKET(4, struct RTCRayHit4, rtcIntersect4)
PACKET(8, struct RTCRayHit8, rtcIntersect8)
PACKET(16, struct RTCRayHit16, rtcIntersect16)

static void *run_job(void *arg) {
    const struct job *j = (const struct job *)arg;
    size_t w = (size_t)j->width;
    for (size_t i = j->begin; i < j->end; i += w) {
        size_t end = i + w < j->end ? i + w : j->end;
        switch (j->width) {
        case 1: trace_one(i); break;
        case 4: trace_4(i, end); break;
        case 8: trace_8(i, end); break;
        default: trace_16(i, end); break;
        }
    }
    return NULL;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int by_value(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    if (argc != 6) {
        fprintf(stderr, "usage: %s TRIS RAYS HITS RUNS THREADS\n", argv[0]);
        return 2;
    }
    size_t n_tris, n_rays, n_hits;
    float *tris = read_floats(argv[1], 9, &n_tris);
    rays = read_floats(argv[2], 8, &n_rays);
    float *want = read_floats(argv[3], 1, &n_hits);
    int runs = atoi(argv[4]), threads = atoi(argv[5]);
    if (n_hits != n_rays || runs < 1 || threads < 1 || threads > 64) {
        fprintf(stderr, "bad input: %zu rays, %zu hits, %d runs, %d threads\n", n_rays,
                n_hits, runs, threads);
        return 2;
    }
    found = (float *)malloc(4 * n_rays);

    RTCDevice device = rtcNewDevice(NULL);
    scene = rtcNewScene(device);
    /* As Mitsuba 3 builds its Embree scene (accel_embree.inl). */
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = (float *)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), 3 * n_tris);
    unsigned *idx = (unsigned *)rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                            3 * sizeof(unsigned), n_tris);
    memcpy(v, tris, 9 * 4 * n_tris);
    for (unsigned i = 0; i < 3 * n_tris; i++) idx[i] = i;
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    double t0 = now();
    rtcCommitScene(scene);
    printf("    Embree: %zu triangles, built in %.1f ms\n", n_tris, 1e3 * (now() - t0));

    const int widths[] = {1, 4, 8, 16};
    for (int wi = 0; wi < 4; wi++) {
        int w = widths[wi];
        double *rate = (double *)malloc(sizeof(double) * (size_t)runs);
        for (int run = -1; run < runs; run++) { /* run -1 warms up */
            pthread_t tid[64];
            struct job jobs[64];
            size_t chunk = (n_rays + (size_t)threads - 1) / (size_t)threads;
            chunk = (chunk + 15) / 16 * 16;
            double start = now();
            for (int t = 0; t < threads; t++) {
                size_t b = (size_t)t * chunk;
                jobs[t].begin = b < n_rays ? b : n_rays;
                jobs[t].end = b + chunk < n_rays ? b + chunk : n_rays;
                jobs[t].width = w;
                pthread_create(&tid[t], NULL, run_job, &jobs[t]);
            }
            for (int t = 0; t < threads; t++) pthread_join(tid[t], NULL);
            if (run >= 0) rate[run] = (double)n_rays / (now() - start) / 1e6;
        }
        qsort(rate, (size_t)runs, sizeof(double), by_value);
        size_t agree = 0;
        for (size_t i = 0; i < n_rays; i++) {
            float a = found[i], b = want[i];
            if ((a < 0.0f && b < 0.0f) ||
                (a >= 0.0f && b >= 0.0f && fabsf(a - b) <= 1e-4f * fmaxf(1.0f, b)))
                agree++;
        }
        printf("    Embree rtcIntersect%-2d %8.2f Mrays/s (median of %d, %.2f-%.2f), "
               "%.3f%% agree with vkpt\n",
               w, rate[runs / 2], runs, rate[0], rate[runs - 1],
               100.0 * (double)agree / (double)n_rays);
        free(rate);
    }
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    return 0;
}
