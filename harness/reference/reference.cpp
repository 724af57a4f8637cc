// The reference light tracer (docs/design.md section 5). See reference.hpp for the contract.
//
// Determinism: photon (replica r, index i) draws its sample values only from PhotonSampler(seed, r, i);
// deposits are summed as 64-bit fixed-point integers (associative), photons are traced in a fixed order
// within each fixed batch (batch_order), and the flux ledger is summed per fixed chunk of that order,
// then over chunks and batches in order. The result is therefore bit-identical for any thread count
// and scheduling, and the bin sums of a reference extended with more photons equal those of one
// computed at once.
//
// Noise: replica r gives E_r = (scale L / n) sum_{its photons in the bin} q / A, an unbiased estimate
// of E_c from its n photons; E = mean(E_r) and se^2 = sum (E_r - E)^2 / (R (R - 1)). The points within
// one replica are dependent (quasi-Monte Carlo), the replicas are independent randomizations.
//
// No result that could not be produced (issue 12): a reference whose lights emit no flux, or whose flux
// leaves nothing in any receiver bin, would read as an exact all-zero map with noise 0 and make every
// error 0. Whether flux reaches the receiver is a property of the scene (and the photon count), fixed
// before anything runs, so such a reference is bad input: an InputError (exit 2) naming the scene file
// and `receiver.object`, with the flux ledger that says where the light went, thrown before the result
// exists, so nothing is cached or written. A reference that traced no photon at all is an internal
// failure (exit 1). reference_cache.cpp never stores or serves an empty entry either.
//
// The photon's path is in reference_transport.cpp, media and the camera_volume view in
// reference_volume.cpp, the waves that trace a chunk's photons together (packet queries) in
// reference_wavefront.cpp, the estimates from the sums in reference_estimate.cpp. Bump kReferenceVersion
// (reference_cache.cpp) whenever the transport or the estimators change.
#include <caustics/reference/reference.hpp>

#include <algorithm>
#include <cstdio>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <caustics/util/errors.hpp>
#include <caustics/util/hash.hpp>
#include <caustics/scene/limits.hpp>
#include <caustics/reference/photon_sampler.hpp>
#include <caustics/reference/photon_source.hpp>
#include <caustics/util/progress.hpp>
#include <caustics/frame/ray_offset.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/reference/reference_rays.hpp>

#include "detail/transport.hpp"

namespace caustics {
namespace {

constexpr std::uint64_t kBatchSize = 65536;
// Photons of one batch traced as one task (and summed into one partial ledger), in the batch's order.
constexpr std::size_t kChunkSize = 2048;

using detail::Accumulators;
using detail::BatchOrder;
using detail::RayRecorder;
using detail::Transport;
using detail::WaveScratch;
using detail::finish_reference;

void add_ledger(FluxLedger& sum, const FluxLedger& l) {
    sum.emitted += l.emitted;
    sum.deposited_receiver += l.deposited_receiver;
    sum.deposited_other += l.deposited_other;
    sum.direct += l.direct;
    sum.escaped += l.escaped;
    sum.absorbed += l.absorbed;
    sum.scattered += l.scattered;
    sum.truncated += l.truncated;
}

// Everything compute_reference needs before tracing; `camera` null for no camera view.
Transport make_transport(const RayTracer& tracer, const ReceiverChart& chart, const CameraGBuffer* camera,
                         const ReferenceSettings& settings, std::unique_ptr<CameraModel>& camera_model) {
    const FrameGeometry& frame = tracer.frame();
    const Scene& scene = *frame.scene;
    const bool camera_view = camera != nullptr;
    Transport transport;
    transport.tracer = &tracer;
    transport.frame = &frame;
    transport.chart = &chart;
    transport.receiver_object = scene.receiver.object_index;
    transport.max_depth = scene.max_specular_depth;
    transport.fresnel = scene.fresnel;
    transport.seed = settings.seed;
    transport.sampler = settings.sampler;
    transport.query_mode = settings.query_mode;
    transport.outside_ior = scene.medium.present ? scene.medium.ior : 1.0;
    transport.scale = 0.0;
    for (const Light& light : scene.lights) {
        transport.emitters.push_back(make_emitter(light, frame));
        transport.scale = std::max(transport.scale, transport.emitters.back().power);
    }
    if (!(transport.scale > 0.0)) transport.scale = 1.0;
    for (const Emitter& e : transport.emitters) transport.start_weight.push_back(e.power / transport.scale);

    if (camera_view) {
        camera_model = std::make_unique<CameraModel>(scene.camera);
        if (camera_model->width != camera->width || camera_model->height != camera->height)
            throw std::runtime_error("reference: camera G-buffer size differs from the scene camera");
        transport.camera = camera_model.get();
        transport.gbuffer = camera;
        // Pixels in parallel (each its own computation): a 1024 x 768 view's table is built per run.
        transport.pixel_info.resize(camera->covered.size());
        const glm::dvec3 eye = camera_model->position;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, camera->covered.size(), 16384),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t i = range.begin(); i < range.end(); ++i) {
                                  if (!camera->covered[i]) {
                                      transport.pixel_info[i] = {0.0, -1};
                                      continue;
                                  }
                                  const glm::dvec3 to_cam = eye - glm::dvec3(camera->position[i]);
                                  const double d2 = glm::dot(to_cam, to_cam);
                                  const double cos_c =
                                      d2 > 0.0 ? glm::dot(glm::dvec3(camera->normal[i]), to_cam) / std::sqrt(d2) : 1.0;
                                  transport.pixel_info[i] = {std::max(d2, 1e-12) / std::clamp(cos_c, 0.05, 1.0),
                                                             camera->object[i]};
                              }
                          });
    }
    detail::setup_media(transport, scene, camera_view && scene_scatters(scene));
    return transport;
}

