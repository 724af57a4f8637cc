#pragma once
// Closed forms of single scattering for the reference's camera_volume tests (test_reference_volume.cpp):
// the in-scattered radiance along one camera ray is the integral, over the part of the ray inside a lit
// region bounded by planes, of sigma_s p_HG(d . w_c) E_perp(x) exp(-sigma_t t), with E_perp the
// irradiance of the (collimated or point-like) light field at x perpendicular to its direction d and
// w_c = -v the direction towards the camera. A pixel's value is that radiance averaged over the pixel's
// solid angle (dOmega = cos^3 theta dA / f^2 on the image plane), by Gauss-Legendre quadrature.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics::test_support {

// Gauss-Legendre nodes and weights on [0, 1], 8 points.
inline const std::array<std::pair<double, double>, 8>& gauss8() {
    static const std::array<std::pair<double, double>, 8> nodes = [] {
        const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
        const double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
        std::array<std::pair<double, double>, 8> n{};
        for (int i = 0; i < 4; ++i) {
            n[2 * i] = {0.5 * (1.0 - x[i]), 0.5 * w[i]};
            n[2 * i + 1] = {0.5 * (1.0 + x[i]), 0.5 * w[i]};
        }
        return n;
    }();
    return nodes;
}

// The part [lo, hi] of the ray t -> o + t v (t in [lo, hi] to begin with) where every plane constraint
// a(x) = dot(n, x) + c >= 0 holds; false if empty.
struct PlaneConstraint {
    glm::dvec3 n;
    double c;
};
inline bool clip_ray(const glm::dvec3& o, const glm::dvec3& v, const std::vector<PlaneConstraint>& planes, double& lo,
                     double& hi) {
    for (const PlaneConstraint& p : planes) {
        const double a = glm::dot(p.n, o) + p.c, b = glm::dot(p.n, v);
        if (b == 0.0) {
            if (a < 0.0) return false;
        } else if (b > 0.0) {
            lo = std::max(lo, -a / b);
        } else {
            hi = std::min(hi, -a / b);
        }
    }
    return lo < hi;
}

// The pixel-averaged single-scattering radiance of every pixel: `radiance(o, v, t_hit)` is the camera
// ray's integral up to its first hit (infinity on a miss), given the pinhole o and unit direction v.
inline std::vector<double> pixel_average(const CameraModel& camera, const RayTracer& tracer,
                                         const std::function<double(const glm::dvec3&, const glm::dvec3&, double)>& radiance) {
    std::vector<double> out(static_cast<std::size_t>(camera.width) * camera.height, 0.0);
    for (int iy = 0; iy < camera.height; ++iy)
        for (int ix = 0; ix < camera.width; ++ix) {
            double sum = 0.0, weight = 0.0;
            for (const auto& [sx, wx] : gauss8())
                for (const auto& [sy, wy] : gauss8()) {
                    const glm::dvec3 v = camera.ray_direction(ix + sx, iy + sy);
                    const double c = glm::dot(v, camera.forward);
                    const double wgt = wx * wy * c * c * c;   // dOmega on the image plane
                    const Hit hit = tracer.intersect(camera.position, v);
                    const double t_hit = hit.valid ? hit.t : std::numeric_limits<double>::infinity();
                    sum += wgt * radiance(camera.position, v, t_hit);
                    weight += wgt;
                }
            out[static_cast<std::size_t>(iy) * camera.width + ix] = sum / weight;
        }
    return out;
}

// A collimated beam refracted into a flat water surface z = 0 (no Fresnel): under the surface light
// travels along d_t with perpendicular irradiance E0 cos(theta_i) / cos(theta_t), attenuated by
// exp(-sigma_t s) over the path s = -z / cos(theta_t) below the surface; the lit region is the column
// under the square patch |x|, |y| <= half sheared along d_t, down to the floor. Light travels in +x.
struct SlabBeam {
    double e0 = 1.0, theta_i = 0.0, ior = 1.33, half = 1.0;
    MediumCoefficients medium;
    double cos_i() const { return std::cos(theta_i); }
    double sin_t() const { return std::sin(theta_i) / ior; }
    double cos_t() const { return std::sqrt(1.0 - sin_t() * sin_t()); }
    glm::dvec3 light_direction() const { return {std::sin(theta_i), 0.0, -std::cos(theta_i)}; }
    glm::dvec3 refracted() const { return {sin_t(), 0.0, -cos_t()}; }

