#include <caustics/run/beauty.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/util/image_io.hpp>

namespace caustics {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMinWeight = 1e-3;   // Fresnel branches contributing less than this are not traced

glm::dvec3 sky(const glm::dvec3& dir) {
    const double up = std::clamp(dir.z, 0.0, 1.0);
    return (0.12 + 0.2 * up) * glm::dvec3(0.62, 0.74, 0.95);
}

// Unpolarised Fresnel reflectance for a ray with cos_i against the surface, relative index eta = n_i / n_t.
double fresnel_reflectance(double cos_i, double eta) {
    const double sin_t2 = eta * eta * std::max(0.0, 1.0 - cos_i * cos_i);
    if (sin_t2 >= 1.0) return 1.0;
    const double cos_t = std::sqrt(1.0 - sin_t2);
    const double rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const double rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

class BeautyTracer {
public:
    BeautyTracer(const RayTracer& tracer, const BeautyInputs& in)
        : tracer_(tracer), in_(in), scene_(*tracer.frame().scene) {
        const Bounds3& b = tracer.frame().scene_bounds;
        const double extent = b.valid() ? glm::length(b.hi - b.lo) : 1.0;
        offset_ = 1e-5 * std::max(1.0, extent);
    }

    // Radiance along a ray. `pixel` is the image pixel of a primary ray (-1 after a specular event).
    glm::dvec3 radiance(const glm::dvec3& origin, const glm::dvec3& dir, int depth, std::size_t pixel,
                        bool primary, double medium_absorption, double weight) const {
        const Hit hit = tracer_.intersect(origin, dir, 1e-7);
        if (!hit.valid) return sky(dir);
        const double transmittance = medium_absorption > 0.0 ? std::exp(-medium_absorption * hit.t) : 1.0;
        const Material& mat = scene_.objects.at(static_cast<std::size_t>(hit.object)).material;

        glm::dvec3 ng = hit.geometric_normal;
        const bool front = glm::dot(dir, ng) < 0.0;
        if (!front) ng = -ng;   // ng now faces the incoming ray
        glm::dvec3 ns = hit.shading_normal;
        if (glm::dot(ns, ng) < 0.0) ns = -ns;

        if (mat.type == MaterialType::Diffuse) {
            const glm::dvec3 p = hit.position + offset_ * ng;
            const double e = direct_irradiance(p, ns) + caustic_irradiance(hit, pixel, primary);
            return transmittance * (mat.albedo / kPi) * e;
        }
        if (depth >= scene_.max_specular_depth) return glm::dvec3(0.0);
        const glm::dvec3 reflected = glm::reflect(dir, ns);
        auto trace_reflection = [&](double w) {
            glm::dvec3 r = reflected;
            if (glm::dot(r, ng) <= 0.0) r = glm::reflect(dir, ng);   // shading normal bent it below the surface
            return radiance(hit.position + offset_ * ng, r, depth + 1, pixel, false, medium_absorption, w);
        };
        if (mat.type == MaterialType::Mirror) return transmittance * trace_reflection(weight);

        // Dielectric: the geometric normal is outward, so a front hit enters the object.
        const double eta = front ? 1.0 / mat.ior : mat.ior;
        const double cos_i = std::min(1.0, -glm::dot(dir, ns));
        const glm::dvec3 refracted = glm::refract(dir, ns, eta);
        const bool tir = glm::dot(refracted, refracted) == 0.0;
        if (tir) return transmittance * trace_reflection(weight);
        const double inside_absorption = front ? mat.absorption : 0.0;
        auto trace_refraction = [&](double w) {
            return radiance(hit.position - offset_ * ng, glm::normalize(refracted), depth + 1, pixel, false,
                            inside_absorption, w);
        };
        if (!scene_.fresnel) return transmittance * trace_refraction(weight);
        const double r = fresnel_reflectance(cos_i, eta);
        glm::dvec3 sum(0.0);
        if (r * weight > kMinWeight) sum += r * trace_reflection(r * weight);
        if ((1.0 - r) * weight > kMinWeight) sum += (1.0 - r) * trace_refraction((1.0 - r) * weight);
        return transmittance * sum;
    }

private:
    double direct_irradiance(const glm::dvec3& p, const glm::dvec3& n) const {
        double e = 0.0;
        for (const Light& light : scene_.lights) {
            if (light.type == LightType::Directional) {
                const glm::dvec3 to_light = -glm::normalize(light.direction);
                const double c = glm::dot(n, to_light);
                if (c <= 0.0 || tracer_.occluded(p, to_light, 0.0, 1e30)) continue;
                e += light.irradiance * c;
            } else {
                glm::dvec3 d = light.position - p;
                const double dist = glm::length(d);
                if (dist <= 0.0) continue;
                d /= dist;
                const double c = glm::dot(n, d);
                if (c <= 0.0 || tracer_.occluded(p, d, 0.0, dist * (1.0 - 1e-6))) continue;
                e += light.intensity * c / (dist * dist);
            }
        }
        return e;
    }

    double caustic_irradiance(const Hit& hit, std::size_t pixel, bool primary) const {
        double e = 0.0;
        if (primary && in_.camera_ec && !in_.camera_ec->empty() && in_.gbuffer &&
            in_.gbuffer->covered[pixel] && in_.gbuffer->object[pixel] == hit.object) {
            e = in_.camera_ec->pixels[pixel];
        } else if (in_.receiver_ec && !in_.receiver_ec->empty() && in_.chart &&
                   hit.object == scene_.receiver.object_index) {
            const int bin = in_.chart->bin_of(hit.position);
            if (bin >= 0) e = in_.receiver_ec->pixels[static_cast<std::size_t>(bin)];
        }
        return std::isfinite(e) ? e : 0.0;
    }

    const RayTracer& tracer_;
    const BeautyInputs& in_;
    const Scene& scene_;
    double offset_ = 1e-5;
};

}  // namespace

Image render_beauty(const RayTracer& tracer, const BeautyInputs& inputs) {
    const Camera& camera = tracer.frame().scene->camera;
    const CameraModel model(camera);
    Image image(camera.width, camera.height, 3);
    const BeautyTracer bt(tracer, inputs);
    const int spp_axis = std::max(1, inputs.samples_per_axis);
    const double inv = 1.0 / (spp_axis * spp_axis);
    tbb::parallel_for(tbb::blocked_range<int>(0, camera.height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < camera.width; ++x) {
                const std::size_t pixel = static_cast<std::size_t>(y) * camera.width + x;
                glm::dvec3 sum(0.0);
                for (int sy = 0; sy < spp_axis; ++sy)
                    for (int sx = 0; sx < spp_axis; ++sx) {
                        const glm::dvec3 dir =
                            model.ray_direction(x + (sx + 0.5) / spp_axis, y + (sy + 0.5) / spp_axis);
                        sum += bt.radiance(model.position, dir, 0, pixel, true, 0.0, 1.0);
                    }
                for (int c = 0; c < 3; ++c) image.at(x, y, c) = static_cast<float>(sum[c] * inv);
            }
    });
    return image;
}

double beauty_exposure(const Image& linear) {
    std::vector<float> lum;
    lum.reserve(static_cast<std::size_t>(linear.width) * linear.height);
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x) {
            float l = linear.channels >= 3
                          ? 0.2126f * linear.at(x, y, 0) + 0.7152f * linear.at(x, y, 1) + 0.0722f * linear.at(x, y, 2)
                          : linear.at(x, y, 0);
            if (std::isfinite(l) && l > 0.0f) lum.push_back(l);
        }
    if (lum.empty()) return 1.0;
    const std::size_t k = std::min(lum.size() - 1, static_cast<std::size_t>(0.97 * static_cast<double>(lum.size())));
    std::nth_element(lum.begin(), lum.begin() + static_cast<std::ptrdiff_t>(k), lum.end());
    const double p97 = lum[k];
    return p97 > 0.0 ? 0.85 / p97 : 1.0;
}

void write_beauty_png(const Image& linear, const std::string& path) {
    write_png(linear, path, beauty_exposure(linear));
}

}  // namespace caustics
