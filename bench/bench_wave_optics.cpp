// wave_optics speed goals (issue 5): grid 1024, one depth: <= 25 ms per frame on 2 cores; grid 512 with
// 16 depth slices: <= 100 ms. Threads are limited with tbb::global_control (default 2; override with
// CAUSTICS_BENCH_THREADS). cpu_all_ms is the CPU time of all threads per frame (load-independent). Scene: a sine water surface 2 m x 2 m (resolution 1024, as scenes/sine.json)
// over a 256 x 256 receiver; the slice benchmark tilts the receiver so the slices span 0.2 .. 0.6 m.
// The timed region is one frame: update + render (resample, phase screen, FFTs, lookup).
#include <ctime>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <caustics/frame/frame.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/scene/scene.hpp>
#include <caustics/scene/water_scene.hpp>

namespace {

using namespace caustics;

int bench_threads() {
    const char* env = std::getenv("CAUSTICS_BENCH_THREADS");
    return env != nullptr ? std::max(1, std::atoi(env)) : 2;
}

Scene sine_scene(bool tilted) {
    WaterOverFloor d;
    d.name = "bench_wave_optics";
    d.water_resolution = 1024;
    d.generator = HeightGenerator::Sine;
    d.amplitude = 0.01;
    d.floor_u = {1.0, 0.0, tilted ? 0.4 : 0.0};
    d.receiver_resolution = 256;
    return make_water_scene(d);
}

void run(benchmark::State& state, const std::map<std::string, std::string>& overrides, bool tilted) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(bench_threads()));
    const Scene scene = sine_scene(tilted);
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
    const MethodInfo& info = require_method("wave_optics");
    std::unique_ptr<Method> method = info.create(ParamSet::resolve(info.name, info.params, overrides));
    method->prepare(scene);
    RenderRequest request;
    request.receiver = &chart;
    for (int i = 0; i < 2; ++i) {   // warm-up: plans, caches, page faults
        method->update(frame);
        benchmark::DoNotOptimize(method->render(frame, request));
    }
    std::map<std::string, double> stages;
    const std::clock_t cpu_start = std::clock();   // process CPU time, all threads
    for (auto _ : state) {
        method->update(frame);
        CausticOutput out = method->render(frame, request);
        for (const auto& [name, ms] : out.stages_ms) stages[name] += ms;
        benchmark::DoNotOptimize(out.receiver.pixels.data());
    }
    const double cpu_ms = 1000.0 * static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    for (const auto& [name, ms] : stages) state.counters[name + "_ms"] = ms / state.iterations();
    // CPU time of all threads per frame: on a loaded machine, cpu_all_ms / threads estimates the frame
    // time an idle machine would give.
    state.counters["cpu_all_ms"] = cpu_ms / state.iterations();
    state.counters["threads"] = bench_threads();
}

void BM_WaveOptics_Grid1024_OneDepth(benchmark::State& state) {
    run(state, {{"grid", "1024"}}, false);
}
void BM_WaveOptics_Grid512_16Slices(benchmark::State& state) {
    run(state, {{"grid", "512"}, {"depth_slices", "16"}}, true);
}

BENCHMARK(BM_WaveOptics_Grid1024_OneDepth)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_WaveOptics_Grid512_16Slices)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
