#pragma once
// Pinhole camera rays and the camera G-buffer: for each pixel, the primary hit and whether it is a
// diffuse receiver. Methods fill caustic irradiance for covered pixels (a deferred renderer's lookup
// pass); building the G-buffer is harness work outside the methods' timed region.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/ray_tracer.hpp>

namespace caustics {

struct CameraModel {
    glm::dvec3 position{0.0}, forward{0, 1, 0}, right{1, 0, 0}, up{0, 0, 1};
    double tan_half_fov_y = 0.4;
    int width = 1, height = 1;

    explicit CameraModel(const Camera& c);
    // Unit direction through pixel (x + dx, y + dy); row 0 is the top of the image.
    glm::dvec3 ray_direction(double px, double py) const;
    // Projects a world point to continuous pixel coordinates; false if behind the camera.
    bool project(const glm::dvec3& p, double& px, double& py) const;
    // Solid angle of pixel (ix, iy) seen from the camera centre.
    double pixel_solid_angle(int ix, int iy) const;
};

// The volume view (camera_volume, api/method.hpp) starts this far from the pinhole [m], like a camera's
// near plane: scattering closer than that is not part of it. Light traced towards a pinhole that sits
// inside a lit medium (the camera under the water of pool_murky) contributes 1/r^2 per point, whose
// variance grows as 1/r_near; a near distance of a few centimetres keeps the reference's per-pixel
// noise within reach of a few million photons and changes a ray's integral by about r_near over its length.
inline constexpr double kVolumeNearDistance = 0.05;

struct CameraGBuffer {
    int width = 0, height = 0;
    std::vector<std::uint8_t> covered;     // 1 where the primary hit is a diffuse object
    std::vector<int> object;               // primary-hit object index or -1
    std::vector<glm::vec3> position;       // primary-hit position
    std::vector<glm::vec3> normal;         // primary-hit shading normal (facing the camera)
    // The dielectric object whose inside holds the camera (-1: outside every dielectric). The medium
    // along every primary ray up to its hit is medium_at(scene, medium_object) (camera_volume).
    int medium_object = -1;
    std::size_t index(int x, int y) const { return static_cast<std::size_t>(y) * width + x; }
};

CameraGBuffer build_camera_gbuffer(const RayTracer& tracer, const Camera& camera);

// The dielectric object whose inside holds point p, or -1: the first surface a ray from p meets, seen
// from its back side, is the inside of that object (a closed object, or the water under a height field).
// Rays in a few fixed directions vote, so a ray that grazes an edge does not decide alone.
int enclosing_dielectric(const RayTracer& tracer, const glm::dvec3& p);

}  // namespace caustics
