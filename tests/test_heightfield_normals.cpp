// HeightField::sample_normals (heightfield_normals.cpp) against sample_normal, bit for bit, on the fields
// and points the reference meets and the edges of the grid; and against an exact closed form on a field
// whose bilinear gradient is exact.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/util/target_clones.hpp>

using namespace caustics;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Points over the field and around it: inside, outside on every side, on vertices and on the far edges
// (the clamped cell), signed zeros and non-finite values.
std::vector<glm::dvec2> probe_points(const HeightField& hf, std::uint32_t seed) {
    const glm::dvec2 lo = hf.origin, hi = hf.origin + hf.extent();
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<glm::dvec2> p;
    for (int k = 0; k < 4000; ++k) p.emplace_back(lo + (hi - lo) * glm::dvec2(u(rng), u(rng)));
    for (int k = 0; k < 400; ++k) p.emplace_back(lo + (hi - lo) * glm::dvec2(3.0 * u(rng) - 1.0, 3.0 * u(rng) - 1.0));
    for (int j = 0; j < hf.ny; j += std::max(1, hf.ny / 7))
        for (int i = 0; i < hf.nx; i += std::max(1, hf.nx / 7)) p.emplace_back(lo + glm::dvec2(i, j) * hf.spacing);
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    for (const glm::dvec2 q : {lo, hi, glm::dvec2(hi.x, lo.y), glm::dvec2(lo.x, hi.y), glm::dvec2(-0.0, 0.0),
                               glm::dvec2(inf, 0.0), glm::dvec2(-inf, inf), glm::dvec2(nan, 0.1), glm::dvec2(0.1, nan),
                               glm::dvec2(std::nextafter(hi.x, inf), std::nextafter(lo.y, -inf))})
        p.push_back(q);
    return p;
}

// sample_normals over the points in runs of 1 to 9 (the four-point groups and the scalar tail), each
// point's bits against sample_normal's.
void expect_same_bits(const HeightField& hf, const std::vector<glm::dvec2>& points) {
    std::vector<double> x, y;
    for (const glm::dvec2 q : points) x.push_back(q.x), y.push_back(q.y);
    std::vector<double> nx(points.size()), ny(points.size()), nz(points.size());
    std::size_t mismatches = 0;
    for (std::size_t first = 0, run = 1; first < points.size(); first += run, run = run % 9 + 1) {
        const std::size_t n = std::min(run, points.size() - first);
        hf.sample_normals(x.data() + first, y.data() + first, n, nx.data() + first, ny.data() + first, nz.data() + first);
    }
    for (std::size_t k = 0; k < points.size(); ++k) {
        const glm::dvec3 want = hf.sample_normal(x[k], y[k]);   // NaN for an exact gradient at infinity
        if (!same_bits(nx[k], want.x) || !same_bits(ny[k], want.y) || !same_bits(nz[k], want.z)) {
            if (++mismatches <= 5)
                ADD_FAILURE() << "at (" << x[k] << ", " << y[k] << "): (" << nx[k] << ", " << ny[k] << ", " << nz[k]
                              << ") against sample_normal's (" << want.x << ", " << want.y << ", " << want.z << ")";
        }
    }
    EXPECT_EQ(mismatches, 0u) << "of " << points.size() << " points";
}

// A field on [-0.7, 0.9] x [-0.4, 0.6], 37 x 23 vertices, with per-vertex gradient(x, y).
template <class Gradient>
HeightField field_with_gradient(Gradient gradient) {
    HeightField hf;
    hf.nx = 37, hf.ny = 23;
    hf.origin = {-0.7, -0.4};
    hf.spacing = {1.6 / 36, 1.0 / 22};
    hf.height.assign(static_cast<std::size_t>(hf.nx) * hf.ny, 0.0f);
    for (int j = 0; j < hf.ny; ++j)
        for (int i = 0; i < hf.nx; ++i)
            hf.gradient.push_back(gradient(hf.origin.x + i * hf.spacing.x, hf.origin.y + j * hf.spacing.y));
    return hf;
}

}  // namespace

TEST(HeightFieldNormals, WavesFieldSameBitsAsSampleNormal) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2: sample_normals is sample_normal point by point";
    // The pool's surface: the waves simulation, neither periodic nor with an exact gradient.
    HeightFieldDesc d;
    d.size = {2.0, 2.0};
    d.resolution = {128, 128};
    d.generator = HeightGenerator::Waves;
    d.amplitude = 0.01;
    const HeightField hf = generate_heightfield(d, 0.5, 15, 30.0);
    ASSERT_FALSE(hf.periodic);
    ASSERT_FALSE(hf.exact_gradient);
    expect_same_bits(hf, probe_points(hf, 1));
}

TEST(HeightFieldNormals, ArbitraryGradientsSameBitsAsSampleNormal) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2: sample_normals is sample_normal point by point";
    // Gradients of every sign and a wide range of magnitudes, steep ones included.
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    auto component = [&] {
        const float mantissa = u(rng);
        return std::ldexp(mantissa, static_cast<int>(rng() % 24) - 12);
    };
    const HeightField hf = field_with_gradient([&](double, double) {
        const float gx = component();
        return glm::vec2(gx, component());
    });
    expect_same_bits(hf, probe_points(hf, 2));
}

