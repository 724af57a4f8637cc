#include <caustics/view/views.hpp>

#include <algorithm>
#include <cmath>

namespace caustics::view {

const char* to_string(ViewKind k) {
    switch (k) {
    case ViewKind::Beauty: return "beauty";
    case ViewKind::MethodReceiver: return "method receiver";
    case ViewKind::ReferenceReceiver: return "reference receiver";
    case ViewKind::DifferenceReceiver: return "difference receiver";
    case ViewKind::MethodCamera: return "method camera";
    case ViewKind::ReferenceCamera: return "reference camera";
    case ViewKind::DifferenceCamera: return "difference camera";
    case ViewKind::MethodVolume: return "method volume";
    case ViewKind::ReferenceVolume: return "reference volume";
    case ViewKind::DifferenceVolume: return "difference volume";
    }
    return "?";
}

Space space_of(ViewKind k) {
    switch (k) {
    case ViewKind::MethodCamera: case ViewKind::ReferenceCamera: case ViewKind::DifferenceCamera: case ViewKind::Beauty:
        return Space::Camera;
    case ViewKind::MethodVolume: case ViewKind::ReferenceVolume: case ViewKind::DifferenceVolume: return Space::Volume;
    default: return Space::Receiver;
    }
}

const Image* method_map(const Session& s, Space space) {
    if (!s.rendered()) return nullptr;
    const CausticOutput& o = s.output();
    const Image& im = space == Space::Receiver ? o.receiver : space == Space::Camera ? o.camera : o.camera_volume;
    return im.empty() ? nullptr : &im;
}

const Image* truth_map(const Session& s, Space space) {
    if (space == Space::Receiver) return s.receiver_truth();
    const auto r = s.reference();
    if (!r) return nullptr;
    const Image& im = space == Space::Camera ? r->camera : r->camera_volume;
    return im.empty() ? nullptr : &im;
}

const Image* truth_stderr(const Session& s, Space space) {
    if (space == Space::Receiver) return s.receiver_truth_stderr();
    const auto r = s.reference();
    if (!r) return nullptr;
    const Image& im = space == Space::Camera ? r->camera_stderr : r->camera_volume_stderr;
    return im.empty() ? nullptr : &im;
}

const std::vector<std::uint8_t>* space_mask(const Session& s, Space space) {
    return space == Space::Camera ? &s.scene_frame().gbuffer().covered : nullptr;
}

Mapping shared_mapping(const Session& s, Space space, const DisplaySettings& d) {
    Mapping m;
    m.exposure = d.exposure;
    m.colormap = d.colormap == ColorMap::Diverging ? ColorMap::Inferno : d.colormap;
    m.decades = d.decades;
    const Image* base = truth_map(s, space);
    if (!base) base = method_map(s, space);
    m.scale = (base ? robust_scale(*base, 0.995, space_mask(s, space)) : 1.0) / std::max(d.exposure_gain, 1e-9);
    return m;
}

namespace {

Image difference(const Image& a, const Image& b) {
    Image d(a.width, a.height, 1);
    for (std::size_t p = 0; p < d.pixels.size(); ++p)
        d.pixels[p] = a.pixels[p * a.channels] - b.pixels[p * b.channels];
    return d;
}

}  // namespace

Mapping difference_mapping(const Session& s, Space space, const DisplaySettings& d) {
    Mapping m = shared_mapping(s, space, d);
    m.signed_range = true;
    m.colormap = ColorMap::Diverging;
    m.exposure = Exposure::Linear;
    // Symmetric about zero at the 99.5th percentile of |method - truth| (the bar says its value), so that
    // the structure of the error shows whatever its size relative to the signal.
    const Image* a = method_map(s, space);
    const Image* b = truth_map(s, space);
    if (a && b && a->width == b->width && a->height == b->height)
        m.scale = robust_scale(difference(*a, *b), 0.995, space_mask(s, space)) / std::max(d.exposure_gain, 1e-9);
    return m;
}

namespace {

Pane unavailable(Pane p, std::string why) {
    p.available = false;
    p.missing = std::move(why);
    return p;
}

}  // namespace

SpaceMappings space_mappings(const Session& s, Space space, const DisplaySettings& d) {
    return {shared_mapping(s, space, d), difference_mapping(s, space, d)};
}

Pane make_pane(const Session& s, ViewKind kind, const DisplaySettings& d, const Image* beauty, const SpaceMappings* mappings) {
    Pane p;
    p.kind = kind;
    p.title = to_string(kind);
    const Space space = space_of(kind);
    if (kind == ViewKind::Beauty) {
        if (!beauty || beauty->empty()) return unavailable(p, "not rendered yet");
        // The sRGB transfer of write_png (util/image_io) with the beauty's exposure (run/beauty.hpp).
        p.width = beauty->width;
        p.height = beauty->height;
        p.rgba.resize(static_cast<std::size_t>(p.width) * p.height * 4);
        double exposure = d.exposure_gain;
        double lum99 = 0.0;
        {
            Image lum(p.width, p.height, 1);
            for (std::size_t i = 0; i < lum.pixels.size(); ++i)
                lum.pixels[i] = 0.2126f * beauty->pixels[i * 3] + 0.7152f * beauty->pixels[i * 3 + 1] + 0.0722f * beauty->pixels[i * 3 + 2];
            lum99 = robust_scale(lum, 0.97);
        }
        exposure *= 0.85 / std::max(lum99, 1e-12);
        for (std::size_t i = 0; i < p.rgba.size() / 4; ++i) {
            for (int c = 0; c < 3; ++c) {
                const double v = std::clamp(beauty->pixels[i * 3 + c] * exposure, 0.0, 1.0);
                const double srgb = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
                p.rgba[i * 4 + c] = static_cast<std::uint8_t>(std::lround(srgb * 255.0));
            }
            p.rgba[i * 4 + 3] = 255;
        }
        p.available = true;
        return p;
    }
    const Image* m = method_map(s, space);
    const Image* t = truth_map(s, space);
    const bool is_method = kind == ViewKind::MethodReceiver || kind == ViewKind::MethodCamera || kind == ViewKind::MethodVolume;
    const bool is_truth = kind == ViewKind::ReferenceReceiver || kind == ViewKind::ReferenceCamera || kind == ViewKind::ReferenceVolume;
    const Image* shown = nullptr;
    Image diff;
    if (is_method) {
        if (!m) return unavailable(p, s.rendered() ? "the method gives no such view" : "not rendered yet");
        shown = m;
        p.mapping = mappings ? mappings->shared : shared_mapping(s, space, d);
    } else if (is_truth) {
        if (!t) return unavailable(p, "no reference yet");
        shown = t;
        p.mapping = mappings ? mappings->shared : shared_mapping(s, space, d);
    } else {
        if (!m || !t) return unavailable(p, !m ? "no method output" : "no reference yet");
        if (m->width != t->width || m->height != t->height) return unavailable(p, "sizes differ");
        diff = difference(*m, *t);
        shown = &diff;
        p.mapping = mappings ? mappings->difference : difference_mapping(s, space, d);
    }
    p.width = shown->width;
    p.height = shown->height;
    p.rgba = map_to_rgba8(*shown, p.mapping, space_mask(s, space));
    p.available = true;
    return p;
}

Readout readout(const Session& s, Space space, int x, int y) {
    Readout r;
    const Image* m = method_map(s, space);
    if (!m || x < 0 || y < 0 || x >= m->width || y >= m->height) return r;
    r.valid = true;
    r.method = m->at(x, y);
    if (const auto* mask = space_mask(s, space); mask && mask->size() == static_cast<std::size_t>(m->width) * m->height)
        r.covered = (*mask)[static_cast<std::size_t>(y) * m->width + x] != 0;
    if (const Image* t = truth_map(s, space); t && t->width == m->width && t->height == m->height) r.truth = t->at(x, y);
    if (const Image* se = truth_stderr(s, space); se && se->width == m->width && se->height == m->height) {
        r.stderr_value = se->at(x, y);
        if (r.truth && *r.stderr_value > 0.0) r.z = (r.method - *r.truth) / *r.stderr_value;
    }
    return r;
}

}  // namespace caustics::view
