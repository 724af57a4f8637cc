// The G-buffer raster, light projections and splats (harness/blocks/gbuffer/gbuffer_raster.hpp, light_projection.hpp,
// splat.hpp): hand-computed coverage, the top-left rule on shared edges, depth test, culling,
// perspective-correct attributes, splat normalisation (also at borders), low-pass conservation and
// thread-count independence.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <span>
#include <vector>

#include <tbb/global_control.h>

#include <caustics/blocks/gbuffer/gbuffer_raster.hpp>
#include <caustics/blocks/gbuffer/light_projection.hpp>
#include <caustics/blocks/splat/splat.hpp>

using namespace caustics;

namespace {

// An orthographic view looking down -z whose pixel (px, py) is world (px, H - py): pixel coordinates
// can be written down directly.
LightProjection pixel_view(int W, int H) {
    Bounds3 b;
    b.extend({0, 0, -1});
    b.extend({static_cast<double>(W), static_cast<double>(H), 1});
    LightProjection p = fit_orthographic({0, 0, -1}, b, W, H, 0.0);
    p.eye = {0.0, 0.0, 10.0};   // view x, y = world x, y; depth = 10 - z
    p.x0 = 0, p.x1 = W, p.y0 = 0, p.y1 = H;
    return p;
}
glm::vec3 at_pixel(double px, double py, double H, double z = 0.0) {
    return glm::vec3(static_cast<float>(px), static_cast<float>(H - py), static_cast<float>(z));
}

int count_covered(const GBuffer& g) {
    int n = 0;
    for (int id : g.id) n += id >= 0;
    return n;
}

}  // namespace

TEST(LightProjection, OrthographicAndPerspectiveRoundTrip) {
    const LightProjection v = pixel_view(8, 8);
    double px, py, d;
    ASSERT_TRUE(v.project({2.5, 8 - 3.5, 0.0}, px, py, d));
    EXPECT_NEAR(px, 2.5, 1e-12);
    EXPECT_NEAR(py, 3.5, 1e-12);
    Bounds3 b;
    b.extend({-1, -1, 0});
    b.extend({1, 1, 0.5});
    LightProjection p;
    ASSERT_TRUE(fit_perspective({0.2, 0.1, 3.0}, b, 64, 64, p));
    for (const glm::dvec3 q : {glm::dvec3(-1, -1, 0), glm::dvec3(1, 1, 0.5), glm::dvec3(0.3, -0.7, 0.2)}) {
        ASSERT_TRUE(p.project(q, px, py, d));
        EXPECT_TRUE(p.inside(px, py));
        const glm::dvec3 dir = p.ray_direction(px, py);
        EXPECT_NEAR(glm::length(glm::cross(dir, glm::normalize(q - p.eye))), 0.0, 1e-9);
    }
    // Too wide for 60 degrees: refused, then accepted when clamped.
    EXPECT_FALSE(fit_perspective({0, 0, 0.1}, b, 64, 64, p, 60.0));
    EXPECT_TRUE(fit_perspective({0, 0, 0.6}, b, 64, 64, p, 60.0, 0.01, true));
    // Solid angles of a full 90-degree cube face sum to 4 pi / 6.
    const auto faces = cube_faces({0, 0, 0}, 64);
    double omega = 0.0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) omega += faces[0].texel_solid_angle(x + 0.5, y + 0.5);
    EXPECT_NEAR(omega, 4.0 * M_PI / 6.0, 1e-3);
    for (int f = 0; f < 6; ++f) EXPECT_EQ(cube_face_of(faces[static_cast<std::size_t>(f)].forward), f);
}

