// exact_sphere_hit and its four-lane form. The AVX2 version does exact_sphere_hit's operations in the
// same order, each correctly rounded by IEEE 754, with its branches as per-lane selections. It uses no
// FMA, and the scalar code contracts none (x86-64's baseline has no FMA, and harness/CMakeLists.txt
// builds this file with -ffp-contract=off should a build enable it), so each lane's bits equal
// exact_sphere_hit's (tests/test_sphere_hits.cpp). The tracer completes a group's sphere hits together:
// one at a time, each hit's square roots and divisions waited on one another
// (docs/reference_throughput.md).
#include <caustics/frame/sphere_hits.hpp>

#include <caustics/util/target_clones.hpp>

#include <cmath>
#include <utility>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define CAUSTICS_SPHERE_AVX2 1
#include <immintrin.h>
#endif

namespace caustics {

SphereHit exact_sphere_hit(const glm::dvec3& center, double radius, const glm::dvec3& origin, const glm::dvec3& dir,
                           double t_embree) {
    double t = t_embree;
    const glm::dvec3 oc = origin - center;
    const double a = glm::dot(dir, dir);
    const double b = glm::dot(oc, dir);
    const double c = glm::dot(oc, oc) - radius * radius;
    const double disc = b * b - a * c;
    if (disc >= 0.0) {
        const double s = std::sqrt(disc);
        // Numerically stable pair of roots.
        const double q = b > 0.0 ? -(b + s) : -(b - s);
        double t0 = q / a, t1 = q != 0.0 ? c / q : t0;
        if (t0 > t1) std::swap(t0, t1);
        const double refined = std::abs(t0 - t) < std::abs(t1 - t) ? t0 : t1;
        if (refined > 0.0) t = refined;
    }
    const glm::dvec3 position = origin + t * dir;
    return {t, position, glm::normalize(position - center)};
}

namespace {

void scalar_hits(const glm::dvec3& center, double radius, std::size_t first, std::size_t n, const SphereHitLanes& l) {
    for (std::size_t k = first; k < n; ++k) {
        const SphereHit h = exact_sphere_hit(center, radius, {l.ox[k], l.oy[k], l.oz[k]}, {l.dx[k], l.dy[k], l.dz[k]}, l.t[k]);
        l.t[k] = h.t;
        l.px[k] = h.position.x, l.py[k] = h.position.y, l.pz[k] = h.position.z;
        l.nx[k] = h.normal.x, l.ny[k] = h.normal.y, l.nz[k] = h.normal.z;
    }
}

#if defined(CAUSTICS_SPHERE_AVX2)

// (ax bx + ay by) + az bz, as glm::dot adds a dvec3's products.
__attribute__((target("avx2"))) inline __m256d dot3(__m256d ax, __m256d ay, __m256d az, __m256d bx, __m256d by,
                                                    __m256d bz) {
    return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(ax, bx), _mm256_mul_pd(ay, by)), _mm256_mul_pd(az, bz));
}

__attribute__((target("avx2"))) std::size_t avx2_hits(const glm::dvec3& center, double radius, std::size_t n,
                                                      const SphereHitLanes& l) {
    const __m256d cx = _mm256_set1_pd(center.x), cy = _mm256_set1_pd(center.y), cz = _mm256_set1_pd(center.z);
    const __m256d r2 = _mm256_set1_pd(radius * radius), zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
    const __m256d sign = _mm256_set1_pd(-0.0);
    std::size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        const __m256d ox = _mm256_loadu_pd(l.ox + k), oy = _mm256_loadu_pd(l.oy + k), oz = _mm256_loadu_pd(l.oz + k);
        const __m256d dx = _mm256_loadu_pd(l.dx + k), dy = _mm256_loadu_pd(l.dy + k), dz = _mm256_loadu_pd(l.dz + k);
        __m256d t = _mm256_loadu_pd(l.t + k);
        const __m256d ocx = _mm256_sub_pd(ox, cx), ocy = _mm256_sub_pd(oy, cy), ocz = _mm256_sub_pd(oz, cz);
        const __m256d a = dot3(dx, dy, dz, dx, dy, dz);
        const __m256d b = dot3(ocx, ocy, ocz, dx, dy, dz);
        const __m256d c = _mm256_sub_pd(dot3(ocx, ocy, ocz, ocx, ocy, ocz), r2);
        const __m256d disc = _mm256_sub_pd(_mm256_mul_pd(b, b), _mm256_mul_pd(a, c));
        const __m256d real = _mm256_cmp_pd(disc, zero, _CMP_GE_OQ);
        const __m256d s = _mm256_sqrt_pd(disc);
        // q = b > 0 ? -(b + s) : -(b - s), negation as a sign flip.
        const __m256d q = _mm256_xor_pd(
            _mm256_blendv_pd(_mm256_sub_pd(b, s), _mm256_add_pd(b, s), _mm256_cmp_pd(b, zero, _CMP_GT_OQ)), sign);
        const __m256d t0 = _mm256_div_pd(q, a);
        const __m256d t1 = _mm256_blendv_pd(t0, _mm256_div_pd(c, q), _mm256_cmp_pd(q, zero, _CMP_NEQ_UQ));
        const __m256d swap = _mm256_cmp_pd(t0, t1, _CMP_GT_OQ);
        const __m256d near = _mm256_blendv_pd(t0, t1, swap), far = _mm256_blendv_pd(t1, t0, swap);
        const __m256d near_closer = _mm256_cmp_pd(_mm256_andnot_pd(sign, _mm256_sub_pd(near, t)),
                                                  _mm256_andnot_pd(sign, _mm256_sub_pd(far, t)), _CMP_LT_OQ);
        const __m256d refined = _mm256_blendv_pd(far, near, near_closer);
        t = _mm256_blendv_pd(t, refined, _mm256_and_pd(real, _mm256_cmp_pd(refined, zero, _CMP_GT_OQ)));
        const __m256d px = _mm256_add_pd(ox, _mm256_mul_pd(t, dx)), py = _mm256_add_pd(oy, _mm256_mul_pd(t, dy));
        const __m256d pz = _mm256_add_pd(oz, _mm256_mul_pd(t, dz));
        // normalize(v) = v * (1 / sqrt(dot(v, v))), as glm computes it.
        const __m256d vx = _mm256_sub_pd(px, cx), vy = _mm256_sub_pd(py, cy), vz = _mm256_sub_pd(pz, cz);
        const __m256d inverse = _mm256_div_pd(one, _mm256_sqrt_pd(dot3(vx, vy, vz, vx, vy, vz)));
        _mm256_storeu_pd(l.t + k, t);
        _mm256_storeu_pd(l.px + k, px), _mm256_storeu_pd(l.py + k, py), _mm256_storeu_pd(l.pz + k, pz);
        _mm256_storeu_pd(l.nx + k, _mm256_mul_pd(vx, inverse)), _mm256_storeu_pd(l.ny + k, _mm256_mul_pd(vy, inverse));
        _mm256_storeu_pd(l.nz + k, _mm256_mul_pd(vz, inverse));
    }
    return k;
}

#endif

}  // namespace

void exact_sphere_hits(const glm::dvec3& center, double radius, std::size_t n, const SphereHitLanes& lanes) {
    std::size_t done = 0;
#if defined(CAUSTICS_SPHERE_AVX2)
    if (cpu_has_avx2()) done = avx2_hits(center, radius, n, lanes);
#endif
    scalar_hits(center, radius, done, n, lanes);
}

}  // namespace caustics
