// The no-caustic baseline: what a flat interface would transmit (docs/design.md section 6). See baseline.hpp.
#include <caustics/frame/baseline.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace caustics {

double fresnel_transmittance(double cos_i, double cos_t, double n_i, double n_t) {
    const double rs = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t);
    const double rp = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}

FlatTransmission flat_interface_transmission(const Light& light, double n_outside, double ior, bool fresnel) {
    // Snell's law at the horizontal interface (normal +z): t = eta d + (eta cos_i - cos_t) z.
    const glm::dvec3 d = glm::normalize(light.direction);
    const double eta = n_outside / ior, cos_i = std::fabs(d.z);
    const double cos2_t = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    FlatTransmission out;
    out.direction = glm::normalize(eta * d + (eta * cos_i - std::sqrt(std::max(cos2_t, 0.0))) * glm::dvec3(0, 0, 1));
    if (!(cos2_t > 0.0)) return out;   // total internal reflection (index below the outside's): nothing enters
    const double transmittance = fresnel ? fresnel_transmittance(cos_i, std::sqrt(cos2_t), n_outside, ior) : 1.0;
    // A beam of irradiance E0 crosses the horizontal plane with flux E0 cos_i per unit area.
    out.horizontal_irradiance = light.irradiance * cos_i * transmittance;
    return out;
}

double refracted_path_length(const glm::dvec3& p, const glm::dvec3& direction, double surface_z) {
    return (surface_z - p.z) / std::max(-direction.z, 1e-6);
}

bool enters_through_rectangle(const glm::dvec3& p, const glm::dvec3& direction, double surface_z,
                              const glm::dvec2& lo, const glm::dvec2& hi) {
    const glm::dvec2 entry = glm::dvec2(p) - refracted_path_length(p, direction, surface_z) * glm::dvec2(direction);
    return entry.x >= lo.x && entry.x <= hi.x && entry.y >= lo.y && entry.y <= hi.y;
}

Image flat_interface_baseline(const FrameGeometry& frame, const ReceiverChart& chart) {
    const Scene& scene = *frame.scene;
    if (scene.lights.empty()) return {};
    for (const Light& l : scene.lights)
        if (l.type != LightType::Directional) return {};
    // Exactly one specular object, a height-field dielectric; everything else diffuse.
    const ObjectInstance* water = nullptr;
    for (const ObjectInstance& inst : frame.objects) {
        if (!inst.object->material.is_specular()) continue;
        if (water || inst.object->material.type != MaterialType::Dielectric || !inst.heightfield) return {};
        water = &inst;
    }
    if (!water) return {};

    const Material& m = water->object->material;
    const double surface_z = water->object->heightfield.base_height;
    const glm::dvec2 lo = water->heightfield->origin, hi = lo + water->heightfield->extent();
    const double n_outside = scene.medium.present ? scene.medium.ior : 1.0;
    // A dispersive index spans [ior, ior + dispersion] uniformly (the reference draws it per photon):
    // average over the midpoints of 4 sub-bands.
    const int bands = m.dispersion > 0.0 ? 4 : 1;
    std::vector<FlatTransmission> beams;
    for (const Light& l : scene.lights)
        for (int b = 0; b < bands; ++b)
            beams.push_back(
                flat_interface_transmission(l, n_outside, m.ior + m.dispersion * (b + 0.5) / bands, scene.fresnel));

    constexpr int kSub = 4;
    const int w = chart.width(), h = chart.height();
    Image out(w, h, 1);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            double sum = 0.0, weight = 0.0;
            for (int b = 0; b < kSub; ++b)
                for (int a = 0; a < kSub; ++a) {
                    const double s = (i + (a + 0.5) / kSub) / w, t = (j + (b + 0.5) / kSub) / h;
                    const glm::dvec3 p = chart.point(s, t), n = chart.normal(s, t);
                    // Bins hold means over true surface area: a height field's sub-point stands for
                    // 1 / n_z of its parameter area.
                    const double area = chart.is_plane() ? 1.0 : 1.0 / std::max(std::fabs(n.z), 1e-6);
                    weight += area;
                    if (!(p.z < surface_z)) continue;
                    double e = 0.0;
                    for (std::size_t k = 0; k < beams.size(); ++k) {
                        const FlatTransmission& beam = beams[k];
                        if (!(beam.horizontal_irradiance > 0.0) || scene.lights[k / bands].direction.z >= 0.0) continue;
                        const glm::dvec3& dir = beam.direction;
                        if (!enters_through_rectangle(p, dir, surface_z, lo, hi)) continue;
                        // A parallel beam of flux F per horizontal area along t puts F |t . n| / |t_z| on a
                        // surface of normal n (a plane receives on either side, a height field on its top).
                        const double facing =
                            chart.is_plane() ? std::fabs(glm::dot(dir, n)) : std::max(0.0, -glm::dot(dir, n));
                        const double path = refracted_path_length(p, dir, surface_z);
                        e += beam.horizontal_irradiance * std::exp(-m.absorption * path) * facing / std::fabs(dir.z);
                    }
                    sum += area * e / bands;
                }
            out.at(i, j) = static_cast<float>(weight > 0.0 ? sum / weight : 0.0);
        }
    return out;
}

}  // namespace caustics
