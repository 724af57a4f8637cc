// caustic_mapping: the lookup mask (lookup_mask.hpp). Its bits against their definition (flux or no
// receiver within one texel), its box query against a scan, and the receiver-map and camera lookups with
// the mask against the same lookups with every bit set (nothing skipped), bit for bit with the same
// counts: orthographic, perspective and cube-map views of sphere.json's floor with an occluder above it
// (shadowed lookups), a sparse caustic map and camera points beside the window (outside lookups). The
// receiver-map and camera points computed in lanes against the same points looked up one at a time, also
// on sand.json's height-field receiver.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "../lookup.hpp"
#include "../lookup_mask.hpp"
#include "method_support.hpp"
#include <caustics/blocks/gbuffer/gbuffer_raster.hpp>
#include <caustics/frame/frame.hpp>

using namespace caustics;
using namespace caustics::caustic_mapping;

namespace {

// The definition: flux != 0 (NaN included) or id -1 in the 3 x 3 block around (x, y), clamped.
bool expected_bit(const GBuffer& g, const Image& flux, int x, int y) {
    for (int j = std::max(0, y - 1); j <= std::min(g.height - 1, y + 1); ++j)
        for (int i = std::max(0, x - 1); i <= std::min(g.width - 1, x + 1); ++i)
            if (flux.at(i, j) != 0.0f || g.id[g.index(i, j)] == -1) return true;
    return false;
}

// Random ids (about 5 % empty, in runs) and a sparse caustic map (blobs, a NaN, a denormal).
void random_face(GBuffer& g, Image& flux, int width, int height, std::mt19937& rng) {
    g.clear(width, height);
    flux = Image(width, height);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (std::size_t i = 0; i < g.id.size(); ++i) g.id[i] = u(rng) < 0.01f ? -1 : (i > 0 && g.id[i - 1] == -1 && u(rng) < 0.7f ? -1 : 0);
    for (int b = 0; b < 6; ++b) {
        const int cx = static_cast<int>(u(rng) * width), cy = static_cast<int>(u(rng) * height), r = 1 + b % 3;
        for (int y = std::max(0, cy - r); y < std::min(height, cy + r); ++y)
            for (int x = std::max(0, cx - r); x < std::min(width, cx + r); ++x) flux.at(x, y) = u(rng);
    }
    flux.at(width - 1, height / 2) = std::numeric_limits<float>::quiet_NaN();
    flux.at(0, height - 1) = 1e-42f;
}

TEST(LookupMask, BitsMatchTheirDefinition) {
    std::mt19937 rng(7);
    for (auto [width, height] : {std::pair{2, 2}, {5, 5}, {63, 63}, {64, 64}, {65, 65}, {130, 130}, {65, 3}, {1, 5}, {130, 2}, {3, 70}}) {
        const std::string size = std::to_string(width) + " x " + std::to_string(height);
        PositionsTexture tex;
        tex.maps.resize(2);
        std::vector<Image> flux(2);
        for (int f = 0; f < 2; ++f)
            random_face(tex.maps[static_cast<std::size_t>(f)], flux[static_cast<std::size_t>(f)], width, height, rng);
        LookupMask mask;
        mask.build(tex, flux);
        int set = 0, clear = 0;
        for (std::size_t f = 0; f < 2; ++f)
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x) {
                    const bool bit = LookupMask::test(mask.face(f), mask.words(), x, y);
                    ASSERT_EQ(bit, expected_bit(tex.maps[f], flux[f], x, y)) << "size " << size << " face " << f << " texel " << x << ", " << y;
                    (bit ? set : clear)++;
                }
        if (width * height >= 63 * 63) {
            EXPECT_GT(clear, 0) << size;
        }
        EXPECT_GT(set, 0) << size;
        // Box queries against a scan of the bits.
        std::uniform_int_distribution<int> at_x(0, width - 1), at_y(0, height - 1);
        for (int k = 0; k < 2000; ++k) {
            int x0 = at_x(rng), x1 = at_x(rng), y0 = at_y(rng), y1 = at_y(rng);
            if (x0 > x1) std::swap(x0, x1);
            if (y0 > y1) std::swap(y0, y1);
            bool scan = false;
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x) scan = scan || LookupMask::test(mask.face(1), mask.words(), x, y);
            ASSERT_EQ(LookupMask::any(mask.face(1), mask.words(), x0, y0, x1, y1), scan)
                << "size " << size << " box " << x0 << ".." << x1 << " x " << y0 << ".." << y1;
        }
    }
}

