// Primary rays (twin: src/cpu/common/camera.rs): a pixel reconstruction filter
// sampled by filter importance sampling, then a pinhole, a thin lens with a
// round or polygonal aperture, or an orthographic projection.
#ifndef CAMERA_GLSL
#define CAMERA_GLSL

#include "loop_count.glsl"

#include "types.glsl"
#include "rng.glsl"
#include "features.glsl"
#include "sampling.glsl"
#include "motion.glsl"

// erf by Abramowitz and Stegun 7.1.26 (absolute error below 1.5e-7): GLSL
// has no erf, and both back ends must evaluate the same formula.
float filter_erf(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * abs(x));
    float poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741
                 + t * (-1.453152027 + t * 1.061405429))));
    float y = 1.0 - poly * exp(-x * x);
    return x < 0.0 ? -y : y;
}

// Normalized CDF at x in [-r, r] of one axis of the separable filter
// profile (Gaussian and Blackman-Harris; box and tent invert in closed form).
// Gaussian: exp(-x^2 / 2s^2) - exp(-r^2 / 2s^2) with s = r / 3 (reaches 0 at
// the radius). Blackman-Harris: the window over [-r, r].
float filter_cdf(uint kind, float r, float x) {
    if (kind == FILTER_GAUSSIAN) {
        float s = r / 3.0;
        float a = 1.0 / (s * sqrt(2.0));
        float edge = exp(-4.5);
        float g = s * sqrt(0.5 * PI);
        float total = 2.0 * g * filter_erf(a * r) - 2.0 * r * edge;
        return (g * (filter_erf(a * x) + filter_erf(a * r)) - edge * (x + r)) / total;
    }
    float t = (x + r) / (2.0 * r);
    float w = 2.0 * PI * t;
    return (BLACKMAN_HARRIS_A0 * t - BLACKMAN_HARRIS_A1 * sin(w) / (2.0 * PI)
            + BLACKMAN_HARRIS_A2 * sin(2.0 * w) / (4.0 * PI)
            - BLACKMAN_HARRIS_A3 * sin(3.0 * w) / (6.0 * PI)) / BLACKMAN_HARRIS_A0;
}

// One axis's offset from the pixel centre, distributed as the filter's
// normalized profile on [-r, r] (u uniform in [0, 1)).
float sample_filter_1d(uint kind, float r, float u) {
    if (kind == FILTER_BOX) return (2.0 * u - 1.0) * r;
    if (kind == FILTER_TENT) {
        return u < 0.5 ? r * (sqrt(2.0 * u) - 1.0) : r * (1.0 - sqrt(2.0 - 2.0 * u));
    }
    if (!FEATURE_FILTER_BISECTION) return 0.0;   // never reached: the host only turns it off for box and tent
    float lo = -r;
    float hi = r;
    for (uint i = 0u; i < FILTER_BISECTION_STEPS; i++) {
        COUNT_LOOP_ITERATION();
        float mid = 0.5 * (lo + hi);
        if (filter_cdf(kind, r, mid) < u) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
}

// Offset of a sample from its pixel's centre, in pixels. Every filter here
// is non-negative, so importance sampling it gives every sample weight 1 and
// samples stay independent (each lands in its own pixel's mean).
vec2 sample_filter(uint kind, float r, vec2 u) {
    return vec2(sample_filter_1d(kind, r, u.x), sample_filter_1d(kind, r, u.y));
}

// A point uniformly distributed over the aperture of circumradius 1: the
// unit disk when blades < 3, else the regular polygon with `blades` vertices
// on the unit circle, the first at angle `rotation`. ublade picks one of the
// polygon's equal triangles (centre, vertex k, vertex k + 1); u is uniform
// inside it.
vec2 sample_aperture(uint blades, float rotation, vec2 u, float ublade) {
    if (blades < 3u) return sample_concentric_disk(u);
    float n = float(blades);
    float k = min(floor(ublade * n), n - 1.0);
    float a0 = rotation + 2.0 * PI * k / n;
    float a1 = rotation + 2.0 * PI * (k + 1.0) / n;
    float s = sqrt(u.x);
    return (s * (1.0 - u.y)) * vec2(cos(a0), sin(a0)) + (s * u.y) * vec2(cos(a1), sin(a1));
}

// Pixels of the film: the rendered region's (the whole image's unless a
// region was asked for).
uint film_pixel_count(RenderParams p) {
    return p.region_width * p.region_height;
}

// Which pixel and sample a path renders. Every schedule (the wavefront's
// generate and its rng key, a per-path loop kernel, the CPU back end) maps
// its paths through this one function, so sample ranges and regions mean
// the same everywhere.
struct PathSample {
    uint film_pixel;     // index into the film (the region, row-major)
    uint pixel;          // index into the full image: camera rays and random numbers use it
    uint sample_index;   // counted from the full render's first sample
};

// Path k of a chunk that starts at film pixel `pixel_start` of the render's
// sample `sample_start` (both as in PushConstants): paths walk the film row
// by row and wrap to the next sample. The sample index adds the render's
// `sample_offset` and the pixel the region's corner, so a render of a
// sample range or a region draws exactly the random numbers, and traces
// exactly the paths, that the full render draws for those samples.
PathSample path_pixel_sample(RenderParams p, uint pixel_start, uint sample_start, uint k) {
    uint pixels = film_pixel_count(p);
    PathSample s;
    s.film_pixel = (pixel_start + k) % pixels;
    s.sample_index = p.sample_offset + sample_start + (pixel_start + k) / pixels;
    uint x = p.region_x + s.film_pixel % p.region_width;
    uint y = p.region_y + s.film_pixel / p.region_width;
    s.pixel = y * p.width + x;
    return s;
}

void generate_camera_ray(RenderParams p, uint pixel, RngKey key, out vec3 origin, out vec3 direction) {
    vec2 offset = sample_filter(p.filter_kind, p.filter_radius, rng_float2(key, DIM_CAMERA_JITTER));
    float x = float(pixel % p.width) + 0.5 + offset.x;
    float y = float(pixel / p.width) + 0.5 + offset.y;
    float sx = 2.0 * x / float(p.width) - 1.0;
    float sy = 1.0 - 2.0 * y / float(p.height);
    vec3 position = p.cam_position;
    vec3 right = p.cam_right;
    vec3 up = p.cam_up;
    vec3 forward = p.cam_forward;
    if (motion_on() && p.motion_camera_base != MOTION_CAMERA_STILL) {
        moving_camera(path_time(key), position, right, up, forward);
    }
    vec3 film = (sx * p.tan_half_fov * p.aspect) * right + (sy * p.tan_half_fov) * up;
    if (p.projection == PROJECTION_ORTHOGRAPHIC) {
        origin = position + film;
        direction = forward;
        return;
    }
    // The pinhole direction has length 1 along the view axis, so it meets
    // the focus plane at focus_distance times itself.
    vec3 pinhole = forward + film;
    if (!FEATURE_THIN_LENS || p.lens_radius <= 0.0) {
        origin = position;
        direction = normalize(pinhole);
        return;
    }
    vec2 lens = p.lens_radius * sample_aperture(p.aperture_blades, p.blade_rotation,
                                                rng_float2(key, DIM_CAMERA_LENS),
                                                rng_float(key, DIM_CAMERA_BLADE));
    vec3 lens_offset = lens.x * right + lens.y * up;
    origin = position + lens_offset;
    direction = normalize(p.focus_distance * pinhole - lens_offset);
}

#endif
