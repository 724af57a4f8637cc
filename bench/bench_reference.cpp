// Reference throughput against raw Embree on the same rays (issue 18, item 2).
// BM_ReferenceVsEmbree/scene:{0 pool, 1 sphere, 2 bunny, 3 sphere_fog}/camera:{0,1}, frame 0 of each:
//   photons_per_s       compute_reference (without / with the camera view), default sampler (scrambled Sobol')
//   embree_*_s          the same photons' rays (recorded once, outside the timed loop) replayed through bare
//                       Embree on the same threads, right after each reference run, in each query mode:
//                         single   rtcIntersect1 / rtcOccluded1 in the order the reference cast them
//                         grouped  the same single-ray queries, each block's rays grouped by their place in
//                                  the photon's path (all emitted rays, then all second rays, ...)
//                         stream   rtcIntersect1M / rtcOccluded1M over those groups, COHERENT context
//                         packet8 / packet16  rtcIntersect8/16 / rtcOccluded8/16 over those groups, COHERENT
//   anchor_mode         the fastest of these modes (0 single ... 4 packet16): the anchor
//   ratio               anchor replay time / reference time for the same photons. Goal >= 0.8.
//   ratio_single        single replay time / reference time (the share of the reference's time spent in
//                       the ray queries it actually makes)
//   tracer_over_anchor  the same rays through RayTracer's batches (packing, Embree, hit completion) in its
//                       fastest QueryMode, over the anchor: what the tracer layer alone costs
//   generation_over_anchor  the same photons' generation alone (sampler, Z order, emitter), over the anchor
//   ceiling_tracer, ceiling_tracer_generation  anchor / (those stages): the ratio if everything else
//                       (transport, waves, deposits) cost nothing; below 0.8, those stages alone miss it
// Rates and ratios are medians over the timed iterations, after one untimed round of everything (the
// process's first reference maps its buffers fresh; later ones reuse them, util/huge_pages.hpp).
// BM_ReferenceQueryMode/scene/mode:{0 single, 1 packet8, 2 packet16, 3 timed choice}: compute_reference
//                       without the camera view, its query mode pinned or chosen (the default).
// BM_PhotonGeneration/scene: the generation alone, with each stage's share of its thread time.
// BM_TracerBatches/scene/mode:{0 single, 1 packet8, 2 packet16}: RayTracer's batches alone on the recorded
//                       rays; over_embree: their time over bare Embree's in the same mode, same rays.
//   ideal_over_anchor, ceiling_ideal  (pool and sphere, with and without the camera view) the idealised
//                       path of ideal_path.hpp on the same photons, over the anchor / the anchor over it:
//                       what a hand-vectorised structure-of-arrays transport without the reference's
//                       generality reaches; ideal_rays_per_photon (without the visibility rays),
//                       ideal_deposits_per_photon and ideal_shadow_rays_per_photon against the
//                       reference's rays, deposits and shadow_rays_per_photon show that it traces the same
//                       paths
// BM_IdealPath/scene:{0 pool, 1 sphere}: the idealised path alone (for profiles).
// BM_Reference/scene/camera: compute_reference alone (for profiles: perf record -g ... --benchmark_filter=BM_Reference/).
//
//   build/release/bench/bench_reference [--benchmark_filter=...]
//   CAUSTICS_BENCH_PHOTONS=N  photons per iteration (default 1e6)
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_reduce.h>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/photon_sampler.hpp>
#include <caustics/reference/photon_source.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/reference/reference_rays.hpp>
#include <caustics/scene/scene.hpp>
#include "ideal_path.hpp"

using namespace caustics;

namespace {

constexpr std::array<const char*, 4> kScenes = {"pool", "sphere", "bunny", "sphere_fog"};
constexpr std::size_t kBlock = 4096;   // rays per replay task (and per grouping block)

std::uint64_t photons_per_iteration() {
    const char* env = std::getenv("CAUSTICS_BENCH_PHOTONS");
    return env ? std::strtoull(env, nullptr, 10) : 1'000'000ull;
}

// One scene's frame 0, built once per process (outside every timed region).
struct BenchScene {
    Scene scene;
    std::unique_ptr<FrameGeometry> frame;
    std::unique_ptr<RayTracer> tracer;
    std::unique_ptr<ReceiverChart> chart;
    CameraGBuffer gbuffer;

