// The bad-input catalog (issue 12), scene part: magnitudes the computation cannot represent (single-
// precision geometry in Embree, float images, the reference's fixed-point weights), resolutions whose
// memory exceeds the ceiling, broken assets (truncated or oversized PNG height maps, GLB meshes with
// non-finite vertices or normals) and scenes whose reference would be empty are refused with exit 2 and
// one line naming the file and the key, nothing under --out and no cache entry (tests/catalog_support.hpp),
// through `caustics reference` and `caustics render`. Before issue 12 these aborted inside Embree, ran out
// of memory, printed libpng's text and exited 1, or exited 0 with an all-zero reference cached as exact.
// Unit tests of the memory estimate and its ceiling (CAUSTICS_MEMORY_LIMIT_GB) follow the catalog.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "catalog_support.hpp"
#include "glb_writer.hpp"
#include <caustics/util/errors.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/scene/limits.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/scene/scene.hpp>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using caustics::test_support::CaseDir;
using caustics::test_support::glb_triangle;
using caustics::test_support::check_refused;
using caustics::test_support::slurp;

// Sets (or, with nullopt, removes) an environment variable for its lifetime; the child programs inherit it.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const std::optional<std::string>& value) : name_(name) {
        if (const char* old = std::getenv(name)) old_ = std::string(old);
        if (value) ::setenv(name, value->c_str(), 1);
        else ::unsetenv(name);
    }
    ~ScopedEnv() {
        if (old_) ::setenv(name_, old_->c_str(), 1);
        else ::unsetenv(name_);
    }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* name_;
    std::optional<std::string> old_;
};

// A small valid scene: sine water (object 0) over a floor receiver (object 1) 0.4 m down; its
// reference of 20000 photons takes well under a second.
json base_scene() {
    const json camera = {{"position", {0, -0.6, -0.03}}, {"look_at", {0, 0.05, -0.4}}, {"up", {0, 0, 1}},
                         {"fov_y", 55}, {"width", 32}, {"height", 24}};
    return caustics::test_support::small_sine_scene(1.25, 32, camera);
}

json diffuse() { return {{"type", "diffuse"}}; }
json glass() { return {{"type", "dielectric"}, {"ior", 1.5}}; }

// ---- assets written by the cases

std::uint32_t crc32(const std::string& bytes) {
    std::uint32_t c = 0xFFFFFFFFu;
    for (const unsigned char b : bytes) {
        c ^= b;
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

std::string be32(std::uint32_t v) {
    return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8), static_cast<char>(v)};
}

std::string png_chunk(const std::string& type, const std::string& data) {
    return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(crc32(type + data));
}

const std::string kPngSignature("\x89PNG\r\n\x1a\n", 8);

// A well-formed PNG structure (IHDR, a small IDAT, IEND, valid CRCs) whose header claims width x height
// 8-bit grey pixels: the reader opens it and learns the size before any pixel is read.
std::string png_claiming(std::uint32_t width, std::uint32_t height) {
    const std::string ihdr = be32(width) + be32(height) + std::string("\x08\x00\x00\x00\x00", 5);
    return kPngSignature + png_chunk("IHDR", ihdr) + png_chunk("IDAT", std::string("\x78\x01\x01\x00\x00\xff\xff", 7)) +
           png_chunk("IEND", "");
}

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

// A glass mesh object (object 2) above the floor, from `file` in the case folder.
void add_mesh(json& s, const std::string& file) {
    s["objects"].push_back({{"name", "prism"}, {"shape", "mesh"}, {"file", file},
                            {"transform", {{"translate", {0, 0, -0.2}}}}, {"material", glass()}});
}

// ---- the catalog

// One scene case: `edit` changes the base scene (and may write assets into the case folder); the
// message must mention the scene file and every string of `expect`. Each case runs `reference` and, with
// `render`, `render --method caustic_triangles`; `extra` options are appended to both.
struct SceneCase {
    std::string name;
    std::function<void(json&, const CaseDir&)> edit;
    std::vector<std::string> expect;
    bool render = true;
    std::vector<std::string> extra = {};
    std::optional<std::string> memory_limit = std::nullopt;   // CAUSTICS_MEMORY_LIMIT_GB for the child
    bool names_scene = true;                                   // the message names the scene file
};
// ctest lists the case by its name, not by a byte dump of the struct.
inline void PrintTo(const SceneCase& c, std::ostream* os) { *os << c.name; }

