// Scene model tests: built-in scenes load (malformed scene files: test_scene_files.cpp), height-field
// generators match their closed forms (or tile, loop, and repeat bit for bit), the
// receiver chart's areas add up, and frames out of range are refused.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/util/errors.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/scene/scene.hpp>

namespace fs = std::filesystem;
using namespace caustics;

// Fingerprint of the waves test frame (see WavesGenerator.FrameBitsAreTheSameOnEveryMachine).
constexpr std::uint64_t WAVES_FRAME30_FINGERPRINT = 5700080908120146773ull;

namespace {

std::string scene_path(const std::string& name) { return std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name; }

}  // namespace

// ---------------------------------------------------------------- built-in scenes

TEST(BuiltinScenes, SineLoadsAsSpecified) {
    const Scene s = load_scene(scene_path("sine.json"));
    EXPECT_EQ(s.name, "sine");
    EXPECT_FALSE(s.source_text.empty());
    ASSERT_EQ(s.lights.size(), 1u);
    EXPECT_EQ(s.lights[0].type, LightType::Directional);
    EXPECT_EQ(s.lights[0].direction, glm::dvec3(0, 0, -1));
    EXPECT_EQ(s.lights[0].irradiance, 1.0);
    const Object& water = s.objects.at(0);
    EXPECT_EQ(water.shape, ShapeType::HeightField);
    EXPECT_EQ(water.material.type, MaterialType::Dielectric);
    EXPECT_DOUBLE_EQ(water.material.ior, 1.33);
    EXPECT_EQ(water.heightfield.generator, HeightGenerator::Sine);
    EXPECT_EQ(water.heightfield.resolution, glm::ivec2(640, 640));
    // Five whole periods, so the surface also tiles; the patch covers the 1 m receiver with a margin.
    EXPECT_EQ(water.heightfield.size, glm::dvec2(1.25, 1.25));
    EXPECT_DOUBLE_EQ(water.heightfield.amplitude, 0.01);
    EXPECT_DOUBLE_EQ(water.heightfield.wavelength, 0.25);
    EXPECT_EQ(s.receiver.object, "floor");
    EXPECT_EQ(s.receiver_object().shape, ShapeType::Plane);
    EXPECT_DOUBLE_EQ(s.receiver_object().center.z, -0.4);
    EXPECT_EQ(s.receiver.width, 256);
    EXPECT_EQ(s.animation.frames, 1);
    EXPECT_FALSE(s.fresnel);
    EXPECT_EQ(s.max_specular_depth, 8);
}

TEST(BuiltinScenes, SphereLoadsAsSpecified) {
    const Scene s = load_scene(scene_path("sphere.json"));
    ASSERT_EQ(s.lights.size(), 1u);
    EXPECT_EQ(s.lights[0].type, LightType::Point);
    EXPECT_EQ(s.lights[0].intensity, 10.0);
    const Object& ball = s.objects.at(0);
    EXPECT_EQ(ball.shape, ShapeType::Sphere);
    EXPECT_DOUBLE_EQ(ball.radius, 0.5);
    EXPECT_DOUBLE_EQ(ball.material.ior, 1.5);
    EXPECT_EQ(s.camera.width, 1024);
    EXPECT_EQ(s.camera.height, 768);
    const FrameGeometry g = build_frame_geometry(s, 0);
    EXPECT_TRUE(g.objects[0].analytic_sphere);
    EXPECT_TRUE(g.objects[0].mesh.empty());
    EXPECT_NEAR(g.specular_bounds.lo.z, 0.3, 1e-12);
    EXPECT_NEAR(g.specular_bounds.hi.z, 1.3, 1e-12);
    EXPECT_NEAR(g.scene_bounds.lo.x, -2.0, 1e-6);
}

TEST(BuiltinScenes, EveryBuiltinSceneLoadsAndBuildsFrameZero) {
    int count = 0;
    for (const auto& entry : fs::directory_iterator(std::string(CAUSTICS_SOURCE_DIR) + "/scenes")) {
        if (entry.path().extension() != ".json") continue;
        SCOPED_TRACE(entry.path().string());
        ++count;
        const Scene s = load_scene(entry.path().string());
        ASSERT_GE(s.receiver.object_index, 0);
        const FrameGeometry g = build_frame_geometry(s, 0);
        EXPECT_EQ(g.objects.size(), s.objects.size());
        EXPECT_TRUE(g.scene_bounds.valid());
        EXPECT_TRUE(g.specular_bounds.valid());
        const ReceiverChart chart(g, s.receiver.width, s.receiver.height);
        EXPECT_GT(chart.total_area(), 0.0);
    }
    EXPECT_GE(count, 3);
}

