#include <caustics/frame/camera.hpp>

#include <algorithm>

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics {
namespace {

// Solid angle subtended at the origin by [0, x] x [0, y] on the plane z = 1 (signed in x and y);
// the rectangle [x0, x1] x [y0, y1] is the inclusion-exclusion sum of four of these.
double corner_solid_angle(double x, double y) { return std::atan(x * y / std::sqrt(1.0 + x * x + y * y)); }

}  // namespace

CameraModel::CameraModel(const Camera& c)
    : position(c.position), width(c.width), height(c.height) {
    forward = glm::normalize(c.look_at - c.position);
    right = glm::normalize(glm::cross(forward, c.up));
    up = glm::cross(right, forward);
    tan_half_fov_y = std::tan(0.5 * c.fov_y_deg * 3.14159265358979323846 / 180.0);
}

// Image-plane coordinates at distance 1: x to the right, y up; square pixels.
glm::dvec3 CameraModel::ray_direction(double px, double py) const {
    const double aspect = static_cast<double>(width) / height;
    const double x = (2.0 * px / width - 1.0) * aspect * tan_half_fov_y;
    const double y = (1.0 - 2.0 * py / height) * tan_half_fov_y;
    return glm::normalize(forward + x * right + y * up);
}

bool CameraModel::project(const glm::dvec3& p, double& px, double& py) const {
    const glm::dvec3 d = p - position;
    const double z = glm::dot(d, forward);
    if (!(z > 0.0)) return false;
    const double aspect = static_cast<double>(width) / height;
    const double x = glm::dot(d, right) / z;
    const double y = glm::dot(d, up) / z;
    px = (x / (aspect * tan_half_fov_y) + 1.0) * 0.5 * width;
    py = (1.0 - y / tan_half_fov_y) * 0.5 * height;
    return true;
}

double CameraModel::pixel_solid_angle(int ix, int iy) const {
    const double aspect = static_cast<double>(width) / height;
    auto plane_x = [&](double px) { return (2.0 * px / width - 1.0) * aspect * tan_half_fov_y; };
    auto plane_y = [&](double py) { return (1.0 - 2.0 * py / height) * tan_half_fov_y; };
    const double x0 = plane_x(ix), x1 = plane_x(ix + 1.0);
    const double y0 = plane_y(iy + 1.0), y1 = plane_y(iy);   // y grows upwards
    return corner_solid_angle(x1, y1) - corner_solid_angle(x0, y1) - corner_solid_angle(x1, y0) +
           corner_solid_angle(x0, y0);
}

CameraGBuffer build_camera_gbuffer(const RayTracer& tracer, const Camera& camera) {
    const CameraModel model(camera);
    CameraGBuffer g;
    g.width = camera.width;
    g.height = camera.height;
    const std::size_t n = static_cast<std::size_t>(g.width) * g.height;
    g.covered.assign(n, 0);
    g.object.assign(n, -1);
    g.position.assign(n, glm::vec3(0.0f));
    g.normal.assign(n, glm::vec3(0.0f));
    const Scene& scene = *tracer.frame().scene;
    tbb::parallel_for(tbb::blocked_range<int>(0, g.height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < g.width; ++x) {
                const glm::dvec3 dir = model.ray_direction(x + 0.5, y + 0.5);
                const Hit hit = tracer.intersect(model.position, dir);
                if (!hit.valid) continue;
                const std::size_t i = g.index(x, y);
                glm::dvec3 n = hit.shading_normal;
                if (glm::dot(n, dir) > 0.0) n = -n;
                g.object[i] = hit.object;
                g.position[i] = glm::vec3(hit.position);
                g.normal[i] = glm::vec3(n);
                const Object& obj = scene.objects.at(static_cast<std::size_t>(hit.object));
                g.covered[i] = obj.material.type == MaterialType::Diffuse ? 1 : 0;
            }
    });
    g.medium_object = enclosing_dielectric(tracer, model.position);
    return g;
}

int enclosing_dielectric(const RayTracer& tracer, const glm::dvec3& p) {
    // Up first (a height field's water lies below it), then five more, none along an axis of the scene.
    static const glm::dvec3 kDirections[] = {{0.013, 0.021, 1.0}, {0.61, 0.37, -0.7}, {-0.53, 0.71, 0.46},
                                             {0.29, -0.83, 0.47}, {-0.77, -0.41, -0.49}, {0.9, -0.2, 0.38}};
    const Scene& scene = *tracer.frame().scene;
    std::vector<int> votes;
    for (const glm::dvec3& d : kDirections) {
        const glm::dvec3 dir = glm::normalize(d);
        const Hit hit = tracer.intersect(p, dir);
        int inside = -1;
        if (hit.valid && glm::dot(dir, hit.geometric_normal) > 0.0 &&
            scene.objects.at(static_cast<std::size_t>(hit.object)).material.type == MaterialType::Dielectric)
            inside = hit.object;
        votes.push_back(inside);
    }
    // The most frequent answer; ties go to the first ray's.
    int best = votes.front(), best_count = 0;
    for (int v : votes) {
        const auto c = static_cast<int>(std::count(votes.begin(), votes.end(), v));
        if (c > best_count) best = v, best_count = c;
    }
    return best;
}

}  // namespace caustics
