// Periodic caustic texture synthesis: see synth.hpp.
#include <caustics/synth/synth.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/util/build_info.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <caustics/util/errors.hpp>
#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/scene/scene_catalog.hpp>
#include <caustics/util/image_io.hpp>
#include <caustics/util/timing.hpp>

namespace caustics {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const char* generator_name(HeightGenerator g) {
    switch (g) {
    case HeightGenerator::Flat: return "flat";
    case HeightGenerator::Sine: return "sine";
    case HeightGenerator::Gaussian: return "gaussian";
    case HeightGenerator::Noise: return "noise";
    case HeightGenerator::Waves: return "waves";
    case HeightGenerator::Image: return "image";
    }
    return "?";
}

std::string frame_name(int i, const char* ext) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "frame_%03d.%s", i, ext);
    return buf;
}

// Box-filtered downsampling by an integer factor (thumbnails).
Image downsample(const Image& img, int factor) {
    if (factor <= 1) return img;
    const int w = std::max(1, img.width / factor), h = std::max(1, img.height / factor);
    Image out(w, h, img.channels);
    const float norm = 1.0f / static_cast<float>(factor * factor);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < img.channels; ++c) {
                float s = 0.0f;
                for (int dy = 0; dy < factor; ++dy)
                    for (int dx = 0; dx < factor; ++dx)
                        s += img.at(std::min(x * factor + dx, img.width - 1), std::min(y * factor + dy, img.height - 1), c);
                out.at(x, y, c) = s * norm;
            }
    return out;
}

const Image& display_image(const SynthFrame& f) { return f.texture_rgb.empty() ? f.texture : f.texture_rgb; }

// An exposure shared by the whole set: the 99.5th percentile of every frame's values maps to 1.
double set_exposure(const std::vector<SynthFrame>& frames) {
    std::vector<float> v;
    for (const SynthFrame& f : frames) {
        const Image& img = display_image(f);
        const std::size_t stride = std::max<std::size_t>(1, img.pixels.size() / 65536);
        for (std::size_t k = 0; k < img.pixels.size(); k += stride)
            if (std::isfinite(img.pixels[k])) v.push_back(img.pixels[k]);
    }
    if (v.empty()) return 1.0;
    const std::size_t q = std::min(v.size() - 1, static_cast<std::size_t>(0.995 * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(q), v.end());
    const double p = v[q];
    return p > 0.0 ? 1.0 / p : 1.0;
}

std::uint8_t srgb8(float linear) {
    float v;
    if (!(linear > 0.0f)) v = 0.0f;
    else if (linear >= 1.0f) v = 1.0f;
    else v = linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
    return static_cast<std::uint8_t>(std::lround(v * 255.0f));
}

// Animated GIF through OpenImageIO's GIF writer (libgif; no new dependency): one subimage per frame,
// looping. Returns false (and writes nothing) where the writer or multi-image output is unavailable.
bool write_gif(const std::vector<SynthFrame>& frames, double exposure, int max_size, double fps,
               const std::string& path, std::string& why) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) {
        why = "no GIF writer in OpenImageIO";
        return false;
    }
    if (!out->supports("multiimage") || !out->supports("appendsubimage")) {
        why = "OpenImageIO's GIF writer cannot write animations";
        return false;
    }
    const Image& first = display_image(frames.front());
    const int factor = std::max(1, (std::max(first.width, first.height) + max_size - 1) / max_size);
    std::vector<Image> small;
    for (const SynthFrame& f : frames) small.push_back(downsample(display_image(f), factor));
    const int w = small.front().width, h = small.front().height;
    // GIF holds 8-bit RGB(A); grey images are expanded to RGB.
    std::vector<OIIO::ImageSpec> specs(small.size(), OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::UINT8));
    for (auto& s : specs) {
        s.attribute("FramesPerSecond", OIIO::TypeRational, std::vector<int>{static_cast<int>(std::lround(fps)), 1}.data());
        s.attribute("gif:LoopCount", 0);
    }
    fs::path p(path);
    const std::string tmp =
        (p.parent_path() / (p.stem().string() + temporary_suffix() + p.extension().string())).string();
    if (!out->open(tmp, static_cast<int>(specs.size()), specs.data())) {
        why = "cannot open " + tmp + ": " + out->geterror();
        return false;
    }
    bool ok = true;
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(w) * h * 3);
    for (std::size_t k = 0; k < small.size() && ok; ++k) {
        if (k > 0) ok = out->open(tmp, specs[k], OIIO::ImageOutput::AppendSubimage);
        const Image& img = small[k];
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c)
                    bytes[(static_cast<std::size_t>(y) * w + x) * 3 + c] =
                        srgb8(static_cast<float>(img.at(x, y, img.channels == 3 ? c : 0) * exposure));
        ok = ok && out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
    }
    ok = out->close() && ok;
    std::error_code ec;
    if (!ok) {
        why = "GIF writer failed: " + out->geterror();
        fs::remove(tmp, ec);
        return false;
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        why = "cannot rename " + tmp;
        return false;
    }
    return true;
}

}  // namespace

