#pragma once
// The geometry of one animation frame: every object as world-space triangles (analytic spheres aside),
// height fields evaluated at the frame's time. Built by the harness outside any timed region and shared
// by the reference, the beauty renderer and the methods.
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/scene/mesh.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

struct Bounds3 {
    glm::dvec3 lo{1e300};
    glm::dvec3 hi{-1e300};
    void extend(const glm::dvec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    void extend(const Bounds3& b) { extend(b.lo); extend(b.hi); }
    bool valid() const { return lo.x <= hi.x; }
    glm::dvec3 center() const { return 0.5 * (lo + hi); }
};

struct ObjectInstance {
    int object_index = -1;
    const Object* object = nullptr;
    TriangleMesh mesh;                          // empty for analytic spheres
    bool analytic_sphere = false;               // sphere: intersected exactly (center, radius)
    std::shared_ptr<const HeightField> heightfield;  // height-field shapes only
    Bounds3 bounds;
};

struct FrameGeometry {
    const Scene* scene = nullptr;
    int frame = 0;
    double time = 0.0;
    std::vector<ObjectInstance> objects;        // same order as scene->objects
    Bounds3 specular_bounds;                    // union over specular (dielectric, mirror) objects
    Bounds3 scene_bounds;

    const ObjectInstance& receiver() const { return objects.at(static_cast<std::size_t>(scene->receiver.object_index)); }
};

// Throws InputError when frame is outside [0, scene.animation.frames).
FrameGeometry build_frame_geometry(const Scene& scene, int frame);

}  // namespace caustics