// Batch buffers handed from one batch to the next.
class BatchPool {
public:
    std::unique_ptr<BatchOrder> take() {
        std::lock_guard<std::mutex> lock(mutex_);
        if (free_.empty()) return std::make_unique<BatchOrder>();
        std::unique_ptr<BatchOrder> b = std::move(free_.back());
        free_.pop_back();
        return b;
    }
    void give_back(std::unique_ptr<BatchOrder> b) {
        std::lock_guard<std::mutex> lock(mutex_);
        free_.push_back(std::move(b));
    }

private:
    std::mutex mutex_;
    std::vector<std::unique_ptr<BatchOrder>> free_;
};

// Traces indices [from, to) of every replica into `sums` (batches of one replica each, fixed order).
void trace_photons(const Transport& transport, ReferenceSums& sums, std::uint64_t from, std::uint64_t to,
                   ProgressBar& progress) {
    const std::size_t bins = sums.bins, pixels = sums.pixels, volume_pixels = sums.volume_pixels;
    const std::uint32_t replicas = sums.replicas;
    tbb::enumerable_thread_specific<WaveScratch> waves;
    BatchPool pool;
    const std::uint64_t per_replica_batches = (to - from + kBatchSize - 1) / kBatchSize;
    const std::uint64_t batches = per_replica_batches * replicas;
    std::vector<FluxLedger> batch_ledgers(batches);
    tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, batches, 1), [&](const tbb::blocked_range<std::uint64_t>& range) {
        for (std::uint64_t b = range.begin(); b < range.end(); ++b) {
            const std::uint32_t replica = static_cast<std::uint32_t>(b / per_replica_batches);
            const std::uint64_t first = from + (b % per_replica_batches) * kBatchSize;
            const std::uint64_t last = std::min(to, first + kBatchSize);
            // Per batch, not per thread (a thread waiting on the chunks below may start another batch),
            // from a pool: 3 MB of fresh memory per batch would fault in every time.
            std::unique_ptr<BatchOrder> buffers = pool.take();
            transport.batch_order(replica, first, last, *buffers);
            const std::vector<std::uint32_t>& order = buffers->order;
            const std::size_t chunks = (order.size() + kChunkSize - 1) / kChunkSize;
            std::vector<FluxLedger> chunk_ledgers(chunks);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& cr) {
                Accumulators acc;
                acc.bins = sums.bin_sums.data() + replica * bins;
                acc.pixels = pixels ? sums.pixel_sums.data() + replica * pixels : nullptr;
                acc.volume = volume_pixels ? sums.volume_sums.data() + replica * volume_pixels : nullptr;
                WaveScratch& wave = waves.local();
                for (std::size_t c = cr.begin(); c < cr.end(); ++c) {
                    FluxLedger ledger;
                    const std::size_t begin = c * kChunkSize, end = std::min(order.size(), begin + kChunkSize);
                    transport.trace_wave(replica, first, order.data() + begin, buffers->emission.data() + begin,
                                         end - begin, ledger, acc, wave);
                    chunk_ledgers[c] = ledger;
                }
            });
            FluxLedger ledger;
            for (const FluxLedger& l : chunk_ledgers) add_ledger(ledger, l);
            batch_ledgers[b] = ledger;
            pool.give_back(std::move(buffers));
            progress.advance(last - first);
        }
    });
    for (const FluxLedger& l : batch_ledgers) add_ledger(sums.ledger_units, l);
    sums.per_replica = to;
}