TEST(GBufferRaster, HandComputedCoverageAndTopLeftRule) {
    // The square [0,4]^2 (pixels) split along its diagonal: centres (i+1/2, j+1/2) with i + j < 3 are
    // strictly inside the upper-left triangle (6), the four with i + j = 3 lie on the shared diagonal
    // and belong to exactly one of the two triangles, the other six are strictly in the second.
    const int W = 8, H = 8;
    const LightProjection v = pixel_view(W, H);
    std::vector<glm::vec3> pos = {at_pixel(0, 0, H), at_pixel(4, 0, H), at_pixel(0, 4, H), at_pixel(4, 4, H)};
    std::vector<glm::uvec3> t1 = {{0, 2, 1}}, t2 = {{1, 2, 3}};
    GBufferRaster raster;
    GBuffer a, b;
    a.clear(W, H);
    b.clear(W, H);
    raster.draw(v, {pos, {}, t1, 1}, CullMode::None, DepthTest::Less, a);
    raster.draw(v, {pos, {}, t2, 2}, CullMode::None, DepthTest::Less, b);
    int on_diagonal_a = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const bool ca = a.id[a.index(i, j)] >= 0, cb = b.id[b.index(i, j)] >= 0;
            const bool in_square = i < 4 && j < 4;
            EXPECT_EQ(ca + cb, in_square ? 1 : 0) << i << "," << j;
            if (in_square && i + j < 3) { EXPECT_TRUE(ca) << i << "," << j; }
            if (in_square && i + j > 3) { EXPECT_TRUE(cb) << i << "," << j; }
            if (in_square && i + j == 3) on_diagonal_a += ca;
        }
    // The diagonal is the first triangle's bottom-right edge (not top-left): it goes to the second.
    EXPECT_EQ(on_diagonal_a, 0);
    EXPECT_EQ(count_covered(a), 6);
    EXPECT_EQ(count_covered(b), 10);
    // A horizontal top edge owns its centres: the rectangle rows [1, 2] x cols [1, 3) with edges through
    // pixel centres (y = 1.5 top, y = 3.5 bottom, x = 1.5 left, x = 3.5 right) covers rows 1, 2 and
    // columns 1, 2 (top and left edges in, bottom and right out): 4 pixels.
    std::vector<glm::vec3> r = {at_pixel(1.5, 1.5, H), at_pixel(3.5, 1.5, H), at_pixel(1.5, 3.5, H), at_pixel(3.5, 3.5, H)};
    std::vector<glm::uvec3> rt = {{0, 2, 1}, {1, 2, 3}};
    GBuffer c;
    c.clear(W, H);
    raster.draw(v, {r, {}, rt, 0}, CullMode::None, DepthTest::Less, c);
    EXPECT_EQ(count_covered(c), 4);
    for (int j = 1; j <= 2; ++j)
        for (int i = 1; i <= 2; ++i) EXPECT_GE(c.id[c.index(i, j)], 0) << i << "," << j;
}

TEST(GBufferRaster, JitteredMeshCoversEveryCentreOnce) {
    // A 9 x 7 grid of quads with jittered interior vertices (two triangles each), every triangle drawn
    // into its own buffer: each pixel centre inside the mesh is covered exactly once.
    const int W = 64, H = 48, nx = 9, ny = 7;
    const LightProjection v = pixel_view(W, H);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-1.5, 1.5);
    std::vector<glm::vec3> pos;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            double x = 4.0 + 6.0 * i, y = 3.0 + 6.0 * j;
            if (i > 0 && i < nx && j > 0 && j < ny) x += jitter(rng), y += jitter(rng);
            pos.push_back(at_pixel(x, y, H));
        }
    std::vector<int> hits(static_cast<std::size_t>(W) * H, 0);
    GBufferRaster raster;
    GBuffer g;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const unsigned a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
            for (const glm::uvec3 tri : {glm::uvec3(a, b, d), glm::uvec3(a, d, c)}) {
                std::vector<glm::uvec3> one = {tri};
                g.clear(W, H);
                raster.draw(v, {pos, {}, one, 0}, CullMode::None, DepthTest::Less, g);
                for (std::size_t k = 0; k < hits.size(); ++k) hits[k] += g.id[k] >= 0;
            }
        }
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const double cx = x + 0.5, cy = y + 0.5;
            const bool inside = cx > 4.0 && cx < 4.0 + 6.0 * nx && cy > 3.0 && cy < 3.0 + 6.0 * ny;
            const bool boundary = cx == 4.0 || cy == 3.0;
            if (!boundary) { EXPECT_EQ(hits[static_cast<std::size_t>(y) * W + x], inside ? 1 : 0) << x << "," << y; }
        }
}

