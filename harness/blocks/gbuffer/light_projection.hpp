#pragma once
// Light-space projections for image-space methods (shadow-map style render targets seen from a light).
//
//   Orthographic (directional light): view axes right/up perpendicular to the light direction
//     `forward`; (x0, x1) x (y0, y1) are world extents of the view rectangle; depth = distance along
//     forward from the eye plane.
//   Perspective (point light): eye at the light; (x0, x1) x (y0, y1) are extents on the tangent plane
//     at unit distance (x / z, y / z), asymmetric frusta allowed; depth = z along forward (not radial).
//
// Pixel coordinates follow harness/blocks/raster/raster.hpp: pixel (i, j) covers [i, i+1) x [j, j+1), row 0 is the
// top (largest y). A six-face cube map (Shah et al. 2007, Sec. III.F: point lights whose caustics leave
// one frustum) is six 90-degree perspective faces (+x, -x, +y, -y, +z, -z) around the light.
#include <array>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>

namespace caustics {

enum class ProjectionType { Orthographic, Perspective };

struct LightProjection {
    ProjectionType type = ProjectionType::Orthographic;
    glm::dvec3 eye{0.0};
    glm::dvec3 right{1, 0, 0}, up{0, 1, 0}, forward{0, 0, -1};   // orthonormal, right x up = -forward
    double x0 = -1, x1 = 1, y0 = -1, y1 = 1;
    int width = 1, height = 1;
    double near_depth = 1e-4;   // perspective: points closer than this (or behind) do not project

    // View-space coordinates (x, y, depth).
    glm::dvec3 view(const glm::dvec3& p) const {
        const glm::dvec3 d = p - eye;
        return {glm::dot(d, right), glm::dot(d, up), glm::dot(d, forward)};
    }
    // Continuous pixel coordinates and depth; false when the point is behind the near plane (perspective).
    // Points outside the image still return true with coordinates outside [0, width) x [0, height).
    bool project(const glm::dvec3& p, double& px, double& py, double& depth) const {
        const glm::dvec3 v = view(p);
        depth = v.z;
        double x = v.x, y = v.y;
        if (type == ProjectionType::Perspective) {
            if (!(v.z > near_depth)) return false;
            x /= v.z;
            y /= v.z;
        }
        px = (x - x0) / (x1 - x0) * width;
        py = (y1 - y) / (y1 - y0) * height;
        return true;
    }
    bool inside(double px, double py) const { return px >= 0.0 && py >= 0.0 && px < width && py < height; }
    // Pixels per unit of the view plane: px = (x - x0) * pixels_per_x(), py = (y1 - y) * pixels_per_y()
    // is project() with the divisions hoisted out of a loop over points (the one definition that every
    // such hoisted copy uses, so that all of them give the same bits).
    double pixels_per_x() const { return width / (x1 - x0); }
    double pixels_per_y() const { return height / (y1 - y0); }
    // Direction light travels through pixel-space point (px, py) (unit).
    glm::dvec3 ray_direction(double px, double py) const;
    // Orthographic: area of one texel perpendicular to the light [m^2].
    double texel_area() const { return (x1 - x0) / width * ((y1 - y0) / height); }
    // Perspective: solid angle of the texel whose centre is at (px, py) [sr].
    double texel_solid_angle(double px, double py) const;
    // Area a texel covers on a surface through p with unit normal n (either orientation) [m^2]; the
    // cosine is clamped at `min_cos` so grazing surfaces stay finite.
    double surface_texel_area(const glm::dvec3& p, const glm::dvec3& n, double min_cos = 1e-3) const;
};

// Directional light (unit direction `dir`): an orthographic view whose rectangle covers `bounds`
// (grown by `margin` of its size on each side).
LightProjection fit_orthographic(const glm::dvec3& dir, const Bounds3& bounds, int width, int height,
                                 double margin = 0.01);
// Point light at `eye`: a perspective view towards the centre of `bounds` whose frustum holds its eight
// corners. Returns false (and leaves `out` untouched) when a corner is behind the light or the frustum
// would need more than `max_half_angle_deg` off-axis in x or y (use a cube map then). With `clamp` the
// frustum is instead clamped to that angle (corners behind the light ignored) and part of the bounds
// may lie outside it; false then only when the eye is at the bounds' centre.
bool fit_perspective(const glm::dvec3& eye, const Bounds3& bounds, int width, int height, LightProjection& out,
                     double max_half_angle_deg = 60.0, double margin = 0.01, bool clamp = false);
// The six 90-degree faces of a cube map around `eye`, each width x width.
std::array<LightProjection, 6> cube_faces(const glm::dvec3& eye, int width);
// The cube face whose frustum holds direction d (dominant axis; ties go to the lower face index).
int cube_face_of(const glm::dvec3& d);

}  // namespace caustics
