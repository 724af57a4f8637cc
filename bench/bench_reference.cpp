// Reference throughput on scenes/pool.json frame 0 (issue 2, "Benchmarks"). BM_ReferenceVsEmbree/camera:{0,1}:
//   photons_per_s       compute_reference (without / with the camera view)
//   embree_rays_per_s   the same photons' rays (recorded once, outside the timed loop) replayed through
//                       bare rtcIntersect1 / rtcOccluded1 on the same threads, right after each run
//   ratio               replay time / reference time for the same photons: the share of the
//                       reference's time spent in ray queries. Goal >= 0.8 (bookkeeping <= 25 %).
//
//   build/release/bench/bench_reference [--benchmark_filter=...]
//   CAUSTICS_BENCH_PHOTONS=N  photons per iteration (default 1e6)
#include <atomic>
#include <chrono>
#include <cstdio>
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
#include <caustics/reference/reference.hpp>
#include <caustics/reference/reference_rays.hpp>
#include <caustics/scene/scene.hpp>

using namespace caustics;

namespace {

std::uint64_t photons_per_iteration() {
    const char* env = std::getenv("CAUSTICS_BENCH_PHOTONS");
    return env ? std::strtoull(env, nullptr, 10) : 1'000'000ull;
}

// pool.json frame 0, built once per process (outside every timed region).
struct PoolScene {
    Scene scene;
    std::unique_ptr<FrameGeometry> frame;
    std::unique_ptr<RayTracer> tracer;
    std::unique_ptr<ReceiverChart> chart;
    CameraGBuffer gbuffer;

    PoolScene() : scene(load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/pool.json")) {
        frame = std::make_unique<FrameGeometry>(build_frame_geometry(scene, 0));
        tracer = std::make_unique<RayTracer>(*frame);
        chart = std::make_unique<ReceiverChart>(*frame, scene.receiver.width, scene.receiver.height);
        gbuffer = build_camera_gbuffer(*tracer, scene.camera);
    }
    static PoolScene& get() {
        static PoolScene pool;
        return pool;
    }
};

ReferenceSettings settings_for(bool camera) {
    ReferenceSettings s;
    s.photons = photons_per_iteration();
    s.camera_view = camera;
    s.progress = false;
    return s;
}

// Replays recorded rays through bare rtcIntersect1 / rtcOccluded1 on all threads; returns seconds.
double replay(RTCScene scene, const std::vector<RecordedRay>& rays) {
    const auto start = std::chrono::steady_clock::now();
    const std::size_t hits = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, rays.size(), 4096), std::size_t{0},
        [&](const tbb::blocked_range<std::size_t>& range, std::size_t count) {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                const RecordedRay& r = rays[i];
                if (r.shadow) {
                    RTCRay ray{r.origin[0], r.origin[1], r.origin[2], r.tnear, r.dir[0], r.dir[1], r.dir[2],
                               0.0f, r.tfar, 0xFFFFFFFFu, 0u, 0u};
                    rtcOccluded1(scene, &context, &ray);
                    count += ray.tfar < 0.0f ? 1 : 0;
                } else {
                    RTCRayHit rh;
                    rh.ray = {r.origin[0], r.origin[1], r.origin[2], r.tnear, r.dir[0], r.dir[1], r.dir[2],
                              0.0f, r.tfar, 0xFFFFFFFFu, 0u, 0u};
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &context, &rh);
                    count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
                }
            }
            return count;
        },
        [](std::size_t a, std::size_t b) { return a + b; });
    benchmark::DoNotOptimize(hits);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Each iteration runs the reference and then replays its rays, back to back, so that both see the same
// machine conditions; the reported time is the reference's.
void BM_ReferenceVsEmbree(benchmark::State& state) {
    const bool camera = state.range(0) != 0;
    PoolScene& pool = PoolScene::get();
    const ReferenceSettings settings = settings_for(camera);
    const CameraGBuffer* gbuffer = camera ? &pool.gbuffer : nullptr;
    const std::vector<RecordedRay> rays = record_reference_rays(*pool.tracer, *pool.chart, gbuffer, settings);
    auto* scene = static_cast<RTCScene>(pool.tracer->embree_scene());
    std::size_t shadow_rays = 0;
    for (const RecordedRay& r : rays) shadow_rays += r.shadow ? 1 : 0;

    double reference_s = 0.0, replay_s = 0.0;
    ReferenceResult last;
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        last = compute_reference(*pool.tracer, *pool.chart, gbuffer, settings);
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        reference_s += t;
        state.SetIterationTime(t);
        state.PauseTiming();
        replay_s += replay(scene, rays);
        state.ResumeTiming();
    }
    const double n = static_cast<double>(state.iterations());
    const double photons = static_cast<double>(settings.photons) * n;
    state.counters["photons_per_s"] = photons / reference_s;
    state.counters["embree_rays_per_s"] = rays.size() * n / replay_s;
    state.counters["reference_rays_per_s"] = rays.size() * n / reference_s;
    state.counters["ratio"] = replay_s / reference_s;   // share of the reference's time in ray queries
    state.counters["rays_per_photon"] = static_cast<double>(rays.size()) / settings.photons;
    state.counters["shadow_rays_per_photon"] = static_cast<double>(shadow_rays) / settings.photons;
    state.counters["s_per_1e8_photons"] = 1e8 * reference_s / photons;
    state.counters["threads"] = tbb::info::default_concurrency();
    state.counters["noise_nrmse"] = last.noise_nrmse;
}

}  // namespace

BENCHMARK(BM_ReferenceVsEmbree)->ArgName("camera")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(5);

BENCHMARK_MAIN();
