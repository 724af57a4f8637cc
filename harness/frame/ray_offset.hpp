#pragma once
// The self-intersection guard of RayTracer: rays skip the first scene_ray_offset() of their length.
// Float vertices near a 4 m scene are exact to ~5e-7 m; 1e-5 of the scene size is well above that and
// well below any feature the scenes model. Shared with the ray recorder of bench/ so that replayed
// rays are the rays the tracer really casts.
#include <algorithm>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>

namespace caustics {

inline double scene_ray_offset(const FrameGeometry& frame) {
    double extent = 1.0;
    if (frame.scene_bounds.valid()) {
        const glm::dvec3 d = frame.scene_bounds.hi - frame.scene_bounds.lo;
        extent = std::max({1e-3, d.x, d.y, d.z, glm::length(frame.scene_bounds.hi), glm::length(frame.scene_bounds.lo)});
    }
    return 1e-5 * extent;
}

}  // namespace caustics
