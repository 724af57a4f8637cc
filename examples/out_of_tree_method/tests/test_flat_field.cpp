// flat_field through the plugin interface, on the installed scenes (CAUSTICS_SOURCE_DIR is the data
// folder of the caustics installation the method is built against).
#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include <caustics/api/registry.hpp>
#include <caustics/frame/camera.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/scene/scene.hpp>

#include "method_support.hpp"

namespace {

using namespace caustics;

Scene installed_scene(const std::string& name) {
    return load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json");
}

// sine.json: a 1 W/m^2 sun straight down through water without Fresnel or absorption, over a floor the
// water covers wholly: a flat interface would transmit exactly 1 W/m^2 to every bin and floor pixel.
TEST(FlatField, TransmitsTheSunUnchangedThroughFlatClearWater) {
    const Scene scene = installed_scene("sine");
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const RayTracer tracer(frame);
    Camera small = scene.camera;
    small.width = 64;
    small.height = 48;
    const CameraGBuffer gbuffer = build_camera_gbuffer(tracer, small);
    const CausticOutput out = test_support::render_method("flat_field", scene, {}, 32, 24, &gbuffer);

    ASSERT_EQ(out.receiver.width, 32);
    ASSERT_EQ(out.receiver.height, 24);
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 32; ++x) EXPECT_NEAR(out.receiver.at(x, y), 1.0, 1e-6) << x << ", " << y;

    ASSERT_EQ(out.camera.width, 64);
    int floor_pixels = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
            const std::size_t i = gbuffer.index(x, y);
            if (!gbuffer.covered[i]) continue;
            ++floor_pixels;
            EXPECT_NEAR(out.camera.at(x, y), 1.0, 1e-6) << x << ", " << y;
        }
    EXPECT_GT(floor_pixels, 64 * 48 / 2) << "the camera looks at the floor";
    EXPECT_EQ(out.health.get("not_covered"), 0);
}

TEST(FlatField, RefusesScenesWithoutFlatWater) {
    const MethodInfo& info = require_method("flat_field");
    const auto method = info.create(ParamSet::resolve(info.name, info.params, {}));
    const Capability sphere = method->capabilities(installed_scene("sphere"));   // point light, glass ball
    EXPECT_FALSE(sphere.supported);
    EXPECT_FALSE(sphere.reason.empty());
}

TEST(FlatField, RegisteredFromItsOwnFolder) {
    EXPECT_EQ(method_origin("flat_field").rfind("flat_field.cpp:", 0), 0u) << method_origin("flat_field");
}

}  // namespace
