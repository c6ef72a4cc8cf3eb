// Warps from [0,1)^2 to directions and points, in triples: sample, pdf,
// invert (twin: src/cpu/common/sampling.rs).
#ifndef SAMPLING_GLSL
#define SAMPLING_GLSL

#define PI 3.14159265358979323846
#define INV_PI 0.31830988618379067154
#define FLT_MAX 3.402823466e38

// Orthonormal basis around unit n (Duff et al., JCGT 2017).
void build_onb(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Concentric map of the square to the unit disk (Shirley and Chiu 1997).
vec2 sample_concentric_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    // The angle is π/4 (y/x) about the x axis and π/2 − π/4 (x/y) about y,
    // where its cosine and sine are the sine and cosine of π/4 (x/y).
    if (abs(o.x) > abs(o.y)) {
        float a = (PI / 4.0) * (o.y / o.x);
        return o.x * vec2(cos(a), sin(a));
    }
    float a = (PI / 4.0) * (o.x / o.y);
    return o.y * vec2(sin(a), cos(a));
}

// Cosine-weighted hemisphere around +z in local coordinates.
vec3 sample_cosine_hemisphere(vec2 u) {
    vec2 d = sample_concentric_disk(u);
    float z = sqrt(max(0.0, 1.0 - dot(d, d)));
    return vec3(d, z);
}

float cosine_hemisphere_pdf(float cos_theta) {
    return max(cos_theta, 0.0) * INV_PI;
}

vec3 sample_uniform_sphere(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

float uniform_sphere_pdf() {
    return 1.0 / (4.0 * PI);
}

// Barycentrics (b1, b2) uniform over a triangle (the square-root warp).
vec2 sample_uniform_triangle(vec2 u) {
    float su = sqrt(u.x);
    return vec2(1.0 - su, u.y * su);
}

// Multiple importance sampling weight for a sample from strategy f.
float power_heuristic(float f_pdf, float g_pdf) {
    float f2 = f_pdf * f_pdf;
    float g2 = g_pdf * g_pdf;
    return f2 + g2 > 0.0 ? f2 / (f2 + g2) : 0.0;
}

#endif
