#pragma once
// The reference light tracer's per-photon transport, shared by reference.cpp (batches, estimates),
// reference_transport.cpp (the photon's path) and reference_volume.cpp (media: extinction and the
// camera_volume view). Private to the reference layer.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <atomic>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/query_mode_chooser.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/util/huge_pages.hpp>
#include <caustics/reference/photon_sampler.hpp>
#include <caustics/reference/photon_source.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/reference/reference_rays.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics::detail {

// One photon's normalised weight q (<= 1) becomes an integer of at most 2^30: 1e9 photons in one bin of
// one replica stay below 2^60, and each contribution keeps ~2^-30 relative precision.
constexpr double kFixedScale = 1073741824.0;  // 2^30

inline std::int64_t to_fixed(double x) {
    // x >= 0: adding 1/2 and truncating rounds to nearest, without a libm call.
    return static_cast<std::int64_t>(x * kFixedScale + 0.5);
}

// The sums are shared by all threads and added to atomically: integer sums are exact, so any order of
// the additions gives the same bits. Deposits are sparse (a photon adds to one bin and at most one
// pixel), so this is far cheaper than a private copy of every view per thread that has to be zeroed and
// merged (for a 1024 x 768 camera and 8 replicas, 50 MB per thread).
inline void add_sum(std::int64_t& acc, std::int64_t x) { std::atomic_ref<std::int64_t>(acc).fetch_add(x, std::memory_order_relaxed); }

// Saturating sum of non-negative fixed-point values (camera_volume; see reference_volume.cpp):
// min(a + b, 2^63 - 1) is associative for non-negative terms, so the result is order independent too.
inline void add_saturating(std::int64_t& acc, std::int64_t x) {
    std::atomic_ref<std::int64_t> a(acc);
    std::int64_t old = a.load(std::memory_order_relaxed), sum;
    do {
        if (__builtin_add_overflow(old, x, &sum)) sum = std::numeric_limits<std::int64_t>::max();
    } while (!a.compare_exchange_weak(old, sum, std::memory_order_relaxed));
}

// The ray log of record_reference_rays: every query, for bench/ replays.
struct RayRecorder {
    double offset = 0.0;   // the tracer's own minimum tnear
    std::vector<RecordedRay> rays;
    void ray(const glm::dvec3& o, const glm::dvec3& d, double tmin, double tmax, bool shadow) {
        RecordedRay r;
        for (int i = 0; i < 3; ++i) r.origin[i] = static_cast<float>(o[i]), r.dir[i] = static_cast<float>(d[i]);
        r.tnear = static_cast<float>(std::max(tmin, offset));
        r.tfar = embree_tfar(tmax);   // as the tracer sends it
        r.shadow = shadow;
        r.segment = 0;   // set per photon by record_reference_rays
        rays.push_back(r);
    }
};

// Where one replica's deposits go: its slices of the receiver, camera and camera_volume sums (bin /
// pixel: the sum of round(2^30 q); null: not measured). A batch belongs to one replica.
struct Accumulators {
    std::int64_t* bins = nullptr;
    std::int64_t* pixels = nullptr;
    std::int64_t* volume = nullptr;
};

// What a camera deposit needs of one pixel, packed so that it costs one cache miss: the pixel's
// G-buffer footprint factor (d_c^2 / cos_c) and the primary-hit object (-1 where not covered).
// Trivially constructible, so that sizing the table writes nothing (HugePageAllocator): the table's
// build writes every element, {0, -1} where no diffuse surface is seen (object -1 matches no hit).
struct PixelInfo {
    double scale;
    int object;
};

// One photon in flight: what its next segment needs. Transport::start sets every field.
struct PhotonState {
    PhotonSampler rng;
    glm::dvec3 origin{0.0}, dir{0.0};
    double w = 0.0;             // weight q now
    int next_dim = 3;           // next sample dimension to read
    int depth = 0;              // specular events so far
    int inside = -1;            // dielectric object the photon travels in (-1: outside medium)
    std::uint32_t slot = 0;     // its place in the photon order of its chunk (ledger events)
    double FluxLedger::*end = nullptr;   // where its path ended (the ledger books its final w there)
};

