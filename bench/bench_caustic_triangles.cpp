// caustic_triangles speed (the real-time baseline): pool.json frame 0, receiver map 1024 x 1024, grid
// 128 / 256 / 512, render() after update(), on 2 threads (goal: >= 200 fps at grid 256) and on 1. A second family
// adds the camera view (deferred receiver-map lookup per G-buffer pixel).
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include <tbb/global_control.h>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/api/registry.hpp>

using namespace caustics;

namespace {

struct PoolFixture {
    Scene scene = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/pool.json");
    FrameGeometry frame = build_frame_geometry(scene, 0);
    ReceiverChart chart{frame, 1024, 1024};
    std::unique_ptr<RayTracer> tracer;
    CameraGBuffer gbuffer;
    static PoolFixture& get() {
        static PoolFixture f;
        return f;
    }
    const CameraGBuffer& camera() {
        if (!tracer) {
            tracer = std::make_unique<RayTracer>(frame);
            gbuffer = build_camera_gbuffer(*tracer, scene.camera);
        }
        return gbuffer;
    }
};

void run(benchmark::State& state, bool with_camera) {
    const int threads = static_cast<int>(state.range(1));
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    PoolFixture& f = PoolFixture::get();
    const MethodInfo& info = require_method("caustic_triangles");
    const char* coverage = state.range(2) ? "center" : "area";
    auto method = info.create(ParamSet::resolve(info.name, info.params,
                                                {{"grid", std::to_string(state.range(0))}, {"coverage", coverage}}));
    method->prepare(f.scene);
    method->update(f.frame);
    RenderRequest request;
    request.receiver = &f.chart;
    if (with_camera) request.camera = &f.camera();
    for (int warm = 0; warm < 3; ++warm) benchmark::DoNotOptimize(method->render(f.frame, request));
    double refract = 0.0, raster = 0.0, camera = 0.0;
    for (auto _ : state) {
        CausticOutput out = method->render(f.frame, request);
        for (const auto& [name, ms] : out.stages_ms) {
            if (name == "refract") refract += ms;
            if (name == "raster") raster += ms;
            if (name == "camera") camera += ms;
        }
        benchmark::DoNotOptimize(out.receiver.pixels.data());
    }
    const double n = static_cast<double>(state.iterations());
    state.counters["fps"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
    state.counters["refract_ms"] = refract / n;
    state.counters["raster_ms"] = raster / n;
    if (with_camera) state.counters["camera_ms"] = camera / n;
    state.counters["threads"] = threads;
}

void BM_CausticTrianglesPool(benchmark::State& state) { run(state, false); }
void BM_CausticTrianglesPoolCamera(benchmark::State& state) { run(state, true); }

}  // namespace

// Args: grid, threads, coverage (0 area, 1 centre). The 1-thread run gives the per-frame CPU cost where
// other work shares the cores.
BENCHMARK(BM_CausticTrianglesPool)
    ->Args({128, 2, 0})->Args({256, 2, 0})->Args({512, 2, 0})->Args({256, 1, 0})->Args({256, 2, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CausticTrianglesPoolCamera)->Args({256, 2, 0})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