TEST(GBufferRaster, SubPixelTrianglesCoverEveryCentreOnce) {
    // Triangles much smaller than a pixel (the setup pass tests their few centres itself): a grid of
    // half-pixel quads whose vertices lie on pixel centres and corners (edges through centres: the
    // top-left rule decides), then the same grid with jittered interior vertices. Each centre inside
    // the mesh is covered by exactly one triangle, drawn one by one and as one batch.
    const int W = 16, H = 16, n = 24;
    const LightProjection v = pixel_view(W, H);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> jitter(-0.2, 0.2);
    for (const bool jittered : {false, true}) {
        std::vector<glm::vec3> pos;
        for (int j = 0; j <= n; ++j)
            for (int i = 0; i <= n; ++i) {
                double x = 2.0 + 0.5 * i, y = 2.0 + 0.5 * j;
                if (jittered && i > 0 && i < n && j > 0 && j < n) x += jitter(rng), y += jitter(rng);
                pos.push_back(at_pixel(x, y, H));
            }
        std::vector<glm::uvec3> tris;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const unsigned a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
                tris.push_back({a, b, d});
                tris.push_back({a, d, c});
            }
        std::vector<int> hits(static_cast<std::size_t>(W) * H, 0);
        GBufferRaster raster;
        GBuffer g;
        for (const glm::uvec3& tri : tris) {
            const std::vector<glm::uvec3> one = {tri};
            g.clear(W, H);
            raster.draw(v, {pos, {}, one, 0}, CullMode::None, DepthTest::Less, g);
            for (std::size_t k = 0; k < hits.size(); ++k) hits[k] += g.id[k] >= 0;
        }
        g.clear(W, H);
        const GBufferStats st = raster.draw(v, {pos, {}, tris, 0}, CullMode::None, DepthTest::Less, g);
        int inside_centres = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const bool inside = x + 0.5 > 2.0 && x + 0.5 < 14.0 && y + 0.5 > 2.0 && y + 0.5 < 14.0;
                inside_centres += inside;
                const std::size_t k = static_cast<std::size_t>(y) * W + x;
                EXPECT_EQ(hits[k], inside ? 1 : 0) << jittered << ": " << x << "," << y;
                EXPECT_EQ(g.id[k] >= 0, inside) << jittered << ": " << x << "," << y;
            }
        EXPECT_EQ(st.fragments, inside_centres) << jittered;
    }
}

