// The files of one render (docs/design.md section 7), each written atomically, metrics.json last.
#include <filesystem>

#include <caustics/run/beauty.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/util/image_io.hpp>

namespace caustics {

namespace fs = std::filesystem;

void write_render_outputs(const std::string& dir, const SceneFrame& sf, const RenderRun& run,
                          const RenderOptions& options) {
    fs::create_directories(dir);
    const fs::path d(dir);
    if (run.status != RunStatus::Skipped) {
        const CausticOutput& out = run.output;
        if (!out.receiver.empty()) write_exr(out.receiver, (d / "receiver.exr").string());
        if (!out.receiver_rgb.empty()) write_exr(out.receiver_rgb, (d / "receiver_rgb.exr").string());
        if (!out.camera.empty()) {
            // Only covered pixels carry a value; the rest is written as 0.
            Image camera = out.camera;
            const auto& covered = sf.gbuffer().covered;
            for (std::size_t p = 0; p < covered.size(); ++p)
                if (!covered[p]) camera.pixels[p] = 0.0f;
            write_exr(camera, (d / "camera.exr").string());
        }
        if (!out.camera_volume.empty()) write_exr(out.camera_volume, (d / "camera_volume.exr").string());
        for (const auto& [name, image] : out.debug)
            if (!image.empty() && (image.channels == 1 || image.channels == 3))
                write_exr(image, (d / ("debug_" + name + ".exr")).string());
        if (options.beauty) {
            BeautyInputs in;
            in.gbuffer = &sf.gbuffer();
            in.camera_ec = &out.camera;
            in.chart = &sf.chart();
            in.receiver_ec = &out.receiver;
            write_beauty_png(render_beauty(sf.tracer(), in), (d / "beauty.png").string());
        }
    }
    // metrics.json last: its presence says the run's files are complete.
    write_text_atomic((d / "metrics.json").string(), run.metrics.dump(2) + "\n");
}

}  // namespace caustics
