#pragma once
// Loading glTF 2.0 (.gltf) and binary glTF (.glb) files into one triangle mesh.
#include <stdexcept>
#include <string>
#include <vector>

#include <caustics/scene/mesh.hpp>

namespace caustics {

// All triangle primitives of all meshes reachable from the default scene (the first scene when none
// is marked default, every mesh when the file has no scenes), with node transforms applied: POSITION,
// NORMAL when every primitive has it (else normals are left empty), indices of any integer type
// (non-indexed primitives too). Triangle strips and fans are converted to lists; points and lines are
// skipped. Throws std::runtime_error with tinygltf's message on an unreadable or malformed file.
// `dependencies`, when given, receives the paths of the external files the glTF reads (.bin buffers),
// so that cache keys can hash them too. A file that parses but holds vertices or normals that are not
// finite (NaN, infinity, or beyond float range after the node transforms) throws MeshDataError naming
// the file, the mesh and the vertex.
struct MeshDataError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

TriangleMesh load_gltf_mesh(const std::string& path, std::vector<std::string>* dependencies = nullptr);

}  // namespace caustics
