#pragma once
// The frame's objects as triangle batches for the light-space G-buffers: meshes, planes and boxes as
// the frame gives them, analytic spheres tessellated (resolution tied to the grid), height fields
// resampled from their samples at a resolution tied to the grid (never finer than their own).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "frame.hpp"
#include "gbuffer_raster.hpp"

namespace caustics::caustic_mapping {

enum class Role { Receiver, SingleSurface, DoubleSurface, Mirror };

struct Batch {
    int object = -1;
    Role role = Role::Receiver;
    const Material* material = nullptr;
    TriangleMesh own;                    // tessellated or resampled geometry (else empty)
    const TriangleMesh* mesh = nullptr;  // what to draw: &own or the frame's mesh
    Bounds3 bounds;
    GBufferTriangles triangles() const {
        return {mesh->positions, mesh->normals, mesh->triangles, static_cast<std::int32_t>(object)};
    }
};

Role role_of(const Object& o);
// UV sphere with `slices` segments around and slices / 2 stacks, exact unit normals.
TriangleMesh tessellate_sphere(const glm::dvec3& center, double radius, int slices);
// A height field resampled at n x n vertices over its rectangle with its interpolated normals.
TriangleMesh resample_heightfield(const HeightField& hf, int n);
// One batch per object of the frame. `grid` sets the tessellation of spheres and height fields.
std::vector<Batch> build_batches(const FrameGeometry& frame, int grid);

}  // namespace caustics::caustic_mapping
