// `caustics synth` speed (issue 5: 32 frames of 512 x 512 with caustic_triangles in <= 1 s, excluding file
// writing): scenes/ocean_tile.json, one iteration = the whole 32-frame set (update + render of each frame,
// as the manifest's total_ms; the height-field evaluation and file writing are outside the timed region).
// Arguments: surface grid (vertices per side), dispersion samples (0 = the scene without dispersion:
// a monochrome set), threads. Counters: total_ms per set, ms_per_frame (wall clock), cpu_ms_per_frame
// (process CPU time over all threads, surface evaluation included: the work, whatever else runs).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <time.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <caustics/synth/synth.hpp>

using namespace caustics;

namespace {

// CPU time of the whole process (every thread) [ms]: the work done, independent of other load on the
// machine (wall-clock timings on a shared machine are not).
double process_cpu_ms() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

// ocean_tile.json, or a copy without dispersion.
std::string scene_path(bool dispersion) {
    const std::string src = std::string(CAUSTICS_SOURCE_DIR) + "/scenes/ocean_tile.json";
    if (dispersion) return src;
    std::ifstream in(src);
    std::stringstream s;
    s << in.rdbuf();
    nlohmann::json j = nlohmann::json::parse(s.str());
    j["objects"][0]["material"]["dispersion"] = 0.0;
    const auto p = std::filesystem::temp_directory_path() / ("bench_synth_mono_" + std::to_string(::getpid()) + ".json");
    std::ofstream(p) << j.dump();
    return p.string();
}

void BM_SynthSet(benchmark::State& state, const std::string& method) {
    const int grid = static_cast<int>(state.range(0));
    const int samples = static_cast<int>(state.range(1));
    const int threads = static_cast<int>(state.range(2));
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    SynthOptions o;
    o.scene_path = scene_path(samples > 0);
    o.method = method;
    o.frames = 32;
    o.size = 512;
    o.overrides["grid"] = std::to_string(grid);
    if (samples > 0 && method == "caustic_triangles") o.overrides["dispersion_samples"] = std::to_string(samples);
    if (samples > 0 && method == "wave_optics") o.overrides["wavelengths"] = std::to_string(samples);
    const SynthPlan plan = plan_synth(o);
    Synthesizer synth(plan);
    (void)synth.frame(0);   // warm-up
    double total = 0.0, sets = 0.0, cpu = 0.0;
    for (auto _ : state) {
        const double cpu0 = process_cpu_ms();
        double set_ms = 0.0;
        for (int i = 0; i < plan.frames; ++i) {
            const SynthFrame f = synth.frame(i);
            set_ms += f.update_ms + f.render_ms;
            benchmark::DoNotOptimize(f.texture.pixels.data());
        }
        cpu += process_cpu_ms() - cpu0;   // includes the surface evaluation (small)
        state.SetIterationTime(set_ms / 1000.0);   // manual time: update + render only
        total += set_ms;
        sets += 1.0;
    }
    state.counters["total_ms"] = total / sets;
    state.counters["ms_per_frame"] = total / sets / plan.frames;
    state.counters["cpu_ms_per_frame"] = cpu / sets / plan.frames;
    state.counters["threads"] = threads;
}

void CausticTriangles(benchmark::State& state) { BM_SynthSet(state, "caustic_triangles"); }
void WaveOptics(benchmark::State& state) { BM_SynthSet(state, "wave_optics"); }

}  // namespace

// grid 256 (default) and 512 vertices per side; monochrome and 8-sample dispersion; 2 threads.
BENCHMARK(CausticTriangles)
    ->ArgsProduct({{256, 512}, {0, 8}, {2}})
    ->ArgNames({"grid", "dispersion", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK(WaveOptics)
    ->ArgsProduct({{512}, {0}, {2}})
    ->ArgNames({"grid", "wavelengths", "threads"})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

BENCHMARK_MAIN();