std::vector<SceneCase> cases() {
    const std::string sine_amplitude = "objects[0].generator.amplitude";
    std::vector<SceneCase> table = {
        // Magnitudes beyond single-precision geometry (they aborted in Embree on `ray.valid()`).
        {"SineAmplitude1e30", [](json& s, const CaseDir&) { s["objects"][0]["generator"]["amplitude"] = 1e30; },
         {sine_amplitude, "valid:", "100000"}},
        {"BaseHeight1e300", [](json& s, const CaseDir&) { s["objects"][0]["base_height"] = 1e300; },
         {"objects[0].base_height", "valid:"}},
        {"HeightFieldSize1e300", [](json& s, const CaseDir&) { s["objects"][0]["size"] = {1e300, 1.25}; },
         {"objects[0].size", "valid:"}},
        {"PointLightAt1e300",
         [](json& s, const CaseDir&) {
             s["lights"] = json::array({{{"type", "point"}, {"position", {0, 0, 1e300}}, {"intensity", 1.0}}});
         },
         {"lights[0].position", "valid:"}},
        {"CameraAt1e300", [](json& s, const CaseDir&) { s["camera"]["position"] = {0, -1e300, 0}; },
         {"camera.position", "valid:"}},
        {"CameraLookAt1e300", [](json& s, const CaseDir&) { s["camera"]["look_at"] = {1e300, 0, 0}; },
         {"camera.look_at", "valid:"}},
        {"ReceiverPlaneAtZMinus1e300", [](json& s, const CaseDir&) { s["objects"][1]["center"] = {0, 0, -1e300}; },
         {"objects[1].center", "valid:"}},
        {"PlaneEdge1e300", [](json& s, const CaseDir&) { s["objects"][1]["u"] = {1e300, 0, 0}; },
         {"objects[1].u", "valid:"}},
        {"BoxSize1e300",
         [](json& s, const CaseDir&) {
             s["objects"].push_back({{"name", "crate"}, {"shape", "box"}, {"center", {0, 0, -0.3}},
                                     {"size", {1e300, 0.1, 0.1}}, {"material", diffuse()}});
         },
         {"objects[2].size", "valid:"}},
        {"SphereRadius1e300",
         [](json& s, const CaseDir&) {
             s["objects"].push_back({{"name", "ball"}, {"shape", "sphere"}, {"center", {0, 0, 1}},
                                     {"radius", 1e300}, {"material", glass()}});
         },
         {"objects[2].radius", "valid:"}},
        {"MeshTranslated1e300",
         [](json& s, const CaseDir& d) {
             d.write("prism.glb", glb_triangle("prism", {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 0}, {0, 0, 1, 0, 0, 1, 0, 0, 1}));
             add_mesh(s, "prism.glb");
             s["objects"][2]["transform"]["translate"] = {0, 0, 1e300};
         },
         {"objects[2].transform", "valid:"}},
        // Degenerate lengths (a Gaussian of width 1e-300 gave a NaN height and aborted in Embree).
        {"GaussianSigma1e-300",
         [](json& s, const CaseDir&) {
             s["objects"][0]["generator"] = {{"type", "gaussian"}, {"amplitude", 0.01}, {"sigma", 1e-300}};
         },
         {"objects[0].generator.sigma", "valid:"}},
        {"SineWavelength1e-300", [](json& s, const CaseDir&) { s["objects"][0]["generator"]["wavelength"] = 1e-300; },
         {"objects[0].generator.wavelength", "valid:"}},
        // Within the stated bounds, but the generated surface is not: a noise surface of RMS height
        // 90 km reaches beyond 100 km (refused when the frame is built; accepted before).
        {"NoiseHeightsBeyondTheBound",
         [](json& s, const CaseDir&) {
             s["objects"][0]["generator"] = {{"type", "noise"}, {"amplitude", 90000.0}, {"time_samples", 4}};
         },
         {"objects[0].generator", "reaches", "valid:"}},
        // Values whose reference is all zeros (reported as noise 0 and cached before).
        {"Absorption1e300", [](json& s, const CaseDir&) { s["objects"][0]["material"]["absorption"] = 1e300; },
         {"objects[0].material.absorption", "valid:"}},
        {"MediumAbsorption1e300", [](json& s, const CaseDir&) { s["medium"] = {{"absorption", 1e300}}; },
         {"medium.absorption", "valid:"}},
        {"Irradiance1e300", [](json& s, const CaseDir&) { s["lights"][0]["irradiance"] = 1e300; },
         {"lights[0].irradiance", "valid:"}},
        {"Irradiance1e-300", [](json& s, const CaseDir&) { s["lights"][0]["irradiance"] = 1e-300; },
         {"lights[0].irradiance", "valid:"}},
        // An infinite literal: nlohmann refuses 1e999 while parsing (out_of_range 406).
        {"AmplitudeInfinite1e999",
         [](json& s, const CaseDir&) { s["objects"][0]["generator"]["amplitude"] = "INF_PLACEHOLDER"; },
         {"1e999"}},
        // No light reaches the receiver: the floor lies 10 m to the side of the water (predictable from
        // the scene, found when the reference is traced: no bin receives flux).
        {"NoLightReachesReceiver", [](json& s, const CaseDir&) { s["objects"][1]["center"] = {10, 0, -0.4}; },
         {"receiver.object", "'floor'", "no caustic flux", "valid:"}},
        // Absorption within the bound, but 0.4 m of it leaves less than the reference resolves (e^-2000).
        {"AbsorptionLeavesNothing", [](json& s, const CaseDir&) { s["objects"][0]["material"]["absorption"] = 5000.0; },
         {"receiver.object", "absorbed", "valid:"}},
        // Resolutions against the memory ceiling (8 GiB by default).
        {"Receiver16384Squared", [](json& s, const CaseDir&) { s["receiver"]["resolution"] = {16384, 16384}; },
         {"receiver.resolution", "memory limit", "CAUSTICS_MEMORY_LIMIT_GB", "valid:"}},
        {"HeightField8192Squared", [](json& s, const CaseDir&) { s["objects"][0]["resolution"] = {8192, 8192}; },
         {"objects[0].resolution", "memory limit", "CAUSTICS_MEMORY_LIMIT_GB", "valid:"}},
        {"Camera16384Squared",
         [](json& s, const CaseDir&) {
             s["camera"]["width"] = 16384;
             s["camera"]["height"] = 16384;
         },
         {"camera.width", "memory limit", "valid:"}},
        // The scene fits the default replicas, but 256 replicas (sums, images and cache payload each)
        // do not: refused by the reference before it allocates.
        {"Replicas256On2048SquaredReceiver", [](json& s, const CaseDir&) { s["receiver"]["resolution"] = {2048, 2048}; },
         {"receiver.resolution", "256 reference replicas", "memory limit", "valid:"}, true,
         {"--replicas", "256", "--threads", "2"}},
        {"MemoryLimitVariableNotANumber", [](json&, const CaseDir&) {}, {"CAUSTICS_MEMORY_LIMIT_GB", "'lots'", "valid:"},
         true, {}, std::string("lots"), false},
        // Waves whose simulation to the last frame (asked for) would not finish: 4.2e6 vertices x 2e4
        // CFL substeps per frame x 999 frames (it ran past the time limit before).
        {"WavesSimulationTooLong",
         [](json& s, const CaseDir&) {
             s["objects"][0]["resolution"] = {2048, 2048};
             s["objects"][0]["generator"] = {{"type", "waves"}, {"amplitude", 0.01}, {"wave_speed", 1000.0}};
             s["animation"] = {{"frames", 1000}, {"fps", 30}};
         },
         {"objects[0].generator", "grid updates", "valid:"}, true, {"--frame", "999"}},
        // Height map images: a header claiming 65535 x 65535 pixels (bad_alloc before), the bare 24-byte
        // header, and sand_height.png cut in half (libpng's text and exit 1 before).
        {"PngHeaderClaims65535Squared",
         [](json& s, const CaseDir& d) {
             d.write("huge.png", png_claiming(65535, 65535));
             s["objects"][1] = {{"name", "floor"}, {"shape", "heightfield"}, {"center", {0, 0}}, {"size", {1, 1}},
                                {"resolution", {16, 16}}, {"base_height", -0.4}, {"material", diffuse()},
                                {"generator", {{"type", "image"}, {"file", "huge.png"}, {"amplitude", 0.05}}}};
         },
         {"objects[1].generator.file", "huge.png", "65535 x 65535", "memory limit", "valid:"}},
        {"PngBare24ByteHeader",
         [](json& s, const CaseDir& d) {
             d.write("header.png", png_claiming(65535, 65535).substr(0, 24));
             s["objects"][1] = {{"name", "floor"}, {"shape", "heightfield"}, {"center", {0, 0}}, {"size", {1, 1}},
                                {"resolution", {16, 16}}, {"base_height", -0.4}, {"material", diffuse()},
                                {"generator", {{"type", "image"}, {"file", "header.png"}, {"amplitude", 0.05}}}};
         },
         {"objects[1].generator.file", "header.png"}},
        {"PngTruncatedInHalf",
         [](json& s, const CaseDir& d) {
             const std::string png = slurp(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/assets/sand_height.png");
             d.write("half.png", png.substr(0, png.size() / 2));
             s["objects"][1] = {{"name", "floor"}, {"shape", "heightfield"}, {"center", {0, 0}}, {"size", {1, 1}},
                                {"resolution", {16, 16}}, {"base_height", -0.4}, {"material", diffuse()},
                                {"generator", {{"type", "image"}, {"file", "half.png"}, {"amplitude", 0.05}}}};
         },
         {"objects[1].generator.file", "half.png", "truncated or corrupt"}},
        // Meshes with non-finite data (an empty reference, exit 0 and cached before).
        {"GlbNaNVertex",
         [](json& s, const CaseDir& d) {
             d.write("nan.glb", glb_triangle("shard", {0, 0, 0, kNaN, 0, 0, 0, 0.1f, 0}, {0, 0, 1, 0, 0, 1, 0, 0, 1}));
             add_mesh(s, "nan.glb");
         },
         {"objects[2].file", "nan.glb", "'shard'", "POSITION 1", "valid:"}},
        // A node graph that is not a tree: node k lists node k + 1 twice, 40 levels down (2^40 visits; the
        // loader limited the depth, not the visits, and hung with memory growing).
        {"GlbNodeListedTwice40Deep",
         [](json& s, const CaseDir& d) {
             json nodes = json::array();
             for (int k = 0; k < 40; ++k) nodes.push_back({{"children", {k + 1, k + 1}}});
             nodes.push_back({{"mesh", 0}});
             d.write("dag.glb", glb_triangle("shard", {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 0}, {0, 0, 1, 0, 0, 1, 0, 0, 1}, nodes));
             add_mesh(s, "dag.glb");
         },
         {"objects[2].file", "dag.glb", "reached twice"}},
        // A vector value nested 100,000 deep (the message serialised it recursively: SIGSEGV).
        {"VectorNested100000Deep", [](json& s, const CaseDir&) { s["camera"]["up"] = "DEEP_PLACEHOLDER"; },
         {"camera.up", "nested deeper than 64"}},
        {"GlbInfiniteNormal",
         [](json& s, const CaseDir& d) {
             d.write("inf.glb", glb_triangle("shard", {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 0}, {0, 0, 1, kInf, 0, 1, 0, 0, 1}));
             add_mesh(s, "inf.glb");
         },
         {"objects[2].file", "inf.glb", "'shard'", "NORMAL 1", "valid:"}},
    };
    return table;
}

std::string write_case_scene(const SceneCase& c, const CaseDir& d) {
    json s = base_scene();
    c.edit(s, d);
    std::string text = s.dump(2);
    const std::string placeholder = "\"INF_PLACEHOLDER\"";
    if (const auto at = text.find(placeholder); at != std::string::npos) text.replace(at, placeholder.size(), "1e999");
    // Written as text: building a value that deep as a json would itself recurse that deep.
    const std::string deep = "\"DEEP_PLACEHOLDER\"";
    if (const auto at = text.find(deep); at != std::string::npos)
        text.replace(at, deep.size(), std::string(100000, '[') + "0" + std::string(100000, ']'));
    return d.write("scene.json", text);
}

class CatalogScene : public ::testing::TestWithParam<SceneCase> {};

TEST_P(CatalogScene, ReferenceRefused) {
    const SceneCase& c = GetParam();
    const CaseDir dir("scene_ref_" + c.name);
    const std::string scene = write_case_scene(c, dir);
    const ScopedEnv env(caustics::kMemoryLimitVariable, c.memory_limit);
    std::vector<std::string> expect = c.expect;
    if (c.names_scene) expect.push_back(scene);
    std::vector<std::string> args = {"reference", scene, "--photons", "20000", "--out", dir.out(), "--cache", dir.cache()};
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    check_refused(dir, args, expect);
}

TEST_P(CatalogScene, RenderRefused) {
    const SceneCase& c = GetParam();
    if (!c.render) GTEST_SKIP() << "reference only";
    const CaseDir dir("scene_render_" + c.name);
    const std::string scene = write_case_scene(c, dir);
    const ScopedEnv env(caustics::kMemoryLimitVariable, c.memory_limit);
    std::vector<std::string> expect = c.expect;
    if (c.names_scene) expect.push_back(scene);
    std::vector<std::string> args = {"render",   scene,       "--method", "caustic_triangles", "--photons", "20000",
                                     "--warmup", "0",         "--repeats", "1",                "--max-time", "0.5",
                                     "--out",    dir.out(),   "--cache",  dir.cache()};
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    check_refused(dir, args, expect);
}

INSTANTIATE_TEST_SUITE_P(Catalog, CatalogScene, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<SceneCase>& info) {
                             std::string n = info.param.name;
                             for (char& ch : n)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return n;
                         });