// Throws unless the reference measured something (see the file comment).
void require_measurable(const Scene& scene, const ReferenceSums& sums, const ReferenceResult& result) {
    if (sums.per_replica == 0 || result.photons == 0)
        throw std::runtime_error("reference: no photon was traced (" + std::to_string(result.photons) + " photons)");
    const std::string receiver = scene.receiver.object;
    const FluxLedger& l = result.ledger;
    auto watts = [](double w) { return format_limit(w) + " W"; };
    if (!(l.emitted > 0.0) || !std::isfinite(l.emitted))
        throw InputError(scene.path, "lights",
                         "the lights emitted no flux toward the scene's objects (" + watts(l.emitted) + " from " +
                             std::to_string(result.photons) +
                             " photons); a reference would be all zeros; valid: lights that reach the objects");
    if (std::any_of(sums.bin_sums.begin(), sums.bin_sums.end(), [](std::int64_t v) { return v != 0; })) return;
    throw InputError(scene.path, "receiver.object",
                     "no caustic flux reached a bin of the receiver '" + receiver + "' from " +
                         std::to_string(result.photons) + " photons (of " + watts(l.emitted) + " emitted: on the receiver " +
                         watts(l.deposited_receiver) + ", on other objects " + watts(l.deposited_other) +
                         ", direct without a specular event " + watts(l.direct) + ", escaped " + watts(l.escaped) +
                         ", absorbed " + watts(l.absorbed) + ", scattered out by a medium " + watts(l.scattered) +
                         ", past max_specular_depth " + watts(l.truncated) +
                         "); its reference would be all zeros with noise 0 and every error 0; valid: a scene whose "
                         "light reaches the receiver through a specular object (check the light's direction and "
                         "position, the objects' positions, absorption and scattering), or more --photons");
}

// What the result says about how it was asked for and made.
void label_result(ReferenceResult& result, const Scene& scene, int frame, const ReferenceSettings& settings,
                  bool camera_view) {
    result.noise_target = settings.noise_target;
    result.noise_target_met = !(settings.noise_target > 0.0) || result.noise_nrmse <= settings.noise_target;
    result.seed = settings.seed;
    result.sampler = settings.sampler;
    ReferenceSettings keyed = settings;
    keyed.camera_view = camera_view;
    result.cache_key = reference_cache_key(scene, frame, keyed) + "-" + std::to_string(result.photons);
}

}  // namespace

std::uint64_t photons_per_replica(std::uint64_t photons, int replicas, std::size_t lights) {
    const std::uint64_t r = static_cast<std::uint64_t>(std::max(1, replicas));
    const std::uint64_t l = std::max<std::uint64_t>(1, lights);
    // Rounded up without overflow (photons + r - 1 wraps for counts near 2^64, which traced nothing).
    const std::uint64_t per = photons / r + (photons % r != 0 ? 1 : 0);
    const std::uint64_t rest = per % l;
    if (rest == 0) return per;
    return per <= std::numeric_limits<std::uint64_t>::max() - (l - rest) ? per + (l - rest) : per - rest;
}

