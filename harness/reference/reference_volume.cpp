// Media in the reference (docs/design.md section 3, issue 15): the per-segment media and the camera_volume
// view, the volume caustic radiance L_v (method.hpp, CausticOutput::camera_volume) estimated by
// connecting one scattering point per photon segment to the pinhole (a light tracer's next-event
// estimate towards the camera, as in Veach's thesis, section 10.2, and pbrt-v4's camera importance).
//
// On a segment of length l (possibly infinite) in the camera's medium, after >= 1 specular event, the
// photon of weight w interacts at distance t with density sigma_t exp(-sigma_t t); the point is drawn
// from that density truncated to [0, l): pdf sigma_t exp(-sigma_t t) / P with P = 1 - exp(-sigma_t l),
// t = -ln(1 - u P) / sigma_t. The in-scattered power it stands for is w exp(-sigma_t t) sigma_s / pdf =
// w P sigma_s / sigma_t. Connected to the pinhole at distance r in direction w_c (the connection must
// cross no surface: scattering seen through a refracting surface is not part of L_v), it adds to its
// pixel's mean radiance over the pixel's solid angle Omega_pix
//     dL = w P (sigma_s / sigma_t) p_HG(dir . w_c) exp(-sigma_t r) / (r^2 Omega_pix),
// because dOmega dt = dV / r^2 along the camera rays. Replicas, standard error and noise are those of
// the other views (reference.cpp).
//
// Fixed point: the sum stores x = dL Omega_pix s_k / (light scale) with s_k = max(d_k, r_min)^2, d_k
// the distance to the pixel's primary hit (the scene bounds' far corner for a miss), so the
// increments are O(w) for points near the surface the pixel sees. Near the pinhole 1/r^2 has
// infinite variance; points closer than r_min = kVolumeMinDistance (the volume view's near distance,
// 5 cm) are not part of L_v by definition, which bounds every increment by w p_max s_k / r_min^2. The increments are clamped to 2^62 and the sums saturate
// at 2^63 - 1 rather than wrap (min(a + b, M) is associative for non-negative terms, so the result stays
// the same for any thread count); no scene here comes within many orders of magnitude of either.
#include "detail/transport.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics::detail {

void setup_media(Transport& transport, const Scene& scene, bool volume) {
    transport.media.assign(scene.objects.size() + 1, MediumCoefficients{});
    transport.media[0] = medium_at(scene, -1);
    for (std::size_t i = 0; i < scene.objects.size(); ++i)
        if (scene.objects[i].material.type == MaterialType::Dielectric)
            transport.media[i + 1] = medium_at(scene, static_cast<int>(i));
    transport.volume = volume && transport.camera != nullptr && transport.gbuffer != nullptr;
    if (!transport.volume) return;
    const CameraGBuffer& g = *transport.gbuffer;
    const glm::dvec3 eye = transport.camera->position;
    transport.camera_medium = g.medium_object;
    double far = 1.0;
    const Bounds3& b = transport.frame->scene_bounds;
    if (b.valid())
        for (int k = 0; k < 8; ++k) {
            const glm::dvec3 c((k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z);
            far = std::max(far, glm::length(c - eye));
        }
    transport.volume_scale.resize(g.covered.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.covered.size(), 16384),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t i = range.begin(); i < range.end(); ++i) {
                              const double d = g.object[i] >= 0 ? glm::length(glm::dvec3(g.position[i]) - eye) : far;
                              const double s = std::max(d, kVolumeMinDistance);
                              transport.volume_scale[i] = s * s;
                          }
                      });
}

void Transport::scatter_to_camera(const glm::dvec3& origin, const glm::dvec3& dir, double length, double w, double u,
                                  const MediumCoefficients& medium, Accumulators& acc,
                                  std::vector<ShadowQuery>& shadows) const {
    const double sigma_t = medium.extinction();
    const double interact = std::isinf(length) ? 1.0 : -std::expm1(-sigma_t * length);   // P
    const double t = -std::log1p(-u * interact) / sigma_t;
    const glm::dvec3 x = origin + t * dir;
    const std::ptrdiff_t pixel = camera_pixel(x);
    if (pixel < 0) return;
    glm::dvec3 to_camera = camera->position - x;
    const double r2 = glm::dot(to_camera, to_camera);
    const double r = std::sqrt(r2);
    if (!(r >= kVolumeMinDistance)) return;
    to_camera /= r;
    const std::size_t k = static_cast<std::size_t>(pixel);
    // The phase function's angle is between the direction of travel before (dir) and after (to_camera).
    const double phase = henyey_greenstein(glm::dot(dir, to_camera), medium.anisotropy);
    const double value = w * interact * (medium.scattering / sigma_t) * phase * std::exp(-sigma_t * r) *
                         volume_scale[k] / r2;
    const double fixed = std::min(value * kFixedScale + 0.5, 0x1.0p62);
    // Added if the pinhole sees the point.
    shadows.push_back({{x, to_camera, 0.0, r * (1.0 - 1e-6)}, &acc.volume[k],
                       static_cast<std::int64_t>(fixed), true});
}

}  // namespace caustics::detail
