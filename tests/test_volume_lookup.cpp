// Receiver lookups into a volume caustic texture (harness/volume_lookup): points on the box's faces.
// (The strip that oblique refracted light cannot reach is tested through wave_pde, test_wave_pde.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/blocks/volume/volume_lookup.hpp>
#include <caustics/scene/water_scene.hpp>

using namespace caustics;

namespace {

// Camera pixels at the given world points (covered, on a floor facing up).
CameraGBuffer pixels_at(const std::vector<glm::vec3>& points) {
    CameraGBuffer gb;
    gb.width = static_cast<int>(points.size());
    gb.height = 1;
    gb.covered.assign(points.size(), 1);
    gb.object.assign(points.size(), 1);
    gb.normal.assign(points.size(), glm::vec3(0, 0, 1));
    gb.position = points;
    return gb;
}

}  // namespace

TEST(VolumeLookup, PointsOnTheBoxFacesReadTheTexture) {
    // A uniform texture over [-1, 1]^2 x [-0.5, 0.1]. A wall on the face x = 1 has float positions a
    // rounding error on either side of it: both must read the texture, while a point half a cell out
    // is outside.
    const Scene scene = make_water_scene(WaterOverFloor{});
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    VolumeShape box;
    box.spacing = 0.1;
    box.nx = box.ny = 20;
    box.nz = 6;
    box.origin = glm::dvec3(-1.0, -1.0, -0.5);
    const VolumeF texture(box, 1.0f);
    VolumeLookup lookup;
    lookup.texture = &texture;
    lookup.normalize_flux = false;
    const float just_out = std::nextafter(1.0f, 2.0f), just_in = std::nextafter(1.0f, 0.0f);
    const CameraGBuffer gb = pixels_at({{just_out, 0.3f, -0.2f}, {just_in, 0.3f, -0.2f}, {1.0f, 0.3f, -0.5f},
                                        {1.05f, 0.3f, -0.2f}, {0.2f, 0.3f, -0.2f}});
    RenderRequest request;
    request.camera = &gb;
    const CausticOutput out = render_volume_texture(frame, request, lookup);
    EXPECT_EQ(out.camera.at(0, 0), 1.0f);
    EXPECT_EQ(out.camera.at(1, 0), 1.0f);
    EXPECT_EQ(out.camera.at(2, 0), 1.0f);   // an edge of the box
    EXPECT_EQ(out.camera.at(3, 0), 0.0f);   // half a cell outside
    EXPECT_EQ(out.camera.at(4, 0), 1.0f);
    EXPECT_EQ(out.health.get("outside_volume"), 1);
}
