// caustic_mapping: the receivers' positions texture extension (extend_positions) against a direct,
// serial statement of its rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "../positions_texture.hpp"

using namespace caustics;
using namespace caustics::caustic_mapping;

namespace {

// Extends line l (texels index(0..len-1)) by up to `texels` past its outermost covered texels, linear
// extrapolation from the two outermost ones (the rule extend_positions documents), serially.
template <class Index>
void extend_line_serial(GBuffer& g, int len, int texels, Index index) {
    int a = 0, b = len - 1;
    while (a < len && g.id[index(a)] == -1) ++a;
    if (a == len) return;
    while (g.id[index(b)] == -1) --b;
    auto fill = [&](int dst, int edge, int inner, float t) {
        const std::size_t d = index(dst), e = index(edge), i = index(inner);
        g.position[d] = g.position[e] + t * (g.position[e] - g.position[i]);
        g.depth[d] = g.depth[e] + t * (g.depth[e] - g.depth[i]);
        g.id[d] = kExtended;
    };
    const int ia = a + 1 <= b ? a + 1 : a, ib = b - 1 >= a ? b - 1 : b;
    for (int k = a - 1; k >= std::max(0, a - texels); --k) fill(k, a, ia, static_cast<float>(a - k));
    for (int k = b + 1; k <= std::min(len - 1, b + texels); ++k) fill(k, b, ib, static_cast<float>(k - b));
}

GBuffer irregular_coverage(int W, int H) {
    GBuffer g;
    g.clear(W, H, DepthTest::Less, false);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            // A disk, a separate bar, a column band and a row left empty, lone texels (at the first and
            // last columns and rows, and at a multiple of the scans' 16 texels from either end).
            const double dx = x - 0.4 * W, dy = y - 0.5 * H;
            const bool disk = dx * dx + dy * dy < 0.09 * W * H;
            const bool bar = x >= W - 12 && x < W - 4 && y > 3 && y < H - 10;
            const bool lone = (x == 3 && y == H - 2) || (x == W - 1 && y == 2) || (x == 0 && y == H / 3) ||
                              (x == 16 && y == 1) || (x == W - 17 && y == H - 1);
            if (!(disk || bar || lone) || (x >= 20 && x < 23) || y == 7) continue;
            const std::size_t i = g.index(x, y);
            g.id[i] = 1;
            g.position[i] = glm::vec3(0.1f * x, -0.05f * y, 0.01f * x * y);
            g.depth[i] = 2.0f + 0.03f * x - 0.02f * y;
        }
    return g;
}

}  // namespace

TEST(CausticMappingPositions, ExtendMatchesSerialRowsThenColumns) {
    // 200: past the texture's size, as the method's default (extend to the whole map) is.
    // 150 x 90: columns in more than one block of 64, and a last partial block; 128 x 64: whole blocks
    // (their rows scanned in vectors); 17 x 33: rows one past a whole scan of 16.
    for (const glm::ivec2 size : {glm::ivec2(150, 90), glm::ivec2(128, 64), glm::ivec2(17, 33)})
    for (int texels : {1, 4, 32, 200}) {
        const int W = size.x, H = size.y;
        GBuffer fast = irregular_coverage(W, H), serial = irregular_coverage(W, H);
        extend_positions(fast, texels);
        for (int y = 0; y < H; ++y) extend_line_serial(serial, W, texels, [&](int k) { return serial.index(k, y); });
        for (int x = 0; x < W; ++x) extend_line_serial(serial, H, texels, [&](int k) { return serial.index(x, k); });
        int extended = 0;
        for (std::size_t i = 0; i < serial.id.size(); ++i) {
            ASSERT_EQ(fast.id[i], serial.id[i]) << "texels " << texels << " at " << i;
            if (serial.id[i] == -1) continue;
            extended += serial.id[i] == kExtended;
            ASSERT_EQ(fast.depth[i], serial.depth[i]) << i;
            ASSERT_EQ(fast.position[i], serial.position[i]) << i;
        }
        EXPECT_GT(extended, 0);
    }
}

TEST(CausticMappingPositions, ExtendLeavesEmptyAndFullTexturesAlone) {
    GBuffer empty;
    empty.clear(70, 20, DepthTest::Less, false);
    extend_positions(empty, 8);
    EXPECT_EQ(std::count(empty.id.begin(), empty.id.end(), -1), 70 * 20);
    GBuffer full;
    full.clear(70, 20, DepthTest::Less, false);
    std::fill(full.id.begin(), full.id.end(), 3);
    extend_positions(full, 8);
    EXPECT_EQ(std::count(full.id.begin(), full.id.end(), 3), 70 * 20);
}

TEST(CausticMappingPositions, LocateAndSideAgreeWithTheProjection) {
    // locate() projects with one reciprocal (LightProjection::project divides): the same texel
    // coordinates up to round-off; side() has the sign of depth(p) - depth(q) wherever they differ
    // beyond round-off, for a perspective and an orthographic face.
    Bounds3 b;
    b.extend({-2.0, -2.0, 0.0});
    b.extend({2.0, 2.0, 0.5});
    LightProjection persp;
    ASSERT_TRUE(fit_perspective({0.6, -0.4, 3.0}, b, 768, 768, persp, 80.0));
    const LightProjection ortho = fit_orthographic(glm::normalize(glm::dvec3(0.2, 0.1, -1.0)), b, 640, 512);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-2.0, 2.0), h(0.0, 0.5);
    for (const LightProjection& face : {persp, ortho}) {
        PositionsTexture tex;
        tex.faces = {face};
        int compared = 0;
        for (int k = 0; k < 2000; ++k) {
            const glm::dvec3 p(u(rng), u(rng), h(rng)), q(u(rng), u(rng), h(rng));
            double px = 0, py = 0, depth = 0;
            ASSERT_TRUE(face.project(p, px, py, depth));
            Texel t;
            if (tex.locate(p, t)) {
                EXPECT_NEAR(t.px, px, 1e-9 * face.width);
                EXPECT_NEAR(t.py, py, 1e-9 * face.height);
                EXPECT_EQ(t.depth, depth);
            } else {
                EXPECT_FALSE(px >= 0.0 && py >= 0.0 && px <= face.width && py <= face.height) << px << " " << py;
            }
            const double diff = tex.depth(p) - tex.depth(q);
            if (std::abs(diff) < 1e-9) continue;
            ++compared;
            EXPECT_EQ(tex.side(p, q) > 0.0, diff > 0.0);
            EXPECT_EQ(tex.side(p, p), 0.0);
        }
        EXPECT_GT(compared, 1900);
    }
}