// ---------------------------------------------------------------- frame geometry

TEST(FrameGeometry, FrameOutOfRangeThrowsNamingTheRange) {
    const Scene s = load_scene(scene_path("sine.json"));
    EXPECT_NO_THROW(build_frame_geometry(s, 0));
    try {
        build_frame_geometry(s, 1);
        FAIL() << "frame 1 of a 1-frame scene was accepted";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), "--frame");
        EXPECT_NE(std::string(e.what()).find("0..0"), std::string::npos) << e.what();
    }
    EXPECT_THROW(build_frame_geometry(s, -1), InputError);
}

TEST(FrameGeometry, PlaneAndBoxTrianglesFaceOutward) {
    Scene s;
    s.name = "t";
    Object plane;
    plane.name = "p";
    plane.shape = ShapeType::Plane;
    plane.center = {0, 0, -1};
    plane.u = {2, 0, 0};
    plane.v = {0, 3, 0};
    Object box;
    box.name = "b";
    box.shape = ShapeType::Box;
    box.center = {1, 2, 3};
    box.size = {1, 2, 3};
    box.material.type = MaterialType::Mirror;
    s.objects = {plane, box};
    s.receiver.object_index = 0;
    const FrameGeometry g = build_frame_geometry(s, 0);
    const TriangleMesh& pm = g.objects[0].mesh;
    ASSERT_EQ(pm.triangles.size(), 2u);
    double area = 0.0;
    for (const glm::uvec3& t : pm.triangles) {
        const glm::dvec3 a(pm.positions[t.x]), b(pm.positions[t.y]), c(pm.positions[t.z]);
        const glm::dvec3 n = glm::cross(b - a, c - a);
        EXPECT_GT(n.z, 0.0);
        area += 0.5 * glm::length(n);
    }
    EXPECT_NEAR(area, 6.0, 1e-6);
    const TriangleMesh& bm = g.objects[1].mesh;
    ASSERT_EQ(bm.triangles.size(), 12u);
    double volume = 0.0;  // divergence theorem: positive only if every face is outward and CCW
    for (const glm::uvec3& t : bm.triangles) {
        const glm::dvec3 a(bm.positions[t.x]), b(bm.positions[t.y]), c(bm.positions[t.z]);
        const glm::dvec3 n = glm::cross(b - a, c - a);
        EXPECT_GT(glm::dot(n, (a + b + c) / 3.0 - box.center), 0.0);
        volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    EXPECT_NEAR(volume, 6.0, 1e-5);
    EXPECT_NEAR(g.specular_bounds.lo.z, 1.5, 1e-6);
    EXPECT_NEAR(g.scene_bounds.lo.z, -1.0, 1e-6);
}

// ---------------------------------------------------------------- analytic generators

TEST(HeightFieldGenerators, SineMatchesClosedForm) {
    HeightFieldDesc d;
    d.center = {0.1, -0.2};
    d.size = {2.0, 1.0};
    d.resolution = {200, 100};
    d.base_height = -0.3;
    d.generator = HeightGenerator::Sine;
    d.amplitude = 0.02;
    d.wavelength = 0.3;
    d.direction = {0.6, 0.8};
    d.phase = 0.4;
    d.speed = 0.1;
    const double t = 0.7;
    const HeightField hf = generate_heightfield(d, t, 21, 30.0);
    ASSERT_EQ(hf.nx, 201);
    ASSERT_EQ(hf.ny, 101);
    const double k = 2.0 * std::numbers::pi / d.wavelength;
    auto arg = [&](double x, double y) { return k * (0.6 * x + 0.8 * y) + d.phase + k * d.speed * t; };
    for (int j = 0; j < hf.ny; j += 7) {
        for (int i = 0; i < hf.nx; i += 5) {
            const double x = hf.origin.x + i * hf.spacing.x, y = hf.origin.y + j * hf.spacing.y;
            EXPECT_NEAR(hf.z(i, j), d.base_height + d.amplitude * std::sin(arg(x, y)), 1e-6);
            const double gs = d.amplitude * k * std::cos(arg(x, y));
            EXPECT_NEAR(hf.grad(i, j).x, gs * 0.6, 1e-5);
            EXPECT_NEAR(hf.grad(i, j).y, gs * 0.8, 1e-5);
        }
    }
    ASSERT_TRUE(hf.exact_gradient);
    const glm::dvec2 g = hf.sample_gradient(0.123, -0.456);
    const double gs = d.amplitude * k * std::cos(arg(0.123, -0.456));
    EXPECT_NEAR(g.x, 0.6 * gs, 1e-12);
    EXPECT_NEAR(g.y, 0.8 * gs, 1e-12);
    // The interpolated height is close to the exact one at this resolution.
    EXPECT_NEAR(hf.sample_height(0.123, -0.456), d.base_height + d.amplitude * std::sin(arg(0.123, -0.456)), 2e-4);
    const glm::dvec3 n = hf.sample_normal(0.123, -0.456);
    EXPECT_NEAR(glm::length(n), 1.0, 1e-12);
    EXPECT_NEAR(n.x, -g.x / std::sqrt(1 + glm::dot(g, g)), 1e-12);
}

TEST(HeightFieldGenerators, GaussianMatchesClosedForm) {
    HeightFieldDesc d;
    d.size = {1.0, 1.0};
    d.resolution = {128, 128};
    d.generator = HeightGenerator::Gaussian;
    d.amplitude = 0.04;
    d.sigma = 0.1;
    d.gauss_center = {0.05, -0.1};
    const HeightField hf = generate_heightfield(d, 0.0, 0, 30.0);
    for (int j = 0; j < hf.ny; j += 3) {
        for (int i = 0; i < hf.nx; i += 3) {
            const double x = hf.origin.x + i * hf.spacing.x, y = hf.origin.y + j * hf.spacing.y;
            const double rx = x - 0.05, ry = y + 0.1;
            const double e = std::exp(-(rx * rx + ry * ry) / (2 * 0.01));
            EXPECT_NEAR(hf.z(i, j), 0.04 * e, 1e-7);
            EXPECT_NEAR(hf.grad(i, j).x, -0.04 * rx / 0.01 * e, 1e-6);
            EXPECT_NEAR(hf.grad(i, j).y, -0.04 * ry / 0.01 * e, 1e-6);
        }
    }
    // Apex radius of curvature sigma^2 / A = 0.25 m: second difference of the exact gradient at the apex.
    const double h = 1e-5;
    const double curvature = (hf.sample_gradient(0.05 + h, -0.1).x - hf.sample_gradient(0.05 - h, -0.1).x) / (2 * h);
    EXPECT_NEAR(-1.0 / curvature, 0.25, 1e-6);
}

TEST(HeightFieldGenerators, TilesItsRectangleWhereOppositeEdgesAgree) {
    // A sine along x with a whole number of periods over the rectangle tiles; 5.43 periods do not; a flat
    // surface does; a field flagged periodic tiles whatever its edges hold.
    HeightFieldDesc d;
    d.size = {1.25, 1.25};
    d.resolution = {250, 250};
    d.generator = HeightGenerator::Sine;
    d.amplitude = 0.01;
    d.direction = {1.0, 0.0};
    d.wavelength = 0.25;
    EXPECT_TRUE(tiles_its_rectangle(generate_heightfield(d, 0.0, 0, 30.0)));
    d.wavelength = 0.23;
    HeightField cut = generate_heightfield(d, 0.0, 0, 30.0);
    EXPECT_FALSE(tiles_its_rectangle(cut));
    cut.periodic = true;
    EXPECT_TRUE(tiles_its_rectangle(cut));
    d.generator = HeightGenerator::Flat;
    EXPECT_TRUE(tiles_its_rectangle(generate_heightfield(d, 0.0, 0, 30.0)));
}

TEST(HeightFieldGenerators, FlatHasExactlyZeroGradient) {
    HeightFieldDesc d;
    d.resolution = {16, 8};
    d.base_height = 0.25;
    const HeightField hf = generate_heightfield(d, 0.0, 0, 30.0);
    for (std::size_t k = 0; k < hf.height.size(); ++k) {
        EXPECT_EQ(hf.height[k], 0.25f);
        EXPECT_EQ(hf.gradient[k], glm::vec2(0.0f));
    }
    EXPECT_EQ(hf.sample_gradient(0.1, 0.2), glm::dvec2(0.0));
    EXPECT_EQ(hf.sample_normal(0.3, -0.2), glm::dvec3(0, 0, 1));
    const TriangleMesh m = hf.triangulate();
    EXPECT_EQ(m.triangles.size(), 16u * 8u * 2u);
    for (const glm::uvec3& t : m.triangles) {
        const glm::dvec3 a(m.positions[t.x]), b(m.positions[t.y]), c(m.positions[t.z]);
        EXPECT_GT(glm::cross(b - a, c - a).z, 0.0);
    }
}

// ---------------------------------------------------------------- receiver chart

TEST(ReceiverChart, PlaneBinAreasSumToThePlaneArea) {
    const Scene s = load_scene(scene_path("sphere.json"));
    const FrameGeometry g = build_frame_geometry(s, 0);
    const ReceiverChart chart(g, 64, 32);
    double sum = 0.0;
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 64; ++i) sum += chart.bin_area(i, j);
    EXPECT_NEAR(sum, 16.0, 1e-9);
    EXPECT_NEAR(chart.total_area(), 16.0, 1e-9);
    EXPECT_TRUE(chart.is_plane());
    // Chart round trip and binning: p(s, t) -> (s, t) -> bin.
    const glm::dvec3 p = chart.point(0.3, 0.8);
    EXPECT_NEAR(p.x, -2.0 + 0.3 * 4.0, 1e-12);
    EXPECT_NEAR(p.y, -2.0 + 0.8 * 4.0, 1e-12);
    double ss, tt;
    EXPECT_TRUE(chart.coords(p + glm::dvec3(0, 0, 0.5), ss, tt));  // projected onto the plane
    EXPECT_NEAR(ss, 0.3, 1e-12);
    EXPECT_NEAR(tt, 0.8, 1e-12);
    EXPECT_EQ(chart.bin_of(p), static_cast<int>(0.8 * 32) * 64 + static_cast<int>(0.3 * 64));
    EXPECT_EQ(chart.bin_of(glm::dvec3(2.5, 0, 0)), -1);
    EXPECT_EQ(chart.normal(0.5, 0.5), glm::dvec3(0, 0, 1));
}

