#pragma once
// The exact hit of a ray on an analytic sphere, refined from Embree's single-precision distance
// (RayTracer: spheres are tessellated for Embree and intersected exactly here), one at a time or for a
// group of hits together.
#include <cstddef>

#include <glm/glm.hpp>

namespace caustics {

struct SphereHit {
    double t;                // the exact distance along dir (Embree's where no root is real or positive)
    glm::dvec3 position;     // origin + t dir
    glm::dvec3 normal;       // unit, outward: normalize(position - center)
};

// The root of |origin + t dir - center| = radius nearest Embree's distance `t_embree`, in double, by the
// numerically stable pair of roots; Embree's distance where the discriminant is negative or the nearest
// root is not positive.
SphereHit exact_sphere_hit(const glm::dvec3& center, double radius, const glm::dvec3& origin, const glm::dvec3& dir,
                           double t_embree);

// The rays of one group on one sphere, one array per coordinate (in: o, d, t; out: t, p, n), n entries each.
struct SphereHitLanes {
    const double *ox, *oy, *oz, *dx, *dy, *dz;
    double *t;   // Embree's distance in, the exact one out
    double *px, *py, *pz, *nx, *ny, *nz;
};

// exact_sphere_hit for n rays: the same bits, four rays at a time with AVX2 where the CPU has it.
void exact_sphere_hits(const glm::dvec3& center, double radius, std::size_t n, const SphereHitLanes& lanes);

}  // namespace caustics
