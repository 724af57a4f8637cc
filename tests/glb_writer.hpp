#pragma once
// Binary glTF (GLB) files written by tests: a minimal valid container around a glTF JSON document and a
// binary chunk, so that cases can vary one thing (the node graph, a vertex, an extra member) at a time.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace caustics::test_support {

inline std::string glb_le32(std::uint32_t v) {
    std::string s(4, '\0');
    std::memcpy(s.data(), &v, 4);
    return s;
}

inline std::string glb_floats(const std::vector<float>& v) {
    std::string s(v.size() * sizeof(float), '\0');
    std::memcpy(s.data(), v.data(), s.size());
    return s;
}

// The GLB container (header, JSON chunk, BIN chunk) around the glTF document's text and its binary buffer.
inline std::string glb_container(std::string json_text, const std::string& bin) {
    json_text += std::string((4 - json_text.size() % 4) % 4, ' ');
    const std::string bin_padded = bin + std::string((4 - bin.size() % 4) % 4, '\0');
    const auto total = static_cast<std::uint32_t>(12 + 8 + json_text.size() + 8 + bin_padded.size());
    return "glTF" + glb_le32(2) + glb_le32(total) + glb_le32(static_cast<std::uint32_t>(json_text.size())) + "JSON" +
           json_text + glb_le32(static_cast<std::uint32_t>(bin_padded.size())) + std::string("BIN\0", 4) + bin_padded;
}

// The glTF document of one mesh named `name` with one non-indexed triangle (POSITION and NORMAL accessors on
// a buffer of `bin_bytes`), under the node graph `nodes` whose scene roots are `roots`.
inline nlohmann::json gltf_triangle_document(const std::string& name, std::size_t bin_bytes,
                                            const nlohmann::json& nodes, const nlohmann::json& roots) {
    using nlohmann::json;
    return {{"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", {{{"nodes", roots}}}},
            {"nodes", nodes},
            {"meshes", {{{"name", name}, {"primitives", {{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}}}}}}},
            {"accessors",
             {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
              {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}}}},
            {"bufferViews",
             {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}}, {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 36}}}},
            {"buffers", {{{"byteLength", bin_bytes}}}}};
}

// A minimal binary glTF: one mesh named `name` with one non-indexed triangle (POSITION and NORMAL), under the
// node graph `nodes` (default: one node holding the mesh) with scene root node 0.
inline std::string glb_triangle(const std::string& name, const std::vector<float>& positions,
                                const std::vector<float>& normals,
                                const nlohmann::json& nodes = nlohmann::json::array({{{"mesh", 0}}})) {
    const std::string bin = glb_floats(positions) + glb_floats(normals);
    return glb_container(gltf_triangle_document(name, bin.size(), nodes, {0}).dump(), bin);
}

}  // namespace caustics::test_support
