#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
// path_loop: the per-path loop schedule, for CPU-class Vulkan devices
// (lavapipe), as Cycles X runs one loop per path on CPUs. Each invocation
// traces paths from the camera to their end, one bounce per loop iteration,
// with the path in registers, and takes the chunk's next unstarted path slot
// (COUNTER_NEXT_PATH) when one ends, so a SIMD group's lanes stay busy. It
// calls what the wavefront kernels call (generate_camera_ray, closest_hit,
// shade_path, shadow_blocker) with the same random numbers: same pixels.
//
// lavapipe ends a SIMD group's loops silently after 65,535 iterations in
// all. So each lane counts its loop iterations (loop_count.glsl), the
// subgroup adds them up after every bounce (at least the group's count:
// every group iteration has a lane in it), and before a bounce each lane
// gets an equal share of what is left of pc.loop_budget: its traversal may
// do at most as much work as fits in the share beside the worst case of the
// bounce's other loops. A path whose trace runs out, and every path once the
// share is below PATH_LOOP_MIN_WORK, is parked: its state from before the
// bounce goes to the path-state arrays and ray queue 0, and the wavefront
// kernels finish it from that bounce (with BVH_MAX_ITERATIONS). The host
// dispatches path_loop until every slot was taken.
// reads: params, scene; writes: radiance and AOVs of finished paths, path
// state and ray queue 0 of parked ones, counters.
#define COUNT_LOOP_ITERATIONS
#include "bindings.glsl"
#include "integrator.glsl"
#include "trace.glsl"
#include "queues.glsl"
#include "path_state.glsl"
#include "aov.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

// The most loop iterations one bounce may take besides traversal: light and
// environment CDF bisections, spherical lights and suns, thin-film sums, the
// camera filter's bisection when a path starts, and the loop's own.
uint other_loop_iterations() {
    return 256u + 4u * (light_params.num_spheres + light_params.num_suns);
}

// Hands path `path` to the wavefront kernels at `bounce`, as shade.comp would
// have left it for the extension ray of that bounce.
void park(uint path, PathState s, uint bounce, vec3 radiance, AovSample a) {
    write_path_origin(path, s.origin, s.prev_pdf);
    write_path_direction(path, s.direction, s.dispersion_channel, s.prev_normal);
    write_path_throughput(path, s.throughput, s.eta_scale);
    write_path_radiance(path, radiance, bounce);
    if (FEATURE_AOV && params.aov != 0u && bounce > 0u) {
        vec4 a0, a1;
        aov_pack(a, a0, a1);
        write_path_aov(path, a0, a1);
    }
    ray_queue[queue_push(COUNTER_RAYS_0)] = path;
}

void add_wide(uint lo, uint n) {
    uint before = atomicAdd(counters[lo], n);
    if (before + n < before) atomicAdd(counters[lo + 1u], 1u);
}

void main() {
    bool aov = FEATURE_AOV && params.aov != 0u;
    uint other = other_loop_iterations();
    uint spent = 0u;   // the subgroup's loop iterations so far, the same in every lane
    uint extension_rays = 0u;
    uint shadow_rays = 0u;
    bool live = false;
    uint path = 0u;
    uint bounce = 0u;
    PathState s;
    RngKey key;
    float time = 0.0;   // the path's moment in the shutter (motion.glsl)
    vec3 radiance = vec3(0.0);
    AovSample a;
    while (true) {
        COUNT_LOOP_ITERATION();
        // This lane's share of what is left, for two traces of at most
        // 3 * max_work + 5 iterations and the other loops.
        uint lanes = subgroupBallotBitCount(subgroupBallot(true));
        uint share = (pc.loop_budget - min(spent, pc.loop_budget)) / lanes;
        uint max_work = share > other + 10u ? min((share - other - 10u) / 6u, BVH_MAX_ITERATIONS) : 0u;
        if (max_work < PATH_LOOP_MIN_WORK) break;
        if (!live) {
            path = queue_push(COUNTER_NEXT_PATH);
            if (path >= pc.count) break;
            PathSample ps = path_pixel_sample(params, pc.pixel_start, pc.sample_start, path);
            key = rng_sampler_key(params.rng_sampler, ps.pixel, ps.sample_index, params.seed);
            vec3 o, d;
            generate_camera_ray(params, ps.pixel, key, o, d);
            s = camera_path_state(o, d);
            time = motion_on() ? path_time(key) : 0.0;
            radiance = vec3(0.0);
            bounce = 0u;
            live = true;
        }
        uint seed = FEATURE_ALPHA_MASK ? rng_coverage_seed(key, bounce, 0u) : 0u;
        Hit hit = closest_hit(s.origin, s.direction, seed, time, max_work);
        bool out_of_work = hit.triangle == OVERFLOW_HIT;
        ShadeResult r;
        bool unblocked = false;
        if (!out_of_work) {
            r = shade_path(s, hit, key, bounce);
            if (r.shadow) {
                seed = FEATURE_ALPHA_MASK ? rng_coverage_seed(key, bounce, 1u) : 0u;
                uint blocker = shadow_blocker(r.shadow_origin, r.shadow_direction, r.shadow_t_max,
                                              seed, time, max_work);
                out_of_work = blocker == OVERFLOW_HIT;
                unblocked = blocker == NO_HIT;
            }
        }
        spent += subgroupAdd(loop_iterations);
        loop_iterations = 0u;
        if (out_of_work) {
            // The wavefront redoes this bounce with BVH_MAX_ITERATIONS.
            park(path, s, bounce, radiance, a);
            live = false;
            continue;
        }
        extension_rays++;
        if (aov) aov_after_bounce(a, bounce, hit, r);
        radiance += r.emitted;
        if (r.shadow) {
            shadow_rays++;
            if (unblocked) radiance += r.shadow_contribution;
        }
        if (r.next) {
            s = r.next_state;
            bounce++;
        } else {
            write_path_radiance(path, radiance, bounce + 1u);
            if (aov) {
                vec4 a0, a1;
                aov_pack(a, a0, a1);
                write_path_aov(path, a0, a1);
            }
            live = false;
        }
    }
    if (live) park(path, s, bounce, radiance, a);
    uint e = subgroupAdd(extension_rays);
    uint sh = subgroupAdd(shadow_rays);
    if (subgroupElect()) {
        add_wide(COUNTER_EXTENSION_RAYS_LO, e);
        add_wide(COUNTER_SHADOW_RAYS_LO, sh);
    }
}
