// Colour maps: piecewise-linear fits of matplotlib's inferno and viridis (van der Walt and Smith 2015;
// 9 control points each, in sRGB), grey, and a blue-white-red diverging map for signed differences
// (Moreland 2009's cool-warm end points) whose middle entry is white, so zero difference reads as white.
#include <caustics/view/colormap.hpp>

#include <algorithm>
#include <cmath>

namespace caustics::view {
namespace {

using Stops = std::array<std::array<double, 3>, 9>;
constexpr Stops kInferno = {{{0.001, 0.000, 0.014}, {0.122, 0.047, 0.282}, {0.333, 0.060, 0.430},
                             {0.533, 0.134, 0.416}, {0.729, 0.212, 0.333}, {0.890, 0.330, 0.217},
                             {0.976, 0.513, 0.051}, {0.982, 0.736, 0.197}, {0.988, 0.998, 0.645}}};
constexpr Stops kViridis = {{{0.267, 0.005, 0.329}, {0.283, 0.141, 0.458}, {0.254, 0.265, 0.530},
                             {0.207, 0.372, 0.553}, {0.164, 0.471, 0.558}, {0.128, 0.567, 0.551},
                             {0.135, 0.659, 0.518}, {0.478, 0.821, 0.318}, {0.993, 0.906, 0.144}}};
constexpr Stops kDiverging = {{{0.230, 0.299, 0.754}, {0.400, 0.505, 0.900}, {0.600, 0.700, 0.970},
                               {0.800, 0.860, 0.990}, {1.000, 1.000, 1.000}, {0.990, 0.840, 0.780},
                               {0.950, 0.640, 0.540}, {0.880, 0.400, 0.320}, {0.706, 0.016, 0.150}}};

// Entries of a table: 256, or 255 for the diverging map, whose middle entry (127) is then exactly t = 1/2.
int last_entry(ColorMap c) { return c == ColorMap::Diverging ? 254 : 255; }

std::array<Rgba, 256> make_table(ColorMap c) {
    std::array<Rgba, 256> table{};
    for (int i = 0; i <= last_entry(c); ++i) {
        const double t = i / static_cast<double>(last_entry(c));
        std::array<double, 3> rgb{t, t, t};
        if (c != ColorMap::Grey) {
            const Stops& s = c == ColorMap::Inferno ? kInferno : c == ColorMap::Viridis ? kViridis : kDiverging;
            const double x = t * 8.0;
            const int k = std::min(7, static_cast<int>(x));
            const double f = x - k;
            for (int ch = 0; ch < 3; ++ch) rgb[ch] = s[k][ch] + f * (s[k + 1][ch] - s[k][ch]);
        }
        for (int ch = 0; ch < 3; ++ch)
            table[i][ch] = static_cast<std::uint8_t>(std::lround(std::clamp(rgb[ch], 0.0, 1.0) * 255.0));
        table[i][3] = 255;
    }
    return table;
}

const std::array<Rgba, 256>& table_of(ColorMap c) {
    static const std::array<std::array<Rgba, 256>, 4> tables = {make_table(ColorMap::Inferno), make_table(ColorMap::Viridis),
                                                                make_table(ColorMap::Grey), make_table(ColorMap::Diverging)};
    return tables[static_cast<int>(c)];
}

}  // namespace

const std::vector<std::string>& colormap_names() {
    static const std::vector<std::string> names = {"inferno", "viridis", "grey", "diverging"};
    return names;
}
const char* to_string(ColorMap c) { return colormap_names()[static_cast<int>(c)].c_str(); }
const char* to_string(Exposure e) { return e == Exposure::Linear ? "linear" : "log"; }

double Mapping::normalise(double v) const {
    const double s = scale > 0.0 ? scale : 1.0;
    double t;
    if (signed_range)
        t = 0.5 + v / (2.0 * s);
    else if (exposure == Exposure::Log)
        t = v > 0.0 ? 1.0 + std::log10(v / s) / std::max(decades, 1e-6) : 0.0;
    else
        t = v / s;
    return std::clamp(t, 0.0, 1.0);
}

Rgba colormap_rgba(ColorMap c, double t) {
    const int i = static_cast<int>(std::lround(std::clamp(t, 0.0, 1.0) * last_entry(c)));
    return table_of(c)[i];
}

Rgba invalid_rgba() { return {255, 0, 255, 255}; }

std::vector<std::uint8_t> map_to_rgba8(const Image& image, const Mapping& m, const std::vector<std::uint8_t>* mask) {
    const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
    std::vector<std::uint8_t> out(n * 4);
    const bool use_mask = mask && mask->size() == n;
    for (std::size_t p = 0; p < n; ++p) {
        const float v = image.pixels[p * image.channels];
        Rgba c;
        if (use_mask && !(*mask)[p]) c = {40, 40, 40, 255};
        else if (!std::isfinite(v)) c = invalid_rgba();
        else c = colormap_rgba(m.colormap, m.normalise(v));
        std::copy(c.begin(), c.end(), out.begin() + static_cast<std::ptrdiff_t>(p * 4));
    }
    return out;
}

std::vector<std::uint8_t> colour_bar_rgba8(const Mapping& m, int width, int height) {
    std::vector<std::uint8_t> out(static_cast<std::size_t>(std::max(width, 0)) * std::max(height, 0) * 4);
    for (int x = 0; x < width; ++x) {
        const Rgba c = colormap_rgba(m.colormap, width > 1 ? x / double(width - 1) : 0.0);
        for (int y = 0; y < height; ++y)
            std::copy(c.begin(), c.end(), out.begin() + (static_cast<std::ptrdiff_t>(y) * width + x) * 4);
    }
    return out;
}

double robust_scale(const Image& image, double q, const std::vector<std::uint8_t>* mask) {
    std::vector<float> values;
    const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
    const bool use_mask = mask && mask->size() == n;
    values.reserve(n);
    for (std::size_t p = 0; p < n; ++p) {
        const float v = std::fabs(image.pixels[p * image.channels]);
        if ((!use_mask || (*mask)[p]) && std::isfinite(v) && v > 0.0f) values.push_back(v);
    }
    if (values.empty()) return 1.0;
    const std::size_t k = std::min(values.size() - 1, static_cast<std::size_t>(q * (values.size() - 1) + 0.5));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k] > 0.0f ? values[k] : 1.0;
}

}  // namespace caustics::view
