// libFuzzer target (issue 12): the scene loader and the per-frame set-up on arbitrary scene files.
//
// Each input is the text of a scene file. It is written next to a link to the shipped assets (so that
// mutations of the shipped scenes can still name their meshes and height maps), loaded, and, when the
// loader accepts it, turned into frame geometry, a ray tracer, a receiver chart and a camera G-buffer
// for its first and last frames. An InputError is the expected answer to bad input; any other
// exception, a crash, a sanitizer report, a hang or an allocation past libFuzzer's -rss_limit_mb is a
// finding. Built only by the `fuzz` preset (clang, -fsanitize=fuzzer,address,undefined); run it with
// scripts/fuzz.sh, whose seed corpus is scenes/*.json.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include <caustics/frame/camera.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/scene/scene.hpp>

namespace fs = std::filesystem;

namespace {

// A private folder holding the input file and a link to scenes/assets.
const fs::path& work_dir() {
    static const fs::path dir = [] {
        const fs::path d = fs::temp_directory_path() / ("caustics_fuzz_" + std::to_string(::getpid()));
        fs::create_directories(d);
        std::error_code ec;
        fs::create_directory_symlink(fs::path(CAUSTICS_SOURCE_DIR) / "scenes" / "assets", d / "assets", ec);
        std::atexit([] {
            std::error_code e;
            fs::remove_all(fs::temp_directory_path() / ("caustics_fuzz_" + std::to_string(::getpid())), e);
        });
        return d;
    }();
    return dir;
}

void set_up_frame(const caustics::Scene& scene, int frame) {
    const caustics::FrameGeometry geometry = caustics::build_frame_geometry(scene, frame);
    const caustics::RayTracer tracer(geometry);
    const caustics::ReceiverChart chart(geometry, scene.receiver.width, scene.receiver.height);
    (void)caustics::build_camera_gbuffer(tracer, scene.camera);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const fs::path file = work_dir() / "scene.json";
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    try {
        const caustics::Scene scene = caustics::load_scene(file.string());
        set_up_frame(scene, 0);
        if (scene.animation.frames > 1) set_up_frame(scene, scene.animation.frames - 1);
    } catch (const caustics::InputError&) {
        // The expected answer to bad input.
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fuzz_scene_loader: unexpected exception: %s\n", e.what());
        std::abort();
    }
    return 0;
}
