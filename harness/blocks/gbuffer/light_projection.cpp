#include <caustics/blocks/gbuffer/light_projection.hpp>

#include <algorithm>
#include <cmath>

namespace caustics {
namespace {

// right, up perpendicular to forward with right x up = -forward; looking straight down gives right = +x,
// up = +y (so light-space images read like a map seen from above).
void basis(const glm::dvec3& forward, glm::dvec3& right, glm::dvec3& up) {
    const glm::dvec3 helper = std::abs(forward.y) > 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
    right = glm::normalize(glm::cross(forward, helper));
    up = glm::cross(right, forward);
}

std::array<glm::dvec3, 8> corners(const Bounds3& b) {
    std::array<glm::dvec3, 8> c;
    for (int k = 0; k < 8; ++k)
        c[static_cast<std::size_t>(k)] = {(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z};
    return c;
}

}  // namespace

glm::dvec3 LightProjection::ray_direction(double px, double py) const {
    if (type == ProjectionType::Orthographic) return forward;
    const double tx = x0 + px / width * (x1 - x0);
    const double ty = y1 - py / height * (y1 - y0);
    return glm::normalize(forward + tx * right + ty * up);
}

double LightProjection::texel_solid_angle(double px, double py) const {
    const double tx = x0 + px / width * (x1 - x0);
    const double ty = y1 - py / height * (y1 - y0);
    const double q = 1.0 + tx * tx + ty * ty;
    return texel_area() / (q * std::sqrt(q));
}

double LightProjection::surface_texel_area(const glm::dvec3& p, const glm::dvec3& n, double min_cos) const {
    if (type == ProjectionType::Orthographic)
        return texel_area() / std::max(std::abs(glm::dot(n, forward)), min_cos);
    const glm::dvec3 v = view(p);
    const double z = std::max(v.z, near_depth);
    const double tx = v.x / z, ty = v.y / z;
    const double q = 1.0 + tx * tx + ty * ty;
    const double omega = texel_area() / (q * std::sqrt(q));
    const glm::dvec3 d = p - eye;
    const double r2 = glm::dot(d, d);
    const double cosine = r2 > 0.0 ? std::abs(glm::dot(n, d)) / std::sqrt(r2) : 1.0;
    return omega * r2 / std::max(cosine, min_cos);
}

LightProjection fit_orthographic(const glm::dvec3& dir, const Bounds3& bounds, int width, int height, double margin) {
    LightProjection p;
    p.type = ProjectionType::Orthographic;
    p.forward = glm::normalize(dir);
    basis(p.forward, p.right, p.up);
    p.width = width;
    p.height = height;
    const glm::dvec3 c = bounds.center();
    const double radius = 0.5 * glm::length(bounds.hi - bounds.lo) + 1e-6;
    p.eye = c - p.forward * (2.0 * radius + 1.0);
    double xl = 1e300, xh = -1e300, yl = 1e300, yh = -1e300;
    for (const glm::dvec3& q : corners(bounds)) {
        const glm::dvec3 v = p.view(q);
        xl = std::min(xl, v.x), xh = std::max(xh, v.x), yl = std::min(yl, v.y), yh = std::max(yh, v.y);
    }
    const double mx = std::max(margin * (xh - xl), 1e-6), my = std::max(margin * (yh - yl), 1e-6);
    p.x0 = xl - mx, p.x1 = xh + mx, p.y0 = yl - my, p.y1 = yh + my;
    return p;
}

bool fit_perspective(const glm::dvec3& eye, const Bounds3& bounds, int width, int height, LightProjection& out,
                     double max_half_angle_deg, double margin, bool clamp) {
    LightProjection p;
    p.type = ProjectionType::Perspective;
    p.eye = eye;
    const glm::dvec3 to_center = bounds.center() - eye;
    if (glm::length(to_center) < 1e-9) return false;
    p.forward = glm::normalize(to_center);
    basis(p.forward, p.right, p.up);
    p.width = width;
    p.height = height;
    const double limit = std::tan(max_half_angle_deg * M_PI / 180.0);
    double xl = 1e300, xh = -1e300, yl = 1e300, yh = -1e300, zmin = 1e300;
    for (const glm::dvec3& q : corners(bounds)) {
        const glm::dvec3 v = p.view(q);
        if (!(v.z > 1e-6)) {
            if (clamp) continue;
            return false;
        }
        zmin = std::min(zmin, v.z);
        xl = std::min(xl, v.x / v.z), xh = std::max(xh, v.x / v.z);
        yl = std::min(yl, v.y / v.z), yh = std::max(yh, v.y / v.z);
    }
    if (!(xl <= xh)) xl = yl = -limit, xh = yh = limit;   // clamp, every corner behind: look ahead anyway
    const double mx = std::max(margin * (xh - xl), 1e-6), my = std::max(margin * (yh - yl), 1e-6);
    p.x0 = xl - mx, p.x1 = xh + mx, p.y0 = yl - my, p.y1 = yh + my;
    if (clamp) {
        p.x0 = std::max(p.x0, -limit), p.x1 = std::min(p.x1, limit);
        p.y0 = std::max(p.y0, -limit), p.y1 = std::min(p.y1, limit);
        if (!(p.x0 < p.x1) || !(p.y0 < p.y1)) p.x0 = p.y0 = -limit, p.x1 = p.y1 = limit;
    } else if (std::max({-p.x0, p.x1, -p.y0, p.y1}) > limit) {
        return false;
    }
    p.near_depth = zmin < 1e300 ? std::min(1e-4, 0.5 * zmin) : 1e-4;
    out = p;
    return true;
}

std::array<LightProjection, 6> cube_faces(const glm::dvec3& eye, int width) {
    static const glm::dvec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    std::array<LightProjection, 6> faces;
    for (int f = 0; f < 6; ++f) {
        LightProjection& p = faces[static_cast<std::size_t>(f)];
        p.type = ProjectionType::Perspective;
        p.eye = eye;
        p.forward = axes[f];
        basis(p.forward, p.right, p.up);
        p.width = p.height = width;
        p.x0 = p.y0 = -1.0;
        p.x1 = p.y1 = 1.0;
    }
    return faces;
}

int cube_face_of(const glm::dvec3& d) {
    const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
    if (ax >= ay && ax >= az) return d.x >= 0.0 ? 0 : 1;
    if (ay >= az) return d.y >= 0.0 ? 2 : 3;
    return d.z >= 0.0 ? 4 : 5;
}

}  // namespace caustics
