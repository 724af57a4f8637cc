#pragma once
// One render of a registered method through the plugin interface, as the tests of every method need it.
#include <map>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/api/method.hpp>
#include <caustics/api/params.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics::test_support {

// Creates `method_name` with `overrides`, expects it to support `scene`, and renders frame 0 after
// prepare() and update(): a receiver map of width x height bins and, when `camera` is given, the camera
// view at its pixels.
inline CausticOutput render_method(const std::string& method_name, const Scene& scene,
                                   const std::map<std::string, std::string>& overrides, int width, int height,
                                   const CameraGBuffer* camera = nullptr) {
    const MethodInfo& info = require_method(method_name);
    std::unique_ptr<Method> method = info.create(ParamSet::resolve(info.name, info.params, overrides));
    const Capability capability = method->capabilities(scene);
    EXPECT_TRUE(capability.supported) << method_name << ": " << capability.reason;
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const ReceiverChart chart(frame, width, height);
    method->prepare(scene);
    method->update(frame);
    RenderRequest request;
    request.receiver = &chart;
    request.camera = camera;
    return method->render(frame, request);
}

}  // namespace caustics::test_support