    explicit BenchScene(const std::string& name)
        : scene(load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json")) {
        frame = std::make_unique<FrameGeometry>(build_frame_geometry(scene, 0));
        tracer = std::make_unique<RayTracer>(*frame);
        chart = std::make_unique<ReceiverChart>(*frame, scene.receiver.width, scene.receiver.height);
        gbuffer = build_camera_gbuffer(*tracer, scene.camera);
    }
    static BenchScene& get(std::size_t index) {
        static std::map<std::size_t, std::unique_ptr<BenchScene>> scenes;
        auto& s = scenes[index];
        if (!s) s = std::make_unique<BenchScene>(kScenes.at(index));
        return *s;
    }
};

ReferenceSettings settings_for(bool camera) {
    ReferenceSettings s;
    s.photons = photons_per_iteration();
    s.camera_view = camera;
    s.progress = false;
    return s;
}

RTCRay to_ray(const RecordedRay& r) {
    return {r.origin[0], r.origin[1], r.origin[2], r.tnear, r.dir[0], r.dir[1], r.dir[2], 0.0f, r.tfar, 0xFFFFFFFFu, 0u, 0u};
}

RTCRayHit to_rayhit(const RecordedRay& r) {
    RTCRayHit rh;
    rh.ray = to_ray(r);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

// Each block of kBlock rays, its shadow rays after its closest-hit rays, each kind ordered by the ray's
// place in its photon's path (stable: photons keep the batch's coherent order within a group).
std::vector<RecordedRay> grouped(const std::vector<RecordedRay>& rays) {
    std::vector<RecordedRay> out(rays);
    for (std::size_t b = 0; b < out.size(); b += kBlock)
        std::stable_sort(out.begin() + b, out.begin() + std::min(out.size(), b + kBlock),
                         [](const RecordedRay& x, const RecordedRay& y) {
                             return x.shadow != y.shadow ? y.shadow : x.segment < y.segment;
                         });
    return out;
}

enum Mode { kSingle, kGrouped, kStream, kPacket8, kPacket16, kModes };

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Packets of W rays from rays[i, i + n), n <= W, all of one kind.
template <int W, class RayHitW, class RayW>
std::size_t packet(RTCScene scene, RTCIntersectContext* context, const RecordedRay* rays, int n) {
    alignas(64) int valid[W];
    if (rays[0].shadow) {
        alignas(64) RayW p;
        for (int k = 0; k < W; ++k) {
            const RecordedRay& r = rays[k < n ? k : 0];
            valid[k] = k < n ? -1 : 0;
            p.org_x[k] = r.origin[0], p.org_y[k] = r.origin[1], p.org_z[k] = r.origin[2], p.tnear[k] = r.tnear;
            p.dir_x[k] = r.dir[0], p.dir_y[k] = r.dir[1], p.dir_z[k] = r.dir[2], p.time[k] = 0.0f, p.tfar[k] = r.tfar;
            p.mask[k] = 0xFFFFFFFFu, p.id[k] = 0u, p.flags[k] = 0u;
        }
        if constexpr (W == 8) rtcOccluded8(valid, scene, context, &p);
        else rtcOccluded16(valid, scene, context, &p);
        std::size_t count = 0;
        for (int k = 0; k < n; ++k) count += p.tfar[k] < 0.0f ? 1 : 0;
        return count;
    }
    alignas(64) RayHitW p;
    for (int k = 0; k < W; ++k) {
        const RecordedRay& r = rays[k < n ? k : 0];
        valid[k] = k < n ? -1 : 0;
        p.ray.org_x[k] = r.origin[0], p.ray.org_y[k] = r.origin[1], p.ray.org_z[k] = r.origin[2], p.ray.tnear[k] = r.tnear;
        p.ray.dir_x[k] = r.dir[0], p.ray.dir_y[k] = r.dir[1], p.ray.dir_z[k] = r.dir[2], p.ray.time[k] = 0.0f;
        p.ray.tfar[k] = r.tfar, p.ray.mask[k] = 0xFFFFFFFFu, p.ray.id[k] = 0u, p.ray.flags[k] = 0u;
        p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID, p.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    if constexpr (W == 8) rtcIntersect8(valid, scene, context, &p);
    else rtcIntersect16(valid, scene, context, &p);
    std::size_t count = 0;
    for (int k = 0; k < n; ++k) count += p.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
    return count;
}

// Replays rays (`mode`: see the file comment; modes past kSingle expect grouped() rays) on all threads;
// returns seconds. The query structs are filled inside the timed region in every mode alike.
double replay(RTCScene scene, const std::vector<RecordedRay>& rays, Mode mode) {
    const auto start = std::chrono::steady_clock::now();
    const std::size_t blocks = (rays.size() + kBlock - 1) / kBlock;
    const std::size_t hits = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, blocks, 1), std::size_t{0},
        [&](const tbb::blocked_range<std::size_t>& range, std::size_t count) {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            if (mode >= kStream) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            std::vector<RTCRayHit> hit_stream;
            std::vector<RTCRay> shadow_stream;
            for (std::size_t b = range.begin(); b < range.end(); ++b) {
                const std::size_t first = b * kBlock, last = std::min(rays.size(), first + kBlock);
                if (mode <= kGrouped) {
                    for (std::size_t i = first; i < last; ++i) {
                        const RecordedRay& r = rays[i];
                        if (r.shadow) {
                            RTCRay ray = to_ray(r);
                            rtcOccluded1(scene, &context, &ray);
                            count += ray.tfar < 0.0f ? 1 : 0;
                        } else {
                            RTCRayHit rh = to_rayhit(r);
                            rtcIntersect1(scene, &context, &rh);
                            count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
                        }
                    }
                } else if (mode == kStream) {
                    hit_stream.clear(), shadow_stream.clear();
                    for (std::size_t i = first; i < last; ++i)
                        if (rays[i].shadow) shadow_stream.push_back(to_ray(rays[i]));
                        else hit_stream.push_back(to_rayhit(rays[i]));
                    rtcIntersect1M(scene, &context, hit_stream.data(), static_cast<unsigned>(hit_stream.size()), sizeof(RTCRayHit));
                    rtcOccluded1M(scene, &context, shadow_stream.data(), static_cast<unsigned>(shadow_stream.size()), sizeof(RTCRay));
                    for (const RTCRayHit& rh : hit_stream) count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
                    for (const RTCRay& r : shadow_stream) count += r.tfar < 0.0f ? 1 : 0;
                } else {
                    const int width = mode == kPacket8 ? 8 : 16;
                    for (std::size_t i = first; i < last;) {
                        int n = 1;
                        while (n < width && i + n < last && rays[i + n].shadow == rays[i].shadow) ++n;
                        count += width == 8 ? packet<8, RTCRayHit8, RTCRay8>(scene, &context, &rays[i], n)
                                            : packet<16, RTCRayHit16, RTCRay16>(scene, &context, &rays[i], n);
                        i += static_cast<std::size_t>(n);
                    }
                }
            }
            return count;
        },
        [](std::size_t a, std::size_t b) { return a + b; });
    benchmark::DoNotOptimize(hits);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The tracer's own batches (RayTracer::intersect / occluded: packing, Embree, hit completion) on the same
// rays as the anchor's grouped replay, in `mode`, as batches of at most 512 queries of one kind like the
// reference's waves (their queries and hits stay in L2); returns seconds. What they cost beyond the
// anchor is the reference's packing and hit completion, measured apart from its transport.
double replay_tracer(const RayTracer& tracer, const std::vector<RecordedRay>& rays, QueryMode mode) {
    constexpr std::size_t kWave = 512;
    const auto start = std::chrono::steady_clock::now();
    const std::size_t blocks = (rays.size() + kBlock - 1) / kBlock;
    const std::size_t hits = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, blocks, 1), std::size_t{0},
        [&](const tbb::blocked_range<std::size_t>& range, std::size_t count) {
            std::vector<RayQuery> queries;
            std::vector<Hit> out(kWave);
            std::vector<std::uint8_t> occluded(kWave);
            queries.reserve(kWave);
            bool shadow = false;
            auto flush = [&] {
                if (shadow) {
                    tracer.occluded(queries.data(), queries.size(), occluded.data(), mode);
                    for (std::size_t k = 0; k < queries.size(); ++k) count += occluded[k];
                } else {
                    tracer.intersect(queries.data(), queries.size(), out.data(), mode);
                    for (std::size_t k = 0; k < queries.size(); ++k) count += out[k].valid ? 1 : 0;
                }
                queries.clear();
            };
            for (std::size_t b = range.begin(); b < range.end(); ++b)
                for (std::size_t i = b * kBlock; i < std::min(rays.size(), (b + 1) * kBlock); ++i) {
                    const RecordedRay& r = rays[i];
                    if (!queries.empty() && (r.shadow != shadow || queries.size() == kWave)) flush();
                    shadow = r.shadow;
                    queries.push_back({{r.origin[0], r.origin[1], r.origin[2]}, {r.dir[0], r.dir[1], r.dir[2]}, r.tnear, r.tfar});
                }
            if (!queries.empty()) flush();
            return count;
        },
        [](std::size_t a, std::size_t b) { return a + b; });
    benchmark::DoNotOptimize(hits);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The photons' generation alone, as compute_reference makes it for the same photons (each replica's
// batches of 65,536: the scrambled Sobol' emission samples, the batch's Z order, the samples gathered in
// that order, the light's origins and directions in waves of 512); returns seconds. One light only.
// stages (if given): each stage's thread seconds summed over the batches, in that order.
using GenerationStages = std::array<double, 4>;
constexpr std::array<const char*, 4> kGenerationStages = {"sampler", "order", "gather", "emitter"};

double generate_photons(const Emitter& emitter, const ReferenceSettings& settings, GenerationStages* stages = nullptr) {
    using Clock = std::chrono::steady_clock;
    constexpr std::size_t kWave = 512;
    const auto replicas = static_cast<std::uint64_t>(settings.replicas);
    const std::uint64_t per_replica = (settings.photons + replicas - 1) / replicas;
    const std::uint64_t per_replica_batches = (per_replica + ideal::kPhotonBatch - 1) / ideal::kPhotonBatch;
    std::vector<GenerationStages> batch_stages(per_replica_batches * replicas);
    const auto start = Clock::now();
    const double sum = tbb::parallel_reduce(
        tbb::blocked_range<std::uint64_t>(0, per_replica_batches * replicas, 1), 0.0,
        [&](const tbb::blocked_range<std::uint64_t>& range, double acc) {
            std::vector<glm::dvec2> by_index, emission;
            std::vector<std::uint32_t> order;
            SortScratch scratch;
            std::vector<glm::dvec3> origins(kWave), dirs(kWave);
            for (std::uint64_t b = range.begin(); b < range.end(); ++b) {
                // Clock reads only where stages are asked (four per batch of 65,536 photons).
                auto lap = [&, last = Clock::now()](int stage) mutable {
                    if (!stages) return;
                    const auto now = Clock::now();
                    batch_stages[b][stage] = std::chrono::duration<double>(now - last).count();
                    last = now;
                };
                const ideal::PhotonBatch batch(b, per_replica_batches, per_replica, settings);
                const auto [replica, first, n, seeds] = batch;
                by_index.resize(n);
                PhotonSampler::emissions(seeds, first, n, reinterpret_cast<double*>(by_index.data()));
                lap(0);
                photon_batch_order(1, first, by_index, order, scratch);
                lap(1);
                emission.resize(n);
                for (std::size_t j = 0; j < n; ++j) emission[j] = by_index[order[j]];
                lap(2);
                for (std::size_t w = 0; w < n; w += kWave) {
                    const std::size_t m = std::min(kWave, n - w);
                    emitter.sample_many(emission.data() + w, m, origins.data(), dirs.data());
                    acc += dirs[m - 1].z + origins[0].x;
                }
                lap(3);
            }
            return acc;
        },
        [](double a, double b) { return a + b; });
    benchmark::DoNotOptimize(sum);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (stages) {
        stages->fill(0.0);
        for (const GenerationStages& b : batch_stages)
            for (std::size_t k = 0; k < b.size(); ++k) (*stages)[k] += b[k];
    }
    return seconds;
}

// Each iteration runs the reference and then replays its rays in every mode, back to back, so that all
// see the same machine conditions; the reported time is the reference's.
void BM_ReferenceVsEmbree(benchmark::State& state) {
    BenchScene& bs = BenchScene::get(static_cast<std::size_t>(state.range(0)));
    const bool camera = state.range(1) != 0;
    const ReferenceSettings settings = settings_for(camera);
    const CameraGBuffer* gbuffer = camera ? &bs.gbuffer : nullptr;
    const std::vector<RecordedRay> rays = record_reference_rays(*bs.tracer, *bs.chart, gbuffer, settings);
    const std::vector<RecordedRay> by_segment = grouped(rays);
    auto* scene = static_cast<RTCScene>(bs.tracer->embree_scene());
    std::size_t shadow_rays = 0;
    for (const RecordedRay& r : rays) shadow_rays += r.shadow ? 1 : 0;

    // One untimed round first: a process's first reference maps its buffers fresh (about 100 MB with the
    // camera view, page fault by page fault), later ones reuse them (util/huge_pages.hpp), as a sweep's
    // or the viewer's do. Compare a process's first call (the README gives it) with the steady state.
    ReferenceResult last = compute_reference(*bs.tracer, *bs.chart, gbuffer, settings);
    for (int m = 0; m < kModes; ++m) replay(scene, m == kSingle ? rays : by_segment, static_cast<Mode>(m));
    // The stages measured apart (generation: single-light scenes only).
    const bool one_light = bs.scene.lights.size() == 1;
    const Emitter emitter = one_light ? make_emitter(bs.scene.lights[0], *bs.frame) : Emitter{};
    for (int m = 0; m < kQueryModes; ++m) replay_tracer(*bs.tracer, by_segment, static_cast<QueryMode>(m));
    if (one_light) generate_photons(emitter, settings);
    // The idealised path on `pool` and `sphere` (ideal_path.hpp), with the camera view where it is measured.
    ideal::IdealScene ideal_scene = ideal::scene_of(bs.scene, *bs.frame, *bs.tracer, *bs.chart);
    const CameraModel camera_model(bs.scene.camera);
    if (camera) ideal::with_camera(ideal_scene, camera_model, bs.gbuffer, *bs.frame);
    const bool with_ideal = ideal_scene.scene != nullptr;
    ideal::Result ideal_run;
    ideal::Buffers ideal_buffers;
    if (with_ideal) ideal_run = ideal::run(ideal_scene, emitter, settings, ideal_buffers);
    std::vector<double> reference_s, generation_s, ideal_s;
    std::array<std::vector<double>, kModes> replay_s;
    std::array<std::vector<double>, kQueryModes> tracer_s;
    for (auto _ : state) {
        last = ReferenceResult{};   // the previous result's memory is freed outside the timed region
        const auto start = std::chrono::steady_clock::now();
        last = compute_reference(*bs.tracer, *bs.chart, gbuffer, settings);
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        reference_s.push_back(t);
        state.SetIterationTime(t);
        state.PauseTiming();
        for (int m = 0; m < kModes; ++m)
            replay_s[m].push_back(replay(scene, m == kSingle ? rays : by_segment, static_cast<Mode>(m)));
        for (int m = 0; m < kQueryModes; ++m)
            tracer_s[m].push_back(replay_tracer(*bs.tracer, by_segment, static_cast<QueryMode>(m)));
        if (one_light) generation_s.push_back(generate_photons(emitter, settings));
        if (with_ideal) ideal_s.push_back((ideal_run = ideal::run(ideal_scene, emitter, settings, ideal_buffers)).seconds);
        state.ResumeTiming();
    }
    // Medians over the iterations (each replay ran right after its reference run).
    const double reference = median(reference_s);
    std::array<double, kModes> replay_median{};
    for (int m = 0; m < kModes; ++m) replay_median[m] = median(replay_s[m]);
    const int anchor =
        static_cast<int>(std::min_element(replay_median.begin(), replay_median.end()) - replay_median.begin());
    const char* names[kModes] = {"single", "grouped", "stream", "packet8", "packet16"};
    for (int m = 0; m < kModes; ++m)
        state.counters[std::string("embree_") + names[m] + "_rays_per_s"] = rays.size() / replay_median[m];
    state.counters["photons_per_s"] = static_cast<double>(settings.photons) / reference;
    state.counters["reference_rays_per_s"] = rays.size() / reference;
    state.counters["anchor_mode"] = anchor;
    state.counters["ratio"] = replay_median[anchor] / reference;
    state.counters["ratio_single"] = replay_median[kSingle] / reference;
    // The stages' ceilings: the ratio if everything but the tracer's batches (and the generation) cost
    // nothing. Below 0.8 means those stages alone rule the goal out.
    double tracer = replay_median[anchor] * 1e30;
    for (int m = 0; m < kQueryModes; ++m) tracer = std::min(tracer, median(tracer_s[m]));
    state.counters["tracer_over_anchor"] = tracer / replay_median[anchor];
    state.counters["ceiling_tracer"] = replay_median[anchor] / tracer;
    if (one_light) {
        const double generation = median(generation_s);
        state.counters["generation_over_anchor"] = generation / replay_median[anchor];
        state.counters["ceiling_tracer_generation"] = replay_median[anchor] / (tracer + generation);
    }
    if (with_ideal) {
        // The idealised path traces the same photons on its own: where the scene makes no Fresnel choices
        // (its LCG draws them, not the reference's Sobol' dimensions) they take the reference's paths, and
        // its rays and deposits per photon equal the reference's.
        state.counters["ideal_over_anchor"] = median(ideal_s) / replay_median[anchor];
        state.counters["ceiling_ideal"] = replay_median[anchor] / median(ideal_s);
        state.counters["ideal_rays_per_photon"] = static_cast<double>(ideal_run.rays) / settings.photons;
        state.counters["ideal_deposits_per_photon"] = static_cast<double>(ideal_run.deposited) / settings.photons;
        state.counters["ideal_shadow_rays_per_photon"] = static_cast<double>(ideal_run.shadow_rays) / settings.photons;
        state.counters["deposits_per_photon"] = static_cast<double>(last.sums->ledger_units.deposited_receiver) /
                                                std::max(1e-300, last.sums->ledger_units.emitted);
    }
    state.counters["rays_per_photon"] = static_cast<double>(rays.size()) / settings.photons;
    state.counters["shadow_rays_per_photon"] = static_cast<double>(shadow_rays) / settings.photons;
    state.counters["threads"] = tbb::info::default_concurrency();
    state.counters["noise_nrmse"] = last.noise_nrmse;
    state.SetLabel(kScenes.at(static_cast<std::size_t>(state.range(0))));
}

// The idealised path alone (ideal_path.hpp), on `pool` (0) and `sphere` (1): for profiles.
void BM_IdealPath(benchmark::State& state) {
    BenchScene& bs = BenchScene::get(static_cast<std::size_t>(state.range(0)));
    const ideal::IdealScene scene = ideal::scene_of(bs.scene, *bs.frame, *bs.tracer, *bs.chart);
    if (!scene.scene) {
        state.SkipWithError("not a scene the idealised path models, or a CPU without AVX2 and FMA");
        return;
    }
    const ReferenceSettings settings = settings_for(false);
    const Emitter emitter = make_emitter(bs.scene.lights[0], *bs.frame);
    ideal::Buffers buffers;
    ideal::run(scene, emitter, settings, buffers);   // untimed
    ideal::Result r;
    for (auto _ : state) r = ideal::run(scene, emitter, settings, buffers);
    state.counters["photons_per_s"] = benchmark::Counter(static_cast<double>(settings.photons) * state.iterations(),
                                                         benchmark::Counter::kIsRate);
    state.counters["rays_per_photon"] = static_cast<double>(r.rays) / settings.photons;
    state.SetLabel(kScenes.at(static_cast<std::size_t>(state.range(0))));
}

void BM_Reference(benchmark::State& state) {
    BenchScene& bs = BenchScene::get(static_cast<std::size_t>(state.range(0)));
    const bool camera = state.range(1) != 0;
    const ReferenceSettings settings = settings_for(camera);
    // Untimed, as in BM_ReferenceVsEmbree.
    benchmark::DoNotOptimize(compute_reference(*bs.tracer, *bs.chart, camera ? &bs.gbuffer : nullptr, settings));
    for (auto _ : state)
        benchmark::DoNotOptimize(compute_reference(*bs.tracer, *bs.chart, camera ? &bs.gbuffer : nullptr, settings));
    state.counters["photons_per_s"] = benchmark::Counter(static_cast<double>(settings.photons) * state.iterations(),
                                                         benchmark::Counter::kIsRate);
    state.SetLabel(kScenes.at(static_cast<std::size_t>(state.range(0))));
}

// The reference with its query mode pinned (mode 0 single rays, 1 8-ray packets, 2 16-ray packets) or
// chosen by timing (mode 3, the default): how the choice compares with the best fixed mode.
void BM_ReferenceQueryMode(benchmark::State& state) {
    BenchScene& bs = BenchScene::get(static_cast<std::size_t>(state.range(0)));
    ReferenceSettings settings = settings_for(false);
    if (state.range(1) < kQueryModes) settings.query_mode = static_cast<QueryMode>(state.range(1));
    benchmark::DoNotOptimize(compute_reference(*bs.tracer, *bs.chart, nullptr, settings));   // untimed
    std::vector<double> seconds;
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(compute_reference(*bs.tracer, *bs.chart, nullptr, settings));
        seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        state.SetIterationTime(seconds.back());
    }
    state.counters["photons_per_s"] = static_cast<double>(settings.photons) / median(seconds);
    state.SetLabel(kScenes.at(static_cast<std::size_t>(state.range(0))));
}

