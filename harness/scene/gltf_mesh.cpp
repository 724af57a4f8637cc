// glTF/GLB -> TriangleMesh with tinygltf (Debian ships it as a shared library: no
// TINYGLTF_IMPLEMENTATION here, docs/design.md section 10).
#include <caustics/scene/gltf_mesh.hpp>

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <tiny_gltf.h>

#include <caustics/util/json_reader.hpp>

namespace caustics {

namespace {

// Images are irrelevant to geometry: accept them without decoding.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
    return true;
}

[[noreturn]] void bad(const std::string& path, const std::string& what) {
    throw std::runtime_error("glTF file '" + path + "': " + what);
}

// The glTF document's JSON text inside the file's bytes: the JSON chunk of a binary glTF (GLB header: magic,
// version, length; then the chunk's length and type), or the whole file. Empty when the container is too
// short to hold the chunk it announces (tinygltf refuses it).
std::string_view gltf_json_text(const std::vector<unsigned char>& bytes, bool binary) {
    const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    if (!binary) return all;
    if (bytes.size() < 20) return {};
    const std::uint32_t length = bytes[12] | bytes[13] << 8 | bytes[14] << 16 | static_cast<std::uint32_t>(bytes[15]) << 24;
    if (length > bytes.size() - 20) return {};
    return all.substr(20, length);
}

bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string triple(const glm::dvec3& v) {
    char text[96];
    std::snprintf(text, sizeof text, "(%g, %g, %g)", v.x, v.y, v.z);
    return text;
}

// "mesh 'Bunny' (meshes[0]) primitive 2" for messages.
std::string mesh_label(const tinygltf::Model& model, int mesh_index, std::size_t primitive) {
    const std::string& name = model.meshes[static_cast<std::size_t>(mesh_index)].name;
    return "mesh " + (name.empty() ? std::string() : "'" + name + "' ") + "(meshes[" + std::to_string(mesh_index) +
           "]) primitive " + std::to_string(primitive);
}

// Vertices and normals must be finite (in the file, and after the node transforms in float).
[[noreturn]] void not_finite(const std::string& path, const std::string& where, const char* what, std::size_t k,
                             const glm::dvec3& value, const char* after) {
    throw MeshDataError("glTF file '" + path + "': " + where + ": " + what + " " + std::to_string(k) + " is " +
                        triple(value) + after + "; valid: finite numbers");
}

// Raw bytes and stride of an accessor, bounds-checked.
struct AccessorView {
    const unsigned char* data = nullptr;
    std::size_t stride = 0;
    std::size_t count = 0;
};

AccessorView view_of(const tinygltf::Model& model, int index, std::size_t element_size, const std::string& path) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) bad(path, "accessor index out of range");
    const tinygltf::Accessor& acc = model.accessors[static_cast<std::size_t>(index)];
    if (acc.sparse.isSparse) bad(path, "sparse accessors are not supported");
    if (acc.bufferView < 0 || static_cast<std::size_t>(acc.bufferView) >= model.bufferViews.size())
        bad(path, "accessor without a valid buffer view");
    const tinygltf::BufferView& bv = model.bufferViews[static_cast<std::size_t>(acc.bufferView)];
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model.buffers.size()) bad(path, "buffer view without a valid buffer");
    const tinygltf::Buffer& buf = model.buffers[static_cast<std::size_t>(bv.buffer)];
    AccessorView v;
    const int stride = acc.ByteStride(bv);
    if (stride <= 0) bad(path, "invalid accessor stride");
    v.stride = static_cast<std::size_t>(stride);
    v.count = acc.count;
    const std::size_t start = bv.byteOffset + acc.byteOffset;
    const std::size_t need = v.count == 0 ? 0 : (v.count - 1) * v.stride + element_size;
    if (start + need > buf.data.size() || acc.byteOffset + need > bv.byteLength) bad(path, "accessor runs past the end of its buffer");
    v.data = buf.data.data() + start;
    return v;
}

