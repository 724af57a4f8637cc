#pragma once
// A scene built in code rather than read from a file: a water height field over a diffuse plane floor,
// lit by one directional light. It is the set-up of most closed-form checks (flat water, sine
// gratings, Snell mappings) and of several benchmarks; callers change what their case needs on the
// returned Scene (objects[0] is the water, objects[1] the floor and receiver).
#include <string>

#include <glm/glm.hpp>

#include <caustics/scene/scene.hpp>

namespace caustics {

struct WaterOverFloor {
    std::string name = "water_over_floor";
    glm::dvec3 light_direction{0.0, 0.0, -1.0};   // normalised by make_water_scene
    double irradiance = 1.0;                       // E0 [W/m^2]
    double ior = 1.33, absorption = 0.0, dispersion = 0.0;
    glm::dvec2 water_size{2.0, 2.0};               // centred on the origin, base height 0
    int water_resolution = 64;                     // height samples along x and y
    HeightGenerator generator = HeightGenerator::Flat;
    double amplitude = 0.0, wavelength = 0.25;     // sine and gaussian generators
    double floor_z = -0.4;
    glm::dvec3 floor_u{1.0, 0.0, 0.0}, floor_v{0.0, 1.0, 0.0};   // plane axes (Object::u, Object::v)
    int receiver_resolution = 64;                  // bins along both axes of the floor
};

Scene make_water_scene(const WaterOverFloor& d);

}  // namespace caustics