ReferenceResult compute_reference(const RayTracer& tracer, const ReceiverChart& chart,
                                  const CameraGBuffer* camera, const ReferenceSettings& settings,
                                  const ReferenceSums* start) {
    const auto clock_start = std::chrono::steady_clock::now();
    const FrameGeometry& frame = tracer.frame();
    const Scene& scene = *frame.scene;
    if (scene.lights.empty()) throw std::runtime_error("reference: the scene has no light");
    if (settings.photons == 0) throw std::runtime_error("reference: photons must be > 0");
    if (settings.replicas < 2 || settings.replicas > ReferenceSettings::kMaxReplicas)
        throw std::runtime_error("reference: replicas must be in [2, " + std::to_string(ReferenceSettings::kMaxReplicas) + "]");
    const bool camera_view = camera != nullptr && settings.camera_view;
    // The sums and the images against the memory ceiling before any of
    // them is allocated (limits.hpp; the scene loader checked the default replicas already).
    check_scene_memory(scene, settings.replicas, worker_threads());

    std::unique_ptr<CameraModel> camera_model;
    const Transport transport = make_transport(tracer, chart, camera_view ? camera : nullptr, settings, camera_model);

    auto sums = std::make_shared<ReferenceSums>();
    sums->replicas = static_cast<std::uint32_t>(settings.replicas);
    sums->lights = static_cast<std::uint32_t>(scene.lights.size());
    sums->bins = static_cast<std::size_t>(chart.width()) * chart.height();
    sums->pixels = camera_view ? camera->covered.size() : 0;
    sums->bin_sums.resize(sums->bins * sums->replicas);   // zeros (HugePageAllocator)
    sums->pixel_sums.resize(sums->pixels * sums->replicas);   // zeros (HugePageAllocator)
    sums->volume_pixels = transport.volume ? sums->pixels : 0;
    sums->volume_sums.resize(sums->volume_pixels * sums->replicas);   // zeros (HugePageAllocator)
    if (start) {
        if (start->replicas != sums->replicas || start->lights != sums->lights || start->bins != sums->bins ||
            start->pixels != sums->pixels || start->volume_pixels != sums->volume_pixels)
            throw std::runtime_error("reference: the reference to extend was made with other settings");
        *sums = *start;
    }

    const std::size_t lights = scene.lights.size();
    const std::uint64_t cap = photons_per_replica(std::max(settings.photon_cap, settings.photons), settings.replicas, lights);
    // One bin of one replica sums up to 2^30 per photon in 64 bits: at most 2^33 photons per replica.
    constexpr std::uint64_t kMaxPerReplica = std::uint64_t{1} << 33;
    const std::uint64_t most = settings.noise_target > 0.0 ? cap : photons_per_replica(settings.photons, settings.replicas, lights);
    if (most > kMaxPerReplica)
        throw invalid_value(settings.noise_target > 0.0 ? "--photon-cap" : "--photons",
                            std::to_string(most) + " photons per replica overflow the fixed-point bin sums",
                            "at most 2^33 = " + std::to_string(kMaxPerReplica) + " photons per replica (" +
                                std::to_string(settings.replicas) + " replicas: " +
                                std::to_string(kMaxPerReplica * static_cast<std::uint64_t>(settings.replicas)) +
                                " photons)");
    std::uint64_t target = photons_per_replica(settings.photons, settings.replicas, lights);
    if (settings.noise_target > 0.0) target = std::min(target, cap);
    ReferenceResult result;
    const std::uint64_t photons_before = sums->per_replica * sums->replicas;
    std::vector<std::uint64_t> round_photons;
    std::vector<double> round_noise;
    int rounds = 0;
    double previous_noise = 0.0;
    std::uint64_t previous_n = 0;
    for (;;) {
        if (target > sums->per_replica) {
            std::string label = "reference " + scene.name;
            if (settings.noise_target > 0.0 && rounds > 0) {
                // The bar's own ETA is the round's; the round is sized to reach the target.
                char text[160];
                std::snprintf(text, sizeof text, " round %d: noise %.4g -> target %.4g, %s photons", rounds + 1,
                              result.noise_nrmse, settings.noise_target,
                              format_count(static_cast<double>(target * sums->replicas)).c_str());
                label += text;
            }
            ProgressBar progress(label, (target - sums->per_replica) * sums->replicas, settings.progress);
            trace_photons(transport, *sums, sums->per_replica, target, progress);
            progress.finish();
            ++rounds;
        }
        result = finish_reference(transport, chart, camera_view ? camera : nullptr, camera_model.get(), sums);
        round_photons.push_back(result.photons);
        round_noise.push_back(result.noise_nrmse);
        if (!(settings.noise_target > 0.0) || !(result.noise_nrmse > settings.noise_target) || sums->per_replica >= cap)
            break;
        // The next round: the photons the measured decay predicts (slope from the last two rounds; until
        // there are two, 1/2 for independent sampling and 3/4 for the scrambled Sobol' points, a little
        // below the 0.71-0.82 measured on sine, pool and sphere), with 10 % to spare, at least 1.25 and at
        // most 8 times the current count (a round that just missed the target adds a little, not twice).
        double slope = settings.sampler == SamplerKind::Sobol ? 0.75 : 0.5;
        if (previous_n > 0 && previous_noise > result.noise_nrmse && result.noise_nrmse > 0.0)
            slope = std::clamp(std::log(previous_noise / result.noise_nrmse) /
                                   std::log(static_cast<double>(sums->per_replica) / previous_n), 0.5, 1.5);
        const double n = static_cast<double>(sums->per_replica);
        const double predicted = result.noise_nrmse > 0.0 ? n * std::pow(result.noise_nrmse / settings.noise_target, 1.0 / slope) * 1.1 : 8.0 * n;
        previous_n = sums->per_replica;
        previous_noise = result.noise_nrmse;
        target = std::min(cap, photons_per_replica(static_cast<std::uint64_t>(std::clamp(predicted, 1.25 * n, 8.0 * n)) * settings.replicas,
                                                   settings.replicas, lights));
    }
    require_measurable(scene, *sums, result);
    result.rounds = rounds;
    result.round_photons = std::move(round_photons);
    result.round_noise = std::move(round_noise);
    result.photons_traced = result.photons - photons_before;
    label_result(result, scene, frame.frame, settings, camera_view);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return result;
}