TEST(GBufferRaster, DepthTestCullingAndPerspectiveAttributes) {
    const int W = 32, H = 32;
    const LightProjection v = pixel_view(W, H);
    // Two overlapping squares at z = 0.2 (nearer to the light above) and z = -0.3: Less keeps the near
    // one in either drawing order, Greater the far one.
    std::vector<glm::vec3> pos;
    for (double z : {0.2, -0.3})
        for (auto [x, y] : {std::pair{4.0, 4.0}, {20.0, 4.0}, {4.0, 20.0}, {20.0, 20.0}}) pos.push_back(at_pixel(x, y, H, z));
    std::vector<glm::uvec3> near_tris = {{0, 2, 1}, {1, 2, 3}}, far_tris = {{4, 6, 5}, {5, 6, 7}};
    GBufferRaster raster;
    for (int order = 0; order < 2; ++order) {
        GBuffer g;
        g.clear(W, H);
        if (order == 0) {
            raster.draw(v, {pos, {}, near_tris, 1}, CullMode::None, DepthTest::Less, g);
            raster.draw(v, {pos, {}, far_tris, 2}, CullMode::None, DepthTest::Less, g);
        } else {
            raster.draw(v, {pos, {}, far_tris, 2}, CullMode::None, DepthTest::Less, g);
            raster.draw(v, {pos, {}, near_tris, 1}, CullMode::None, DepthTest::Less, g);
        }
        EXPECT_EQ(g.id[g.index(10, 10)], 1);
        EXPECT_NEAR(g.position[g.index(10, 10)].z, 0.2f, 1e-6f);
        GBuffer f;
        f.clear(W, H, DepthTest::Greater);
        raster.draw(v, {pos, {}, near_tris, 1}, CullMode::None, DepthTest::Greater, f);
        raster.draw(v, {pos, {}, far_tris, 2}, CullMode::None, DepthTest::Greater, f);
        EXPECT_EQ(f.id[f.index(10, 10)], 2);
    }
    // Culling: these triangles' counter-clockwise normals point up (+z), towards the light looking down.
    GBuffer g;
    g.clear(W, H);
    const GBufferStats front = raster.draw(v, {pos, {}, near_tris, 1}, CullMode::Front, DepthTest::Less, g);
    EXPECT_EQ(front.culled, 2);
    EXPECT_EQ(count_covered(g), 0);
    raster.draw(v, {pos, {}, near_tris, 1}, CullMode::Back, DepthTest::Less, g);
    EXPECT_EQ(count_covered(g), 16 * 16);

    // Perspective: a tilted quad seen from a point light; every fragment's interpolated position lies on
    // the quad's plane and projects back onto its own pixel centre (perspective-correct interpolation).
    std::vector<glm::vec3> quad = {{-1, -1, 0}, {1, -1, 0.6f}, {-1, 1, 0}, {1, 1, 0.6f}};
    std::vector<glm::uvec3> qt = {{0, 1, 3}, {0, 3, 2}};
    Bounds3 b;
    for (const glm::vec3& p : quad) b.extend(glm::dvec3(p));
    LightProjection persp;
    ASSERT_TRUE(fit_perspective({0.3, -0.2, 2.0}, b, 48, 48, persp));
    GBuffer pg;
    pg.clear(48, 48);
    raster.draw(persp, {quad, {}, qt, 0}, CullMode::Back, DepthTest::Less, pg);
    int covered = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x) {
            const std::size_t i = pg.index(x, y);
            if (pg.id[i] < 0) continue;
            ++covered;
            const glm::dvec3 p(pg.position[i]);
            EXPECT_NEAR(p.z, 0.3 * (p.x + 1.0), 1e-5);
            double px, py, d;
            ASSERT_TRUE(persp.project(p, px, py, d));
            // Up to the vertices' 1/256-pixel snapping.
            EXPECT_NEAR(px, x + 0.5, 1.0 / 128);
            EXPECT_NEAR(py, y + 0.5, 1.0 / 128);
            EXPECT_NEAR(d, pg.depth[i], 1e-5 * d);
        }
    EXPECT_GT(covered, 48 * 48 / 4);
}

