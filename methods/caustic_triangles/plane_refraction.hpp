#pragma once
// Refraction of one surface vertex onto a plane receiver in single precision (caustic_triangles' plane
// path): Snell's law with the vertex normal, unpolarised Fresnel transmittance, Beer-Lambert absorption
// over the path in water, and the ray-plane intersection expressed in the receiver's map coordinates.
// Everything is relative to the plane's origin, so the float operands stay of the order of the scene's
// size and the image point carries a relative error of a few float epsilons (a few 1e-7 of the map,
// bounded in tests/test_caustic_triangles.cpp against a double-precision evaluation). Branch-light and
// call-free so that the per-vertex loop over the grid stays a straight loop.
#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

namespace caustics::caustic_triangles {

struct PlaneRefraction {
    glm::vec3 light{0.0f, 0.0f, -1.0f};   // unit direction the light travels
    float eta = 1.0f / 1.33f;             // n_air / n_water
    float ior = 1.33f;
    bool fresnel = true;
    float absorption = 0.0f;              // Ka [1/m]; 0: no attenuation
    glm::vec3 normal{0.0f, 0.0f, 1.0f};   // receiver plane through the origin (coordinates below are relative)
    glm::vec3 dual_s{1.0f, 0.0f, 0.0f}, dual_t{0.0f, 1.0f, 0.0f};   // map coordinates: s = dual_s . r
    float width = 1.0f, height = 1.0f;    // map size in bins (image = (s * width, t * height))
};

struct RefractedVertex {
    glm::vec2 image;   // receiver map coordinates in bins (NaN when lost)
    float weight;      // Fresnel transmittance * exp(-Ka * path); 0 when lost
    bool lost;         // faces away from the light, or the ray never reaches the plane
    bool outside;      // reaches the plane outside the map [0, 1]^2
};

// The refracted ray at a vertex: direction into the water and Fresnel transmittance (1 without Fresnel).
struct RefractedRay {
    glm::vec3 dir;
    float transmittance;
    bool faces_light;
};

// Snell's law at a vertex whose surface slope is `gradient` (dh/dx, dh/dy).
inline RefractedRay refract_ray(const PlaneRefraction& c, glm::vec2 gradient) {
    const float inv_len = 1.0f / std::sqrt(gradient.x * gradient.x + gradient.y * gradient.y + 1.0f);
    const glm::vec3 n(-gradient.x * inv_len, -gradient.y * inv_len, inv_len);
    const float cos_i = -glm::dot(c.light, n);
    const float sin2_t = c.eta * c.eta * (1.0f - cos_i * cos_i);
    const float cos_t = std::sqrt(std::max(0.0f, 1.0f - sin2_t));   // no total reflection entering water
    RefractedRay ray;
    ray.dir = c.eta * c.light + (c.eta * cos_i - cos_t) * n;
    ray.transmittance = 1.0f;
    if (c.fresnel) {
        const float rs = (cos_i - c.ior * cos_t) / (cos_i + c.ior * cos_t);
        const float rp = (c.ior * cos_i - cos_t) / (c.ior * cos_i + cos_t);
        ray.transmittance = 1.0f - 0.5f * (rs * rs + rp * rp);
    }
    ray.faces_light = cos_i > 0.0f;
    return ray;
}

// Follows the ray from the vertex `r` (relative to the plane's origin) to the receiver plane.
inline RefractedVertex intersect_plane(const PlaneRefraction& c, const RefractedRay& ray, glm::vec3 r) {
    const float denom = glm::dot(c.normal, ray.dir);
    const float t = std::abs(denom) > 1e-12f ? -glm::dot(c.normal, r) / denom : -1.0f;
    RefractedVertex out;
    out.lost = !ray.faces_light || !(t > 0.0f) || !std::isfinite(t);
    const glm::vec3 q = r + t * ray.dir;
    const float s = glm::dot(c.dual_s, q), u = glm::dot(c.dual_t, q);
    out.outside = !(s >= 0.0f && s <= 1.0f && u >= 0.0f && u <= 1.0f);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    out.image = out.lost ? glm::vec2(nan, nan) : glm::vec2(s * c.width, u * c.height);
    const float attenuation = c.absorption != 0.0f ? std::exp(-c.absorption * t) : 1.0f;   // exp(-0) == 1
    out.weight = out.lost ? 0.0f : ray.transmittance * attenuation;
    return out;
}

// One vertex: `gradient` the surface slope, `r` the vertex minus the plane's origin. The grid loop runs
// the two halves over short runs of vertices instead, which keeps several vertices' long dependency
// chains (two square roots, four divisions) in flight at once.
inline RefractedVertex refract_to_plane(const PlaneRefraction& c, glm::vec2 gradient, glm::vec3 r) {
    return intersect_plane(c, refract_ray(c, gradient), r);
}

}  // namespace caustics::caustic_triangles
