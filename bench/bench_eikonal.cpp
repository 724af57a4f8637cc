// Mercier 2013, Table 1: computing the 3-D caustic texture of the pool scene at 64^3 / 128^3 / 256^3
// (marching 0.3 / 2.5 / 26 s) and the frame rate once it is computed (49 / 12 / 2 fps). Here:
// eikonal_fmm (solver=fmm and solver=sweep) through the plugin interface, update() (the texture) and
// render() (receiver map 256 x 256 + camera view lookups) timed separately. The pool's floor is moved
// to z = -2 so the 2 m x 2 m water volume is a cube of grid^3 cells. Counters: texture_MB (the
// texture's bytes), maxrss_MB (process peak; run one 256 case per process for per-method peaks, e.g.
// --benchmark_filter='update/eikonal_fmm_fmm/256').
#include <benchmark/benchmark.h>

#include <sys/resource.h>

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

std::unique_ptr<Method> make(const std::string& method, const std::map<std::string, std::string>& params) {
    return bench::make_method(method, params);
}

// update(): the first texture a method object builds (its grids are allocated and first touched inside
// the timing). update_steady: a later one, as in an animation, where the grids are reused.
void update_impl(benchmark::State& state, const std::string& method, std::map<std::string, std::string> params,
                 bool steady) {
    PoolCube& p = pool();
    params["grid"] = std::to_string(state.range(0));
    auto m = make(method, params);
    if (steady) m->update(*p.frame);
    for (auto _ : state) m->update(*p.frame);
    RenderRequest request{p.chart.get(), p.gbuffer.get()};
    CausticOutput out = m->render(*p.frame, request);
    const double n = static_cast<double>(state.range(0));
    state.counters["texture_MB"] = n * n * (n + 2) * sizeof(float) / 1e6;
    state.counters["maxrss_MB"] = maxrss_mb();
    state.counters["not_converged"] = static_cast<double>(out.health.get("not_converged"));
    state.counters["nonfinite"] = static_cast<double>(out.health.get("nonfinite"));
    if (out.health.get("steps")) state.counters["steps"] = static_cast<double>(out.health.get("steps"));
}

void update(benchmark::State& state, const std::string& method, std::map<std::string, std::string> params) {
    update_impl(state, method, std::move(params), false);
}

void update_steady(benchmark::State& state, const std::string& method, std::map<std::string, std::string> params) {
    update_impl(state, method, std::move(params), true);
}

void lookup(benchmark::State& state, const std::string& method, std::map<std::string, std::string> params) {
    bench::lookup_benchmark(state, method, std::move(params));
}

}  // namespace

BENCHMARK_CAPTURE(update, eikonal_fmm_fmm, "eikonal_fmm", {{"solver", "fmm"}})
    ->Arg(64)->Arg(128)->Arg(256)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(update, eikonal_fmm_fmm_order1, "eikonal_fmm", {{"solver", "fmm"}, {"order", "1"}})
    ->Arg(64)->Arg(128)->Arg(256)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(update, eikonal_fmm_sweep, "eikonal_fmm", {{"solver", "sweep"}})
    ->Arg(64)->Arg(128)->Arg(256)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(update, eikonal_fmm_sweep_order1, "eikonal_fmm", {{"solver", "sweep"}, {"order", "1"}})
    ->Arg(64)->Arg(128)->Arg(256)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(update_steady, eikonal_fmm_sweep_order1, "eikonal_fmm", {{"solver", "sweep"}, {"order", "1"}})
    ->Arg(64)->Arg(128)->Arg(256)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(lookup, eikonal_fmm, "eikonal_fmm", {})
    ->Arg(64)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