// The base scene itself is accepted and gives a non-empty reference (so that every refusal above is
// the case's own doing).
TEST(CatalogSceneBase, BaseSceneRuns) {
    const CaseDir dir("scene_base");
    const ScopedEnv env(caustics::kMemoryLimitVariable, std::nullopt);
    const std::string scene = dir.write("scene.json", base_scene().dump(2));
    const auto r = caustics::test_support::run_program(
        CAUSTICS_BINARY, {"reference", scene, "--photons", "20000", "--out", dir.out(), "--cache", dir.cache()}, dir.path());
    ASSERT_EQ(r.code, 0) << r.err;
    const json ref = json::parse(slurp(fs::path(dir.out()) / "reference.json"));
    EXPECT_GT(ref["ledger"]["deposited_receiver"].get<double>(), 0.0);
    EXPECT_GT(ref["noise_nrmse"].get<double>(), 0.0);
}

// Photon counts near 2^64 no longer wrap to 0 photons per replica (a reference that traced nothing).
TEST(ReferencePhotons, PerReplicaCountDoesNotWrap) {
    const std::uint64_t max = std::numeric_limits<std::uint64_t>::max();
    EXPECT_EQ(caustics::photons_per_replica(max, 8, 1), max / 8 + 1);
    EXPECT_GT(caustics::photons_per_replica(max, 2, 3), 0u);
    EXPECT_EQ(caustics::photons_per_replica(max, 1, 1), max);
    EXPECT_EQ(caustics::photons_per_replica(1000, 8, 1), 125u);
    EXPECT_EQ(caustics::photons_per_replica(1001, 8, 2), 126u);
}