// The tracer's batches alone on the reference's recorded rays, grouped as the anchor replays them, in
// mode {0 single, 1 packet8, 2 packet16} (for profiles of RayTracer's packing and hit completion).
void BM_TracerBatches(benchmark::State& state) {
    BenchScene& bs = BenchScene::get(static_cast<std::size_t>(state.range(0)));
    const std::vector<RecordedRay> rays = grouped(record_reference_rays(*bs.tracer, *bs.chart, nullptr, settings_for(false)));
    const auto mode = static_cast<QueryMode>(state.range(1));
    // Bare Embree in the same mode on the same rays, right after each run: over_embree is the tracer's
    // time over Embree's.
    const Mode bare = mode == QueryMode::Single ? kGrouped : mode == QueryMode::Packet8 ? kPacket8 : kPacket16;
    auto* scene = static_cast<RTCScene>(bs.tracer->embree_scene());
    replay_tracer(*bs.tracer, rays, mode);   // untimed
    replay(scene, rays, bare);
    std::vector<double> tracer_s, embree_s;
    for (auto _ : state) {
        tracer_s.push_back(replay_tracer(*bs.tracer, rays, mode));
        state.SetIterationTime(tracer_s.back());
        embree_s.push_back(replay(scene, rays, bare));
    }
    state.counters["rays_per_s"] = static_cast<double>(rays.size()) / median(tracer_s);
    state.counters["over_embree"] = median(tracer_s) / median(embree_s);
    state.SetLabel(kScenes.at(static_cast<std::size_t>(state.range(0))));
}

