// adaptive_beams speed (Liktor and Dachsbacher 2011, Table 1: 22 to 26 fps at 1024 x 768 with 1,600 to
// 5,300 beams on a GTX 470; goal here: 22 fps on sphere_fog on 2 cores): render() after update() at the
// scenes' 1024 x 768 camera (pool_murky's 640 x 480 scaled to it), all three views, with the stages
// (beam generation, camera beams = volume accumulation with the camera's surface caustics, receiver
// surface caustics) as counters. Families: the scene (0 sphere_fog, 1 pool_murky, 2.1 x past its focus: its
// surfaces' beams get a finest grid of 512 at the defaults, fold_iterations), adaptive (the defaults: 32, 2 levels)
// against the uniform 64 x 64 grid (beams and fill), and the tight hull against the prism (fill and time);
// the second argument is the thread count (1 or 2); BM_VolumeView sweeps the volume view's levers
// (volume_step, volume_subpixels: 1, 1 is the paper's one ray per pixel centre, 2, 2 the defaults);
// BM_OracleAndSurface compares the split oracle and camera surface settings with the former defaults;
// BM_VolumeLanes the volume view's integrals in AVX2 lanes (1) against one ray at a time (0); BM_VolumeCull
// culling faint volume beams (volume_cull); BM_VolumePareto points of the volume view's time-vs-error front;
// BM_HeapPolicy times the defaults under glibc's default heap limits (0: a fresh process's, before the
// adaptation util/heap_policy.hpp describes) and under the program's policy (1); BM_IntegralFloor the
// arithmetic of one ray-beam integral on this CPU at its throughput (the volume view's idealised bound).
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif

#include <caustics/api/registry.hpp>
#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/util/heap_policy.hpp>

using namespace caustics;

namespace {

struct Fixture {
    Scene scene;
    FrameGeometry frame;
    ReceiverChart chart;
    std::unique_ptr<RayTracer> tracer;
    CameraGBuffer gbuffer;
    explicit Fixture(const std::string& name)
        : scene(load(name)), frame(build_frame_geometry(scene, 0)), chart(frame, 256, 256) {
        tracer = std::make_unique<RayTracer>(frame);
        gbuffer = build_camera_gbuffer(*tracer, scene.camera);
    }
    static Scene load(const std::string& name) {
        Scene s = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json");
        s.camera.width = 1024;
        s.camera.height = 768;
        return s;
    }
    static Fixture& get(int which) {
        static Fixture fog("sphere_fog"), pool("pool_murky");
        return which == 0 ? fog : pool;
    }
};

void run(benchmark::State& state, const std::map<std::string, std::string>& params) {
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                    static_cast<std::size_t>(state.range(1)));
    Fixture& f = Fixture::get(static_cast<int>(state.range(0)));
    const MethodInfo& info = require_method("adaptive_beams");
    auto method = info.create(ParamSet::resolve(info.name, info.params, params));
    method->prepare(f.scene);
    method->update(f.frame);
    RenderRequest request;
    request.receiver = &f.chart;
    request.camera = &f.gbuffer;
    request.camera_volume = true;
    benchmark::DoNotOptimize(method->render(f.frame, request));
    std::map<std::string, double> stages;
    CausticOutput last;
    for (auto _ : state) {
        last = method->render(f.frame, request);
        for (const auto& [name, ms] : last.stages_ms) stages[name] += ms;
    }
    for (const auto& [name, ms] : stages) state.counters[name + "_ms"] = ms / static_cast<double>(state.iterations());
    state.counters["beams"] = static_cast<double>(last.health.get("beams_generated"));
    state.counters["fill"] = static_cast<double>(last.health.get("fill"));
    state.counters["volume_rays"] = static_cast<double>(last.health.get("volume_rays"));
    state.counters["volume_culled"] = static_cast<double>(last.health.get("volume_culled"));
    state.SetLabel(std::string(state.range(0) == 0 ? "sphere_fog" : "pool_murky") + ", " +
                   std::to_string(state.range(1)) + " thread(s)");
}

void BM_Adaptive(benchmark::State& state) { run(state, {}); }
void BM_Uniform64(benchmark::State& state) { run(state, {{"adaptive", "false"}, {"grid", "64"}}); }
void BM_Prism(benchmark::State& state) { run(state, {{"hull", "prism"}}); }
// The volume view's levers (volume_view.hpp): node spacing (third argument; 1 = every pixel) and the
// edge-pixel box filter (fourth argument: sub-rays per side of a refined pixel).
void BM_VolumeView(benchmark::State& state) {
    run(state, {{"volume_step", std::to_string(state.range(2))}, {"volume_subpixels", std::to_string(state.range(3))}});
}

