// The shared triangle raster (harness/blocks/raster/raster.hpp): coverage by pixel centres with the top-left rule,
// exact area coverage with flux conservation, toroidal wrap, determinism across thread counts.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include <tbb/global_control.h>

#include <caustics/blocks/raster/raster.hpp>

using namespace caustics;

namespace {

struct Batch {
    std::vector<glm::vec2> positions;
    std::vector<glm::uvec3> triangles;
    std::vector<float> values;
    std::vector<float> vertex_values;
    void add(glm::vec2 a, glm::vec2 b, glm::vec2 c, float v) {
        const unsigned n = static_cast<unsigned>(positions.size());
        positions.insert(positions.end(), {a, b, c});
        triangles.push_back({n, n + 1, n + 2});
        values.push_back(v);
    }
    RasterTriangles view() const { return {positions, triangles, values, vertex_values}; }
};

Image draw(const Batch& b, RasterCoverage coverage, int w, int h, bool wrap = false, RasterStats* stats = nullptr) {
    Image img(w, h);
    TriangleRaster raster;
    RasterStats s = raster.draw(b.view(), {coverage, wrap, true}, img);
    if (stats) *stats = s;
    return img;
}

double sum(const Image& img) { return std::accumulate(img.pixels.begin(), img.pixels.end(), 0.0); }

// Area of a triangle inside the pixel [i, i+1) x [j, j+1): Sutherland-Hodgman clipping (independent of
// the raster's scanline accumulation).
double clipped_area(std::vector<glm::dvec2> poly, int i, int j) {
    auto clip = [&](auto inside, auto intersect) {
        std::vector<glm::dvec2> out;
        for (std::size_t k = 0; k < poly.size(); ++k) {
            glm::dvec2 a = poly[k], b = poly[(k + 1) % poly.size()];
            bool ia = inside(a), ib = inside(b);
            if (ia) out.push_back(a);
            if (ia != ib) out.push_back(intersect(a, b));
        }
        poly = out;
    };
    auto clip_x = [&](double x0, bool keep_greater) {
        clip([&](glm::dvec2 p) { return keep_greater ? p.x >= x0 : p.x <= x0; },
             [&](glm::dvec2 a, glm::dvec2 b) { return a + (x0 - a.x) / (b.x - a.x) * (b - a); });
    };
    auto clip_y = [&](double y0, bool keep_greater) {
        clip([&](glm::dvec2 p) { return keep_greater ? p.y >= y0 : p.y <= y0; },
             [&](glm::dvec2 a, glm::dvec2 b) { return a + (y0 - a.y) / (b.y - a.y) * (b - a); });
    };
    clip_x(i, true);
    clip_x(i + 1, false);
    clip_y(j, true);
    clip_y(j + 1, false);
    double a = 0.0;
    for (std::size_t k = 0; k < poly.size(); ++k) {
        glm::dvec2 p = poly[k], q = poly[(k + 1) % poly.size()];
        a += p.x * q.y - p.y * q.x;
    }
    return std::abs(0.5 * a);
}

}  // namespace

TEST(RasterCenter, HandComputedCoverage) {
    // Legs on x = 0.9 and y = 0.9, hypotenuse x + y = 4.2: the centres (i+.5, j+.5) inside are those with
    // i, j >= 1 and i + j + 1 < 4.2, i.e. (1,1), (2,1), (1,2). No centre lies on an edge.
    Batch b;
    b.add({0.9f, 0.9f}, {3.3f, 0.9f}, {0.9f, 3.3f}, 2.0f);
    Image img = draw(b, RasterCoverage::PixelCenter, 5, 5);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 5; ++x) {
            const bool in = (x == 1 && y == 1) || (x == 2 && y == 1) || (x == 1 && y == 2);
            EXPECT_EQ(img.at(x, y), in ? 2.0f : 0.0f) << x << "," << y;
        }
    // Clockwise order covers the same centres.
    Batch cw;
    cw.add({0.9f, 0.9f}, {0.9f, 3.3f}, {3.3f, 0.9f}, 2.0f);
    EXPECT_EQ(draw(cw, RasterCoverage::PixelCenter, 5, 5).pixels, img.pixels);
}

TEST(RasterCenter, InterpolatesVertexValues) {
    Batch b;
    b.add({0.0f, 0.0f}, {8.0f, 0.0f}, {0.0f, 8.0f}, 0.0f);
    b.vertex_values = {0.0f, 8.0f, 16.0f};   // v = x + 2 y
    Image img = draw(b, RasterCoverage::PixelCenter, 8, 8);
    EXPECT_NEAR(img.at(1, 2), 1.5 + 2 * 2.5, 1e-5);
    EXPECT_NEAR(img.at(3, 0), 3.5 + 2 * 0.5, 1e-5);
    EXPECT_EQ(img.at(7, 7), 0.0f);
}

