#pragma once
// Shared by the reference's tests: a scene with its frame, tracer and receiver chart, and the sine test
// scene.
#include <cstdint>
#include <memory>
#include <string>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics::test_support {

inline std::string scene_path(const std::string& name) { return std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name; }

// A scene with its frame, tracer and chart, kept at fixed addresses (each refers to the previous).
struct TracedScene {
    Scene scene;
    std::unique_ptr<FrameGeometry> frame;
    std::unique_ptr<RayTracer> tracer;
    std::unique_ptr<ReceiverChart> chart;

    explicit TracedScene(Scene s, int frame_index = 0) : scene(std::move(s)) {
        frame = std::make_unique<FrameGeometry>(build_frame_geometry(scene, frame_index));
        tracer = std::make_unique<RayTracer>(*frame);
        chart = std::make_unique<ReceiverChart>(*frame, scene.receiver.width, scene.receiver.height);
    }
    ReferenceResult run(std::uint64_t photons, int threads = 0, const CameraGBuffer* camera = nullptr) const {
        ReferenceSettings settings;
        settings.photons = photons;
        settings.threads = threads;
        settings.camera_view = camera != nullptr;
        settings.progress = false;
        return compute_reference(*tracer, *chart, camera, settings);
    }
};

inline int find_object(const Scene& s, const std::string& name) {
    for (std::size_t i = 0; i < s.objects.size(); ++i)
        if (s.objects[i].name == name) return static_cast<int>(i);
    return -1;
}

// The sine scene with a smaller water patch (1.2 m instead of 2 m, same cell size): photons that can
// reach the 1 m floor all start within it, so fewer are wasted. Coarser receiver for speed.
inline Scene sine_test_scene(int bins_x, int bins_y) {
    Scene s = load_scene(scene_path("sine.json"));
    Object& water = s.objects.at(static_cast<std::size_t>(find_object(s, "water")));
    water.heightfield.size = {1.2, 1.2};
    water.heightfield.resolution = {600, 600};
    s.receiver.width = bins_x;
    s.receiver.height = bins_y;
    return s;
}

}  // namespace caustics::test_support
