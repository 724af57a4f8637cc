#pragma once
// The frame's objects as triangle batches for the light-space G-buffers: meshes, planes and boxes as
// the frame gives them, analytic spheres tessellated (resolution tied to the grid), height fields
// resampled from their samples at a resolution tied to the grid (never finer than their own).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>
#include <caustics/blocks/gbuffer/gbuffer_raster.hpp>
#include <caustics/blocks/gbuffer/light_projection.hpp>

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

// The receivers' positions texture's window seen from the light: the receivers' rectangle with a margin
// (room for the extrapolated rim) and the specular objects' rectangle, so that every lookup of the
// receiver estimator, from the light ray through the specular vertex to the landing point, reads a
// stored or extrapolated position. Directional light: the bounding rectangle of the two rectangles in
// one orthographic view. Point light: one frustum fitted to both (as fit_perspective, the same limits),
// else, when the union does not fit, to the receivers alone (false: neither fits, use a cube map).
LightProjection receivers_view(const glm::dvec3& light_dir, const Bounds3& receivers, const Bounds3& specular, int map,
                               double margin);
bool receivers_view(const glm::dvec3& eye, const Bounds3& receivers, const Bounds3& specular, int map,
                    double max_half_angle_deg, double margin, bool clamp, LightProjection& out);

// The rim of extrapolated texels the receivers' window leaves room for with extend = -1 (auto).
constexpr int kRimTexels = 32;

}  // namespace caustics::caustic_mapping