// The split oracle and the camera's surface pass, before and after in one run (third argument): 0 the
// former defaults (deviation 0.05, no fold split, point-in-beam camera surface), 1 the oracle at 1 % and on
// folds with point-in-beam, 2 the defaults (the oracle and the camera surface by pixel coverage).
void BM_OracleAndSurface(benchmark::State& state) {
    const int v = static_cast<int>(state.range(2));
    std::map<std::string, std::string> params;
    if (v == 0) params = {{"deviation", "0.05"}, {"fold_split", "false"}};
    if (v <= 1) params["camera_surface"] = "point";
    run(state, params);
}

// The volume view on a beam set of its own with fewer levels, before and after in one run (third argument:
// volume_iterations; -1 the surfaces' beams, the former default; measured from grid 16 with 3 levels, as
// pinned here, where 2 was the default).
void BM_VolumeBeams(benchmark::State& state) {
    run(state, {{"grid", "16"}, {"iterations", "3"}, {"volume_samples", "2"}, {"volume_iterations", std::to_string(state.range(2))}});
}

// The volume view's integrals four rays at a time in AVX2 lanes (1, the default) or one at a time (0): the
// same values to the bit.
void BM_VolumeLanes(benchmark::State& state) {
    run(state, {{"volume_lanes", state.range(2) ? "true" : "false"}});
}

// Points of the volume view's time-vs-error front at the scene cameras (scripts/sweeps/volume_pareto.json),
// third argument: 0 the former defaults (two Gauss points per interval), 1 the defaults (the paper's midpoint,
// volume_samples 1), 2 the same on the volume's unrefined beams (volume_iterations 0).
void BM_VolumePareto(benchmark::State& state) {
    const int v = static_cast<int>(state.range(2));
    run(state, {{"volume_samples", v == 0 ? "2" : "1"}, {"volume_iterations", v == 2 ? "0" : "1"}});
}

// Culling faint volume beams (third argument: volume_cull in thousandths; 0 none, the default).
void BM_VolumeCull(benchmark::State& state) {
    run(state, {{"volume_cull", std::to_string(static_cast<double>(state.range(2)) / 1000.0)}});
}

void BM_HeapPolicy(benchmark::State& state) {
#if defined(__GLIBC__)
    if (state.range(2) == 0) {
        // glibc's initial limits (128 KiB), fixed so that they do not adapt during the benchmark.
        mallopt(M_MMAP_THRESHOLD, 128 * 1024);
        mallopt(M_TRIM_THRESHOLD, 128 * 1024);
    }
#endif
    run(state, {});
    apply_heap_policy();
}

// The idealised bound of the volume view: the arithmetic no ray-beam integral can skip, at this CPU's
// throughput. Each integral needs the ends of its ray's interval in the beam, which cost two divisions for
// the slab and, for each of the three edge quadratics, a square root and two divisions (ray_beam.hpp,
// roots_lanes); each quadrature node of an inside interval costs three divisions (the barycentric
// coordinates, the phase function's cosine, the density), two square roots (the stretch and d^(3/2)) and
// an exponential. The loop does exactly these, four integrals at a time in AVX2 lanes on independent data,
// so that the divider and the exponential's throughput, not latency, bound it; the additions, products,
// sorting, tests, memory traffic and the pixel loop of the real integral are left out (the lanes also skip
// a quadratic's two divisions where none of four rays has a real root, so this is an idealised cost, not a
// strict floor). The argument is the number of quadrature nodes per integral (0: the interval's ends alone;
// 2: one inside interval at the default volume_samples). Counter seconds_per_integral: on one core (the
// console prints it in ns).
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("avx2"))) double integral_floor(const double* a, const double* b, std::size_t n, int nodes) {
    __m256d acc = _mm256_setzero_pd();
    double exps[4] = {0.0, 0.0, 0.0, 0.0};   // one sum per lane: no chain through the four calls
    for (std::size_t i = 0; i + 4 <= n; i += 4) {
        const __m256d x = _mm256_loadu_pd(a + i), y = _mm256_loadu_pd(b + i);
        __m256d t = _mm256_add_pd(_mm256_div_pd(x, y), _mm256_div_pd(y, x));   // the slab's interval
        for (int k = 0; k < 3; ++k) {   // the edge quadratics' roots
            const __m256d r = _mm256_sqrt_pd(_mm256_add_pd(x, _mm256_set1_pd(k)));
            t = _mm256_add_pd(t, _mm256_add_pd(_mm256_div_pd(r, y), _mm256_div_pd(x, r)));
        }
        for (int q = 0; q < nodes; ++q) {   // the integrand at a node
            const __m256d s = _mm256_add_pd(t, _mm256_set1_pd(q + 1.0));
            const __m256d u = _mm256_add_pd(_mm256_div_pd(x, s), _mm256_div_pd(y, s));
            const __m256d v = _mm256_div_pd(_mm256_sqrt_pd(u), _mm256_sqrt_pd(s));
            alignas(32) double e[4];
            _mm256_store_pd(e, v);
            for (int l = 0; l < 4; ++l) exps[l] += std::exp(-e[l]);
        }
        acc = _mm256_add_pd(acc, t);
    }
    alignas(32) double sum[4];
    _mm256_store_pd(sum, acc);
    return sum[0] + sum[1] + sum[2] + sum[3] + exps[0] + exps[1] + exps[2] + exps[3];
}

