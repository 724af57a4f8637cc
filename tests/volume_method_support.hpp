#pragma once
// Shared by the tests of the 3-D caustic texture methods (eikonal_fmm, wave_pde): a height-field water
// scene over a floor, a sine surface, and one render through the plugin interface with a receiver map
// and a row of camera pixels on the floor (both methods read their texture at any receiver point).
#include <map>
#include <string>

#include <glm/glm.hpp>

#include <caustics/frame/camera.hpp>
#include "method_support.hpp"
#include <caustics/scene/scene.hpp>
#include <caustics/scene/water_scene.hpp>

namespace caustics::test_support {

// `water` over a floor of side floor_size at floor_z (a 32 x 32 receiver), directional light straight down.
inline Scene volume_test_scene(const HeightFieldDesc& water, double floor_z, double floor_size) {
    WaterOverFloor d;
    d.name = "test";
    d.floor_z = floor_z;
    d.floor_u = {floor_size, 0.0, 0.0};
    d.floor_v = {0.0, floor_size, 0.0};
    d.receiver_resolution = 32;
    Scene scene = make_water_scene(d);
    scene.objects[0].heightfield = water;
    return scene;
}

inline HeightFieldDesc sine_desc(double amplitude, double wavelength, int resolution = 256) {
    HeightFieldDesc d;
    d.size = glm::dvec2(2.0);
    d.resolution = glm::ivec2(resolution);
    d.generator = HeightGenerator::Sine;
    d.amplitude = amplitude;
    d.wavelength = wavelength;
    return d;
}

// Camera pixels (width x 1) on the floor along x from x0 in steps dx, at y = 0.
inline CameraGBuffer floor_pixels(const Scene& scene, int width, float x0, float dx) {
    CameraGBuffer gb;
    gb.width = width;
    gb.height = 1;
    gb.covered.assign(static_cast<std::size_t>(width), 1);
    gb.object.assign(static_cast<std::size_t>(width), 1);
    gb.normal.assign(static_cast<std::size_t>(width), glm::vec3(0, 0, 1));
    const float z = static_cast<float>(scene.objects[1].center.z);
    for (int k = 0; k < width; ++k) gb.position.push_back(glm::vec3(x0 + dx * static_cast<float>(k), 0.0f, z));
    return gb;
}

// render_method with the scene's receiver map and `camera_pixels` floor pixels from x = -0.6 over 0.96 m.
inline CausticOutput render_volume_method(const std::string& method_name, const Scene& scene,
                                          const std::map<std::string, std::string>& params, int camera_pixels) {
    const CameraGBuffer gb = floor_pixels(scene, camera_pixels, -0.6f, 0.96f / static_cast<float>(camera_pixels));
    return render_method(method_name, scene, params, scene.receiver.width, scene.receiver.height, &gb);
}

}  // namespace caustics::test_support
