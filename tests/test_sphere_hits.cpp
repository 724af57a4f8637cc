// exact_sphere_hits (harness/frame/sphere_hits.cpp) against exact_sphere_hit, bit for bit, on rays from
// outside and inside, grazing, missing and behind; and exact_sphere_hit against the sphere's equation.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <caustics/frame/sphere_hits.hpp>
#include <caustics/util/target_clones.hpp>

using namespace caustics;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

const glm::dvec3 kCenter{0.3, -0.2, 1.1};
constexpr double kRadius = 0.75;

struct Ray {
    glm::dvec3 o, d;
    double t;   // a single-precision distance as Embree gives it (or any other)
};

// Rays of every kind the reference meets, each with a float-rounded exact distance (or a wrong one).
std::vector<Ray> probe_rays() {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    auto unit = [&] {
        for (;;) {
            const glm::dvec3 v(u(rng), u(rng), u(rng));
            if (glm::dot(v, v) > 1e-6 && glm::dot(v, v) <= 1.0) return glm::normalize(v);
        }
    };
    std::vector<Ray> rays;
    for (int k = 0; k < 3000; ++k) {
        const int kind = k % 5;
        glm::dvec3 o, d;
        if (kind == 0) {   // from outside towards the sphere
            o = kCenter + 3.0 * unit();
            d = glm::normalize(kCenter + 0.9 * kRadius * unit() - o);
        } else if (kind == 1) {   // from inside (a refracted photon), unnormalised directions too
            o = kCenter + 0.9 * kRadius * unit() * std::abs(u(rng));
            d = unit() * (1.0 + 0.5 * u(rng));
        } else if (kind == 2) {   // grazing: towards a point just inside or outside the silhouette
            o = kCenter + 4.0 * unit();
            const glm::dvec3 axis = glm::normalize(kCenter - o), side = glm::normalize(glm::cross(axis, unit()));
            d = glm::normalize(kCenter + kRadius * (1.0 + 1e-9 * u(rng)) * side - o);
        } else if (kind == 3) {   // from the surface (a hit's origin), outward or inward
            const glm::dvec3 n = unit();
            o = kCenter + kRadius * n;
            d = unit();
        } else {   // away from the sphere: both roots behind
            o = kCenter + 2.0 * unit();
            d = glm::normalize(o - kCenter);
        }
        const glm::dvec3 oc = o - kCenter;
        const double a = glm::dot(d, d), b = glm::dot(oc, d), c = glm::dot(oc, oc) - kRadius * kRadius;
        const double disc = b * b - a * c;
        double t = disc >= 0.0 ? (-b - std::sqrt(disc)) / a : 1.0;
        if (t <= 0.0 && disc >= 0.0) t = (-b + std::sqrt(disc)) / a;
        if (k % 7 == 0) t = 10.0 * std::abs(u(rng));   // a distance no root is near
        rays.push_back({o, d, static_cast<double>(static_cast<float>(t))});
    }
    return rays;
}

}  // namespace

TEST(SphereHits, GroupsSameBitsAsOneAtATime) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2: exact_sphere_hits is exact_sphere_hit ray by ray";
    std::vector<Ray> rays = probe_rays();
    // The branches' edges: a tangent ray from the surface (b = 0 and disc = 0, so q = 0 and t1 = t0),
    // Embree's distance exactly between the two roots (a tie the far root wins), at a root, NaN, and a
    // ray whose roots are both behind it.
    const glm::dvec3 side = kCenter + glm::dvec3(kRadius, 0.0, 0.0);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    rays.push_back({side, {0.0, 1.0, 0.0}, 0.5});
    rays.push_back({side, {0.0, 0.0, -1.0}, 0.0});
    rays.push_back({kCenter + glm::dvec3(0.0, 0.0, 2.0), {0.0, 0.0, -1.0}, 2.0});   // roots 1.25, 2.75
    rays.push_back({kCenter + glm::dvec3(0.0, 0.0, 2.0), {0.0, 0.0, -1.0}, 1.25});
    rays.push_back({kCenter + glm::dvec3(0.0, 0.0, 2.0), {0.0, 0.0, -1.0}, nan});
    rays.push_back({kCenter + glm::dvec3(0.0, 0.0, 2.0), {0.0, 0.0, 1.0}, 1.0});
    rays.push_back({kCenter, {0.0, 0.0, 1.0}, 0.75});
    const std::size_t n = rays.size();
    std::vector<double> ox(n), oy(n), oz(n), dx(n), dy(n), dz(n), t(n), px(n), py(n), pz(n), nx(n), ny(n), nz(n);
    for (std::size_t k = 0; k < n; ++k) {
        ox[k] = rays[k].o.x, oy[k] = rays[k].o.y, oz[k] = rays[k].o.z;
        dx[k] = rays[k].d.x, dy[k] = rays[k].d.y, dz[k] = rays[k].d.z;
        t[k] = rays[k].t;
    }
    // Runs of 1 to 9: the four-ray groups and the scalar tail.
    for (std::size_t first = 0, run = 1; first < n; first += run, run = run % 9 + 1) {
        const std::size_t m = std::min(run, n - first);
        exact_sphere_hits(kCenter, kRadius, m,
                          {ox.data() + first, oy.data() + first, oz.data() + first, dx.data() + first, dy.data() + first,
                           dz.data() + first, t.data() + first, px.data() + first, py.data() + first, pz.data() + first,
                           nx.data() + first, ny.data() + first, nz.data() + first});
    }
    std::size_t mismatches = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const SphereHit h = exact_sphere_hit(kCenter, kRadius, rays[k].o, rays[k].d, rays[k].t);
        const bool same = same_bits(t[k], h.t) && same_bits(px[k], h.position.x) && same_bits(py[k], h.position.y) &&
                          same_bits(pz[k], h.position.z) && same_bits(nx[k], h.normal.x) &&
                          same_bits(ny[k], h.normal.y) && same_bits(nz[k], h.normal.z);
        if (!same && ++mismatches <= 5)
            ADD_FAILURE() << "ray " << k << ": t " << t[k] << " against " << h.t << ", normal (" << nx[k] << ", " << ny[k]
                          << ", " << nz[k] << ") against (" << h.normal.x << ", " << h.normal.y << ", " << h.normal.z << ")";
    }
    EXPECT_EQ(mismatches, 0u) << "of " << n << " rays";
}

TEST(SphereHits, RefinedHitsLieOnTheSphere) {
    // Where Embree's distance is within 1e-6 of a root, the refined point satisfies the sphere's equation
    // to double precision and the normal is the unit radius vector; behind the origin nothing is refined.
    int refined = 0;
    for (const Ray& r : probe_rays()) {
        const SphereHit h = exact_sphere_hit(kCenter, kRadius, r.o, r.d, r.t);
        EXPECT_EQ(h.position, r.o + h.t * r.d);
        EXPECT_NEAR(glm::length(h.normal), 1.0, 1e-15);
        if (h.t == r.t) continue;   // no positive real root: Embree's distance kept
        ++refined;
        EXPECT_GT(h.t, 0.0);
        EXPECT_NEAR(glm::length(h.position - kCenter), kRadius, 1e-14) << "t " << h.t;
        EXPECT_LT(glm::length(h.normal - (h.position - kCenter) / kRadius), 1e-14);
    }
    EXPECT_GT(refined, 2000);
}
