#pragma once
// The scene model (docs/design.md section 8). Coordinates are right-handed with +z up: height fields are
// z = h(x, y) and water lies below its surface. Lengths are in metres.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/mesh.hpp>

namespace caustics {

enum class LightType { Directional, Point };

struct Light {
    LightType type = LightType::Directional;
    glm::dvec3 direction{0.0, 0.0, -1.0};  // directional: unit direction light travels in
    double irradiance = 1.0;               // directional: E0 [W/m^2] on a plane perpendicular to it
    glm::dvec3 position{0.0};              // point: position
    double intensity = 1.0;                // point: I [W/sr]
};

enum class MaterialType { Dielectric, Mirror, Diffuse };

struct Material {
    MaterialType type = MaterialType::Diffuse;
    double ior = 1.5;          // dielectric: index of refraction (the outside is air, n = 1)
    double dispersion = 0.0;   // dielectric: the index spans [ior, ior + dispersion] over the visible band
    double absorption = 0.0;   // dielectric: Beer-Lambert coefficient Ka [1/m] inside the object
    // dielectric: the homogeneous medium inside ("medium" on the material: murky water). Scattering
    // [1/m] takes light out of the caustic (extinction = absorption + scattering) and scatters it once
    // towards the camera (camera_volume); anisotropy is the Henyey-Greenstein g.
    double scattering = 0.0;
    double anisotropy = 0.0;
    glm::dvec3 albedo{0.8};    // diffuse: reflectance, for beauty images only
    bool is_specular() const { return type != MaterialType::Diffuse; }
};

enum class ShapeType { Plane, Box, Sphere, Mesh, HeightField };

enum class HeightGenerator { Flat, Sine, Gaussian, Noise, Waves, Image };

// A height field z = base_height + h(x, y, t) over the rectangle center +- size/2, sampled on a grid of
// resolution.x x resolution.y cells ((resolution + 1) vertices per axis).
struct HeightFieldDesc {
    glm::dvec2 center{0.0};
    glm::dvec2 size{1.0};
    glm::ivec2 resolution{256};
    double base_height = 0.0;
    HeightGenerator generator = HeightGenerator::Flat;
    // sine: amplitude * sin(2 pi (d . p) / wavelength + phase + 2 pi speed t / wavelength)
    // gaussian: amplitude * exp(-|p - gauss_center|^2 / (2 sigma^2))
    double amplitude = 0.0;
    double wavelength = 1.0;
    double phase = 0.0;
    double speed = 0.0;            // sine: phase speed [m/s] (0 = static)
    glm::dvec2 direction{1.0, 0.0};
    double sigma = 0.1;
    glm::dvec2 gauss_center{0.0};
    // noise: fractal surface periodic in space (the rectangle) and time (period seconds)
    double spectral_exponent = 3.0; // power spectrum ~ k^-exponent
    double min_wavelength = 0.0;    // smallest wavelength kept (0 = two grid cells)
    double max_wavelength = 0.0;    // largest wavelength kept (0 = the tile size)
    double period = 2.0;            // time period [s]
    int time_samples = 32;          // frames synthesised per period
    std::uint64_t seed = 1;
    // waves: deterministic 2-D wave simulation seeded with Gaussian drops
    int drops = 8;
    double drop_radius = 0.05;
    double wave_speed = 0.5;        // [m/s]
    double damping = 0.2;           // [1/s]
    double animation_length = 2.0;  // [s] the scene's animation (frames / fps); drops fall in its first half
    // image: height map file; pixel values (first channel, [0, 1]) times amplitude
    std::string image_path;
};

struct Object {
    std::string name;
    ShapeType shape = ShapeType::Plane;
    Material material;
    // plane: the parallelogram center + s u + t v, s, t in [-1/2, 1/2]; normal = normalize(u x v)
    glm::dvec3 center{0.0};
    glm::dvec3 u{1.0, 0.0, 0.0};
    glm::dvec3 v{0.0, 1.0, 0.0};
    glm::dvec3 size{1.0};          // box: full extents along x, y, z, centred on `center`
    double radius = 1.0;           // sphere: radius, centred on `center`
    std::string mesh_path;         // mesh: glTF/GLB file (resolved against the scene file's folder)
    glm::dmat4 transform{1.0};     // mesh: object-to-world
    TriangleMesh mesh;             // mesh: loaded and transformed to world space by load_scene
    HeightFieldDesc heightfield;   // heightfield
};

struct Camera {
    glm::dvec3 position{0.0, -3.0, 2.0};
    glm::dvec3 look_at{0.0};
    glm::dvec3 up{0.0, 0.0, 1.0};
    double fov_y_deg = 45.0;
    int width = 512;
    int height = 384;
};

// The measurement receiver: one plane or height-field object binned into a width x height map.
struct Receiver {
    std::string object;
    int object_index = -1;
    int width = 256;
    int height = 256;
};

// An optional homogeneous participating medium filling the scene outside every dielectric (fog).
struct Medium {
    bool present = false;
    double ior = 1.0;
    double absorption = 0.0;   // [1/m]
    double scattering = 0.0;   // [1/m]
    double anisotropy = 0.0;   // Henyey-Greenstein g in (-1, 1)
};

struct Animation {
    int frames = 1;
    double fps = 30.0;
    double time(int frame) const { return frame / fps; }
};

struct Scene {
    std::string path;                 // the scene file as given
    std::string name;                 // file stem, e.g. "pool"
    std::string source_text;          // the file's bytes (cache keys hash them)
    std::vector<std::string> assets;  // resolved paths of every asset file it reads
    std::vector<Light> lights;
    Camera camera;
    std::vector<Object> objects;
    Medium medium;
    Receiver receiver;
    Animation animation;
    bool fresnel = false;             // false: dielectrics transmit everything (TIR still reflects)
    int max_specular_depth = 8;       // longest specular chain the reference follows