// The same arithmetic in single precision, eight integrals at a time (the float-lanes lever's idealised gain:
// the divider and the square root take about as long for eight floats as for four doubles).
__attribute__((target("avx2"))) float integral_floor_float(const float* a, const float* b, std::size_t n, int nodes) {
    __m256 acc = _mm256_setzero_ps();
    float exps[8] = {};
    for (std::size_t i = 0; i + 8 <= n; i += 8) {
        const __m256 x = _mm256_loadu_ps(a + i), y = _mm256_loadu_ps(b + i);
        __m256 t = _mm256_add_ps(_mm256_div_ps(x, y), _mm256_div_ps(y, x));
        for (int k = 0; k < 3; ++k) {
            const __m256 r = _mm256_sqrt_ps(_mm256_add_ps(x, _mm256_set1_ps(static_cast<float>(k))));
            t = _mm256_add_ps(t, _mm256_add_ps(_mm256_div_ps(r, y), _mm256_div_ps(x, r)));
        }
        for (int q = 0; q < nodes; ++q) {
            const __m256 s = _mm256_add_ps(t, _mm256_set1_ps(static_cast<float>(q) + 1.0f));
            const __m256 u = _mm256_add_ps(_mm256_div_ps(x, s), _mm256_div_ps(y, s));
            const __m256 v = _mm256_div_ps(_mm256_sqrt_ps(u), _mm256_sqrt_ps(s));
            alignas(32) float e[8];
            _mm256_store_ps(e, v);
            for (int l = 0; l < 8; ++l) exps[l] += std::exp(-e[l]);
        }
        acc = _mm256_add_ps(acc, t);
    }
    alignas(32) float sum[8];
    _mm256_store_ps(sum, acc);
    float total = 0.0f;
    for (int l = 0; l < 8; ++l) total += sum[l] + exps[l];
    return total;
}

// Arguments: quadrature nodes per integral; 0 double precision in four lanes, 1 single precision in eight.
void BM_IntegralFloor(benchmark::State& state) {
    if (!__builtin_cpu_supports("avx2")) {
        state.SkipWithError("needs AVX2");
        return;
    }
    const int nodes = static_cast<int>(state.range(0));
    const bool single = state.range(1) != 0;
    constexpr std::size_t n = 4096;   // 64 KiB of operands: in the first two cache levels
    std::vector<double> a(n), b(n);
    for (std::size_t i = 0; i < n; ++i) a[i] = 1.0 + 0.001 * static_cast<double>(i), b[i] = 2.0 + 0.0007 * static_cast<double>(i);
    const std::vector<float> af(a.begin(), a.end()), bf(b.begin(), b.end());
    for (auto _ : state) {
        if (single)
            benchmark::DoNotOptimize(integral_floor_float(af.data(), bf.data(), n, nodes));
        else
            benchmark::DoNotOptimize(integral_floor(a.data(), b.data(), n, nodes));
    }
    state.counters["seconds_per_integral"] = benchmark::Counter(static_cast<double>(n) * static_cast<double>(state.iterations()),
                                                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.SetLabel(std::to_string(nodes) + " quadrature node(s) per integral, " + (single ? "float x 8" : "double x 4") +
                   ", 1 thread");
}
#endif

}  // namespace

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
BENCHMARK(BM_IntegralFloor)->ArgsProduct({{0, 2}, {0, 1}})->Repetitions(5)->ReportAggregatesOnly(true);
#endif
BENCHMARK(BM_VolumeBeams)->ArgsProduct({{0, 1}, {2}, {-1, 2, 1}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_VolumePareto)->ArgsProduct({{0, 1}, {2}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_VolumeCull)->ArgsProduct({{0, 1}, {2}, {0, 10, 100}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_VolumeLanes)->ArgsProduct({{0, 1}, {1, 2}, {0, 1}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_HeapPolicy)->ArgsProduct({{0, 1}, {2}, {0, 1}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_OracleAndSurface)->ArgsProduct({{0, 1}, {2}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_Adaptive)->ArgsProduct({{0, 1}, {1, 2}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_Uniform64)->ArgsProduct({{0, 1}, {2}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(BM_Prism)->ArgsProduct({{0, 1}, {2}})->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();

BENCHMARK(BM_VolumeView)->ArgsProduct({{0, 1}, {1, 2}, {1, 2}, {1, 2}})->Unit(benchmark::kMillisecond)->Repetitions(3)->ReportAggregatesOnly(true)->UseRealTime();

BENCHMARK_MAIN();