TEST(RasterCenter, SharedEdgesCountEveryPixelOnce) {
    // A jittered mesh of the square [0, 32]^2; some vertices sit exactly on pixel centres or edges, and
    // the diagonals pass through centres, so the tie rule decides. Every pixel must be hit exactly once.
    const int n = 9;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> jitter(-1.5f, 1.5f);
    Batch b;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            glm::vec2 p(i * 4.0f, j * 4.0f);
            const bool border_x = i == 0 || i == n - 1, border_y = j == 0 || j == n - 1;
            if ((i + j) % 3 == 0) p += glm::vec2(0.5f, 0.5f);          // exactly on a centre
            else if ((i + j) % 3 == 1) p += glm::vec2(jitter(rng), jitter(rng));
            if (border_x) p.x = i * 4.0f;
            if (border_y) p.y = j * 4.0f;
            b.positions.push_back(p);
        }
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const unsigned v00 = j * n + i, v10 = v00 + 1, v01 = v00 + n, v11 = v01 + 1;
            if ((i + j) % 2) {
                b.triangles.push_back({v00, v10, v11});
                b.triangles.push_back({v00, v11, v01});
            } else {
                b.triangles.push_back({v00, v10, v01});
                b.triangles.push_back({v10, v11, v01});
            }
        }
    b.values.assign(b.triangles.size(), 1.0f);
    Image img = draw(b, RasterCoverage::PixelCenter, 32, 32);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) ASSERT_EQ(img.at(x, y), 1.0f) << x << "," << y;

    // Two triangles of the 4x4 square sharing the diagonal x + y = 4: four centres lie exactly on it.
    Batch sq;
    sq.add({0, 0}, {4, 0}, {0, 4}, 1.0f);
    sq.add({4, 0}, {4, 4}, {0, 4}, 1.0f);
    Image s = draw(sq, RasterCoverage::PixelCenter, 4, 4);
    for (float v : s.pixels) EXPECT_EQ(v, 1.0f);
}

TEST(RasterArea, HandComputedCoverage) {
    // Triangle (0,0), (2,0), (0,2) of area 2 with value (flux) 2: pixel (0,0) is fully covered (area 1),
    // (1,0) and (0,1) half covered, nothing else.
    Batch b;
    b.add({0, 0}, {2, 0}, {0, 2}, 2.0f);
    Image img = draw(b, RasterCoverage::Area, 4, 4);
    EXPECT_NEAR(img.at(0, 0), 1.0, 1e-6);
    EXPECT_NEAR(img.at(1, 0), 0.5, 1e-6);
    EXPECT_NEAR(img.at(0, 1), 0.5, 1e-6);
    EXPECT_NEAR(img.at(1, 1), 0.0, 1e-6);
    EXPECT_NEAR(sum(img), 2.0, 1e-6);
}

TEST(RasterArea, MatchesPolygonClippingAndConservesFlux) {
    // Random triangles of all sizes and both orientations, some partly outside, slivers and sub-pixel
    // ones: each pixel gets value * (area inside the pixel) / (triangle area), computed independently.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-4.0, 28.0), size(0.05, 12.0), v(0.5, 2.0);
    const int W = 24, H = 20;
    for (int trial = 0; trial < 200; ++trial) {
        glm::dvec2 c(u(rng), u(rng));
        const double s = size(rng);
        std::uniform_real_distribution<double> o(-s, s);
        glm::dvec2 p[3] = {c + glm::dvec2(o(rng), o(rng)), c + glm::dvec2(o(rng), o(rng)), c + glm::dvec2(o(rng), o(rng))};
        const double value = v(rng);
        const double tri_area = 0.5 * std::abs((p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[1].y - p[0].y) * (p[2].x - p[0].x));
        if (tri_area < 1e-3) continue;
        Batch b;
        b.add(glm::vec2(p[0]), glm::vec2(p[1]), glm::vec2(p[2]), static_cast<float>(value));
        // Compare against the float-rounded vertices the raster sees.
        std::vector<glm::dvec2> poly = {glm::dvec2(b.positions[0]), glm::dvec2(b.positions[1]), glm::dvec2(b.positions[2])};
        const double a = 0.5 * std::abs((poly[1].x - poly[0].x) * (poly[2].y - poly[0].y) -
                                        (poly[1].y - poly[0].y) * (poly[2].x - poly[0].x));
        Image img = draw(b, RasterCoverage::Area, W, H);
        double expected_total = 0.0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const double expected = static_cast<float>(value) * clipped_area(poly, x, y) / a;
                expected_total += expected;
                ASSERT_NEAR(img.at(x, y), expected, 2e-5 * value) << "trial " << trial << " pixel " << x << "," << y;
            }
        EXPECT_NEAR(sum(img), expected_total, 1e-5 * value);
    }
}

