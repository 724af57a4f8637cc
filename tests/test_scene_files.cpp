// Scene files: malformed scenes are rejected with the file and the key named (one corruption of a valid
// base scene per case), and the asset paths a scene file can take (glTF with external buffers and node
// transforms, mesh transforms, image height maps) load as specified.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include <caustics/util/errors.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/scene/scene.hpp>

namespace fs = std::filesystem;
using namespace caustics;

namespace {

std::string scene_path(const std::string& name) { return std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name; }

}  // namespace

// ---------------------------------------------------------------- malformed scenes

namespace {

// A temporary folder with a valid small scene that each test corrupts in one place.
class MalformedScene : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("caustics_test_scene_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "assets");
        fs::copy_file(scene_path("assets/ring.glb"), dir_ / "assets/ring.glb");
        base_ = nlohmann::json::parse(R"({
          "lights": [ {"type": "directional", "direction": [0, 0, -1], "irradiance": 1.0} ],
          "objects": [
            {"name": "water", "shape": "heightfield", "center": [0, 0], "size": [2, 2], "resolution": [16, 16],
             "material": {"type": "dielectric", "ior": 1.33},
             "generator": {"type": "sine", "amplitude": 0.01, "wavelength": 0.25}},
            {"name": "floor", "shape": "plane", "center": [0, 0, -0.4], "u": [1, 0, 0], "v": [0, 1, 0],
             "material": {"type": "diffuse"}},
            {"name": "ring", "shape": "mesh", "file": "assets/ring.glb", "material": {"type": "mirror"}},
            {"name": "ball", "shape": "sphere", "center": [0, 0, 1], "radius": 0.2, "material": {"type": "dielectric", "ior": 1.5}}
          ],
          "receiver": {"object": "floor", "resolution": [32, 32]}
        })");
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string write(const std::string& text, const std::string& name = "scene.json") {
        const fs::path p = dir_ / name;
        std::ofstream(p, std::ios::binary) << text;
        return p.string();
    }
    std::string write_json(const nlohmann::json& j) { return write(j.dump(2)); }

    // Loading `path` must throw an InputError naming the file and (when given) the key path.
    static void expect_rejected(const std::string& path, const std::string& key, const std::string& phrase = {}) {
        try {
            load_scene(path);
            ADD_FAILURE() << "accepted a bad scene; expected an error at '" << key << "'";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(e.file(), path);
            EXPECT_NE(what.find(path), std::string::npos) << what;
            if (!key.empty()) {
                EXPECT_EQ(e.key(), key) << what;
                EXPECT_NE(what.find("'" + key + "'"), std::string::npos) << what;
            }
            if (!phrase.empty()) {
                EXPECT_NE(what.find(phrase), std::string::npos) << what;
            }
        }
    }

    fs::path dir_;
    nlohmann::json base_;
};

}  // namespace

TEST_F(MalformedScene, TheBaseSceneIsValid) {
    const Scene s = load_scene(write_json(base_));
    EXPECT_EQ(s.objects.size(), 4u);
    EXPECT_EQ(s.receiver.object_index, 1);
    EXPECT_EQ(s.assets.size(), 1u);
    EXPECT_EQ(s.name, "scene");
}

TEST_F(MalformedScene, MissingFile) { expect_rejected((dir_ / "nope.json").string(), "", "does not exist"); }

TEST_F(MalformedScene, BadJsonGivesLineAndColumn) {
    expect_rejected(write("{\n  \"lights\": [\n    {\"type\": \"point\",, }\n  ]\n}\n"), "", "line 3");
}

TEST_F(MalformedScene, UnknownKeys) {
    auto j = base_;
    j["lightz"] = 1;
    expect_rejected(write_json(j), "lightz", "valid keys");
    j = base_;
    j["objects"][1]["material"]["colour"] = {1, 0, 0};
    expect_rejected(write_json(j), "objects[1].material.colour", "albedo");
    j = base_;
    j["objects"][0]["generator"]["wavelenght"] = 0.3;
    expect_rejected(write_json(j), "objects[0].generator.wavelenght", "wavelength");
}

TEST_F(MalformedScene, NegativeZeroAndHugeResolution) {
    auto j = base_;
    j["objects"][0]["resolution"] = {-4, 16};
    expect_rejected(write_json(j), "objects[0].resolution", "integers in [1,");
    j["objects"][0]["resolution"] = {16, 0};
    expect_rejected(write_json(j), "objects[0].resolution");
    j["objects"][0]["resolution"] = {100000, 16};
    expect_rejected(write_json(j), "objects[0].resolution");
    j = base_;
    j["receiver"]["resolution"] = {32, -1};
    expect_rejected(write_json(j), "receiver.resolution");
    j = base_;
    j["camera"] = {{"width", 1.5}};
    expect_rejected(write_json(j), "camera.width", "integer");
}

