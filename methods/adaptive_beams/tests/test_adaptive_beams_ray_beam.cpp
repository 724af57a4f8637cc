// RayBeam (the ray-beam integral with the beam's constants hoisted per camera origin) against the
// point-by-point formulation on random beams: diverging, converging and passing a focus, seen from random
// origins inside and outside them, with 1 to 4 Gauss points. The two regroup the same sums (edge
// functions as polynomials in s instead of a cross-section per node, one exponential instead of two), so
// they agree to rounding: relative 1e-9 of the larger value, except where a rounding difference moves a
// crossing root across an end of the slab (a sub-interval split or not), which changes only the
// quadrature error of that piece; those are counted and must stay rare and within that error (1e-3).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "../beam.hpp"
#include "../ray_beam.hpp"

using namespace caustics;
using namespace caustics::adaptive_beams;

namespace {

glm::dvec3 random_unit(std::mt19937_64& rng) {
    std::normal_distribution<double> n;
    return glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
}

// Three edge rays from a small triangle around the origin towards +z, each aimed at a point at height
// `focus` spread by `spread` (spread 0: a true focus; focus < 0: diverging).
bool random_beam(std::mt19937_64& rng, Beam& b) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double focus = 2.0 * u(rng) + (u(rng) > 0 ? 1.0 : -3.0), spread = 0.05 * (u(rng) + 1.0);
    std::array<EdgeRay, 3> e;
    for (int i = 0; i < 3; ++i) {
        const double a = 2.0944 * i + 0.3 * u(rng);
        const glm::dvec3 start{0.3 * std::cos(a), 0.3 * std::sin(a), 0.05 * u(rng)};
        const glm::dvec3 target{spread * u(rng), spread * u(rng), focus};
        glm::dvec3 d = glm::normalize(target - start);
        if (focus < 0) d = -d;
        e[i] = {start, d, 2.0 + 2.0 * (u(rng) + 1.0), 0.5 + 0.25 * (u(rng) + 1.0)};
    }
    return make_beam(e, 1.0 + u(rng) * 0.5, -1, 1e-3, b) == BeamStatus::Ok;
}

}  // namespace

TEST(AdaptiveBeamsRayBeam, EqualsThePointwiseIntegralToRounding) {
    std::mt19937_64 rng(18);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const MediumCoefficients medium{0.1, 0.4, 0.3};
    int beams = 0, hits = 0, exact = 0, split = 0, flipped = 0;
    while (beams < 400) {
        Beam b;
        if (!random_beam(rng, b)) continue;
        ++beams;
        flipped += b.flipped;
        // Origins: around the beam and inside it (the camera among the beams).
        for (int o_try = 0; o_try < 4; ++o_try) {
            const glm::dvec3 o = o_try == 0 ? glm::dvec3(0.02 * u(rng), 0.02 * u(rng), 1.0 + u(rng))
                                            : glm::dvec3(3.0 * u(rng), 3.0 * u(rng), 2.0 + 3.0 * u(rng));
            const RayBeam seen(b, o, medium);
            for (int r = 0; r < 64; ++r) {
                // Rays aimed near the beam's axis so that most of them cross it.
                const glm::dvec3 target{0.4 * u(rng), 0.4 * u(rng), 1.0 + 2.0 * u(rng)};
                glm::dvec3 w = target - o;
                if (glm::length(w) < 1e-6) w = random_unit(rng);
                w = glm::normalize(w);
                const double s_max = r % 3 == 0 ? 1e30 : 6.0 * (u(rng) + 1.0);
                const int samples = 1 + r % 4;
                BeamCounters c1, c2;
                const double fast = seen.radiance(w, s_max, samples, c1, 0.01);
                const double slow = volume_radiance_pointwise(b, medium, o, w, s_max, samples, c2, 0.01);
                ASSERT_TRUE(std::isfinite(fast));
                if (slow > 0.0 || fast > 0.0) ++hits;
                if (fast == slow) ++exact;
                const double scale = std::max(std::abs(fast), std::abs(slow));
                if (std::abs(fast - slow) <= 1e-9 * scale) continue;
                ++split;
                EXPECT_LE(std::abs(fast - slow), 1e-3 * scale) << "beam " << beams << " ray " << r;
            }
        }
    }
    std::printf("ray-beam: %d beams (%d through a focus), %d rays inside, %d equal bit for bit, %d differ > 1e-9\n",
                beams, flipped, hits, exact, split);
    EXPECT_GT(flipped, 50);
    EXPECT_GT(hits, 20000);
    EXPECT_LE(split, hits / 1000);
}

