// Mercier 2013, Table 1, wave column: computing the 3-D caustic texture of the pool scene with the wave
// method takes 17 / 21 / 107 s at 64^3 / 128^3 / 256^3, and the frame rate once it is computed is
// 49 / 12 / 2 fps. Here wave_pde through the plugin interface at its default settings: update() (the
// texture) and render() (receiver map + camera view lookups) timed separately. The pool's floor is moved
// to z = -2 so the 2 m x 2 m water volume is a cube of grid^3 cells (plus the damping band). Counters:
// steps (time steps taken), band_Mcells (cells updated per step: the narrow band), texture_MB (the texture's bytes), maxrss_MB (process peak; run one 256 case
// per process for its own peak, e.g. --benchmark_filter='Update/wave_pde/256').
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <algorithm>
#include <map>
#include <memory>
#include <string>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/api/registry.hpp>
#include "pool_cube.hpp"
#include <caustics/scene/scene.hpp>

using namespace caustics;

namespace {

using bench::PoolCube;
using bench::maxrss_mb;
PoolCube& pool() { return bench::pool_cube(); }

std::unique_ptr<Method> make(const std::map<std::string, std::string>& params) {
    return bench::make_method("wave_pde", params);
}

void Update(benchmark::State& state, std::map<std::string, std::string> params) {
    PoolCube& p = pool();
    params["grid"] = std::to_string(state.range(0));
    auto m = make(params);
    for (auto _ : state) m->update(*p.frame);
    RenderRequest request{p.chart.get(), p.gbuffer.get()};
    const CausticOutput out = m->render(*p.frame, request);
    const double n = static_cast<double>(state.range(0));
    state.counters["texture_MB"] = n * n * (n + 2) * sizeof(float) / 1e6;
    state.counters["maxrss_MB"] = maxrss_mb();
    state.counters["steps"] = static_cast<double>(out.health.get("steps"));
    // Cells updated per step (the narrow band), in millions.
    state.counters["band_Mcells"] = static_cast<double>(out.health.get("cells_updated")) / 1e6 /
                                    std::max<double>(1.0, static_cast<double>(out.health.get("steps")));
    state.counters["not_converged"] = static_cast<double>(out.health.get("not_converged"));
    state.counters["nonfinite"] = static_cast<double>(out.health.get("nonfinite"));
}

void Lookup(benchmark::State& state, std::map<std::string, std::string> params) {
    bench::lookup_benchmark(state, "wave_pde", std::move(params));
}

}  // namespace

// One update per repetition: the 256^3 case is seconds long.
BENCHMARK_CAPTURE(Update, wave_pde, {})->Arg(64)->Arg(128)->Arg(256)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(Lookup, wave_pde, {})->Arg(64)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
