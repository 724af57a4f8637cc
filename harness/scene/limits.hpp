#pragma once
// What a scene may ask for (issue 12), with bounds that follow from what the computation can represent.
// Every bound is checked where the value is read (scene_loader.cpp, frame.cpp, the reference) and named
// in the message; scenes/README.md lists them.
//
// - Geometry is single precision: Embree and the TriangleMesh every method receives hold float
//   coordinates, and Embree refuses (asserts on) rays whose origin or direction is not finite or beyond
//   ~1.8e18. Every coordinate the geometry can reach (positions, centres, sizes, heights, amplitudes,
//   transformed mesh vertices, lights, the camera) stays within |x| <= kMaxCoordinate: 100 km, where a
//   float still resolves 8 mm, and every derived quantity (distances, their squares, emitter rectangles)
//   stays far inside float range. The harness is built for metre-scale scenes.
// - Lengths that divide (sizes, radii, plane edges, wavelengths, Gaussian widths, drop radii) are at
//   least kMinLength: below it float positions collapse and inverse lengths overflow.
// - Absorption and scattering coefficients are at most kMaxCoefficient: at 1e4 /m light falls below the
//   reference's fixed-point resolution (2^-30 of a photon's flux, e^-21) within 2.1 mm.
// - Light powers (irradiance, intensity) lie in [kMinPower, kMaxPower]: the images are float32, and
//   irradiance is the light's power times a concentration that spans many orders of magnitude; 1e+-10
//   keeps it and its square inside float range with a margin of 1e8 either way.
// - Memory: every resolution is checked against an estimate of what the reference and a render allocate
//   (estimate_scene_memory) before anything is allocated, against a ceiling of 8 GiB, raised or lowered
//   with the environment variable CAUSTICS_MEMORY_LIMIT_GB (GiB, 2^30 bytes).
#include <cstdint>
#include <string>
#include <vector>

#include <caustics/scene/scene.hpp>

namespace caustics {

inline constexpr double kMaxCoordinate = 1e5;     // [m] |x|, |y|, |z| of anything the geometry reaches
inline constexpr double kMinLength = 1e-6;        // [m] sizes, radii, edges, wavelengths, widths
inline constexpr double kMaxCoefficient = 1e4;    // [1/m] absorption, scattering
inline constexpr double kMinPower = 1e-10;        // irradiance [W/m^2], intensity [W/sr]
inline constexpr double kMaxPower = 1e10;
// The waves generator's work to reach the last frame: grid vertices x (substeps x frames + drops).
// 2e10 vertex updates are about a minute on one core.
inline constexpr double kMaxWaveUpdates = 2e10;
inline constexpr double kDefaultMemoryLimitGiB = 8.0;
inline constexpr const char* kMemoryLimitVariable = "CAUSTICS_MEMORY_LIMIT_GB";
// The replicas a reference uses unless asked otherwise (ReferenceSettings::kDefaultReplicas).
inline constexpr int kMemoryDefaultReplicas = 8;

// A bound or value for messages: %g ("1e+05", "0.25").
std::string format_limit(double x);
// "1.5 GiB", "320 MiB", "12 KiB", "800 B".
std::string format_bytes(double bytes);

// The memory ceiling in bytes: $CAUSTICS_MEMORY_LIMIT_GB GiB, else 8 GiB. InputError naming the variable
// when it is set to anything but a number > 0.
double memory_limit_bytes();
// The TBB worker threads a parallel loop gets now (after any ThreadLimit / global_control).
int worker_threads();

// Bytes per receiver bin / camera pixel at the peak of a reference and a render (see limits.cpp for the
// terms): R replicas, T threads.
double reference_bytes_per_bin(int replicas, int threads);
double reference_bytes_per_pixel(int replicas, int threads);
// Bytes per cell of a height field (its grid, triangles, Embree's copy and BVH; measured).
double heightfield_bytes_per_cell();

struct MemoryItem {
    std::string key;     // the scene key that sets it ("receiver.resolution", "objects[2].resolution", ...)
    std::string what;    // how it was estimated, for the message
    double bytes = 0.0;
    double per_unit = 0.0;   // bytes per bin / pixel / cell (0: not a resolution)
    std::string unit;        // "bins", "pixels", "cells"
};

struct MemoryEstimate {
    std::vector<MemoryItem> items;
    double total() const;
    const MemoryItem* largest() const;
};

// What loading, the frame geometry, the reference (R replicas, T threads) and a render of `scene` hold
// at their peak, item by item.
MemoryEstimate estimate_scene_memory(const Scene& scene, int replicas, int threads);

// Throws InputError(scene.path, the largest item's key, ...) when the estimate exceeds the ceiling.
void check_scene_memory(const Scene& scene, int replicas, int threads);

// Throws InputError(file, key, ...) when one allocation of `bytes` (described by `what`) exceeds the
// ceiling.
void check_allocation(const std::string& file, const std::string& key, double bytes, const std::string& what);

}  // namespace caustics