ReferenceResult reference_from_sums(const RayTracer& tracer, const ReceiverChart& chart, const CameraGBuffer* camera,
                                    const ReferenceSettings& settings, std::shared_ptr<const ReferenceSums> sums) {
    const bool camera_view = camera != nullptr && settings.camera_view && sums->pixels > 0;
    std::unique_ptr<CameraModel> camera_model;
    const Transport transport = make_transport(tracer, chart, camera_view ? camera : nullptr, settings, camera_model);
    ReferenceResult result = finish_reference(transport, chart, camera_view ? camera : nullptr, camera_model.get(), std::move(sums));
    result.rounds = 0;
    label_result(result, *tracer.frame().scene, tracer.frame().frame, settings, camera_view);
    return result;
}

}  // namespace caustics

namespace caustics {

std::vector<RecordedRay> record_reference_rays(const RayTracer& tracer, const ReceiverChart& chart,
                                               const CameraGBuffer* camera, const ReferenceSettings& settings) {
    const bool camera_view = camera != nullptr && settings.camera_view;
    std::unique_ptr<CameraModel> camera_model;
    const Transport transport = make_transport(tracer, chart, camera_view ? camera : nullptr, settings, camera_model);
    const std::uint32_t replicas = static_cast<std::uint32_t>(std::max(2, settings.replicas));
    const std::size_t bins = static_cast<std::size_t>(chart.width()) * chart.height();
    const std::size_t pixels = camera_view ? camera->covered.size() : 0;
    std::vector<std::int64_t> bin_sums(bins * replicas, 0), pixel_sums(pixels * replicas, 0),
        volume_sums(transport.volume ? pixels * replicas : 0, 0);
    Accumulators acc;
    RayRecorder recorder;
    recorder.offset = scene_ray_offset(tracer.frame());
    FluxLedger ledger;
    // The same batches and the same order within each batch as compute_reference.
    const std::uint64_t per = photons_per_replica(settings.photons, static_cast<int>(replicas), transport.emitters.size());
    BatchOrder batch;
    std::vector<SamplerSeeds> seeds;
    for (std::uint32_t r = 0; r < replicas; ++r) {
        transport.seeds_of(r, seeds);
        acc.bins = bin_sums.data() + r * bins;
        acc.pixels = camera_view ? pixel_sums.data() + r * pixels : nullptr;
        acc.volume = transport.volume ? volume_sums.data() + r * pixels : nullptr;
        for (std::uint64_t first = 0; first < per; first += kBatchSize) {
            const std::uint64_t last = std::min(per, first + kBatchSize);
            transport.batch_order(r, first, last, batch);
            for (std::size_t j = 0; j < batch.order.size(); ++j) {
                const std::size_t before = recorder.rays.size();
                transport.trace(seeds.data(), first + batch.order[j], batch.emission[j], ledger, acc, recorder);
                for (std::size_t k = before; k < recorder.rays.size(); ++k)
                    recorder.rays[k].segment = static_cast<std::uint8_t>(std::min<std::size_t>(k - before, 255));
            }
        }
    }
    return std::move(recorder.rays);
}

}  // namespace caustics