// One addition to the flux ledger. The ledger is a floating-point sum, so its bits depend on the order of
// the additions to each of its fields: in photon order (each photon's own in the order it made them),
// the order of tracing one photon after another. A wave books every photon's emitted weight as it
// starts and its end (PhotonState::end, one per photon) as the wave finishes, both in photon order;
// only the media's absorbed and scattered shares, any number per photon, become events, which the wave
// replays in photon order.
struct LedgerEvent {
    std::uint32_t slot;
    double FluxLedger::*field;
    double value;
};

// A visibility query whose integer increment lands in `target` when nothing blocks it (camera deposits
// and camera_volume points). Deferred so that a wave's queries go to Embree as packets.
struct ShadowQuery {
    RayQuery ray;
    std::int64_t* target;
    std::int64_t increment;
    bool saturating;   // camera_volume: add_saturating (reference_volume.cpp)
};

// One batch's photon order and emission samples (Transport::batch_order). `emission` is in the traced
// order: emission[j] belongs to photon first + order[j], so that the waves read it front to back (read
// by photon index through the order, it was a cache miss per photon: 1 MB per batch, in Z order).
struct BatchOrder {
    std::vector<std::uint32_t> order;
    SortScratch scratch;
    std::vector<glm::dvec2> emission, by_index;
};

// Per thread: the wave's buffers, kept from chunk to chunk.
struct WaveScratch {
    std::vector<PhotonState> photons;
    std::vector<glm::dvec3> origins, dirs;   // the wave's photons as they leave their lights
    std::vector<std::uint32_t> active, next;
    std::vector<RayQuery> queries;
    std::vector<Hit> hits;
    std::vector<ShadowQuery> shadows;
    std::vector<RayQuery> shadow_rays;
    std::vector<std::uint8_t> occluded;
    std::vector<LedgerEvent> events, sorted;
    std::vector<std::uint32_t> event_start;
    std::vector<SamplerSeeds> seeds;
    QueryModeChooser modes;   // this thread's timings of its batches, kept over all its chunks
};

// Everything one photon needs, shared read-only by all threads.
struct Transport {
    const RayTracer* tracer = nullptr;
    const FrameGeometry* frame = nullptr;
    const ReceiverChart* chart = nullptr;
    const CameraGBuffer* gbuffer = nullptr;
    const CameraModel* camera = nullptr;
    // camera: per pixel, d_c^2 / cos_c of its G-buffer point and its G-buffer object (covered pixels).
    std::vector<PixelInfo, HugePageAllocator<PixelInfo>> pixel_info;
    std::vector<Emitter> emitters;
    std::vector<double> start_weight;  // q of a photon of each light as it leaves (power / largest power)
    double scale = 1.0;                // the largest light's power [W]: converts q sums to flux
    double outside_ior = 1.0;
    int receiver_object = -1;
    int max_depth = 8;
    bool fresnel = false;
    std::uint64_t seed = 1;
    SamplerKind sampler = SamplerKind::Sobol;
    std::optional<QueryMode> query_mode;   // ReferenceSettings::query_mode
    // Media (reference_volume.cpp): media[object + 1] is medium_at(scene, object), [0] the outside.
    std::vector<MediumCoefficients> media;
    // camera_volume: measured when `volume` (the scene scatters and the camera view is asked).
    bool volume = false;
    int camera_medium = -1;             // CameraGBuffer::medium_object
    std::vector<double, HugePageAllocator<double>> volume_scale;   // per pixel: s_k [m^2] (reference_volume.cpp)