SynthPlan plan_synth(const SynthOptions& options) {
    SynthPlan plan;
    if (options.frames < 1 || options.frames > 10000)
        throw InputError("--frames", "", "must be an integer in [1, 10000], got " + std::to_string(options.frames));
    if (options.size < 8 || options.size > 8192)
        throw InputError("--size", "", "must be an integer in [8, 8192], got " + std::to_string(options.size));
    if (!(options.depth >= 0.0) || !std::isfinite(options.depth))
        throw InputError("--depth", "", "must be a finite depth > 0 in metres (or 0: from the scene's receiver)");
    plan.scene = load_scene(resolve_scene_path(options.scene_path));
    plan.method = resolve_method(options.method, options.overrides);
    plan.frames = options.frames;
    const Scene& scene = plan.scene;

    // The water surface: exactly one dielectric height field, periodic in space and time.
    int water = -1, count = 0;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const Object& o = scene.objects[i];
        if (o.shape == ShapeType::HeightField && o.material.type == MaterialType::Dielectric) {
            ++count;
            if (water < 0) water = static_cast<int>(i);
        }
    }
    if (count != 1)
        throw InputError(scene.path, "objects",
                         "synth needs exactly one dielectric height-field water surface (found " + std::to_string(count) +
                             ") with the 'noise' generator, which is periodic in space and time");
    const Object& w = scene.objects[static_cast<std::size_t>(water)];
    const HeightFieldDesc& d = w.heightfield;
    const std::string key = "objects[" + std::to_string(water) + "].generator";
    if (d.generator != HeightGenerator::Noise)
        throw InputError(scene.path, key,
                         std::string("the water surface '") + w.name + "' uses the '" + generator_name(d.generator) +
                             "' generator, which is not periodic in space and time: a synthesized texture would "
                             "show seams and the animation would not loop; synth needs the 'noise' generator "
                             "(periodic over its rectangle and over 'period' seconds)");
    if (!(d.period > 0.0) || !std::isfinite(d.period))
        throw InputError(scene.path, key + ".period", "must be a finite time period > 0 s for synth");
    plan.water_index = water;
    plan.period = d.period;
    plan.tile_origin = d.center - 0.5 * d.size;
    plan.tile_size = d.size;

    // The texture plane: --depth, else the receiver's height below the water's base level.
    double depth = options.depth;
    if (depth == 0.0) {
        const Object& r = scene.receiver_object();
        const double z = r.shape == ShapeType::HeightField ? r.heightfield.base_height : r.center.z;
        depth = d.base_height - z;
        if (!(depth > 0.0))
            throw InputError(scene.path, "receiver",
                             "the receiver '" + r.name + "' is not below the water surface (depth " + std::to_string(depth) +
                                 " m); give --depth");
    }
    plan.texture.depth = depth;
    plan.texture.width = options.size;
    plan.texture.height = std::max(1, static_cast<int>(std::lround(options.size * d.size.y / d.size.x)));

    // The method must synthesise periodic textures for this scene.
    const std::unique_ptr<Method> m = plan.method.info->create(plan.method.params);
    const Capability cap = m->texture_capability(scene);
    if (!cap.supported) {
        // Name the methods that can, at their defaults, on this scene.
        std::string able;
        for (const MethodInfo* info : registered_methods()) {
            const std::unique_ptr<Method> other = info->create(ParamSet::resolve(info->name, info->params, {}));
            if (other->texture_capability(scene).supported) able += (able.empty() ? "" : ", ") + info->name;
        }
        throw InputError("--method", plan.method.info->name,
                         "cannot synthesise a periodic texture for " + scene.name + ": " + cap.reason +
                             "; valid: " + (able.empty() ? std::string("no registered method can for this scene") : able));
    }
    return plan;
}

