#pragma once
#include <memory>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

// Everything about one (scene, frame) that does not depend on the method. Neither copyable nor
// movable: the frame geometry, tracer and chart point into it.
class SceneFrame {
public:
    SceneFrame(Scene scene, int frame);   // throws InputError for a frame out of range
    SceneFrame(const SceneFrame&) = delete;
    SceneFrame& operator=(const SceneFrame&) = delete;

    const Scene& scene() const { return scene_; }
    const FrameGeometry& geometry() const { return geometry_; }
    const RayTracer& tracer() const { return *tracer_; }
    const ReceiverChart& chart() const { return *chart_; }
    const CameraGBuffer& gbuffer() const { return gbuffer_; }

private:
    Scene scene_;
    FrameGeometry geometry_;
    std::unique_ptr<RayTracer> tracer_;
    std::unique_ptr<ReceiverChart> chart_;
    CameraGBuffer gbuffer_;
};

}  // namespace caustics