// A positions-only target (the receivers' maps: spans whose fragments all pass the depth test are stored
// without a test per texel) holds the same depths, positions and ids as a target with normals (written
// fragment by fragment), for both depth tests: random overlapping triangles with rows long and short,
// tilted in depth, some reaching far outside the image (edge functions beyond 2^53, where the
// barycentrics keep their 64-bit path; both targets share the barycentrics, which the coverage tests
// above and the method's image comparisons check).
TEST(GBufferRaster, PositionsOnlyTargetEqualsTheFullTarget) {
    const int W = 300, H = 200;
    const LightProjection v = pixel_view(W, H);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> x(-20.0, W + 20.0), y(-20.0, H + 20.0), z(-0.9, 0.9), far(-3e5, 3e5);
    std::vector<glm::vec3> pos;
    std::vector<glm::uvec3> tris;
    for (unsigned t = 0; t < 60; ++t) {
        const bool huge = t % 15 == 0;
        for (int k = 0; k < 3; ++k) pos.push_back(huge ? at_pixel(far(rng), far(rng), H, z(rng)) : at_pixel(x(rng), y(rng), H, z(rng)));
        tris.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    GBufferRaster raster;
    for (DepthTest test : {DepthTest::Less, DepthTest::Greater}) {
        GBuffer full, positions;
        full.clear(W, H, test, true);
        positions.clear(W, H, test, false);
        // Two batches, so that the second one's fragments are tested against the first one's depths.
        for (std::size_t half : {0, 1}) {
            const std::span<const glm::uvec3> part(tris.data() + 30 * half, 30);
            raster.draw(v, {pos, {}, part, static_cast<std::int32_t>(half)}, CullMode::None, test, full);
            raster.draw(v, {pos, {}, part, static_cast<std::int32_t>(half)}, CullMode::None, test, positions);
        }
        int covered = 0;
        for (std::size_t i = 0; i < full.id.size(); ++i) {
            ASSERT_EQ(positions.id[i], full.id[i]) << i;
            ASSERT_EQ(positions.depth[i], full.depth[i]) << i;
            if (full.id[i] < 0) continue;
            ++covered;
            ASSERT_EQ(positions.position[i], full.position[i]) << i;
        }
        EXPECT_GT(covered, W * H / 2);
    }
}

// One set-up for both faces of a closed mesh gives exactly the buffers of two culled draws (front faces
// with CullMode::Back, back faces with CullMode::Front), in both projections.
TEST(GBufferRaster, FrontBackInOnePassEqualsTwoCulledDraws) {
    std::vector<glm::vec3> pos, nrm;
    std::vector<glm::uvec3> tris;
    const int slices = 40, stacks = 20;
    for (int j = 0; j <= stacks; ++j)
        for (int i = 0; i <= slices; ++i) {
            const double th = M_PI * j / stacks, ph = 2 * M_PI * i / slices;
            const glm::dvec3 n(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
            pos.emplace_back(glm::dvec3(0.1, -0.2, 0.5) + 0.7 * n);
            nrm.emplace_back(n);
        }
    for (unsigned j = 0; j < static_cast<unsigned>(stacks); ++j)
        for (unsigned i = 0; i < static_cast<unsigned>(slices); ++i) {
            const unsigned a = j * (slices + 1) + i, c = a + slices + 1;
            tris.push_back({a, c, a + 1});
            tris.push_back({a + 1, c, c + 1});
        }
    Bounds3 b;
    for (const glm::vec3& p : pos) b.extend(glm::dvec3(p));
    LightProjection persp;
    ASSERT_TRUE(fit_perspective({0.4, -0.3, 3.0}, b, 64, 64, persp));
    for (const LightProjection& view : {fit_orthographic({0.2, 0.1, -1.0}, b, 64, 64), persp}) {
        GBufferRaster raster;
        GBuffer front, back, f2, b2;
        for (GBuffer* g : {&front, &back, &f2, &b2}) g->clear(64, 64);
        const GBufferTriangles batch{pos, nrm, tris, 3};
        raster.draw(view, batch, CullMode::Back, DepthTest::Less, front);
        raster.draw(view, batch, CullMode::Front, DepthTest::Less, back);
        raster.draw_front_back(view, batch, DepthTest::Less, f2, b2);
        EXPECT_GT(count_covered(front), 64 * 64 / 4);
        EXPECT_EQ(count_covered(front), count_covered(back));
        for (auto [one, two] : {std::pair{&front, &f2}, {&back, &b2}}) {
            EXPECT_EQ(one->id, two->id);
            EXPECT_EQ(one->depth, two->depth);
            for (std::size_t i = 0; i < one->id.size(); ++i)
                if (one->id[i] >= 0) {
                    ASSERT_EQ(one->position[i], two->position[i]);
                    ASSERT_EQ(one->normal[i], two->normal[i]);
                }
        }
        // Back faces lie behind the front faces seen from the light.
        for (std::size_t i = 0; i < front.id.size(); ++i)
            if (front.id[i] >= 0 && back.id[i] >= 0) {
                EXPECT_LT(front.depth[i], back.depth[i]);
            }
    }
}

TEST(Splat, NormalisedFootprintAndBorders) {
    SplatRaster s;
    Image img(40, 30);
    // Interior Gaussian: its weights sum to its value.
    std::vector<Splat> one = {{{20.3f, 14.7f}, 2.5f}};
    SplatStats st = s.draw(one, SplatKernel::Gaussian, 6.0, img);
    double sum = std::accumulate(img.pixels.begin(), img.pixels.end(), 0.0);
    EXPECT_NEAR(sum, 2.5, 1e-5);
    EXPECT_NEAR(st.value_inside, 2.5, 1e-9);
    EXPECT_NEAR(st.value_outside, 0.0, 1e-12);
    // Near a corner: what lands plus what is reported outside is the value; nothing is renormalised.
    img = Image(40, 30);
    one = {{{1.2f, 0.4f}, 1.0f}};
    st = s.draw(one, SplatKernel::Gaussian, 6.0, img);
    sum = std::accumulate(img.pixels.begin(), img.pixels.end(), 0.0);
    EXPECT_NEAR(sum, st.value_inside, 1e-6);
    EXPECT_NEAR(st.value_inside + st.value_outside, 1.0, 1e-9);
    EXPECT_GT(st.value_outside, 0.3);
    EXPECT_LT(st.value_outside, 0.9);
    // Point splats land in the pixel holding the point; outside ones are counted, non-finite skipped.
    img = Image(40, 30);
    std::vector<Splat> pts = {{{3.99f, 7.0f}, 1.0f}, {{-0.5f, 3.0f}, 1.0f}, {{NAN, 1.0f}, 1.0f}};
    st = s.draw(pts, SplatKernel::Point, 0.0, img);
    EXPECT_FLOAT_EQ(img.at(3, 7), 1.0f);
    EXPECT_EQ(st.splatted, 1);
    EXPECT_EQ(st.outside, 1);
    EXPECT_EQ(st.nonfinite, 1);
}

TEST(Splat, ThreadCountIndependentAndLowpassConserves) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-5.0f, 133.0f);
    std::vector<Splat> splats;
    for (int k = 0; k < 20000; ++k) splats.push_back({{u(rng), u(rng)}, 0.001f * (1 + k % 7)});
    Image a(128, 128), b(128, 128);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        SplatRaster s;
        s.draw(splats, SplatKernel::Gaussian, 4.5, a);
    }
    SplatRaster s;
    const SplatStats st = s.draw(splats, SplatKernel::Gaussian, 4.5, b);
    EXPECT_EQ(a.pixels, b.pixels);
    const double total = std::accumulate(b.pixels.begin(), b.pixels.end(), 0.0);
    EXPECT_NEAR(total, st.value_inside, 1e-4 * total);
    gaussian_lowpass(b, 5.0);
    EXPECT_NEAR(std::accumulate(b.pixels.begin(), b.pixels.end(), 0.0), total, 1e-4 * total);

    // The G-buffer raster too: a jittered mesh drawn on 1 and on all threads.
    const LightProjection v = pixel_view(96, 80);
    std::vector<glm::vec3> pos;
    std::vector<glm::uvec3> tris;
    std::uniform_real_distribution<float> w(0.0f, 96.0f), zz(-1.0f, 1.0f);
    for (int k = 0; k < 3000; ++k) {
        const unsigned base = static_cast<unsigned>(pos.size());
        const float x = w(rng), y = w(rng) * 80.0f / 96.0f, z = zz(rng);
        pos.push_back({x, y, z});
        pos.push_back({x + 6.0f, y + 1.0f, z + 0.1f});
        pos.push_back({x + 2.0f, y + 5.0f, z - 0.2f});
        tris.push_back({base, base + 1, base + 2});
    }
    GBuffer g1, g2;
    g1.clear(96, 80);
    g2.clear(96, 80);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        GBufferRaster r;
        r.draw(v, {pos, {}, tris, 0}, CullMode::None, DepthTest::Less, g1);
    }
    GBufferRaster r;
    r.draw(v, {pos, {}, tris, 0}, CullMode::None, DepthTest::Less, g2);
    EXPECT_EQ(g1.depth, g2.depth);
    EXPECT_EQ(g1.id, g2.id);
}