    // Photon i of a replica belongs to light i mod L and is that light's sample i / L: its sampler is
    // PhotonSampler(seeds[i mod L], i / L), the seeds hashed once per light and replica.
    void seeds_of(std::uint32_t replica, std::vector<SamplerSeeds>& seeds) const;
    // The batch's photon order (photon_source.hpp) and, in that order, each photon's sample values of
    // dimensions 0 and 1, which the order is made from and its emission reads.
    void batch_order(std::uint32_t replica, std::uint64_t first, std::uint64_t last, BatchOrder& batch) const;
    // The light photon i belongs to (i mod L).
    std::size_t light_of(std::uint64_t i) const {
        return emitters.size() == 1 ? 0 : static_cast<std::size_t>(i % emitters.size());
    }
    // Photon i of a replica as it leaves its light from `origin` along `dir` (Emitter::sample of its
    // dimensions 0 and 1; seeds: seeds_of its replica), written into every field of p in place (a
    // returned copy was read back across its field-by-field stores, a store-forwarding stall per photon).
    // The caller books its emitted weight w.
    void start(const SamplerSeeds* seeds, std::uint64_t i, const glm::dvec3& origin, const glm::dvec3& dir,
               std::uint32_t slot, PhotonState& p) const;
    // Everything one segment does after its closest-hit query `hit`: extinction, the camera_volume
    // point, the deposit, or the next direction. Media's ledger additions go to `ledger`, visibility
    // queries to `shadows` (the caller resolves both). False when the photon's path has ended: then
    // p.end says where the ledger books p.w.
    bool step(PhotonState& p, const Hit& hit, std::vector<LedgerEvent>& ledger, Accumulators& acc,
              std::vector<ShadowQuery>& shadows) const;
    // One photon, one query at a time, each logged (record_reference_rays); seeds and emission as for start().
    void trace(const SamplerSeeds* seeds, std::uint64_t i, const glm::dvec2& emission, FluxLedger& ledger,
               Accumulators& acc, RayRecorder& log) const;
    // Photons first + order[0 .. n) of one replica, in that order as far as the ledger's bits go, traced
    // as waves: all live photons' next segments as one batch of packet queries, then their visibility
    // queries as another (reference_wavefront.cpp). Adds to `ledger` and `acc`.
    // emission[k]: the dimensions 0 and 1 of photon first + order[k] (batch_order).
    void trace_wave(std::uint32_t replica, std::uint64_t first, const std::uint32_t* order, const glm::dvec2* emission,
                    std::size_t n, FluxLedger& ledger, Accumulators& acc, WaveScratch& scratch) const;
    // The pixel a deposit at p would land in, or -1 (outside the image or behind the camera).
    std::ptrdiff_t camera_pixel(const glm::dvec3& p) const;
    void deposit_camera(const Hit& hit, std::size_t index, const glm::dvec3& dir_in, double w, Accumulators& acc,
                        std::vector<ShadowQuery>& shadows) const;
    // camera_volume: one scattering point on the segment origin + t dir, t in [0, length) (length may
    // be infinite), of a photon of weight w at the segment's start; `u` is its sample value.
    void scatter_to_camera(const glm::dvec3& origin, const glm::dvec3& dir, double length, double w, double u,
                           const MediumCoefficients& medium, Accumulators& acc, std::vector<ShadowQuery>& shadows) const;
};

// Adds a resolved visibility query's increment (when not occluded).
inline void apply_shadow(const ShadowQuery& q) {
    if (q.saturating) add_saturating(*q.target, q.increment);
    else add_sum(*q.target, q.increment);
}

// The result that `sums` hold: estimates, standard errors, replica images and ledger
// (reference_estimate.cpp). `camera` null: no camera view.
ReferenceResult finish_reference(const Transport& transport, const ReceiverChart& chart, const CameraGBuffer* camera,
                                 const CameraModel* camera_model, std::shared_ptr<const ReferenceSums> sums);

// The media and, when `volume`, the camera_volume set-up of `transport` (reference_volume.cpp).
void setup_media(Transport& transport, const Scene& scene, bool volume);


}  // namespace caustics::detail