std::vector<glm::vec3> read_vec3(const tinygltf::Model& model, int index, const std::string& path, const char* what) {
    const tinygltf::Accessor& acc = model.accessors.at(static_cast<std::size_t>(index));
    if (acc.type != TINYGLTF_TYPE_VEC3 || acc.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
        bad(path, std::string(what) + " must be a float VEC3 accessor");
    const AccessorView v = view_of(model, index, sizeof(float) * 3, path);
    std::vector<glm::vec3> out(v.count);
    for (std::size_t k = 0; k < v.count; ++k) std::memcpy(&out[k], v.data + k * v.stride, sizeof(float) * 3);
    return out;
}

std::vector<std::uint32_t> read_indices(const tinygltf::Model& model, int index, const std::string& path) {
    const tinygltf::Accessor& acc = model.accessors.at(static_cast<std::size_t>(index));
    if (acc.type != TINYGLTF_TYPE_SCALAR) bad(path, "indices must be a SCALAR accessor");
    std::size_t size = 0;
    switch (acc.componentType) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: case TINYGLTF_COMPONENT_TYPE_BYTE: size = 1; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: case TINYGLTF_COMPONENT_TYPE_SHORT: size = 2; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: case TINYGLTF_COMPONENT_TYPE_INT: size = 4; break;
    default: bad(path, "indices must have an integer component type");
    }
    const AccessorView v = view_of(model, index, size, path);
    std::vector<std::uint32_t> out(v.count);
    for (std::size_t k = 0; k < v.count; ++k) {
        const unsigned char* p = v.data + k * v.stride;
        if (size == 1) out[k] = p[0];
        else if (size == 2) { std::uint16_t s; std::memcpy(&s, p, 2); out[k] = s; }
        else std::memcpy(&out[k], p, 4);
    }
    return out;
}

glm::dmat4 node_matrix(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());  // column-major, as glTF
    glm::dmat4 m(1.0);
    if (node.translation.size() == 3) m[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
    if (node.rotation.size() == 4) {
        const glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);  // glTF: x, y, z, w
        m = m * glm::mat4_cast(q);
    }
    if (node.scale.size() == 3) m = m * glm::scale(glm::dmat4(1.0), glm::dvec3(node.scale[0], node.scale[1], node.scale[2]));
    return m;
}

struct Accumulator {
    TriangleMesh mesh;
    bool all_have_normals = true;
};

void add_mesh(const tinygltf::Model& model, int mesh_index, const glm::dmat4& m, const std::string& path, Accumulator& acc) {
    if (mesh_index < 0 || static_cast<std::size_t>(mesh_index) >= model.meshes.size()) bad(path, "node names a missing mesh");
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(m)));
    const bool flip = glm::determinant(glm::dmat3(m)) < 0.0;  // mirroring keeps triangles outward-CCW
    const auto& primitives = model.meshes[static_cast<std::size_t>(mesh_index)].primitives;
    for (std::size_t p = 0; p < primitives.size(); ++p) {
        const tinygltf::Primitive& prim = primitives[p];
        const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) continue;
        auto pos_it = prim.attributes.find("POSITION");
        if (pos_it == prim.attributes.end()) bad(path, "a triangle primitive has no POSITION attribute");
        const std::vector<glm::vec3> positions = read_vec3(model, pos_it->second, path, "POSITION");
        std::vector<glm::vec3> normals;
        auto nrm_it = prim.attributes.find("NORMAL");
        if (nrm_it != prim.attributes.end()) {
            normals = read_vec3(model, nrm_it->second, path, "NORMAL");
            if (normals.size() != positions.size()) bad(path, "NORMAL and POSITION counts differ");
        } else {
            acc.all_have_normals = false;
        }
        std::vector<std::uint32_t> idx;
        if (prim.indices >= 0) {
            idx = read_indices(model, prim.indices, path);
        } else {
            idx.resize(positions.size());
            for (std::size_t k = 0; k < idx.size(); ++k) idx[k] = static_cast<std::uint32_t>(k);
        }
        for (std::uint32_t i : idx)
            if (i >= positions.size()) bad(path, "an index is out of range of its vertices");
        const auto base = static_cast<std::uint32_t>(acc.mesh.positions.size());
        for (std::size_t k = 0; k < positions.size(); ++k) {
            if (!finite3(positions[k]))
                not_finite(path, mesh_label(model, mesh_index, p), "POSITION", k, glm::dvec3(positions[k]), "");
            const glm::vec3 world(m * glm::dvec4(glm::dvec3(positions[k]), 1.0));
            if (!finite3(world))
                not_finite(path, mesh_label(model, mesh_index, p), "POSITION", k, glm::dvec3(world),
                           " after the node transforms");
            acc.mesh.positions.push_back(world);
            if (!normals.empty()) {
                if (!finite3(normals[k]))
                    not_finite(path, mesh_label(model, mesh_index, p), "NORMAL", k, glm::dvec3(normals[k]), "");
                const glm::dvec3 n = normal_matrix * glm::dvec3(normals[k]);
                const double len = glm::length(n);
                const glm::vec3 unit = len > 0.0 ? glm::vec3(n / len) : glm::vec3(0.0f, 0.0f, 1.0f);
                if (!finite3(unit))
                    not_finite(path, mesh_label(model, mesh_index, p), "NORMAL", k, glm::dvec3(unit),
                               " after the node transforms");
                acc.mesh.normals.push_back(unit);
            } else {
                acc.mesh.normals.push_back(glm::vec3(0.0f));  // dropped below if any primitive lacks normals
            }
        }
        auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
            if (a == b || b == c || a == c) return;  // degenerate (strip restarts)
            if (flip) std::swap(b, c);
            acc.mesh.triangles.emplace_back(base + a, base + b, base + c);
        };
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            for (std::size_t k = 0; k + 2 < idx.size(); k += 3) emit(idx[k], idx[k + 1], idx[k + 2]);
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (std::size_t k = 0; k + 2 < idx.size(); ++k) {
                if (k % 2 == 0) emit(idx[k], idx[k + 1], idx[k + 2]);
                else emit(idx[k + 1], idx[k], idx[k + 2]);
            }
        } else {
            for (std::size_t k = 1; k + 1 < idx.size(); ++k) emit(idx[0], idx[k], idx[k + 1]);
        }
    }
}

}  // namespace