    const Object& receiver_object() const { return objects.at(static_cast<std::size_t>(receiver.object_index)); }
};

// The homogeneous medium light travels through at one place: inside dielectric `object`, or outside
// every dielectric (object -1: the scene's medium, or vacuum).
struct MediumCoefficients {
    double absorption = 0.0;   // sigma_a [1/m]
    double scattering = 0.0;   // sigma_s [1/m]
    double anisotropy = 0.0;   // Henyey-Greenstein g in (-1, 1)
    double extinction() const { return absorption + scattering; }   // sigma_t
    bool scatters() const { return scattering > 0.0; }
};

inline MediumCoefficients medium_at(const Scene& scene, int object) {
    if (object >= 0) {
        const Material& m = scene.objects.at(static_cast<std::size_t>(object)).material;
        return {m.absorption, m.scattering, m.anisotropy};
    }
    if (!scene.medium.present) return {};
    return {scene.medium.absorption, scene.medium.scattering, scene.medium.anisotropy};
}

// Whether some medium of the scene scatters: then its caustics include volume caustic radiance
// (camera_volume, docs/design.md section 3) and every caustic path is attenuated by extinction.
inline bool scene_scatters(const Scene& scene) {
    if (scene.medium.present && scene.medium.scattering > 0.0) return true;
    for (const Object& o : scene.objects)
        if (o.material.type == MaterialType::Dielectric && o.material.scattering > 0.0) return true;
    return false;
}

// The Henyey-Greenstein phase function [1/sr] for the cosine between the direction light travels in
// before and after scattering (g > 0: forward scattering); it integrates to 1 over the sphere.
inline double henyey_greenstein(double cos_theta, double g) {
    const double d = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * 3.14159265358979323846 * d * std::sqrt(d));
}

// Reads and validates a scene file. Throws InputError (file, key, what is valid) on any bad input.
Scene load_scene(const std::string& path);

}  // namespace caustics
