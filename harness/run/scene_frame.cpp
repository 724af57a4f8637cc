#include <caustics/run/scene_frame.hpp>

#include <utility>

namespace caustics {

SceneFrame::SceneFrame(Scene scene, int frame)
    : scene_(std::move(scene)), geometry_(build_frame_geometry(scene_, frame)) {
    tracer_ = std::make_unique<RayTracer>(geometry_);
    chart_ = std::make_unique<ReceiverChart>(geometry_, scene_.receiver.width, scene_.receiver.height);
    gbuffer_ = build_camera_gbuffer(*tracer_, scene_.camera);
}

}  // namespace caustics