TEST(ReceiverChart, HeightFieldBinAreasAreSurfaceAreas) {
    Scene s;
    s.name = "t";
    Object floor;
    floor.name = "floor";
    floor.shape = ShapeType::HeightField;
    floor.heightfield.size = {1.0, 1.0};
    floor.heightfield.resolution = {256, 256};
    floor.heightfield.generator = HeightGenerator::Sine;
    floor.heightfield.amplitude = 0.05;
    floor.heightfield.wavelength = 0.5;
    s.objects = {floor};
    s.receiver.object_index = 0;
    const FrameGeometry g = build_frame_geometry(s, 0);
    const ReceiverChart chart(g, 32, 32);
    EXPECT_FALSE(chart.is_plane());
    // Exact area of z = A sin(k x) over the unit square: integral of sqrt(1 + (A k cos k x)^2) dx.
    const double k = 2 * std::numbers::pi / 0.5;
    double exact = 0.0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        const double x = -0.5 + (i + 0.5) / n;
        const double gx = 0.05 * k * std::cos(k * x);
        exact += std::sqrt(1 + gx * gx) / n;
    }
    EXPECT_NEAR(chart.total_area(), exact, 1e-4 * exact);
    EXPECT_GT(chart.total_area(), 1.05);
    const glm::dvec3 p = chart.point(0.25, 0.75);
    EXPECT_NEAR(p.z, 0.05 * std::sin(k * -0.25), 1e-4);
    EXPECT_EQ(chart.bin_of(p), 24 * 32 + 8);
}

