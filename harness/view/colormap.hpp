#pragma once
// Display mappings of the viewer: exposure (linear or logarithmic) and colour maps from a float map to
// 8-bit RGBA. These are for looking, not measuring; the numbers a pane shows come from the float maps.
//
// Every pane goes through map_to_rgba8(), so a test can put a receiver map written by `caustics render`
// through the same function and compare it with the viewer's screenshot pixel for pixel.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <caustics/util/image.hpp>

namespace caustics::view {

enum class ColorMap { Inferno, Viridis, Grey, Diverging };
enum class Exposure { Linear, Log };

const std::vector<std::string>& colormap_names();   // "inferno", "viridis", "grey", "diverging"
const char* to_string(ColorMap c);
const char* to_string(Exposure e);

// How values become [0, 1] before the colour map.
//   Linear:  t = v / scale
//   Log:     t = 1 + log10(v / scale) / decades   (scale maps to 1, scale 10^-decades to 0)
//   signed:  t = 1/2 + v / (2 scale)              (a symmetric range [-scale, scale]: difference views)
// t is clamped to [0, 1]; non-finite values map to the colour map's "invalid" colour (magenta).
struct Mapping {
    Exposure exposure = Exposure::Linear;
    ColorMap colormap = ColorMap::Inferno;
    double scale = 1.0;        // > 0
    double decades = 3.0;      // Log only
    bool signed_range = false; // [-scale, scale] (Log is ignored)
    double normalise(double v) const;
};

using Rgba = std::array<std::uint8_t, 4>;
// The colour of t in [0, 1]: a 256-entry table, entry round(255 t) (diverging: 255 entries, round(254 t),
// so that t = 1/2, a zero difference, is its white middle entry).
Rgba colormap_rgba(ColorMap c, double t);
Rgba invalid_rgba();

// Channel 0 of `image` as RGBA8, row 0 first (the image's own row order: receiver row 0 is the least v of
// the chart, camera row 0 the top of the picture). `mask` (optional, one byte per pixel): zero pixels
// are drawn dark grey (the camera view's uncovered pixels).
std::vector<std::uint8_t> map_to_rgba8(const Image& image, const Mapping& m, const std::vector<std::uint8_t>* mask = nullptr);

// A horizontal colour bar width x height (RGBA8) of the mapping, from t = 0 at the left to 1 at the right.
std::vector<std::uint8_t> colour_bar_rgba8(const Mapping& m, int width, int height);

// A scale that makes a map readable: the q-quantile of the finite, positive |values| (of channel 0;
// `mask` selects), or 1 when there is none. The method and reference panes share one.
double robust_scale(const Image& image, double q = 0.995, const std::vector<std::uint8_t>* mask = nullptr);

}  // namespace caustics::view