TEST(RasterArea, FluxConservedForManyTrianglesInside) {
    // Sum of deposits == sum of source flux for triangles inside the map, including folded (clockwise),
    // sub-pixel, degenerate (zero-area) and needle triangles.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(1.0f, 62.0f), o(-1.0f, 1.0f), f(0.1f, 3.0f);
    Batch b;
    double flux = 0.0;
    for (int k = 0; k < 5000; ++k) {
        const glm::vec2 c(u(rng), u(rng));
        const float s = (k % 4 == 0) ? 0.01f : (k % 4 == 1 ? 0.3f : 1.0f);
        glm::vec2 p0 = c + s * glm::vec2(o(rng), o(rng)), p1 = c + s * glm::vec2(o(rng), o(rng));
        glm::vec2 p2 = (k % 50 == 0) ? 0.5f * (p0 + p1) : c + s * glm::vec2(o(rng), o(rng));  // zero area
        const float value = f(rng);
        b.add(p0, p1, p2, value);
        flux += value;
    }
    RasterStats stats;
    Image img = draw(b, RasterCoverage::Area, 64, 64, false, &stats);
    EXPECT_GT(stats.point_deposits, 0);
    EXPECT_NEAR(sum(img), flux, 1e-5 * flux);
    for (float v : img.pixels) EXPECT_GE(v, -1e-4f);
}

TEST(RasterArea, GridPathMatchesGeneralPath) {
    // A g x g vertex grid split as {v00, v10, v11}, {v00, v11, v01} takes the shared-edge path. Warped
    // so that it folds over, spills past every border, has sub-pixel and zero-area cells, a non-finite
    // vertex and zero values; the same triangles with one unused extra position (not a grid) take the
    // general path. Both must give the same map up to round-off, the same statistics, and conserve the
    // flux of the triangles inside the map to the general path's bound (1e-5).
    const int g = 48, W = 40, H = 36;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> jitter(-0.4f, 0.4f), f(0.1f, 2.0f);
    Batch grid;
    for (int j = 0; j < g; ++j)
        for (int i = 0; i < g; ++i) {
            glm::vec2 p(-4.0f + 1.0f * i + jitter(rng), -3.0f + 0.9f * j + jitter(rng));
            p.x += 3.0f * std::sin(0.3f * j);                            // shears rows: folds
            if (i >= 20 && i < 24 && j >= 10 && j < 14) p = glm::vec2(12.3f + 0.05f * i, 9.6f + 0.05f * j);  // sub-pixel
            if (i >= 30 && i < 33) p.y = 20.0f + 0.5f * static_cast<float>(i);   // columns collapse: zero-area cells
            grid.positions.push_back(p);
        }
    grid.positions[static_cast<std::size_t>(5 * g + 7)].x = std::nanf("");
    for (unsigned j = 0; j + 1 < static_cast<unsigned>(g); ++j)
        for (unsigned i = 0; i + 1 < static_cast<unsigned>(g); ++i) {
            const unsigned v00 = j * g + i, v10 = v00 + 1, v01 = v00 + g, v11 = v01 + 1;
            grid.triangles.push_back({v00, v10, v11});
            grid.triangles.push_back({v00, v11, v01});
            grid.values.push_back((i + j) % 17 == 0 ? 0.0f : f(rng));
            grid.values.push_back(f(rng));
        }
    Batch general = grid;
    general.positions.push_back({0.0f, 0.0f});   // g * g + 1 positions: not a grid
    RasterStats sg, sn;
    const Image a = draw(grid, RasterCoverage::Area, W, H, false, &sg);
    const Image b = draw(general, RasterCoverage::Area, W, H, false, &sn);
    EXPECT_EQ(sg.drawn, sn.drawn);
    EXPECT_EQ(sg.nonfinite, sn.nonfinite);
    EXPECT_EQ(sg.point_deposits, sn.point_deposits);
    EXPECT_GT(sg.point_deposits, 0);
    EXPECT_GT(sg.nonfinite, 0);
    for (std::size_t k = 0; k < a.pixels.size(); ++k) ASSERT_NEAR(a.pixels[k], b.pixels[k], 2e-5) << k;
    // Flux of the triangles lying inside the map (pixels' area fully inside: nothing clipped).
    double inside = 0.0, total = 0.0;
    for (std::size_t t = 0; t < grid.triangles.size(); ++t) {
        const glm::uvec3 tri = grid.triangles[t];
        bool in = true;
        for (unsigned v : {tri.x, tri.y, tri.z}) {
            const glm::vec2 p = grid.positions[v];
            in = in && p.x >= 0.0f && p.x <= W && p.y >= 0.0f && p.y <= H;   // false for NaN
        }
        if (in) inside += grid.values[t];
        total += grid.values[t];
    }
    ASSERT_GT(inside, 0.3 * total);
    Batch inner = grid;   // the same grid with the outside triangles' values zeroed
    for (std::size_t t = 0; t < inner.triangles.size(); ++t) {
        const glm::uvec3 tri = inner.triangles[t];
        for (unsigned v : {tri.x, tri.y, tri.z}) {
            const glm::vec2 p = inner.positions[v];
            if (!(p.x >= 0.0f && p.x <= W && p.y >= 0.0f && p.y <= H)) inner.values[t] = 0.0f;
        }
    }
    EXPECT_NEAR(sum(draw(inner, RasterCoverage::Area, W, H)), inside, 1e-5 * inside);
    // The same for any thread count.
    Image one, four;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = draw(grid, RasterCoverage::Area, W, H);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 4);
        four = draw(grid, RasterCoverage::Area, W, H);
    }
    EXPECT_EQ(one.pixels, four.pixels);
}