// ---------------------------------------------------------------- meshes (glTF)

TEST(MeshScenes, RingIsClosedAndOutward) {
    const Scene s = load_scene(scene_path("ring.json"));
    const Object& ring = s.objects.at(0);
    ASSERT_EQ(ring.shape, ShapeType::Mesh);
    EXPECT_EQ(ring.material.type, MaterialType::Mirror);
    ASSERT_EQ(ring.mesh.triangles.size(), 2048u);
    ASSERT_EQ(ring.mesh.normals.size(), ring.mesh.positions.size());
    ASSERT_EQ(s.assets.size(), 1u);
    EXPECT_TRUE(fs::equivalent(s.assets[0], scene_path("assets/ring.glb")));
    double volume = 0.0;
    for (const glm::uvec3& t : ring.mesh.triangles) {
        const glm::dvec3 a(ring.mesh.positions[t.x]), b(ring.mesh.positions[t.y]), c(ring.mesh.positions[t.z]);
        const glm::dvec3 n = glm::cross(b - a, c - a);
        EXPECT_GT(glm::dot(n, glm::dvec3(ring.mesh.normals[t.x])), 0.0);  // winding agrees with the normals
        volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    EXPECT_NEAR(volume, std::numbers::pi * (0.51 * 0.51 - 0.25) * 0.25, 1e-4);
    EXPECT_EQ(s.lights[0].direction, glm::normalize(glm::dvec3(0.7, 0, -0.5)));
}

TEST(MeshScenes, BunnyIsAboutSixtyCentimetresTallOnTheFloor) {
    const Scene s = load_scene(scene_path("bunny.json"));
    const FrameGeometry g = build_frame_geometry(s, 0);
    const Bounds3& b = g.objects.at(0).bounds;
    EXPECT_NEAR(b.lo.z, 0.0, 1e-5);
    EXPECT_NEAR(b.hi.z - b.lo.z, 0.6, 1e-3);
    EXPECT_NEAR(b.center().x, 0.0, 1e-3);
    EXPECT_GT(g.objects[0].mesh.triangles.size(), 60000u);
    EXPECT_EQ(g.objects[0].mesh.normals.size(), g.objects[0].mesh.positions.size());
}


// ---------------------------------------------------------------- noise and waves

namespace {

HeightFieldDesc noise_desc() {
    HeightFieldDesc d;
    d.size = {2.0, 1.0};
    d.resolution = {64, 32};
    d.generator = HeightGenerator::Noise;
    d.amplitude = 0.01;
    d.min_wavelength = 8 * 2.0 / 64;  // smooth enough for finite differences to check the gradient
    d.period = 2.0;
    d.time_samples = 16;
    d.seed = 7;
    return d;
}

std::uint64_t fnv1a(const std::vector<float>& v) {
    std::uint64_t h = 1469598103934665603ull;
    for (float f : v) {
        std::uint32_t bits;
        std::memcpy(&bits, &f, 4);
        for (int k = 0; k < 4; ++k) h = (h ^ ((bits >> (8 * k)) & 0xFFu)) * 1099511628211ull;
    }
    return h;
}

}  // namespace

TEST(NoiseGenerator, TilesInSpace) {
    const HeightFieldDesc d = noise_desc();
    const HeightField hf = generate_heightfield(d, 0.3, 9, 30.0);
    ASSERT_TRUE(hf.periodic);
    for (int j = 0; j < hf.ny; ++j) {
        EXPECT_EQ(hf.z(0, j), hf.z(hf.nx - 1, j));
        EXPECT_EQ(hf.grad(0, j), hf.grad(hf.nx - 1, j));
    }
    for (int i = 0; i < hf.nx; ++i) EXPECT_EQ(hf.z(i, 0), hf.z(i, hf.ny - 1));
    // The gradient is continuous across the wrap: the central difference that straddles the seam
    // matches the spectral gradient as well as it does inside the tile.
    float max_grad = 0.0f;
    for (const glm::vec2& g : hf.gradient) max_grad = std::max(max_grad, std::max(std::abs(g.x), std::abs(g.y)));
    ASSERT_GT(max_grad, 0.0f);
    for (int j = 0; j < hf.ny; ++j) {
        const double across = (double(hf.z(1, j)) - hf.z(hf.nx - 2, j)) / (2 * hf.spacing.x);
        EXPECT_NEAR(across, hf.grad(0, j).x, 0.15 * max_grad);
        const double inside = (double(hf.z(11, j)) - hf.z(9, j)) / (2 * hf.spacing.x);
        EXPECT_NEAR(inside, hf.grad(10, j).x, 0.15 * max_grad);
    }
    for (int i = 0; i < hf.nx; ++i) {
        const double across = (double(hf.z(i, 1)) - hf.z(i, hf.ny - 2)) / (2 * hf.spacing.y);
        EXPECT_NEAR(across, hf.grad(i, 0).y, 0.15 * max_grad);
    }
    // Sampling wraps: one tile to the right is the same surface.
    EXPECT_NEAR(hf.sample_height(0.123, 0.2), hf.sample_height(0.123 + 2.0, 0.2), 1e-6);
}

TEST(NoiseGenerator, LoopsInTimeAndHasTheRequestedRms) {
    const HeightFieldDesc d = noise_desc();
    const HeightField a = generate_heightfield(d, 0.0, 0, 30.0);
    const HeightField b = generate_heightfield(d, d.period, 60, 30.0);
    const HeightField c = generate_heightfield(d, 0.5, 15, 30.0);
    EXPECT_EQ(a.height, b.height);
    EXPECT_NE(a.height, c.height);
    double sum2 = 0.0;
    for (int j = 0; j + 1 < a.ny; ++j)
        for (int i = 0; i + 1 < a.nx; ++i) sum2 += double(a.z(i, j)) * a.z(i, j);
    const double rms = std::sqrt(sum2 / ((a.nx - 1) * (a.ny - 1)));
    EXPECT_GT(rms, 0.5 * d.amplitude);
    EXPECT_LT(rms, 1.5 * d.amplitude);
    // Same seed, same surface; another seed, another surface.
    HeightFieldDesc other = d;
    other.seed = 8;
    EXPECT_NE(generate_heightfield(other, 0.0, 0, 30.0).height, a.height);
    EXPECT_EQ(generate_heightfield(d, 0.0, 0, 30.0).height, a.height);
}

namespace {

HeightFieldDesc waves_desc() {
    HeightFieldDesc d;
    d.size = {2.0, 2.0};
    d.resolution = {64, 64};
    d.generator = HeightGenerator::Waves;
    d.amplitude = 0.01;
    d.drops = 8;
    d.drop_radius = 0.08;
    d.wave_speed = 0.5;
    d.damping = 0.2;
    d.seed = 1;
    d.animation_length = 4.0;  // load_scene sets it from frames / fps
    return d;
}

}  // namespace

TEST(WavesGenerator, SameFrameSameBitsAndFramesDiffer) {
    const HeightFieldDesc d = waves_desc();
    const HeightField f10 = generate_heightfield(d, 10 / 30.0, 10, 30.0);
    const HeightField f20 = generate_heightfield(d, 20 / 30.0, 20, 30.0);
    const HeightField again10 = generate_heightfield(d, 10 / 30.0, 10, 30.0);  // restarts from frame 0
    const HeightField f5 = generate_heightfield(d, 5 / 30.0, 5, 30.0);
    const HeightField stepped10 = generate_heightfield(d, 10 / 30.0, 10, 30.0);  // continues from frame 5
    EXPECT_EQ(fnv1a(f10.height), fnv1a(again10.height));
    EXPECT_EQ(f10.height, stepped10.height);
    EXPECT_EQ(f10.gradient, again10.gradient);
    EXPECT_NE(f10.height, f20.height);
    EXPECT_NE(f5.height, f10.height);
    for (const HeightField* hf : {&f5, &f10, &f20})
        for (float z : hf->height) {
            ASSERT_TRUE(std::isfinite(z));
            ASSERT_LT(std::abs(z), 4 * d.amplitude);
        }
    // Frame 0 already carries the first drop.
    const HeightField f0 = generate_heightfield(d, 0.0, 0, 30.0);
    float peak = 0.0f;
    for (float z : f0.height) peak = std::max(peak, z);
    EXPECT_GT(peak, 0.5f * static_cast<float>(d.amplitude));
}

TEST(WavesGenerator, FrameBitsAreTheSameOnEveryMachine) {
    // A fingerprint of frame 30: a fixed operation order, no fused multiply-adds and no libm calls make
    // these bits the same on every IEEE-754 machine and build type. If this changes, the simulation
    // changed (and cached references of animated scenes are stale).
    const HeightFieldDesc d = waves_desc();
    const HeightField f30 = generate_heightfield(d, 1.0, 30, 30.0);
    EXPECT_EQ(fnv1a(f30.height), WAVES_FRAME30_FINGERPRINT) << std::hex << fnv1a(f30.height);
}

TEST(BuiltinScenes, PoolWavesAreAnimated) {
    const Scene s = load_scene(scene_path("pool.json"));
    EXPECT_EQ(s.animation.frames, 120);
    EXPECT_DOUBLE_EQ(s.objects[0].heightfield.animation_length, 4.0);
    EXPECT_THROW(build_frame_geometry(s, 120), InputError);
    const FrameGeometry a = build_frame_geometry(s, 119);
    const FrameGeometry b = build_frame_geometry(s, 60);
    EXPECT_NE(a.objects[0].heightfield->height, b.objects[0].heightfield->height);
    const ReceiverChart chart(a, 64, 64);
    EXPECT_NEAR(chart.total_area(), 4.0, 1e-9);
}