TEST_F(MalformedScene, NanStringAndNonPositiveIor) {
    auto j = base_;
    j["objects"][0]["material"]["ior"] = "NaN";
    expect_rejected(write_json(j), "objects[0].material.ior", "finite number > 0");
    j["objects"][0]["material"]["ior"] = "nan";
    expect_rejected(write_json(j), "objects[0].material.ior");
    j["objects"][0]["material"]["ior"] = 0.0;
    expect_rejected(write_json(j), "objects[0].material.ior", "> 0");
    j["objects"][0]["material"]["ior"] = -1.33;
    expect_rejected(write_json(j), "objects[0].material.ior");
    // A bare NaN is not JSON at all; an overflowing literal is not finite.
    expect_rejected(write(std::string(R"({"lights": [{"type": "point", "position": [0, 0, NaN]}]})")), "");
    std::string text = base_.dump();
    text.replace(text.find("\"irradiance\":1.0"), 16, "\"irradiance\":1e999");
    expect_rejected(write(text), "", "1e999");  // nlohmann refuses it while parsing
}

TEST_F(MalformedScene, ZeroLengthVectors) {
    auto j = base_;
    j["lights"][0]["direction"] = {0, 0, 0};
    expect_rejected(write_json(j), "lights[0].direction", "non-zero");
    j = base_;
    j["objects"][1]["u"] = {0, 0, 0};
    expect_rejected(write_json(j), "objects[1].u");
    j = base_;
    j["objects"][1]["v"] = {2, 0, 0};  // parallel to u
    expect_rejected(write_json(j), "objects[1].v", "parallel");
}

TEST_F(MalformedScene, EmptyMesh) {
    // A valid GLB whose default scene has no mesh at all.
    const std::string json = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[]}]})";
    std::string padded = json + std::string((4 - json.size() % 4) % 4, ' ');
    std::string glb(20, '\0');
    const std::uint32_t header[5] = {0x46546C67u, 2u, static_cast<std::uint32_t>(20 + padded.size()),
                                     static_cast<std::uint32_t>(padded.size()), 0x4E4F534Au};
    std::memcpy(glb.data(), header, sizeof(header));
    write(glb + padded, "assets/empty.glb");
    auto j = base_;
    j["objects"][2]["file"] = "assets/empty.glb";
    expect_rejected(write_json(j), "objects[2].file", "no triangles");
}

TEST_F(MalformedScene, MissingOrUnreadableAsset) {
    auto j = base_;
    j["objects"][2]["file"] = "assets/missing.glb";
    expect_rejected(write_json(j), "objects[2].file", "does not exist");
    write("this is not a glb file at all", "assets/garbage.glb");
    j["objects"][2]["file"] = "assets/garbage.glb";
    expect_rejected(write_json(j), "objects[2].file", "cannot load");
    j["objects"][2]["file"] = "assets";  // a folder
    expect_rejected(write_json(j), "objects[2].file");
    j = base_;
    j["objects"][0]["generator"] = {{"type", "image"}, {"file", "assets/nothing.png"}};
    expect_rejected(write_json(j), "objects[0].generator.file", "does not exist");
}

TEST_F(MalformedScene, ReceiverNamingNoObjectOrASphere) {
    auto j = base_;
    j["receiver"]["object"] = "flor";
    expect_rejected(write_json(j), "receiver.object", "no object is named 'flor'");
    j["receiver"]["object"] = "ball";
    expect_rejected(write_json(j), "receiver.object", "not a plane or height field");
    j["receiver"]["object"] = "ring";
    expect_rejected(write_json(j), "receiver.object", "'floor'");
    j = base_;
    j.erase("receiver");
    expect_rejected(write_json(j), "receiver", "missing");
}

TEST_F(MalformedScene, DuplicateName) {
    auto j = base_;
    j["objects"][3]["name"] = "water";
    expect_rejected(write_json(j), "objects[3].name", "duplicate");
}

TEST_F(MalformedScene, DuplicateKey) {
    std::string text = base_.dump();
    const std::string radius = "\"radius\":0.2";
    text.replace(text.find(radius), radius.size(), radius + "," + radius);
    expect_rejected(write(text), "objects[3].radius", "duplicate key");
    text = base_.dump();
    text.replace(text.find("{\"lights\""), 1, "{\"fresnel\":true,\"fresnel\":false,");
    expect_rejected(write(text), "fresnel", "duplicate key");
}

