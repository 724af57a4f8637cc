#pragma once
// The set-up of the 3-D caustic texture benchmarks (Mercier 2013, Table 1): pool.json with its floor
// moved to z = -2, so that the 2 m x 2 m water volume is a cube of grid^3 cells, with its receiver chart
// and camera G-buffer; the process's peak resident memory; and the per-frame lookup benchmark.
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
#include <caustics/scene/scene.hpp>

namespace caustics::bench {

struct PoolCube {
    Scene scene;
    std::unique_ptr<FrameGeometry> frame;
    std::unique_ptr<ReceiverChart> chart;
    std::unique_ptr<CameraGBuffer> gbuffer;
};

inline PoolCube& pool_cube() {
    static PoolCube p = [] {
        PoolCube c;
        c.scene = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/pool.json");
        for (Object& o : c.scene.objects)
            if (o.name == "floor") o.center.z = -2.0;
        c.frame = std::make_unique<FrameGeometry>(build_frame_geometry(c.scene, 0));
        c.chart = std::make_unique<ReceiverChart>(*c.frame, c.scene.receiver.width, c.scene.receiver.height);
        RayTracer tracer(*c.frame);
        c.gbuffer = std::make_unique<CameraGBuffer>(build_camera_gbuffer(tracer, c.scene.camera));
        return c;
    }();
    return p;
}

inline double maxrss_mb() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_maxrss) / 1024.0;
}

inline std::unique_ptr<Method> make_method(const std::string& name, const std::map<std::string, std::string>& params) {
    const MethodInfo& info = require_method(name);
    return info.create(ParamSet::resolve(info.name, info.params, params));
}

// The frame once the texture is built (the paper's "frame rate after texture computation"): render()
// reads the texture at the 256 x 256 receiver bins and the covered camera pixels; grid = state.range(0).
inline void lookup_benchmark(benchmark::State& state, const std::string& method, std::map<std::string, std::string> params) {
    PoolCube& p = pool_cube();
    params["grid"] = std::to_string(state.range(0));
    auto m = make_method(method, params);
    m->update(*p.frame);
    RenderRequest request{p.chart.get(), p.gbuffer.get()};
    for (auto _ : state) benchmark::DoNotOptimize(m->render(*p.frame, request));
    std::size_t covered = 0;
    for (auto c : p.gbuffer->covered) covered += c;
    state.counters["lookups"] = static_cast<double>(p.chart->width() * p.chart->height() + covered);
}

}  // namespace caustics::bench