TEST(AdaptiveBeamsRayBeam, LanesEqualTheOneRayFormToTheBit) {
    // radiance_lanes on batches of 1 to 13 rays (full and partial groups of four lanes, nodes carried over
    // between groups) against radiance ray by ray, with the clamp counts: the same values and counts, bit
    // for bit. Rays parallel to the slab (a bounding-sphere interval) and beams past a focus included.
    if (!RayBeam::lanes_available()) GTEST_SKIP() << "this CPU has no AVX2: radiance_lanes takes the one-ray form";
    std::mt19937_64 rng(29);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const MediumCoefficients medium{0.1, 0.4, 0.3};
    int beams = 0, rays = 0, nonzero = 0, parallel = 0, flipped = 0;
    long long clamped = 0;
    std::vector<glm::dvec3> w;
    std::vector<double> s_max, lanes;
    while (beams < 300) {
        Beam b;
        if (!random_beam(rng, b)) continue;
        ++beams;
        flipped += b.flipped;
        const glm::dvec3 o = beams % 2 ? glm::dvec3(0.02 * u(rng), 0.02 * u(rng), 1.0 + u(rng))
                                       : glm::dvec3(3.0 * u(rng), 3.0 * u(rng), 2.0 + 3.0 * u(rng));
        const RayBeam seen(b, o, medium);
        const int n = 1 + beams % 13;
        w.clear(), s_max.clear();
        for (int r = 0; r < n; ++r) {
            glm::dvec3 d = glm::normalize(glm::dvec3(0.4 * u(rng), 0.4 * u(rng), 1.0 + 2.0 * u(rng)) - o);
            if (r == 3) {   // parallel to the beam's slab
                d -= glm::dot(d, b.n) * b.n;
                d = glm::length(d) > 1e-9 ? glm::normalize(d) : glm::normalize(glm::cross(b.n, glm::dvec3(1, 0, 0)));
                ++parallel;
            }
            w.push_back(d);
            s_max.push_back(r % 3 == 0 ? 1e30 : 6.0 * (u(rng) + 1.0));
        }
        const int samples = 1 + beams % 4;
        lanes.assign(static_cast<std::size_t>(n), -1.0);
        BeamCounters c_lanes, c_one;
        seen.radiance_lanes(w.data(), s_max.data(), n, samples, c_lanes, 0.01, lanes.data());
        for (int r = 0; r < n; ++r) {
            const double one = seen.radiance(w[r], s_max[r], samples, c_one, 0.01);
            ASSERT_EQ(std::memcmp(&one, &lanes[r], sizeof one), 0) << "beam " << beams << " ray " << r << ": " << one << " vs " << lanes[r];
            nonzero += one != 0.0;
            ++rays;
        }
        EXPECT_EQ(c_lanes.clamped, c_one.clamped);
        clamped += c_one.clamped;
    }
    std::printf("%d rays against %d beams (%d past a focus, %d rays parallel to the slab): %d non-zero, %lld clamped\n",
                rays, beams, flipped, parallel, nonzero, clamped);
    EXPECT_GT(nonzero, rays / 4);
    EXPECT_GT(flipped, 10);
    EXPECT_GT(clamped, 0);
}

TEST(AdaptiveBeamsRayBeam, SinglePrecisionFollowsTheDoubleIntegral) {
    // radiance_each_single (volume_precision=float: what float lanes would compute) against the double
    // integral on the random beams above: finite and non-negative everywhere, and close to double where
    // the beam is well conditioned. Float's rounding of the edge functions' metre-sized cross products
    // (f0 = cross(a_j, a_l), summing to twice a small section's area) moves the crossing roots and |A| near
    // a focus, so a few rays differ by percents; around sphere_fog's focus pixels were up to 14 % off
    // (median 0.05 %), nrmse 0.0225 against the double image (methods/adaptive_beams/README.md, "The levers").
    std::mt19937_64 rng(41);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const MediumCoefficients medium{0.1, 0.4, 0.3};
    std::vector<double> rel;
    int beams = 0;
    while (beams < 200) {
        Beam b;
        if (!random_beam(rng, b)) continue;
        ++beams;
        const glm::dvec3 o(3.0 * u(rng), 3.0 * u(rng), 2.0 + 3.0 * u(rng));
        const RayBeam seen(b, o, medium);
        for (int r = 0; r < 32; ++r) {
            const glm::dvec3 w = glm::normalize(glm::dvec3(0.4 * u(rng), 0.4 * u(rng), 1.0 + 2.0 * u(rng)) - o);
            const double s_max = 1e30;
            BeamCounters c1, c2;
            double single = -1.0;
            seen.radiance_each_single(&w, &s_max, 1, 1 + r % 4, c1, 0.01, &single);
            const double dbl = seen.radiance(w, s_max, 1 + r % 4, c2, 0.01);
            ASSERT_TRUE(std::isfinite(single)) << "beam " << beams << " ray " << r;
            EXPECT_GE(single, 0.0);
            if (dbl > 0.0) rel.push_back(std::abs(single - dbl) / dbl);
        }
    }
    ASSERT_GT(rel.size(), 1000u);
    std::sort(rel.begin(), rel.end());
    const double median = rel[rel.size() / 2], p99 = rel[rel.size() * 99 / 100];
    std::printf("single against double on %zu rays: median relative difference %.3g, 99th percentile %.3g, largest %.3g\n",
                rel.size(), median, p99, rel.back());
    EXPECT_LT(median, 1e-5);   // a few float ulps (4.6e-7 measured): the arithmetic is float, not coarser
    EXPECT_GT(median, 0.0);    // and it is float: double would agree to the bit
}
