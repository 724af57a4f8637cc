#pragma once
// The ground truth (DESIGN.md section 5): an Embree light tracer of caustic irradiance E_c.
//
// Photons leave the light (directional: uniformly over a rectangle perpendicular to the light that
// covers the specular objects' footprint; point: uniformly in the cone around the specular objects),
// follow specular refraction/reflection (Fresnel and absorption where the scene asks) and deposit on the
// first diffuse object they reach after at least one specular event. Photon k uses a counter-based RNG
// keyed by (seed, k) and deposits are accumulated in fixed point, so the result is bit-identical for
// any thread count. Per-bin standard errors come from per-photon second moments.
#include <cstdint>
#include <string>
#include <vector>

#include "camera.hpp"
#include "frame.hpp"
#include "image.hpp"
#include "receiver_chart.hpp"

namespace caustics {

// Where the emitted flux went [W]. emitted == sum of the others up to round-off.
struct FluxLedger {
    double emitted = 0.0;
    double deposited_receiver = 0.0;  // caustic flux on the measurement receiver
    double deposited_other = 0.0;     // caustic flux on other diffuse objects
    double direct = 0.0;              // reached a diffuse object with no specular event (not caustic)
    double escaped = 0.0;             // left the scene
    double absorbed = 0.0;            // Beer-Lambert absorption inside dielectrics
    double truncated = 0.0;           // exceeded scene.max_specular_depth
    double accounted() const {
        return deposited_receiver + deposited_other + direct + escaped + absorbed + truncated;
    }
};

struct ReferenceSettings {
    std::uint64_t photons = 10'000'000;
    std::uint64_t seed = 1;
    int threads = 0;            // 0 = all
    bool camera_view = true;    // also produce the camera view (one visibility ray per deposit)
    bool progress = true;       // progress bar on stderr when it runs longer than a second
};

struct ReferenceResult {
    Image receiver;             // E_c per bin [W/m^2]
    Image receiver_stderr;      // standard error per bin
    Image camera;               // E_c per camera pixel (0 where not covered)
    Image camera_stderr;
    std::vector<std::uint8_t> camera_covered;
    double noise_nrmse = 0.0;   // sqrt(mean(stderr^2)) / mean(E_c) on the receiver map
    double noise_nrmse_camera = 0.0;
    FluxLedger ledger;
    std::uint64_t photons = 0;
    std::uint64_t seed = 0;
    std::string cache_key;
    double seconds = 0.0;       // compute time (0 when loaded from cache)
    bool from_cache = false;
};

// Traces the reference for one frame. `camera` may be null (no camera view).
ReferenceResult compute_reference(const RayTracer& tracer, const ReceiverChart& chart,
                                  const CameraGBuffer* camera, const ReferenceSettings& settings);

// The cache key: a hash of the scene file bytes and every asset's bytes, the frame, photons, seed,
// camera_view and the reference code version.
std::string reference_cache_key(const Scene& scene, int frame, const ReferenceSettings& settings);

// Loads the cached reference for (scene, frame, settings) from cache_dir, or computes and stores it
// (atomically: temporary name, then rename). A truncated, corrupt or stale entry is rebuilt. A scene
// built in code (no source_text) is computed every time: its key could not tell it from another one.
// A loaded scene changed in code keeps its file's key: compute such a scene with compute_reference.
ReferenceResult load_or_compute_reference(const FrameGeometry& frame, const RayTracer& tracer,
                                          const ReceiverChart& chart, const CameraGBuffer* camera,
                                          const ReferenceSettings& settings,
                                          const std::string& cache_dir);

// Default cache folder: $CAUSTICS_CACHE_DIR, else results/cache.
std::string default_cache_dir();

}  // namespace caustics