Synthesizer::Synthesizer(const SynthPlan& plan) : plan_(plan) {
    geometry_ = build_frame_geometry(plan_.scene, 0);
    method_ = plan_.method.info->create(plan_.method.params);
    Stopwatch clock;
    method_->prepare(plan_.scene);
    prepare_ms_ = clock.ms();
}

Synthesizer::~Synthesizer() = default;

double Synthesizer::time_of(int i) const { return static_cast<double>(i) * plan_.period / plan_.frames; }

SynthFrame Synthesizer::frame(int i) {
    SynthFrame f;
    f.index = i;
    f.time = time_of(i);
    const Scene& scene = plan_.scene;
    const Object& water = scene.objects[static_cast<std::size_t>(plan_.water_index)];
    // The surface at the frame's time (the noise generator wraps time by its period).
    Stopwatch clock;
    auto hf = std::make_shared<HeightField>(generate_heightfield(water.heightfield, f.time, 0, scene.animation.fps));
    ObjectInstance& inst = geometry_.objects[static_cast<std::size_t>(plan_.water_index)];
    inst.mesh = hf->triangulate();
    inst.heightfield = std::move(hf);
    geometry_.time = f.time;
    f.surface_ms = clock.ms();

    clock.reset();
    method_->update(geometry_);
    f.update_ms = clock.ms();
    RenderRequest request;
    request.texture = &plan_.texture;
    clock.reset();
    CausticOutput out = method_->render(geometry_, request);
    f.render_ms = clock.ms();
    if (out.texture.width != plan_.texture.width || out.texture.height != plan_.texture.height || out.texture.channels != 1)
        throw std::runtime_error(plan_.method.info->name + ": did not fill the requested periodic texture");
    std::int64_t nonfinite = 0;
    for (float& v : out.texture.pixels)
        if (!std::isfinite(v)) ++nonfinite;
    if (nonfinite > 0) f.health.add("nonfinite_texels", nonfinite);
    f.texture = std::move(out.texture);
    f.texture_rgb = std::move(out.texture_rgb);
    f.stages_ms = std::move(out.stages_ms);
    for (const auto& [k, v] : out.health.counters) f.health.add(k, v);
    return f;
}

