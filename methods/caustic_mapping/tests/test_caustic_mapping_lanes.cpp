// caustic_mapping: the estimator in lanes (estimator_lanes.hpp) against the scalar estimator
// (estimator.hpp), bit for bit, on rasterised positions textures: a wavy surface with holes, seen from an
// orthographic and from a perspective light, under every estimator setting the method offers. The rays
// cover the lanes' own path (clean Newton or approximate iterations) and every case they hand to the
// scalar estimator (null values in the holes and outside the window, texels with an empty neighbour,
// oscillation and bisection, bad derivatives, non-finite starts).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "../estimator_lanes.hpp"
#include <caustics/blocks/gbuffer/gbuffer_raster.hpp>

using namespace caustics;
using namespace caustics::caustic_mapping;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same_bits(const glm::dvec3& a, const glm::dvec3& b) {
    return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z);
}

// A wavy surface z = 0.3 sin(3x) cos(2y) over [-2, 2]^2 with vertex normals, minus a few holes.
struct Wavy {
    std::vector<glm::vec3> positions, normals;
    std::vector<glm::uvec3> triangles;
    Wavy() {
        const int n = 64;
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) {
                const float x = -2.0f + 4.0f * i / n, y = -2.0f + 4.0f * j / n;
                positions.emplace_back(x, y, 0.3f * std::sin(3.0f * x) * std::cos(2.0f * y));
                const float dzdx = 0.9f * std::cos(3.0f * x) * std::cos(2.0f * y);
                const float dzdy = -0.6f * std::sin(3.0f * x) * std::sin(2.0f * y);
                normals.push_back(glm::normalize(glm::vec3(-dzdx, -dzdy, 1.0f)));
            }
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                if ((i / 8 + j / 8) % 5 == 3 && i % 8 < 3 && j % 8 < 3) continue;   // holes
                const unsigned a = static_cast<unsigned>(j * (n + 1) + i), b = a + 1, c = a + n + 1, d = c + 1;
                triangles.push_back({a, b, d});
                triangles.push_back({a, d, c});
            }
    }
};

PositionsTexture texture(const LightProjection& face, const Wavy& w) {
    PositionsTexture tex;
    tex.faces = {face};
    tex.maps.resize(1);
    tex.maps[0].clear(face.width, face.height, DepthTest::Less, true);
    GBufferRaster raster;
    raster.draw(face, {w.positions, w.normals, w.triangles, 0}, CullMode::None, DepthTest::Less, tex.maps[0]);
    return tex;
}

}  // namespace

TEST(CausticMappingLanes, SameBitsAsTheScalarEstimator) {
    const Wavy wavy;
    Bounds3 b;
    b.extend({-2.0, -2.0, -0.3});
    b.extend({2.0, 2.0, 0.3});
    LightProjection persp;
    ASSERT_TRUE(fit_perspective({0.4, -0.3, 3.0}, b, 192, 160, persp, 80.0));
    const LightProjection ortho = fit_orthographic(glm::normalize(glm::dvec3(0.3, 0.1, -1.0)), b, 192, 160);

    std::vector<EstimatorSettings> settings(5);
    settings[1].kind = EstimatorKind::Approx;
    settings[2].safeguard = Safeguard::None;
    settings[3].iterations = 8;
    settings[3].eps = 0.1;
    settings[4].iterations = 0;

    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-2.5, 2.5), tilt(-0.6, 0.6), start(0.0, 3.0);
    for (const LightProjection& face : {ortho, persp}) {
        const PositionsTexture tex = texture(face, wavy);
        ASSERT_TRUE(lanes_apply(tex));
        // Rays from above the surface, downwards with a tilt; a few with a non-finite start.
        std::vector<EstimateRay> rays;
        for (int k = 0; k < 1203; ++k) {
            EstimateRay r;
            r.v = {u(rng), u(rng), 1.0 + 0.5 * std::abs(u(rng))};
            r.r = glm::normalize(glm::dvec3(tilt(rng), tilt(rng), -1.0));
            r.d_start = k % 97 == 5 ? std::numeric_limits<double>::quiet_NaN() : start(rng);
            rays.push_back(r);
        }
        for (const EstimatorSettings& s : settings) {
            for (bool with_normals : {false, true}) {
                std::vector<EstimateResult> lanes(rays.size());
                std::vector<glm::dvec3> lane_normals(rays.size(), glm::dvec3(7.0));
                const std::size_t finished = estimate_rays(tex, s, rays.data(), rays.size(), lanes.data(),
                                                           with_normals ? lane_normals.data() : nullptr);
                int nulls = 0, oscillating = 0, converged = 0;
                for (std::size_t k = 0; k < rays.size(); ++k) {
                    glm::dvec3 n(7.0);
                    const EstimateResult e = estimate_intersection(tex, rays[k].v, rays[k].r, s, rays[k].d_start,
                                                                   with_normals ? &n : nullptr);
                    const EstimateResult& l = lanes[k];
                    ASSERT_EQ(l.hit, e.hit) << k;
                    ASSERT_TRUE(same_bits(l.point, e.point)) << k;
                    ASSERT_TRUE(same_bits(l.d, e.d) || (std::isnan(l.d) && std::isnan(e.d))) << k;
                    ASSERT_EQ(l.lookups, e.lookups) << k;
                    ASSERT_EQ(l.iterations, e.iterations) << k;
                    ASSERT_EQ(l.converged, e.converged) << k;
                    ASSERT_EQ(l.null_value, e.null_value) << k;
                    ASSERT_EQ(l.oscillating, e.oscillating) << k;
                    ASSERT_EQ(l.bisected, e.bisected) << k;
                    ASSERT_EQ(l.bad_derivative, e.bad_derivative) << k;
                    ASSERT_EQ(l.nonfinite, e.nonfinite) << k;
                    if (with_normals && e.hit) {
                        ASSERT_TRUE(same_bits(lane_normals[k], n)) << k;
                    }
                    nulls += e.null_value, oscillating += e.oscillating, converged += e.converged;
                }
                // Both paths ran: the lanes (about 40-50 % of these rays) and the scalar estimator for the
                // hard cases (a fifth of the origins lie outside the surface, and it has holes).
                EXPECT_GT(finished, rays.size() / 4);
                EXPECT_LT(finished, rays.size());
                EXPECT_GT(nulls, 0);
                if (s.iterations > 0) {
                    EXPECT_GT(converged, 0);
                }
                if (s.iterations >= 3 && s.kind == EstimatorKind::Newton) {
                    EXPECT_GT(oscillating, 0);
                }
            }
        }
    }
}

TEST(CausticMappingLanes, CubeMapsAndNearestLookupsStayScalar) {
    PositionsTexture tex;
    tex.faces.resize(1);
    tex.faces[0].width = 8, tex.faces[0].height = 6;
    tex.maps.resize(1);
    tex.maps[0].clear(8, 6);
    tex.bilinear = false;
    EXPECT_FALSE(lanes_apply(tex));
    tex.bilinear = true;
    tex.cube = true;
    EXPECT_FALSE(lanes_apply(tex));
    tex.cube = false;
    EXPECT_TRUE(lanes_apply(tex));
    tex.maps[0].clear(8, 7);   // a map of another size than its face
    EXPECT_FALSE(lanes_apply(tex));
}