TriangleMesh load_gltf_mesh(const std::string& path, std::vector<std::string>* dependencies) {
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    std::string err, warn;
    // The file is read once: checked here, then parsed from memory (what tinygltf's *FromFile calls do after
    // reading it, with the file's folder as the base for external buffers).
    std::error_code size_error;
    const std::uintmax_t file_size = std::filesystem::file_size(path, size_error);
    if (size_error) bad(path, "could not be read: " + size_error.message());
    if (file_size == 0) bad(path, "Empty file.");
    std::vector<unsigned char> bytes(file_size);
    std::ifstream in(path, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())))
        bad(path, "could not be read");
    // Binary glTF starts with the magic "glTF"; anything else is read as JSON glTF.
    const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
    // tinygltf converts `extras` and `extensions` recursively: a document nested deeper than any glTF needs
    // (kMaxJsonDepth, as for scene files) is refused before it parses.
    if (json_nesting_depth(gltf_json_text(bytes, binary), kMaxJsonDepth) > kMaxJsonDepth)
        bad(path, "JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                      " arrays and objects; no valid glTF document nests that deep");
    const std::string base_dir = std::filesystem::path(path).parent_path().string();
    const auto size = static_cast<unsigned int>(bytes.size());
    const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), size, base_dir)
                           : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                                        size, base_dir);
    if (!ok) bad(path, err.empty() ? "could not be parsed" : err);

    if (dependencies) {
        for (const tinygltf::Buffer& b : model.buffers) {
            if (b.uri.empty() || b.uri.rfind("data:", 0) == 0) continue;
            dependencies->push_back((std::filesystem::path(path).parent_path() / b.uri).lexically_normal().string());
        }
    }

    Accumulator acc;
    // glTF 2.0 nodes form disjoint strict trees (no node has two parents, no cycles): a node reached twice is
    // refused, which bounds the visits by the node count (a node listing its child twice, repeated 40 levels
    // down, would otherwise be 2^40 visits).
    std::vector<std::uint8_t> reached(model.nodes.size(), 0);
    std::function<void(int, const glm::dmat4&, int)> visit = [&](int node_index, const glm::dmat4& parent, int depth) {
        if (node_index < 0 || static_cast<std::size_t>(node_index) >= model.nodes.size()) bad(path, "node index out of range");
        if (depth > 256) bad(path, "node hierarchy too deep (a cycle?)");
        if (reached[static_cast<std::size_t>(node_index)]++)
            bad(path, "node " + std::to_string(node_index) +
                          " is reached twice: the glTF node hierarchy must be a set of trees (each node one parent at most)");
        const tinygltf::Node& node = model.nodes[static_cast<std::size_t>(node_index)];
        const glm::dmat4 m = parent * node_matrix(node);
        if (node.mesh >= 0) add_mesh(model, node.mesh, m, path, acc);
        for (int child : node.children) visit(child, m, depth + 1);
    };
    if (!model.scenes.empty()) {
        const int s = model.defaultScene >= 0 && static_cast<std::size_t>(model.defaultScene) < model.scenes.size() ? model.defaultScene : 0;
        for (int root : model.scenes[static_cast<std::size_t>(s)].nodes) visit(root, glm::dmat4(1.0), 0);
    } else {
        for (std::size_t k = 0; k < model.meshes.size(); ++k) add_mesh(model, static_cast<int>(k), glm::dmat4(1.0), path, acc);
    }
    if (!acc.all_have_normals) acc.mesh.normals.clear();
    return std::move(acc.mesh);
}

}  // namespace caustics