TEST_F(MalformedScene, WrongTypes) {
    auto j = base_;
    j["fresnel"] = "yes";
    expect_rejected(write_json(j), "fresnel", "true or false");
    j = base_;
    j["objects"][3]["radius"] = "0.2";
    expect_rejected(write_json(j), "objects[3].radius", "number");
    j = base_;
    j["objects"][3]["center"] = {0, 1};
    expect_rejected(write_json(j), "objects[3].center", "3 finite numbers");
    j = base_;
    j["objects"][0]["generator"]["type"] = "perlin";
    expect_rejected(write_json(j), "objects[0].generator.type", "\"noise\"");
    j = base_;
    j["objects"][1]["shape"] = "disk";
    expect_rejected(write_json(j), "objects[1].shape", "\"plane\"");
    j = base_;
    j["objects"] = nlohmann::json::object();
    expect_rejected(write_json(j), "objects", "array");
    j = base_;
    j["objects"][3].erase("material");
    expect_rejected(write_json(j), "objects[3].material", "missing");
    expect_rejected(write(std::string("[1, 2, 3]")), "", "object");
}

TEST_F(MalformedScene, OutOfRangeValues) {
    auto j = base_;
    j["objects"][3]["radius"] = 0;
    expect_rejected(write_json(j), "objects[3].radius", "> 0");
    j = base_;
    j["objects"][1]["material"]["albedo"] = {0.5, 1.5, 0.5};
    expect_rejected(write_json(j), "objects[1].material.albedo", "[0, 1]");
    j = base_;
    j["animation"] = {{"frames", 0}};
    expect_rejected(write_json(j), "animation.frames");
    j = base_;
    j["medium"] = {{"anisotropy", 1.0}};
    expect_rejected(write_json(j), "medium.anisotropy");
    // The medium inside a dielectric (issue 15): every key validated, named with its path.
    j = base_;
    j["objects"][3]["material"]["medium"] = {{"scattering", -0.1}};
    expect_rejected(write_json(j), "objects[3].material.medium.scattering", ">= 0");
    j = base_;
    j["objects"][3]["material"]["medium"] = {{"anisotropy", -1.0}};
    expect_rejected(write_json(j), "objects[3].material.medium.anisotropy");
    j = base_;
    j["objects"][3]["material"]["medium"] = {{"absorption", 1e300}};
    expect_rejected(write_json(j), "objects[3].material.medium.absorption", "valid:");
    j = base_;
    j["objects"][3]["material"]["medium"] = {{"density", 1.0}};
    expect_rejected(write_json(j), "objects[3].material.medium.density");
    j = base_;
    j["objects"][3]["material"]["absorption"] = 0.5;
    j["objects"][3]["material"]["medium"] = {{"absorption", 0.5}};
    expect_rejected(write_json(j), "objects[3].material.medium.absorption", "one place");
    j = base_;
    j["objects"][1]["material"]["medium"] = {{"scattering", 0.5}};   // a diffuse floor has no inside
    expect_rejected(write_json(j), "objects[1].material.medium");
    j = base_;
    j["objects"][0]["generator"]["wavelength"] = -0.25;
    expect_rejected(write_json(j), "objects[0].generator.wavelength", "> 0");
    j = base_;
    j["objects"][2]["transform"] = {{"scale", 0}};
    expect_rejected(write_json(j), "objects[2].transform.scale", "non-zero");
    j = base_;
    j["objects"][0]["resolution"] = {2048, 2048};
    j["objects"][0]["generator"] = {{"type", "noise"}, {"amplitude", 0.01}, {"time_samples", 64}};
    expect_rejected(write_json(j), "objects[0].generator.time_samples", "exceeds");
}

