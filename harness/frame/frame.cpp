// One animation frame's geometry: every object as world-space triangles (spheres stay analytic),
// height fields evaluated at the frame's time.
#include <caustics/frame/frame.hpp>

#include <cmath>
#include <cstdio>
#include <string>

#include <caustics/util/errors.hpp>
#include <caustics/scene/limits.hpp>

namespace caustics {

namespace {

glm::vec3 to_float(const glm::dvec3& p) { return glm::vec3(p); }

// The parallelogram center + s u + t v, s, t in [-1/2, 1/2], counter-clockwise seen from u x v.
TriangleMesh plane_mesh(const Object& o) {
    TriangleMesh m;
    const glm::dvec3 hu = 0.5 * o.u, hv = 0.5 * o.v;
    m.positions = {to_float(o.center - hu - hv), to_float(o.center + hu - hv), to_float(o.center + hu + hv),
                   to_float(o.center - hu + hv)};
    m.triangles = {{0u, 1u, 2u}, {0u, 2u, 3u}};
    return m;
}

// An axis-aligned box of full extents `size` centred on `center`: 12 triangles, outward and
// counter-clockwise seen from outside. No shared normals (flat shading).
TriangleMesh box_mesh(const Object& o) {
    TriangleMesh m;
    const glm::dvec3 h = 0.5 * o.size;
    for (int k = 0; k < 8; ++k) {
        const glm::dvec3 s((k & 1) ? 1.0 : -1.0, (k & 2) ? 1.0 : -1.0, (k & 4) ? 1.0 : -1.0);
        m.positions.push_back(to_float(o.center + s * h));
    }
    // Vertex k has x = bit 0, y = bit 1, z = bit 2.
    m.triangles = {
        {0u, 4u, 6u}, {0u, 6u, 2u},  // -x
        {1u, 3u, 7u}, {1u, 7u, 5u},  // +x
        {0u, 1u, 5u}, {0u, 5u, 4u},  // -y
        {2u, 6u, 7u}, {2u, 7u, 3u},  // +y
        {0u, 2u, 3u}, {0u, 3u, 1u},  // -z
        {4u, 5u, 7u}, {4u, 7u, 6u},  // +z
    };
    return m;
}

// Every vertex of an object's frame geometry must be finite and within the coordinate bound (Embree's
// float rays are refused beyond it; limits.hpp), every normal finite. The loader bounds what a scene
// states; this catches what a generator makes of it (noise and waves heights, drops adding up).
void check_frame_mesh(const Scene& scene, std::size_t index, const TriangleMesh& mesh, int frame) {
    const Object& o = scene.objects[index];
    const std::string key = "objects[" + std::to_string(index) + "]" + (o.shape == ShapeType::HeightField ? ".generator" : "");
    auto text = [](const glm::vec3& v) {
        char t[96];
        std::snprintf(t, sizeof t, "(%g, %g, %g)", v.x, v.y, v.z);
        return std::string(t);
    };
    const float bound = static_cast<float>(kMaxCoordinate * (1.0 + 1e-6));
    for (const glm::vec3& p : mesh.positions) {
        if (std::abs(p.x) <= bound && std::abs(p.y) <= bound && std::abs(p.z) <= bound) continue;
        throw InputError(scene.path, key,
                         "the object '" + o.name + "' reaches " + text(p) + " at frame " + std::to_string(frame) +
                             "; valid: finite coordinates with |x|, |y|, |z| <= " + format_limit(kMaxCoordinate) +
                             " m (geometry is single precision in Embree): lower the amplitude or base_height");
    }
    for (const glm::vec3& n : mesh.normals)
        if (!(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z)))
            throw InputError(scene.path, key,
                             "the object '" + o.name + "' has a normal " + text(n) + " at frame " + std::to_string(frame) +
                                 "; valid: finite normals");
}

Bounds3 mesh_bounds(const TriangleMesh& m) {
    Bounds3 b;
    for (const glm::vec3& p : m.positions) b.extend(glm::dvec3(p));
    return b;
}

}  // namespace

FrameGeometry build_frame_geometry(const Scene& scene, int frame) {
    const int frames = scene.animation.frames;
    if (frame < 0 || frame >= frames) {
        throw InputError("--frame", "",
                         std::to_string(frame) + " is out of range: the scene '" + scene.name + "' has " +
                             std::to_string(frames) + " frame(s), valid frames are 0.." + std::to_string(frames - 1));
    }
    FrameGeometry g;
    g.scene = &scene;
    g.frame = frame;
    g.time = scene.animation.time(frame);
    g.objects.reserve(scene.objects.size());
    for (std::size_t k = 0; k < scene.objects.size(); ++k) {
        const Object& o = scene.objects[k];
        ObjectInstance inst;
        inst.object_index = static_cast<int>(k);
        inst.object = &o;
        switch (o.shape) {
        case ShapeType::Plane:
            inst.mesh = plane_mesh(o);
            break;
        case ShapeType::Box:
            inst.mesh = box_mesh(o);
            break;
        case ShapeType::Sphere:
            inst.analytic_sphere = true;
            inst.bounds.extend(o.center - glm::dvec3(o.radius));
            inst.bounds.extend(o.center + glm::dvec3(o.radius));
            break;
        case ShapeType::Mesh:
            inst.mesh = o.mesh;
            break;
        case ShapeType::HeightField: {
            auto hf = std::make_shared<HeightField>(
                generate_heightfield(o.heightfield, g.time, frame, scene.animation.fps));
            inst.mesh = hf->triangulate();
            inst.heightfield = std::move(hf);
            break;
        }
        }
        if (!inst.analytic_sphere) {
            check_frame_mesh(scene, k, inst.mesh, frame);
            inst.bounds = mesh_bounds(inst.mesh);
        }
        if (inst.bounds.valid()) {
            g.scene_bounds.extend(inst.bounds);
            if (o.material.is_specular()) g.specular_bounds.extend(inst.bounds);
        }
        g.objects.push_back(std::move(inst));
    }
    return g;
}

}  // namespace caustics