// A ray Embree would refuse (it asserts and aborts on a non-finite or huge origin or direction) is an
// internal failure that names it, not an abort, should a bug upstream ever make one.
TEST(RayTracerGuard, InvalidRayThrowsInsteadOfAborting) {
    caustics::Scene scene;
    caustics::Object floor;
    floor.name = "floor";
    floor.shape = caustics::ShapeType::Plane;
    scene.objects.push_back(floor);
    scene.receiver.object = "floor";
    scene.receiver.object_index = 0;
    const caustics::FrameGeometry frame = caustics::build_frame_geometry(scene, 0);
    const caustics::RayTracer tracer(frame);
    EXPECT_TRUE(tracer.intersect({0, 0, 1}, {0, 0, -1}).valid);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(tracer.intersect({0, 0, 1}, {nan, 0, -1}), std::runtime_error);
    EXPECT_THROW(tracer.intersect({0, 0, 1e300}, {0, 0, -1}), std::runtime_error);
    EXPECT_THROW(tracer.occluded({0, 0, nan}, {0, 0, -1}, 0.0, 2.0), std::runtime_error);
}

// ---- the memory estimate and its ceiling

TEST(MemoryEstimate, PerBinAndPerPixelTerms) {
    // R = 8, T = 2: trace 8 R (1 + T) = 192, finish 8 R + 2 (8 + 4 R) = 144, store 8 R + 8 + 4 R + 16 R = 232.
    EXPECT_DOUBLE_EQ(caustics::reference_bytes_per_bin(8, 2), 8.0 + 232.0 + 16.0);
    EXPECT_DOUBLE_EQ(caustics::reference_bytes_per_pixel(8, 2), 29.0 + 16.0 + 1.0 + 232.0 + 24.0);
    // The threads deposit atomically into one copy of the sums: the estimate does not grow with them.
    EXPECT_DOUBLE_EQ(caustics::reference_bytes_per_bin(8, 16), caustics::reference_bytes_per_bin(8, 2));
    EXPECT_DOUBLE_EQ(caustics::reference_bytes_per_pixel(8, 64), caustics::reference_bytes_per_pixel(8, 2));
}