SynthResult run_synth(const SynthOptions& options) {
    const SynthPlan plan = plan_synth(options);
    ThreadLimit limit(options.threads);
    SynthResult result;
    Synthesizer synth(plan);
    (void)synth.frame(0);   // warm-up: first-call allocations and plans stay out of the timings
    std::vector<double> per_frame;
    double surface_ms = 0.0;
    for (int i = 0; i < plan.frames; ++i) {
        result.frames.push_back(synth.frame(i));
        const SynthFrame& f = result.frames.back();
        per_frame.push_back(f.update_ms + f.render_ms);
        result.total_ms += f.update_ms + f.render_ms;
        surface_ms += f.surface_ms;
    }

    json& m = result.manifest;
    m["scene"] = plan.scene.name;
    m["scene_path"] = plan.scene.path;
    m["method"] = plan.method.info->name;
    m["params"] = params_json(*plan.method.info, plan.method.params);
    m["radiometric"] = plan.method.info->radiometric_at(plan.method.params);
    m["frames"] = plan.frames;
    m["size"] = {plan.texture.width, plan.texture.height};
    m["period"] = plan.period;
    m["depth"] = plan.texture.depth;
    m["tile"] = {{"origin", {plan.tile_origin.x, plan.tile_origin.y}}, {"size", {plan.tile_size.x, plan.tile_size.y}}};
    m["colour"] = !result.frames.empty() && !result.frames.front().texture_rgb.empty();
    m["units"] = "caustic irradiance E_c [W/m^2] on the plane 'depth' below the water's base height";
    json frames = json::array();
    Health total;
    for (const SynthFrame& f : result.frames) {
        double mean = 0.0;
        for (float v : f.texture.pixels) mean += v;
        mean /= static_cast<double>(std::max<std::size_t>(1, f.texture.pixels.size()));
        json stages = json::object();
        for (const auto& [k, v] : f.stages_ms) stages[k] = json_number(v);
        json health = json::object();
        for (const auto& [k, v] : f.health.counters) {
            health[k] = v;
            total.add(k, v);
        }
        frames.push_back({{"index", f.index}, {"time", f.time}, {"update_ms", json_number(f.update_ms)},
                          {"render_ms", json_number(f.render_ms)}, {"surface_ms", json_number(f.surface_ms)},
                          {"mean", json_number(mean)}, {"stages_ms", stages}, {"health", health}});
    }
    m["per_frame"] = frames;
    const TimingSummary t = summarize_ms(per_frame);
    m["timing"] = {{"total_ms", json_number(result.total_ms)},
                   {"frame_ms", {{"median", json_number(t.median)}, {"min", json_number(t.min)}, {"p90", json_number(t.p90)}}},
                   {"prepare_ms", json_number(synth.prepare_ms())},
                   {"surface_ms_total", json_number(surface_ms)},
                   {"note", "total_ms = sum over frames of update + render; the height-field evaluation (surface_ms), "
                            "one untimed warm-up frame and file writing are excluded"}};
    m["threads"] = ThreadLimit::effective();
    m["build_type"] = build_type();
    json h = json::object();
    for (const auto& [k, v] : total.counters) h[k] = v;
    m["health"] = h;
    if (!options.out_dir.empty()) write_synth_outputs(options.out_dir, plan, result, options.gif);
    return result;
}

void write_synth_outputs(const std::string& dir, const SynthPlan& plan, SynthResult& result, bool gif) {
    fs::create_directories(dir);
    const double exposure = set_exposure(result.frames);
    json files = json::object();
    json exr = json::array(), png = json::array();
    for (const SynthFrame& f : result.frames) {
        const Image& img = display_image(f);
        write_exr(img, (fs::path(dir) / frame_name(f.index, "exr")).string());
        write_png(img, (fs::path(dir) / frame_name(f.index, "png")).string(), exposure);
        exr.push_back(frame_name(f.index, "exr"));
        png.push_back(frame_name(f.index, "png"));
    }
    files["exr"] = exr;
    files["png"] = png;

    // Contact sheet: thumbnails of at most 128 pixels, up to 8 per row, 2-pixel gaps.
    if (!result.frames.empty()) {
        const Image& first = display_image(result.frames.front());
        const int factor = std::max(1, (std::max(first.width, first.height) + 127) / 128);
        const int n = static_cast<int>(result.frames.size());
        const int cols = std::min(n, 8), rows = (n + cols - 1) / cols, gap = 2;
        const int tw = std::max(1, first.width / factor), th = std::max(1, first.height / factor);
        Image sheet(cols * tw + (cols - 1) * gap, rows * th + (rows - 1) * gap, first.channels, 0.0f);
        for (int k = 0; k < n; ++k) {
            const Image t = downsample(display_image(result.frames[static_cast<std::size_t>(k)]), factor);
            const int ox = (k % cols) * (tw + gap), oy = (k / cols) * (th + gap);
            for (int y = 0; y < std::min(th, t.height); ++y)
                for (int x = 0; x < std::min(tw, t.width); ++x)
                    for (int c = 0; c < sheet.channels; ++c) sheet.at(ox + x, oy + y, c) = t.at(x, y, c);
        }
        write_png(sheet, (fs::path(dir) / "contact_sheet.png").string(), exposure);
        files["contact_sheet"] = "contact_sheet.png";
        write_png(tile_image(first, 2, 2), (fs::path(dir) / "tile_2x2.png").string(), exposure);
        files["tile_2x2"] = "tile_2x2.png";
    }
    files["preview_png_sequence"] = "frame_%03d.png";
    if (gif && !result.frames.empty()) {
        std::string why;
        const double fps = plan.frames / plan.period;
        if (write_gif(result.frames, exposure, 256, fps, (fs::path(dir) / "preview.gif").string(), why))
            files["preview_gif"] = "preview.gif";
        else
            files["preview_gif_skipped"] = why;
    }
    result.manifest["files"] = files;
    result.manifest["png_exposure"] = exposure;
    write_text_atomic((fs::path(dir) / "manifest.json").string(), result.manifest.dump(2) + "\n");
}

