// caustic_mapping speed (Shah et al. 2007, Fig. 6 and 9 settings): sphere.json at grid 128, map 768,
// camera 1024 x 768 -- the caustic-map passes alone (G-buffers, estimator, splats; goal >= 245 fps) and
// the whole frame with the receiver-map and camera lookups (goal >= 60 fps); bunny.json map passes at
// grid 128 (goal >= 200 fps); raster throughput of the shared G-buffer raster (triangles/s) and splat
// raster (splats/s). Args: threads (2 = the goal's core count, 1 = the per-frame CPU cost).
// MeasureProcessCPUTime: the CPU column is the whole process's CPU time (all threads).
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <random>
#include <string>

#include <tbb/global_control.h>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/blocks/gbuffer/gbuffer_raster.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/blocks/splat/splat.hpp>

using namespace caustics;

namespace {

struct SceneFixture {
    Scene scene;
    FrameGeometry frame;
    ReceiverChart chart;
    std::unique_ptr<RayTracer> tracer;
    CameraGBuffer gbuffer;
    explicit SceneFixture(const std::string& name)
        : scene(load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json")),
          frame(build_frame_geometry(scene, 0)),
          chart(frame, scene.receiver.width, scene.receiver.height) {}
    const CameraGBuffer& camera() {
        if (!tracer) {
            tracer = std::make_unique<RayTracer>(frame);
            gbuffer = build_camera_gbuffer(*tracer, scene.camera);
        }
        return gbuffer;
    }
    static SceneFixture& get(const std::string& name) {
        static std::map<std::string, std::unique_ptr<SceneFixture>> cache;
        auto& f = cache[name];
        if (!f) f = std::make_unique<SceneFixture>(name);
        return *f;
    }
};

void run(benchmark::State& state, const std::string& scene, bool whole_frame,
         std::map<std::string, std::string> params) {
    const int threads = static_cast<int>(state.range(0));
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    SceneFixture& f = SceneFixture::get(scene);
    const MethodInfo& info = require_method("caustic_mapping");
    auto method = info.create(ParamSet::resolve(info.name, info.params, params));
    method->prepare(f.scene);
    method->update(f.frame);
    RenderRequest request;
    if (whole_frame) {
        request.receiver = &f.chart;
        request.camera = &f.camera();
    }
    for (int warm = 0; warm < 3; ++warm) benchmark::DoNotOptimize(method->render(f.frame, request));
    std::map<std::string, double> stages;
    for (auto _ : state) {
        CausticOutput out = method->render(f.frame, request);
        for (const auto& [name, ms] : out.stages_ms) stages[name] += ms;
        benchmark::DoNotOptimize(out.receiver.pixels.data());
    }
    const double n = static_cast<double>(state.iterations());
    state.counters["fps"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
    double map_ms = 0.0;
    for (const auto& [name, ms] : stages) {
        state.counters[name + "_ms"] = ms / n;
        if (name == "gbuffers" || name == "estimator" || name == "splat") map_ms += ms / n;
    }
    state.counters["map_passes_ms"] = map_ms;
    state.counters["threads"] = threads;
}

const std::map<std::string, std::string> kPaper = {{"grid", "128"}, {"map", "768"}, {"iterations", "3"}};

// kPaper runs the defaults (Newton-Raphson, elliptic splats, receivers extended past their edges, n x n
// lookups per receiver bin); the approximate estimator for comparison.
// kPaperAlgorithm is the paper's own algorithm at the same settings (Newton with the paper's d0 = 1 and
// eps = 0.1, one-texel point splats, the null value at receiver edges, one lookup per receiver bin): the
// features the defaults add for accuracy (elliptic splats, the extension, the bin's area mean) are not in
// the 245 / 200 fps the goals are anchored to, so the two rows together say what each part costs.
const std::map<std::string, std::string> kPaperAlgorithm = {
    {"grid", "128"}, {"map", "768"}, {"iterations", "3"}, {"estimator", "newton"}, {"d0", "1"}, {"eps", "0.1"},
    {"splat", "point"}, {"extend", "0"}, {"bin_samples", "1"}};
void BM_SphereMapPasses(benchmark::State& s) { run(s, "sphere", false, kPaper); }
void BM_SphereMapPassesPaperAlgorithm(benchmark::State& s) { run(s, "sphere", false, kPaperAlgorithm); }
void BM_SphereWholeFramePaperAlgorithm(benchmark::State& s) { run(s, "sphere", true, kPaperAlgorithm); }
void BM_BunnyMapPassesPaperAlgorithm(benchmark::State& s) { run(s, "bunny", false, kPaperAlgorithm); }
void BM_SphereMapPassesApprox(benchmark::State& s) {
    auto p = kPaper;
    p["estimator"] = "approx";
    run(s, "sphere", false, p);
}
void BM_SphereWholeFrame(benchmark::State& s) { run(s, "sphere", true, kPaper); }
void BM_BunnyMapPasses(benchmark::State& s) { run(s, "bunny", false, kPaper); }
void BM_BunnyWholeFrame(benchmark::State& s) { run(s, "bunny", true, kPaper); }

// Raster throughput: a UV sphere of `range(0)` triangles (about 1-30 pixels each) into a 768^2 G-buffer.
void BM_GBufferTriangles(benchmark::State& state) {
    const int slices = static_cast<int>(state.range(0));
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(1)));
    TriangleMesh m;
    for (int j = 0; j <= slices / 2; ++j)
        for (int i = 0; i <= slices; ++i) {
            const double th = M_PI * j / (slices / 2), ph = 2 * M_PI * i / slices;
            const glm::dvec3 n(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
            m.positions.emplace_back(n);
            m.normals.emplace_back(n);
        }
    const unsigned row = static_cast<unsigned>(slices + 1);
    for (unsigned j = 0; j < static_cast<unsigned>(slices / 2); ++j)
        for (unsigned i = 0; i < static_cast<unsigned>(slices); ++i) {
            const unsigned a = j * row + i;
            m.triangles.push_back({a, a + row, a + 1});
            m.triangles.push_back({a + 1, a + row, a + row + 1});
        }
    Bounds3 b;
    b.extend({-1, -1, -1});
    b.extend({1, 1, 1});
    const LightProjection view = fit_orthographic({0.2, 0.1, -1}, b, 768, 768);
    GBuffer g;
    GBufferRaster raster;
    for (auto _ : state) {
        g.clear(768, 768);
        raster.draw(view, {m.positions, m.normals, m.triangles, 0}, CullMode::None, DepthTest::Less, g);
        benchmark::DoNotOptimize(g.depth.data());
    }
    state.counters["triangles_per_s"] =
        benchmark::Counter(static_cast<double>(m.triangles.size()) * state.iterations(), benchmark::Counter::kIsRate);
    state.counters["triangles"] = static_cast<double>(m.triangles.size());
}

// Splat throughput: 100k splats over a 768^2 map; radius 0 = point splats.
void BM_Splats(benchmark::State& state) {
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(1)));
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.0f, 768.0f);
    std::vector<Splat> splats;
    for (int k = 0; k < 100000; ++k) splats.push_back({{u(rng), u(rng)}, 1.0f});
    Image img(768, 768);
    SplatRaster raster;
    const double radius = static_cast<double>(state.range(0));
    for (auto _ : state) {
        std::fill(img.pixels.begin(), img.pixels.end(), 0.0f);
        raster.draw(splats, radius > 0 ? SplatKernel::Gaussian : SplatKernel::Point, radius, img);
        benchmark::DoNotOptimize(img.pixels.data());
    }
    state.counters["splats_per_s"] =
        benchmark::Counter(static_cast<double>(splats.size()) * state.iterations(), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_SphereMapPasses)->Arg(2)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_SphereMapPassesPaperAlgorithm)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_SphereWholeFramePaperAlgorithm)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_BunnyMapPassesPaperAlgorithm)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_SphereMapPassesApprox)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_SphereWholeFrame)->Arg(2)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_BunnyMapPasses)->Arg(2)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_BunnyWholeFrame)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_GBufferTriangles)->Args({256, 2})->Args({1024, 2})->Args({1024, 1})->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(BM_Splats)->Args({0, 2})->Args({6, 2})->Args({6, 1})->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_MAIN();
