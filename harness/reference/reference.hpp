#pragma once
// The ground truth (docs/design.md section 5): an Embree light tracer of caustic irradiance E_c.
//
// Photons leave the light (directional: uniformly over a rectangle perpendicular to the light that
// covers the specular objects' footprint; point: uniformly in the cone around the specular objects),
// follow specular refraction/reflection (Fresnel where the scene asks), lose exp(-sigma_t l) of their flux
// over every segment in a medium (absorption and scattering, reference_transport.cpp) and deposit on the
// first diffuse object they reach after at least one specular event. Where a medium scatters, each
// segment after a specular event in the camera's medium also adds one scattering point, connected to the
// pinhole, to the volume caustic radiance camera_volume (reference_volume.cpp). The sample values come from
// photon_sampler.hpp (randomized quasi-Monte Carlo by default) in R independent replicas; the per-bin
// standard error is the spread between replicas (R - 1 degrees of freedom). Deposits are accumulated in
// fixed point, so the result is bit-identical for any thread count, and a reference can be extended with
// more photons (each replica continues its own sequence) to the same bits as one computed at once.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/util/hash.hpp>
#include <caustics/util/image.hpp>
#include <caustics/util/huge_pages.hpp>
#include <caustics/reference/photon_sampler.hpp>
#include <caustics/frame/receiver_chart.hpp>

namespace caustics {

// The reference's fixed-point sums (ReferenceSums): zeroed when sized, without a pass over them.
using SumVector = std::vector<std::int64_t, HugePageAllocator<std::int64_t>>;

// Where the emitted flux went [W]. emitted == sum of the others up to round-off.
struct FluxLedger {
    double emitted = 0.0;
    double deposited_receiver = 0.0;  // caustic flux on the measurement receiver
    double deposited_other = 0.0;     // caustic flux on other diffuse objects
    double direct = 0.0;              // reached a diffuse object with no specular event (not caustic)
    double escaped = 0.0;             // left the scene
    double absorbed = 0.0;            // absorption by a medium (inside dielectrics or the scene's)
    double scattered = 0.0;           // scattered out of the path by a medium (extinction minus absorption)
    double truncated = 0.0;           // exceeded scene.max_specular_depth
    double accounted() const {
        return deposited_receiver + deposited_other + direct + escaped + absorbed + scattered + truncated;
    }
};

// camera_volume leaves out scattering closer than this to the pinhole [m]: the volume view's near
// distance (frame/camera.hpp), where 1/r^2 would otherwise have infinite variance (reference_volume.cpp).
constexpr double kVolumeMinDistance = kVolumeNearDistance;

struct ReferenceSettings {
    // Photons over all replicas, rounded up to a multiple of replicas x lights. With a noise target it is
    // the first round's count.
    std::uint64_t photons = 10'000'000;
    std::uint64_t seed = 1;
    SamplerKind sampler = SamplerKind::Sobol;
    int replicas = kDefaultReplicas;
    double noise_target = 0.0;  // > 0: add photons in rounds until noise_nrmse <= noise_target
    std::uint64_t photon_cap = kDefaultPhotonCap;   // a noise target stops here (reported as not met)
    int threads = 0;            // 0 = all
    bool camera_view = true;    // also produce the camera view (one visibility ray per deposit)
    bool progress = true;       // progress bar on stderr when it runs longer than a second
    // How the rays go to Embree. Empty (the default): each thread times its batches and uses the fastest
    // mode (query_mode_chooser.hpp). Set: every batch in that mode, for tests and measurements. The
    // sums are the same bits either way (tests/test_reference_bits.cpp), so it is not part of the cache key.
    std::optional<QueryMode> query_mode{};