caustics::Scene scene_with(int receiver, int camera_w, int camera_h, int grid) {
    caustics::Scene s;
    s.receiver.width = s.receiver.height = receiver;
    s.camera.width = camera_w;
    s.camera.height = camera_h;
    caustics::Object water;
    water.shape = caustics::ShapeType::HeightField;
    water.heightfield.resolution = {grid, grid};
    s.objects.push_back(water);
    return s;
}

TEST(MemoryEstimate, ItemsAndTotal) {
    const caustics::Scene s = scene_with(1024, 640, 480, 512);
    const caustics::MemoryEstimate e = caustics::estimate_scene_memory(s, 8, 2);
    ASSERT_EQ(e.items.size(), 3u);
    EXPECT_DOUBLE_EQ(e.items[0].bytes, 1024.0 * 1024.0 * caustics::reference_bytes_per_bin(8, 2));
    EXPECT_EQ(e.items[0].key, "receiver.resolution");
    EXPECT_DOUBLE_EQ(e.items[1].bytes, 640.0 * 480.0 * caustics::reference_bytes_per_pixel(8, 2));
    EXPECT_EQ(e.items[1].key, "camera.width");
    EXPECT_DOUBLE_EQ(e.items[2].bytes, 512.0 * 512.0 * caustics::heightfield_bytes_per_cell());
    EXPECT_EQ(e.items[2].key, "objects[0].resolution");
    EXPECT_DOUBLE_EQ(e.total(), e.items[0].bytes + e.items[1].bytes + e.items[2].bytes);
    EXPECT_EQ(e.largest(), &e.items[0]);
}