TEST_F(MalformedScene, MeshTransformMovesPositionsAndNormals) {
    auto j = base_;
    j["objects"][2]["transform"] = {{"translate", {1, 2, 3}}, {"rotate_deg", {90, 0, 0}}, {"scale", 2}};
    const Scene s = load_scene(write_json(j));
    const TriangleMesh& m = s.objects[2].mesh;
    // The ring (z in [0, 0.25], radius 0.51) scaled by 2, turned +90 degrees about x, moved by (1, 2, 3).
    Bounds3 b;
    for (const glm::vec3& p : m.positions) b.extend(glm::dvec3(p));
    EXPECT_NEAR(b.lo.y, 1.5, 1e-5);  // right-handed: +90 degrees about x takes +z to -y
    EXPECT_NEAR(b.hi.y, 2.0, 1e-5);
    EXPECT_NEAR(b.hi.x, 1.0 + 1.02, 1e-5);
    EXPECT_NEAR(b.hi.z, 3.0 + 1.02, 1e-3);
    for (const glm::uvec3& t : m.triangles) {
        const glm::dvec3 a(m.positions[t.x]), bb(m.positions[t.y]), c(m.positions[t.z]);
        EXPECT_GT(glm::dot(glm::cross(bb - a, c - a), glm::dvec3(m.normals[t.x])), 0.0);
        EXPECT_NEAR(glm::length(glm::dvec3(m.normals[t.x])), 1.0, 1e-5);
    }
    // A mirroring scale keeps triangles outward (winding flipped with the normals).
    j["objects"][2]["transform"] = {{"scale", {-1, 1, 1}}};
    const Scene s2 = load_scene(write_json(j));
    const TriangleMesh& m2 = s2.objects[2].mesh;
    for (const glm::uvec3& t : m2.triangles) {
        const glm::dvec3 a(m2.positions[t.x]), bb(m2.positions[t.y]), c(m2.positions[t.z]);
        EXPECT_GT(glm::dot(glm::cross(bb - a, c - a), glm::dvec3(m2.normals[t.x])), 0.0);
    }
}

TEST_F(MalformedScene, GltfWithExternalBufferAndNodeTransform) {
    // One triangle in tri.bin (3 float VEC3 positions, then 3 uint16 indices), under a node that
    // translates by (0, 0, 1) and scales by 2; no NORMAL, so the mesh has no normals.
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::uint16_t indices[3] = {0, 1, 2};
    std::string bin(reinterpret_cast<const char*>(positions), sizeof(positions));
    bin.append(reinterpret_cast<const char*>(indices), sizeof(indices));
    write(bin, "assets/tri.bin");
    write(R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
      "nodes": [{"children": [1], "translation": [0, 0, 1]}, {"mesh": 0, "scale": [2, 2, 2]}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
      "buffers": [{"uri": "tri.bin", "byteLength": 42}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})",
          "assets/tri.gltf");
    auto j = base_;
    j["objects"][2]["file"] = "assets/tri.gltf";
    j["objects"][2]["transform"] = {{"translate", {10, 0, 0}}};
    const Scene s = load_scene(write_json(j));
    const TriangleMesh& m = s.objects[2].mesh;
    ASSERT_EQ(m.triangles.size(), 1u);
    EXPECT_TRUE(m.normals.empty());
    EXPECT_EQ(m.positions[1], glm::vec3(12, 0, 1));
    EXPECT_EQ(m.positions[2], glm::vec3(10, 2, 1));
    ASSERT_EQ(s.assets.size(), 2u);
    EXPECT_TRUE(fs::equivalent(s.assets[1], dir_ / "assets/tri.bin"));
    // The same file with a buffer that is too short is rejected, naming the key.
    write(bin.substr(0, 20), "assets/tri.bin");
    expect_rejected(write_json(j), "objects[2].file", "cannot load");
}

TEST_F(MalformedScene, ImageHeightMap) {
    // 4 x 2 image, value = (x + 10 y) / 100; the top row is +y.
    const int w = 4, h = 2;
    std::vector<float> pixels;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) pixels.push_back(static_cast<float>(x + 10 * y) / 100.0f);
    const std::string png = (dir_ / "assets/height.exr").string();
    auto out = OIIO::ImageOutput::create(png);
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(png, OIIO::ImageSpec(w, h, 1, OIIO::TypeDesc::FLOAT)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
    out->close();
    auto j = base_;
    j["objects"][0]["resolution"] = {3, 1};  // 4 x 2 vertices: one per pixel
    j["objects"][0]["base_height"] = -0.5;
    j["objects"][0]["generator"] = {{"type", "image"}, {"file", "assets/height.exr"}, {"amplitude", 2.0}};
    const Scene s = load_scene(write_json(j));
    ASSERT_EQ(s.assets.size(), 2u);
    const HeightField hf = generate_heightfield(s.objects[0].heightfield, 0.0, 0, 30.0);
    ASSERT_EQ(hf.nx, 4);
    ASSERT_EQ(hf.ny, 2);
    for (int jj = 0; jj < 2; ++jj)
        for (int i = 0; i < 4; ++i)
            EXPECT_NEAR(hf.z(i, jj), -0.5 + 2.0 * (i + 10 * (1 - jj)) / 100.0, 1e-6) << i << "," << jj;
    EXPECT_NEAR(hf.grad(1, 0).x, 2.0 * 0.01 / (2.0 / 3.0), 1e-5);
    EXPECT_NEAR(hf.grad(1, 0).y, -2.0 * 0.1 / 2.0, 1e-5);
}