TEST(HeightFieldNormals, GridEdgesAndSignedZerosSameBits) {
    if (!cpu_has_avx2()) GTEST_SKIP() << "no AVX2: sample_normals is sample_normal point by point";
    // A grid whose origin is (0, 0): x = -0 gives the grid coordinate -0 (kept by std::clamp, then
    // truncated to cell 0 with f = -0), tiny negatives clamp to +0, and the far edges land in the last
    // cell with f = 1.
    // The second field's gradients are all -0, so a cell position of -0 against +0 shows in the normal's
    // sign bits.
    for (const float zero_sign : {1.0f, -1.0f}) {
        HeightField hf = field_with_gradient([&](double x, double y) {
            return zero_sign > 0.0f ? glm::vec2(float(0.3 - x), float(y * y)) : glm::vec2(-0.0f, -0.0f);
        });
        hf.origin = {0.0, 0.0};
        const glm::dvec2 hi = hf.extent();
        std::vector<glm::dvec2> points;
        for (const double x : {-0.0, 0.0, -1e-300, 1e-300, -5e-324, hi.x, std::nextafter(hi.x, 0.0), 2.0 * hi.x})
            for (const double y : {-0.0, 0.0, -1e-300, 0.5 * hi.y, hi.y, std::nextafter(hi.y, 0.0)}) points.emplace_back(x, y);
        expect_same_bits(hf, points);
    }
}

TEST(HeightFieldNormals, FieldsOutsideTheVectorPathSameBits) {
    // Periodic (noise), exact gradient (sine) and a single vertex along an axis go point by point.
    auto generated = [](HeightGenerator generator, glm::ivec2 resolution) {
        HeightFieldDesc d;
        d.resolution = resolution;
        d.generator = generator;
        d.amplitude = 0.02;
        return generate_heightfield(d, 0.0, 0, 30.0);
    };
    const HeightField periodic = generated(HeightGenerator::Noise, {32, 32});
    ASSERT_TRUE(periodic.periodic);
    expect_same_bits(periodic, probe_points(periodic, 3));
    const HeightField exact = generated(HeightGenerator::Sine, {32, 16});
    ASSERT_TRUE(exact.exact_gradient);
    expect_same_bits(exact, probe_points(exact, 4));
    HeightField line = field_with_gradient([](double x, double) { return glm::vec2(float(x), 0.5f); });
    line.ny = 1;
    line.height.resize(static_cast<std::size_t>(line.nx));
    line.gradient.resize(static_cast<std::size_t>(line.nx));
    expect_same_bits(line, probe_points(line, 5));
}

TEST(HeightFieldNormals, BilinearGradientIsExactForAnAffineGradient) {
    // The gradient (0.5 x - 0.25, -0.75 y + 0.125) is affine in x and y, so its bilinear interpolation is
    // exact inside the domain, and the normal is (-g, 1) / |(-g, 1)| in closed form; outside it, the
    // domain's edge (clamped).
    auto g = [](double x, double y) { return glm::dvec2(0.5 * x - 0.25, -0.75 * y + 0.125); };
    const HeightField hf = field_with_gradient([&](double x, double y) { return glm::vec2(g(x, y)); });
    const std::vector<glm::dvec2> points = probe_points(hf, 6);
    std::vector<double> x, y;
    for (const glm::dvec2 q : points) x.push_back(q.x), y.push_back(q.y);
    std::vector<double> nx(points.size()), ny(points.size()), nz(points.size());
    hf.sample_normals(x.data(), y.data(), points.size(), nx.data(), ny.data(), nz.data());
    const glm::dvec2 lo = hf.origin, hi = hf.origin + hf.extent();
    for (std::size_t k = 0; k < points.size(); ++k) {
        if (std::isnan(x[k]) || std::isnan(y[k])) {
            // NaN maps to the grid's first cell, not outside the arrays.
            EXPECT_TRUE(std::isfinite(nx[k]) && std::isfinite(ny[k]) && std::isfinite(nz[k]));
            continue;
        }
        const glm::dvec2 q = glm::clamp(glm::dvec2(x[k], y[k]), lo, hi);
        const glm::dvec2 gq = g(q.x, q.y);
        const glm::dvec3 want = glm::dvec3(-gq.x, -gq.y, 1.0) / std::sqrt(1.0 + gq.x * gq.x + gq.y * gq.y);
        // The vertices' gradients are floats: 2^-24 relative, on gradients below 1.
        EXPECT_NEAR(nx[k], want.x, 1e-7) << x[k] << ", " << y[k];
        EXPECT_NEAR(ny[k], want.y, 1e-7) << x[k] << ", " << y[k];
        EXPECT_NEAR(nz[k], want.z, 1e-7) << x[k] << ", " << y[k];
    }
}
