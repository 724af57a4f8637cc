#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace caustics {

// An indexed triangle mesh in world space. `normals` is either empty (flat shading) or one unit
// normal per vertex (interpolated shading). Triangles are counter-clockwise seen from the outside.
struct TriangleMesh {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::uvec3> triangles;

    bool empty() const { return triangles.empty(); }
};

}  // namespace caustics