// sphere.json's floor, and a 0.6 m square occluder 0.5 m above it, rasterised into `faces`.
PositionsTexture floor_texture(const FrameGeometry& frame, std::vector<LightProjection> faces, bool cube) {
    PositionsTexture tex;
    tex.faces = std::move(faces);
    tex.cube = cube;
    tex.maps.resize(tex.faces.size());
    const TriangleMesh& floor = frame.receiver().mesh;
    const std::vector<glm::vec3> lid = {{-0.3f, -0.3f, 0.5f}, {0.3f, -0.3f, 0.5f}, {-0.3f, 0.3f, 0.5f}, {0.3f, 0.3f, 0.5f}};
    const std::vector<glm::vec3> up(4, glm::vec3(0, 0, 1));
    const std::vector<glm::uvec3> lid_tris = {{0, 1, 3}, {0, 3, 2}};
    GBufferRaster raster;
    for (std::size_t f = 0; f < tex.faces.size(); ++f) {
        tex.maps[f].clear(tex.faces[f].width, tex.faces[f].height, DepthTest::Less, false);
        raster.draw(tex.faces[f], {floor.positions, floor.normals, floor.triangles, 0}, CullMode::None, DepthTest::Less, tex.maps[f]);
        raster.draw(tex.faces[f], {lid, up, lid_tris, 1}, CullMode::None, DepthTest::Less, tex.maps[f]);
    }
    return tex;
}

// Camera points: on the floor (some beyond the light's window), on the occluder, a few above the point
// light (behind its near plane) and a few not covered.
CameraGBuffer camera_points(std::mt19937& rng) {
    CameraGBuffer gb;
    gb.width = 96, gb.height = 64;
    const std::size_t n = static_cast<std::size_t>(gb.width * gb.height);
    gb.covered.assign(n, 1);
    gb.position.resize(n);
    gb.normal.assign(n, glm::vec3(0, 0, 1));
    std::uniform_real_distribution<float> u(-2.6f, 2.6f), v(0.0f, 1.0f);
    for (std::size_t i = 0; i < n; ++i) {
        const float r = v(rng);
        if (r < 0.05f) gb.covered[i] = 0;
        else if (r < 0.15f) gb.position[i] = {0.6f * v(rng) - 0.3f, 0.6f * v(rng) - 0.3f, 0.5f};
        else if (r < 0.18f) gb.position[i] = {u(rng), u(rng), 3.5f};
        else gb.position[i] = {u(rng), u(rng), 0.0f};
    }
    return gb;
}

// A cube map whose six faces are copies of the single face of `tex`: whichever face a point picks, it is
// looked up in that face, one point at a time (the cube-map paths).
PositionsTexture six_copies(const PositionsTexture& tex) {
    PositionsTexture six = tex;
    six.cube = true;
    six.faces.assign(6, tex.faces[0]);
    six.maps.assign(6, tex.maps[0]);
    return six;
}

bool same_pixels(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
}

// One pass's image and counts.
struct Looked {
    Image image;
    LookupCounts counts;
};

template <class Pass>
Looked looked(Pass&& pass) {
    Looked l;
    pass(l.image, l.counts);
    return l;
}

void expect_same(const Looked& a, const Looked& b, const std::string& what) {
    EXPECT_TRUE(same_pixels(a.image, b.image)) << what;
    EXPECT_EQ(a.counts.outside, b.counts.outside) << what;
    EXPECT_EQ(a.counts.shadowed, b.counts.shadowed) << what;
}