    // Camera ray integral: exp(-sigma_t (s + t)) is exp(beta + alpha t), integrated in closed form.
    double radiance(const glm::dvec3& o, const glm::dvec3& v, double t_hit) const {
        const double k = sin_t() / cos_t();   // a point at depth -z lit through the surface at x + k z
        std::vector<PlaneConstraint> planes = {{{1.0, 0.0, k}, half}, {{-1.0, 0.0, -k}, half},
                                               {{0.0, 1.0, 0.0}, half},  {{0.0, -1.0, 0.0}, half},
                                               {{0.0, 0.0, -1.0}, 0.0}};
        double lo = kVolumeMinDistance, hi = t_hit;
        if (!clip_ray(o, v, planes, lo, hi)) return 0.0;
        const double st = medium.extinction(), ct = cos_t();
        const double e_perp = e0 * cos_i() / ct;
        const double phase = henyey_greenstein(glm::dot(refracted(), -v), medium.anisotropy);
        const double alpha = st * (v.z / ct - 1.0), beta = st * o.z / ct;
        const double integral = std::abs(alpha) < 1e-12 ? std::exp(beta) * (hi - lo)
                                                        : std::exp(beta) * (std::exp(alpha * hi) - std::exp(alpha * lo)) / alpha;
        return medium.scattering * phase * e_perp * integral;
    }
};

// A point light of intensity I at `light` (on the z axis) over a square mirror |x|, |y| <= half in the plane z = 0, in
// a homogeneous medium: above the mirror, the reflected light comes from the image source P' (the
// light mirrored in z = 0) with irradiance I exp(-sigma_t rho) / rho^2, rho = |x - P'| (the whole path
// length), inside the pyramid from P' through the mirror. Quadrature along the ray (composite
// Gauss-Legendre, the integrand is smooth inside the pyramid; 40 / sigma_t past its start it is below
// e^-40).
struct MirrorBeam {
    double intensity = 1.0, half = 0.5;
    glm::dvec3 light{0.0, 0.0, 1.0};   // (0, 0, height)
    MediumCoefficients medium;

    double radiance(const glm::dvec3& o, const glm::dvec3& v, double t_hit) const {
        const glm::dvec3 image(light.x, light.y, -light.z);
        const double h = -image.z;   // the pyramid: |x - x'| <= half (z + h) / h, z >= 0
        const double s = half / h;
        std::vector<PlaneConstraint> planes = {{{-1.0, 0.0, s}, s * h}, {{1.0, 0.0, s}, s * h},
                                               {{0.0, -1.0, s}, s * h}, {{0.0, 1.0, s}, s * h},
                                               {{0.0, 0.0, 1.0}, 0.0}};
        double lo = kVolumeMinDistance, hi = t_hit;
        if (!clip_ray(o, v, planes, lo, hi)) return 0.0;
        const double st = medium.extinction();
        hi = std::min(hi, lo + 40.0 / st);
        constexpr int kPanels = 256;
        const double width = (hi - lo) / kPanels;
        double sum = 0.0;
        for (int p = 0; p < kPanels; ++p)
            for (const auto& [u, w] : gauss8()) {
                const double t = lo + (p + u) * width;
                const glm::dvec3 x = o + t * v;
                const glm::dvec3 d = x - image;
                const double rho = glm::length(d);
                const double phase = henyey_greenstein(glm::dot(d / rho, -v), medium.anisotropy);
                sum += w * width * medium.scattering * phase * intensity * std::exp(-st * (rho + t)) / (rho * rho);
            }
        return sum;
    }
};

}  // namespace caustics::test_support
