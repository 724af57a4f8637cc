#pragma once
// Periodic caustic texture synthesis behind `caustics synth` (issue 5; Stam, "Periodic Caustic Textures"):
// a set of caustic textures that tile in space and loop in time, from a scene whose water surface is the
// `noise` height field (periodic over its rectangle and over `period` seconds). Frame i is the texture at
// time i * period / frames, so frame `frames` equals frame 0 again.
//
// Any method may synthesise textures: one whose texture_capability(scene) says yes fills
// CausticOutput::texture for a RenderRequest::texture (harness/api/method.hpp); no method is named here.
//
// Files (all written atomically) in the output folder:
//   frame_000.exr ...   linear E_c [W/m^2]; RGB when the method filled texture_rgb (dispersion)
//   frame_000.png ...   8-bit sRGB with one exposure for the whole set (so the animation does not flicker);
//                       together they are the animated preview as a PNG sequence
//   preview.gif         animated preview (looping), when OpenImageIO has a GIF writer
//   contact_sheet.png   every frame as a thumbnail, row by row
//   tile_2x2.png        frame 0 tiled 2 x 2 (look for a seam)
//   manifest.json       scene, method, params, frames, size, period, depth, timing per frame, health
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <caustics/frame/frame.hpp>
#include <caustics/util/image.hpp>
#include <caustics/api/method.hpp>
#include <caustics/run/render_run.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

struct SynthOptions {
    std::string scene_path;                           // a path, or a name in scenes/
    std::string method;
    std::map<std::string, std::string> overrides;     // --set KEY=VALUE
    int frames = 32;
    int size = 512;            // texture width; height = size * (tile height / tile width), rounded
    double depth = 0.0;        // > 0: receiver plane depth below the water's base height [m]; 0: from the scene's receiver
    std::string out_dir;       // empty: write no files
    int threads = 0;           // 0: every core
    bool gif = true;           // write preview.gif
};

struct SynthFrame {
    int index = 0;
    double time = 0.0;         // [s]
    Image texture;             // 1 channel, E_c [W/m^2]
    Image texture_rgb;         // 3 channels, or empty
    double surface_ms = 0.0;   // height-field evaluation (not timed as method work)
    double update_ms = 0.0;    // Method::update
    double render_ms = 0.0;    // Method::render with the texture request
    std::vector<std::pair<std::string, double>> stages_ms;
    Health health;
};

// Everything validated before any work or output: the scene, the method and its parameters, the water
// surface and its periods, the texture plane. Throws InputError (-> exit 2) for an unknown method or
// parameter, a method that does not synthesise periodic textures (its reason), a water surface that is
// not periodic in space and time (the reason), a bad frame count, size or depth.
struct SynthPlan {
    Scene scene;
    ResolvedMethod method;
    int water_index = -1;
    double period = 0.0;       // time period of the surface [s]
    glm::dvec2 tile_origin{0.0}, tile_size{1.0};
    TextureRequest texture;    // width, height, depth
    int frames = 32;
};
SynthPlan plan_synth(const SynthOptions& options);

// Renders frames of a plan: creates and prepares the method once; frame(i) for any i >= 0 (i = frames
// gives frame 0 again). Not thread-safe.
class Synthesizer {
public:
    explicit Synthesizer(const SynthPlan& plan);
    ~Synthesizer();
    Synthesizer(const Synthesizer&) = delete;
    Synthesizer& operator=(const Synthesizer&) = delete;

    const SynthPlan& plan() const { return plan_; }
    double time_of(int i) const;
    SynthFrame frame(int i);
    double prepare_ms() const { return prepare_ms_; }

private:
    SynthPlan plan_;   // a copy: the frame geometry points into its scene
    std::unique_ptr<Method> method_;
    FrameGeometry geometry_;
    double prepare_ms_ = 0.0;
};

struct SynthResult {
    std::vector<SynthFrame> frames;
    nlohmann::json manifest;
    double total_ms = 0.0;     // sum over frames of update + render (file writing and the surface excluded)
};

// The whole `caustics synth`: plan (every InputError before any output), one untimed warm-up frame, every
// frame timed, then the files when options.out_dir is set.
SynthResult run_synth(const SynthOptions& options);

// Writes the files listed above for a finished synthesis.
void write_synth_outputs(const std::string& dir, const SynthPlan& plan, SynthResult& result, bool gif);

// Frame-to-frame helpers used by the files and the tests.
Image tile_image(const Image& image, int nx, int ny);   // the image repeated nx x ny times
// Seam statistics of a periodic image (channel 0): the differences between horizontally (vertically)
// adjacent pixels inside the image versus across the wrapped edge (last column to first, last row to
// first). A seamless tile has wrap statistics like the interior ones.
struct SeamStats {
    double interior_mean_abs = 0.0, interior_rms = 0.0;   // over all interior neighbour pairs (x and y)
    double wrap_mean_abs = 0.0, wrap_rms = 0.0;           // over the wrapped pairs (x and y)
    // The same number of pairs as the wrap, across the middle column and row (W/2 - 1 to W/2, H/2 - 1
    // to H/2): a baseline with the wrap's sampling noise.
    double mid_mean_abs = 0.0;
    // Pearson correlation of neighbouring columns (and rows), averaged over the x and y directions:
    // across the wrap (last column with the first, last row with the first) and inside (mean over every
    // adjacent pair). Caustic textures are rough at the pixel scale, so the mean absolute differences are
    // noisy; the correlation separates a seam (two unrelated lines: ~0) from a seamless wrap (like inside).
    double wrap_correlation = 0.0, interior_correlation = 0.0;
};
SeamStats seam_stats(const Image& image);

}  // namespace caustics