TEST(MemoryEstimate, CeilingFromTheEnvironment) {
    {
        const ScopedEnv env(caustics::kMemoryLimitVariable, std::nullopt);
        EXPECT_DOUBLE_EQ(caustics::memory_limit_bytes(), 8.0 * 1073741824.0);
    }
    {
        const ScopedEnv env(caustics::kMemoryLimitVariable, std::string("64"));
        EXPECT_DOUBLE_EQ(caustics::memory_limit_bytes(), 64.0 * 1073741824.0);
    }
    for (const char* bad : {"lots", "-1", "0", "nan", "inf", "8GB"}) {
        const ScopedEnv env(caustics::kMemoryLimitVariable, std::string(bad));
        EXPECT_THROW(caustics::memory_limit_bytes(), caustics::InputError) << bad;
    }
}

TEST(MemoryEstimate, TheLargestAllowedResolutionsAreRefusedByDefaultAndAcceptedWhenRaised) {
    const caustics::Scene receiver = scene_with(16384, 64, 48, 16);
    const caustics::Scene grid = scene_with(16, 64, 48, 8192);
    {
        const ScopedEnv env(caustics::kMemoryLimitVariable, std::nullopt);
        try {
            caustics::check_scene_memory(receiver, 8, 2);
            ADD_FAILURE() << "16384 x 16384 receiver accepted";
        } catch (const caustics::InputError& e) {
            EXPECT_EQ(e.key(), "receiver.resolution");
            EXPECT_NE(std::string(e.what()).find("CAUSTICS_MEMORY_LIMIT_GB"), std::string::npos) << e.what();
        }
        EXPECT_THROW(caustics::check_scene_memory(grid, 8, 2), caustics::InputError);
    }
    {
        const ScopedEnv env(caustics::kMemoryLimitVariable, std::string("1000"));
        EXPECT_NO_THROW(caustics::check_scene_memory(receiver, 8, 2));
        EXPECT_NO_THROW(caustics::check_scene_memory(grid, 8, 2));
    }
}

// Every shipped scene fits the default ceiling with up to 64 worker threads.
TEST(MemoryEstimate, ShippedScenesFitTheDefaultCeiling) {
    const ScopedEnv env(caustics::kMemoryLimitVariable, std::nullopt);
    for (const auto& entry : fs::directory_iterator(std::string(CAUSTICS_SOURCE_DIR) + "/scenes")) {
        if (entry.path().extension() != ".json") continue;
        const caustics::Scene s = caustics::load_scene(entry.path().string());
        EXPECT_NO_THROW(caustics::check_scene_memory(s, caustics::kMemoryDefaultReplicas, 64)) << entry.path();
    }
}

}  // namespace