    static constexpr int kDefaultReplicas = 8;
    static constexpr std::uint64_t kDefaultPhotonCap = 2'000'000'000;
    // The valid settings, in one place: the command line (--photons, --seed, --replicas, --noise-target,
    // --photon-cap) and the sweep spec's reference fields check against these.
    static constexpr std::uint64_t kMinPhotons = 1000;
    static constexpr std::uint64_t kMaxPhotons = 100'000'000'000;   // 1e11
    static constexpr std::uint64_t kMaxSeed = std::uint64_t{1} << 62;
    static constexpr int kMinReplicas = 2;
    static constexpr int kMaxReplicas = 256;
    static constexpr double kMaxNoiseTarget = 10.0;
};

// The integer sums a reference is made of, kept so that it can be cached and extended. Fixed point:
// each photon adds round(2^30 * q) with q = (its flux now) / (the largest light's flux per photon at
// count 1), so the sums do not depend on how many photons there are.
struct ReferenceSums {
    std::uint64_t per_replica = 0;   // photons traced in each replica
    std::uint32_t replicas = 0;
    std::uint32_t lights = 0;
    std::size_t bins = 0, pixels = 0;
    SumVector bin_sums;     // replica-major: [r * bins + b]
    SumVector pixel_sums;   // [r * pixels + p]
    std::size_t volume_pixels = 0;          // camera_volume: pixels (0: not measured)
    SumVector volume_sums;  // [r * volume_pixels + p]
    FluxLedger ledger_units;                // in units of q (converted to W by the result)
};

struct ReferenceResult {
    Image receiver;             // E_c per bin [W/m^2]: the mean of the replicas
    Image receiver_stderr;      // standard error per bin (from the replicas: replicas - 1 dof)
    std::vector<Image> receiver_replicas;   // each replica's own estimate (independent of the others)
    Image camera;               // E_c per camera pixel (0 where not covered)
    Image camera_stderr;
    std::vector<Image> camera_replicas;
    std::vector<std::uint8_t> camera_covered;
    double noise_nrmse = 0.0;   // sqrt(mean(stderr^2)) / mean(E_c) on the receiver map
    double noise_nrmse_camera = 0.0;
    // Volume caustic radiance L_v per camera pixel [W/(m^2 sr)] (method.hpp, CausticOutput::camera_volume),
    // measured where the scene scatters (scene_scatters) and the camera view is asked; empty otherwise.
    Image camera_volume;
    Image camera_volume_stderr;
    std::vector<Image> camera_volume_replicas;
    double noise_nrmse_volume = 0.0;   // over every pixel
    FluxLedger ledger;
    std::uint64_t photons = 0;  // over all replicas
    std::uint64_t seed = 0;
    SamplerKind sampler = SamplerKind::Sobol;
    int replicas = 0;
    double noise_target = 0.0;  // the target asked for (0: none)
    bool noise_target_met = true;
    int rounds = 1;             // tracing rounds of this computation (noise target)
    std::vector<std::uint64_t> round_photons;   // photons (all replicas) after each round of this computation
    std::vector<double> round_noise;            // noise_nrmse after each round
    std::uint64_t photons_traced = 0;           // photons this computation traced (0 when loaded)
    std::shared_ptr<const ReferenceSums> sums;
    std::string cache_key;
    double seconds = 0.0;       // compute time (0 when loaded from cache)
    bool from_cache = false;
};

// Traces the reference for one frame. `camera` may be null (no camera view). `start` (optional) is a
// smaller reference of the same scene, frame, seed, sampler, replicas and camera view to extend: its
// photons are kept and only the new ones are traced (same bits as computing all at once). With a noise
// target, photons are added in rounds until noise_nrmse <= target or the photon cap.
ReferenceResult compute_reference(const RayTracer& tracer, const ReceiverChart& chart,
                                  const CameraGBuffer* camera, const ReferenceSettings& settings,
                                  const ReferenceSums* start = nullptr);

// The reference that `sums` (made with `settings`' seed, sampler and replicas on this scene frame) hold,
// without tracing: what a cache entry is turned back into.
ReferenceResult reference_from_sums(const RayTracer& tracer, const ReceiverChart& chart, const CameraGBuffer* camera,
                                    const ReferenceSettings& settings, std::shared_ptr<const ReferenceSums> sums);

// Photons per replica for a requested total: rounded up to a multiple of `lights`.
std::uint64_t photons_per_replica(std::uint64_t photons, int replicas, std::size_t lights);

// Adds the scene file's bytes and every asset's bytes (the name of one that cannot be read) to `h`:
// what makes two loads of a scene the same input.
void hash_scene_contents(Hash128& h, const Scene& scene);

// The cache key: a hash of the scene file bytes and every asset's bytes, the frame, seed, sampler,
// replicas, camera_view and the reference code version (not the photon count: entries of one key
// differ in photons, and a larger one extends a smaller one).
std::string reference_cache_key(const Scene& scene, int frame, const ReferenceSettings& settings);

// Loads the cached reference for (scene, frame, settings) from cache_dir, or computes and stores it
// (atomically: temporary name, then rename). Without a noise target: the entry with exactly the asked
// photons, else the largest smaller one extended. With one: the smallest entry that meets it, else the
// largest one extended until it does. A truncated, corrupt or stale entry is rebuilt. A scene
// built in code (no source_text) is computed every time: its key could not tell it from another one.
// A loaded scene changed in code keeps its file's key: compute such a scene with compute_reference.
ReferenceResult load_or_compute_reference(const FrameGeometry& frame, const RayTracer& tracer,
                                          const ReceiverChart& chart, const CameraGBuffer* camera,
                                          const ReferenceSettings& settings,
                                          const std::string& cache_dir);

// Default cache folder: $CAUSTICS_CACHE_DIR, else results/cache.
std::string default_cache_dir();

}  // namespace caustics