Image tile_image(const Image& image, int nx, int ny) {
    Image out(image.width * nx, image.height * ny, image.channels);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < image.channels; ++c) out.at(x, y, c) = image.at(x % image.width, y % image.height, c);
    return out;
}

SeamStats seam_stats(const Image& img) {
    SeamStats s;
    const int W = img.width, H = img.height;
    double in_abs = 0.0, in_sq = 0.0, wr_abs = 0.0, wr_sq = 0.0, mid_abs = 0.0;
    std::size_t in_n = 0, wr_n = 0, mid_n = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const double v = img.at(x, y);
            const double dx = img.at((x + 1) % W, y) - v, dy = img.at(x, (y + 1) % H) - v;
            const bool wrap_x = x == W - 1, wrap_y = y == H - 1;
            (wrap_x ? wr_abs : in_abs) += std::abs(dx);
            (wrap_x ? wr_sq : in_sq) += dx * dx;
            ++(wrap_x ? wr_n : in_n);
            (wrap_y ? wr_abs : in_abs) += std::abs(dy);
            (wrap_y ? wr_sq : in_sq) += dy * dy;
            ++(wrap_y ? wr_n : in_n);
            if (x == W / 2 - 1) {
                mid_abs += std::abs(dx);
                ++mid_n;
            }
            if (y == H / 2 - 1) {
                mid_abs += std::abs(dy);
                ++mid_n;
            }
        }
    s.interior_mean_abs = in_n ? in_abs / in_n : 0.0;
    s.interior_rms = in_n ? std::sqrt(in_sq / in_n) : 0.0;
    s.wrap_mean_abs = wr_n ? wr_abs / wr_n : 0.0;
    s.wrap_rms = wr_n ? std::sqrt(wr_sq / wr_n) : 0.0;
    s.mid_mean_abs = mid_n ? mid_abs / mid_n : 0.0;
    // Correlations of adjacent lines: column a with column b (vertical = false) or row a with row b.
    auto corr = [&img, W, H](int a, int b, bool rows) {
        const int n = rows ? W : H;
        double ma = 0.0, mb = 0.0;
        for (int k = 0; k < n; ++k) {
            ma += rows ? img.at(k, a) : img.at(a, k);
            mb += rows ? img.at(k, b) : img.at(b, k);
        }
        ma /= n;
        mb /= n;
        double sab = 0.0, saa = 0.0, sbb = 0.0;
        for (int k = 0; k < n; ++k) {
            const double u = (rows ? img.at(k, a) : img.at(a, k)) - ma, v = (rows ? img.at(k, b) : img.at(b, k)) - mb;
            sab += u * v;
            saa += u * u;
            sbb += v * v;
        }
        return saa > 0.0 && sbb > 0.0 ? sab / std::sqrt(saa * sbb) : 1.0;
    };
    double cx = 0.0, cy = 0.0;
    for (int x = 0; x + 1 < W; ++x) cx += corr(x, x + 1, false);
    for (int y = 0; y + 1 < H; ++y) cy += corr(y, y + 1, true);
    s.interior_correlation = 0.5 * (W > 1 ? cx / (W - 1) : 1.0) + 0.5 * (H > 1 ? cy / (H - 1) : 1.0);
    s.wrap_correlation = 0.5 * (corr(W - 1, 0, false) + corr(H - 1, 0, true));
    return s;
}

}  // namespace caustics
