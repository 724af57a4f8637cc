#pragma once
// The front half of the receiver lookups (lookup.cpp) in lanes: points' light-view coordinates, 1 / depth
// and texel coordinates, four or eight points at a time (the divisions dominate a scalar lookup's front
// half), by the scalar operations in the same order -- the method is compiled without FMA contraction --
// so with the same bits: v = (dot(p - eye, right), dot(p - eye, up), dot(p - eye, forward)) as glm::dot
// associates, then in perspective inv_depth = 1 / v.z and x = v.x * inv_depth (orthographic:
// inv_depth = 1, x = v.x), px = (x - x0) sx, py = (y1 - y) sy. Points behind the near plane get values
// that the caller does not use (a division by a depth <= 0 included).
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

namespace caustics::caustic_mapping {

// One light view's transform and texel scales (LightProjection, with pixels_per_x / pixels_per_y).
struct ViewProjection {
    glm::dvec3 eye{0.0}, right{1, 0, 0}, up{0, 1, 0}, forward{0, 0, -1};
    double x0 = 0, y1 = 0, sx = 1, sy = 1;   // px = (x - x0) sx, py = (y1 - y) sy
};

// One point's 1 / depth and texel coordinates from its view-space coordinates (x, y, z): in
// perspective inv_depth = 1 / z and x, y scaled by it; orthographic inv_depth = 1.
template <bool kPerspective>
inline void texel_coordinates(double x0, double y1, double sx, double sy, double x, double y, double z,
                              double& inv_depth, double& px, double& py) {
    if constexpr (kPerspective) {
        inv_depth = 1.0 / z;
        x *= inv_depth;
        y *= inv_depth;
    } else {
        inv_depth = 1.0;
    }
    px = (x - x0) * sx, py = (y1 - y) * sy;
}

// The lanes' outputs, one entry per point.
struct RowLanes {
    std::vector<double> vx, vy, vz, inv_depth, px, py;
    void resize(std::size_t n) {
        for (std::vector<double>* v : {&vx, &vy, &vz, &inv_depth, &px, &py}) v->resize(n);
    }
};

// n world points (a camera G-buffer row's positions, floats).
void project_row(const ViewProjection& view, bool perspective, const glm::vec3* p, int n, RowLanes& r);
// n view-space points q_a = left + (a + 1/2) step, a < n (a row of a receiver-map bin's points).
void project_samples(const ViewProjection& view, bool perspective, const glm::dvec3& left, const glm::dvec3& step,
                     int n, RowLanes& r);

}  // namespace caustics::caustic_mapping
