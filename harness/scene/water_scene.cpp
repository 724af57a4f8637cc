#include <caustics/scene/water_scene.hpp>

namespace caustics {

Scene make_water_scene(const WaterOverFloor& d) {
    Scene scene;
    scene.path = d.name;
    scene.name = d.name;
    Light light;
    light.type = LightType::Directional;
    light.direction = glm::normalize(d.light_direction);
    light.irradiance = d.irradiance;
    scene.lights.push_back(light);

    Object water;
    water.name = "water";
    water.shape = ShapeType::HeightField;
    water.material.type = MaterialType::Dielectric;
    water.material.ior = d.ior;
    water.material.absorption = d.absorption;
    water.material.dispersion = d.dispersion;
    water.heightfield.center = {0.0, 0.0};
    water.heightfield.size = d.water_size;
    water.heightfield.resolution = {d.water_resolution, d.water_resolution};
    water.heightfield.generator = d.generator;
    water.heightfield.amplitude = d.amplitude;
    water.heightfield.wavelength = d.wavelength;
    water.heightfield.direction = {1.0, 0.0};

    Object floor;
    floor.name = "floor";
    floor.shape = ShapeType::Plane;
    floor.center = {0.0, 0.0, d.floor_z};
    floor.u = d.floor_u;
    floor.v = d.floor_v;
    floor.material.type = MaterialType::Diffuse;

    scene.objects = {water, floor};
    scene.receiver.object = "floor";
    scene.receiver.object_index = 1;
    scene.receiver.width = scene.receiver.height = d.receiver_resolution;
    return scene;
}

}  // namespace caustics
