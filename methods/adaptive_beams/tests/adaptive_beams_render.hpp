#pragma once
// The adaptive_beams tests' shared helpers: a render through the plugin interface with the camera's G-buffer,
// and the nrmse against a reference image.
#include <cmath>
#include <cstddef>
#include <map>
#include <memory>
#include <string>

#include <tbb/global_control.h>

#include <caustics/api/registry.hpp>
#include <caustics/frame/camera.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/util/image.hpp>

#include "sine_truth_support.hpp"

namespace caustics::adaptive_beams_test {

constexpr const char* kMethod = "adaptive_beams";

// A sine 2.25 x its first focus down under 20 deg light, on a 2 mm height-field cell: the past-the-focus case
// two tests measure against its exact closed form.
inline Scene past_focus_sine_scene() {
    test_support::SineSetup c = test_support::sine_case(20.0, -1.2, 0.2, false);
    c.cell = 0.002;
    return test_support::make_sine_scene(c);
}

struct Rendered {
    CausticOutput out;
    CameraGBuffer gbuffer;
};

inline Rendered render(const Scene& scene, const std::map<std::string, std::string>& overrides, int bins, int threads = 2,
                bool volume = true) {
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    const MethodInfo& info = require_method(kMethod);
    std::unique_ptr<Method> method = info.create(ParamSet::resolve(info.name, info.params, overrides));
    EXPECT_TRUE(method->capabilities(scene).supported);
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const RayTracer tracer(frame);
    Rendered r;
    r.gbuffer = build_camera_gbuffer(tracer, scene.camera);
    const ReceiverChart chart(frame, bins, bins);
    method->prepare(scene);
    method->update(frame);
    RenderRequest request;
    request.receiver = &chart;
    request.camera = &r.gbuffer;
    request.camera_volume = volume;
    r.out = method->render(frame, request);
    return r;
}

inline bool all_finite(const Image& image) {
    for (float v : image.pixels)
        if (!std::isfinite(v)) return false;
    return true;
}

inline double nrmse(const Image& m, const Image& r) {
    double se = 0.0, sum = 0.0;
    for (std::size_t i = 0; i < r.pixels.size(); ++i) {
        se += (m.pixels[i] - r.pixels[i]) * static_cast<double>(m.pixels[i] - r.pixels[i]);
        sum += r.pixels[i];
    }
    const double n = static_cast<double>(r.pixels.size());
    return std::sqrt(se / n) / (sum / n);
}

}  // namespace caustics::adaptive_beams_test