// The photons' generation alone (single-light scenes), with each stage's share of its thread time
// (medians over the iterations; the stage timings themselves are not in the generation_s counter).
void BM_PhotonGeneration(benchmark::State& state) {
    BenchScene& bs = BenchScene::get(static_cast<std::size_t>(state.range(0)));
    if (bs.scene.lights.size() != 1) {
        state.SkipWithError("one light only");
        return;
    }
    const ReferenceSettings settings = settings_for(false);
    const Emitter emitter = make_emitter(bs.scene.lights[0], *bs.frame);
    generate_photons(emitter, settings);   // untimed
    std::vector<double> seconds;
    std::array<std::vector<double>, 4> shares;
    for (auto _ : state) {
        seconds.push_back(generate_photons(emitter, settings));
        state.SetIterationTime(seconds.back());
        state.PauseTiming();
        GenerationStages stages;
        generate_photons(emitter, settings, &stages);
        double total = 0.0;
        for (double t : stages) total += t;
        for (std::size_t k = 0; k < stages.size(); ++k) shares[k].push_back(stages[k] / total);
        state.ResumeTiming();
    }
    state.counters["generation_s"] = median(seconds);
    state.counters["ns_per_photon"] = 1e9 * median(seconds) * tbb::info::default_concurrency() / settings.photons;
    for (std::size_t k = 0; k < shares.size(); ++k)
        state.counters[std::string("share_") + kGenerationStages[k]] = median(shares[k]);
    state.SetLabel(kScenes.at(static_cast<std::size_t>(state.range(0))));
}

}  // namespace

BENCHMARK(BM_PhotonGeneration)->ArgName("scene")->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(5);
BENCHMARK(BM_TracerBatches)
    ->ArgNames({"scene", "mode"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime()
    ->Iterations(5);
BENCHMARK(BM_ReferenceQueryMode)
    ->ArgNames({"scene", "mode"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime()
    ->Iterations(5);
BENCHMARK(BM_ReferenceVsEmbree)
    ->ArgNames({"scene", "camera"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime()
    ->Iterations(5);
BENCHMARK(BM_IdealPath)->ArgName("scene")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_Reference)
    ->ArgNames({"scene", "camera"})
    ->ArgsProduct({{0, 1, 2, 3}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(5);

BENCHMARK_MAIN();