TEST(RasterWrap, TrianglesReenterOnTheOtherSide) {
    const int W = 16, H = 12;
    // A triangle crossing the right and bottom borders.
    Batch b;
    b.add({13.3f, 9.2f}, {19.7f, 10.1f}, {14.1f, 15.6f}, 5.0f);
    for (RasterCoverage cov : {RasterCoverage::Area, RasterCoverage::PixelCenter}) {
        Image wrapped = draw(b, cov, W, H, true);
        // Expected: the same triangle drawn without wrap at its four tile positions.
        Image expected(W, H);
        for (int sy : {0, -1})
            for (int sx : {0, -1}) {
                Batch shifted;
                const glm::vec2 s(sx * W, sy * H);
                shifted.add(b.positions[0] + s, b.positions[1] + s, b.positions[2] + s, 5.0f);
                Image part = draw(shifted, cov, W, H);
                for (std::size_t k = 0; k < part.pixels.size(); ++k) expected.pixels[k] += part.pixels[k];
            }
        for (std::size_t k = 0; k < expected.pixels.size(); ++k)
            ASSERT_NEAR(wrapped.pixels[k], expected.pixels[k], 1e-5) << k;
        if (cov == RasterCoverage::Area) {
            EXPECT_NEAR(sum(wrapped), 5.0, 1e-5);   // nothing lost across the border
            Image clipped = draw(b, cov, W, H, false);
            EXPECT_LT(sum(clipped), 4.0);          // without wrap the outside part is dropped
        } else {
            // An integer shift of the whole triangle inside the image covers as many centres.
            Batch inside;
            const glm::vec2 s(-8.0f, -6.0f);
            inside.add(b.positions[0] + s, b.positions[1] + s, b.positions[2] + s, 5.0f);
            EXPECT_EQ(sum(wrapped), sum(draw(inside, cov, W, H)));
        }
    }
}

TEST(Raster, DeterministicForAnyThreadCount) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-10.0f, 300.0f), o(-6.0f, 6.0f), f(0.1f, 3.0f);
    Batch b;
    for (int k = 0; k < 20000; ++k) {
        const glm::vec2 c(u(rng), u(rng));
        b.add(c + glm::vec2(o(rng), o(rng)), c + glm::vec2(o(rng), o(rng)), c + glm::vec2(o(rng), o(rng)), f(rng));
    }
    for (RasterCoverage cov : {RasterCoverage::Area, RasterCoverage::PixelCenter})
        for (bool wrap : {false, true}) {
            Image one, two;
            {
                tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
                one = draw(b, cov, 256, 256, wrap);
            }
            {
                tbb::global_control c(tbb::global_control::max_allowed_parallelism, 4);
                two = draw(b, cov, 256, 256, wrap);
            }
            EXPECT_EQ(one.pixels, two.pixels);
        }
}

TEST(Raster, OverwriteModeAndBadInput) {
    Batch b;
    b.add({0, 0}, {2, 0}, {0, 2}, 2.0f);
    b.add({1, 1}, {2, 1}, {1, std::nanf("")}, 1.0f);
    Image img(4, 4, 1, 7.0f);
    TriangleRaster raster;
    RasterStats st = raster.draw(b.view(), {RasterCoverage::Area, false, false}, img);
    EXPECT_EQ(st.nonfinite, 1);
    EXPECT_NEAR(sum(img), 2.0, 1e-6);   // the 7s were overwritten
    Batch bad = b;
    bad.vertex_values = {1, 2, 3, 4, 5, 6};
    EXPECT_THROW(raster.draw(bad.view(), {RasterCoverage::Area, false, true}, img), std::invalid_argument);
}