TEST(LookupMask, LookupsEqualLookupsWithoutTheMask) {
    // sphere.json: a plane for receiver; sand.json: a height field (its chart's normals vary).
    const Scene sphere = load_scene("scenes/sphere.json"), sand = load_scene("scenes/sand.json");
    const FrameGeometry sphere_frame = build_frame_geometry(sphere, 0), sand_frame = build_frame_geometry(sand, 0);
    const ReceiverChart sphere_chart(sphere_frame, 48, 40), sand_chart(sand_frame, 40, 48);
    const glm::dvec3 eye = sphere.lights[0].position;
    const int map = 160;
    LightProjection persp, sand_persp;
    ASSERT_TRUE(fit_perspective(eye, sphere_frame.receiver().bounds, map, map, persp, 80.0));
    ASSERT_TRUE(fit_perspective(eye, sand_frame.receiver().bounds, map, map, sand_persp, 80.0));
    const std::array<LightProjection, 6> cube = cube_faces(eye, map);
    const glm::dvec3 tilted = glm::normalize(glm::dvec3(0.2, -0.1, -1));
    struct Case {
        const char* name;
        const ReceiverChart* chart;
        PositionsTexture tex;
    };
    const Case cases[] = {
        {"orthographic", &sphere_chart, floor_texture(sphere_frame, {fit_orthographic(tilted, sphere_frame.receiver().bounds, map, map)}, false)},
        {"perspective", &sphere_chart, floor_texture(sphere_frame, {persp}, false)},
        {"cube", &sphere_chart, floor_texture(sphere_frame, std::vector<LightProjection>(cube.begin(), cube.end()), true)},
        {"sand orthographic", &sand_chart, floor_texture(sand_frame, {fit_orthographic(tilted, sand_frame.receiver().bounds, map, map)}, false)},
        {"sand perspective", &sand_chart, floor_texture(sand_frame, {sand_persp}, false)},
    };
    std::mt19937 rng(11);
    const CameraGBuffer gb = camera_points(rng);
    for (const Case& c : cases) {
        const ReceiverChart& chart = *c.chart;
        // A sparse caustic map: blobs over the floor, and flux over the occluder.
        std::vector<Image> flux(c.tex.faces.size(), Image(map, map)), ones(c.tex.faces.size(), Image(map, map));
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        for (std::size_t f = 0; f < flux.size(); ++f) {
            std::fill(ones[f].pixels.begin(), ones[f].pixels.end(), 1.0f);
            for (int b = 0; b < 12; ++b) {
                const int cx = static_cast<int>(u(rng) * map), cy = static_cast<int>(u(rng) * map), r = 2 + b % 9;
                for (int y = std::max(0, cy - r); y < std::min(map, cy + r); ++y)
                    for (int x = std::max(0, cx - r); x < std::min(map, cx + r); ++x) flux[f].at(x, y) = u(rng);
            }
            for (std::size_t i = 0; i < flux[f].pixels.size(); ++i)   // the occluder's texels: lookups under it fail the depth test
                if (c.tex.maps[f].id[i] == 1) flux[f].pixels[i] = u(rng);
        }
        LookupMask mask, every;
        mask.build(c.tex, flux);
        every.build(c.tex, ones);   // every bit set: no lookup is skipped
        // The single face's points go through lanes (project_row, project_samples); a "cube" of six
        // copies of that face takes the one-point-at-a-time path.
        const PositionsTexture six = c.tex.cube ? PositionsTexture{} : six_copies(c.tex);
        const std::vector<Image> flux6(6, flux[0]);
        LookupMask mask6;
        if (!c.tex.cube) mask6.build(six, flux6);
        for (int n : {1, 3}) {
            const std::string what = std::string(c.name) + " receiver n " + std::to_string(n);
            ReceiverScratch scratch;
            const Looked with = looked([&](Image& out, LookupCounts& k) { receiver_irradiance(out, scratch, c.tex, flux, mask, chart, n, 1.0, k); });
            expect_same(with, looked([&](Image& out, LookupCounts& k) { receiver_irradiance(out, scratch, c.tex, flux, every, chart, n, 1.0, k); }), what);
            if (!c.tex.cube)
                expect_same(with, looked([&](Image& out, LookupCounts& k) { receiver_irradiance(out, scratch, six, flux6, mask6, chart, n, 1.0, k); }),
                            what + ", lanes against one point at a time");
            EXPECT_GT(std::count_if(with.image.pixels.begin(), with.image.pixels.end(), [](float p) { return p > 0.0f; }), 0) << what;
        }
        const std::string what = std::string(c.name) + " camera";
        const Looked with = looked([&](Image& out, LookupCounts& k) { camera_irradiance(out, c.tex, flux, mask, gb, 1.0, k); });
        const Looked without = looked([&](Image& out, LookupCounts& k) { camera_irradiance(out, c.tex, flux, every, gb, 1.0, k); });
        expect_same(with, without, what);
        if (!c.tex.cube)
            expect_same(with, looked([&](Image& out, LookupCounts& k) { camera_irradiance(out, six, flux6, mask6, gb, 1.0, k); }),
                        what + ", lanes against one point at a time");
        if (c.chart == &sphere_chart) {
            EXPECT_GT(without.counts.shadowed, 0) << c.name << ": the occluder shadows some lookups with flux";
        }
        EXPECT_GT(std::count_if(with.image.pixels.begin(), with.image.pixels.end(), [](float p) { return p > 0.0f; }), 0) << what;
    }
}

}  // namespace
