#pragma once
// The wave_optics method's per-frame data around the propagator: the surface resampled to the FFT grid
// (made periodic), the intensity table (depth slices x grid x grid, mono plus optional RGB) and its
// lookup at world points (Stam 1996: "storing caustic textures for different depths in a three
// dimensional table").
#include <algorithm>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/util/image.hpp>
#include "wave_propagator.hpp"

namespace caustics::wave_optics {

// The FFT window: one period of the field the propagator sees. A surface that tiles is its own window. A
// surface whose edges do not match gets a border of `pad` on every side, outside the surface, in which the
// heights fall to the edge mean over a raised cosine: the window then tiles, and the surface keeps its own
// slopes out to its edges (only the border's light is not the scene's; the claim keeps it off the receiver).
struct FftWindow {
    double lx = 1.0, ly = 1.0;     // window size, the period of the FFT [m]
    double pad = 0.0;              // border added on each side of the surface [m] (0 when it tiles)
    bool periodic = true;          // the surface tiles
    double edge_mean = 0.0;        // what the border falls to
    double spacing(int grid) const { return std::max(lx, ly) / grid; }
};

struct SurfaceSamples {
    std::vector<float> height;   // grid x grid heights above the mean level [m], over the window
    double level = 0.0;          // world z of the mean level (the phase screen's reference plane)
    FftWindow window;
};

struct ShadePoint {
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0, 0.0, 1.0};
};

struct LookupGeometry {
    glm::dvec2 origin{0.0};        // world x, y of grid sample (0, 0)
    double lx = 1.0, ly = 1.0;     // period [m]
    double level = 0.0;            // water mean level
    std::vector<double> depths;    // slice depths, ascending, evenly spaced
    glm::dvec2 walk{0.0};          // lateral walk per depth removed by the propagator
    glm::dvec3 refracted{0, 0, -1};  // refracted beam direction (mean index)
    double pad = 0.0;              // the window's border: the surface spans [pad, l - pad] on each axis
    double reach_per_m = 0.0;      // how far sideways the border's light may reach, per metre of depth
    double irradiance = 1.0;       // transmitted irradiance on a horizontal plane, E0 cos(theta_i) T
    double absorption = 0.0;       // Beer-Lambert Ka [1/m] of the water
};

struct LookupCounters {
    std::int64_t not_covered = 0;  // above the water, or lit through a point outside the surface
    std::int64_t tapered = 0;      // lit within the reach of the border's light (non-tiling surfaces)
};

// Whether the surface tiles (flagged periodic, or opposite edges equal to 1e-3 of the height range), and
// the mean of its edge heights (what the FFT window's border around a non-periodic surface falls to).
struct EdgeCheck {
    bool periodic = true;
    double edge_mean = 0.0;
};
EdgeCheck check_edges(const HeightField& hf);

// Width of the raised-cosine border around a non-periodic surface: 1/16 of its shorter side.
inline double border_pad_width(double lx, double ly) { return std::min(lx, ly) / 16.0; }
// The window for a surface of size lx x ly (fft_window: the edge check, then the border when needed).
FftWindow fft_window(const EdgeCheck& edges, double lx, double ly);
inline FftWindow fft_window(const HeightField& hf, double lx, double ly) { return fft_window(check_edges(hf), lx, ly); }

class WaveFieldTable {
public:
    WaveFieldTable(int nx, int ny, bool rgb);

    // Resamples `hf` (bilinear; its rectangle lx x ly) to the grid over `window`. Surfaces flagged
    // periodic, or whose opposite edges match to 1e-3 of their height range, are their own window; others
    // sit in the middle of a larger window whose border falls to their edge mean (FftWindow).
    // Where every grid sample falls on a vertex (no border, and (vertices - 1) a multiple of the grid along
    // both axes, e.g. a 1024-cell surface on grid 1024 or 512), the bilinear weights are exactly 0 and the
    // samples are copied (ResamplePath::Auto); the result is bit-identical to the bilinear path.
    enum class ResamplePath { Auto, Bilinear };
    const SurfaceSamples& resample(const HeightField& hf, const FftWindow& window, double lx, double ly,
                                   ResamplePath path = ResamplePath::Auto);
    const SurfaceSamples& resample(const HeightField& hf, double lx, double ly, ResamplePath path = ResamplePath::Auto) {
        return resample(hf, fft_window(hf, lx, ly), lx, ly, path);
    }
    // The samples of the last resample().
    const SurfaceSamples& samples() const { return surface_; }

    // Sizes the table for `slices` depths (contents undefined until the first sample assigns them).
    void begin(int slices);
    // Fills `targets` (up to 4) for wavelength sample `sample` at `slice`: mono with weight
    // `mono_weight`, RGB with `rgb`; sample 0 assigns, later ones accumulate. Returns the count.
    int targets(int slice, int sample, float mono_weight, const float rgb[3], IntensityTarget* targets);
    // Periodic separable Gaussian blur of every slice and channel, sigma in metres (period lx x ly).
    void blur(double sigma_m, double lx, double ly);
    // E_c at each point: (mono, r, g, b).
    void lookup(const LookupGeometry& geo, const std::vector<ShadePoint>& points, std::vector<glm::vec4>& values,
                LookupCounters& counters) const;

    // Slice s of channel c (0 mono, 1..3 RGB): nx * ny intensities (1 = the incident wave).
    const float* slice(int s, int channel = 0) const;
    int slices() const { return slices_; }

private:
    int nx_, ny_;
    bool rgb_;
    int slices_ = 0;
    std::vector<float> data_;   // [channel][slice][ny][nx]
    SurfaceSamples surface_;
    float* slice_mut(int s, int channel);
};

// Periodic texture from slice 0 of the table (its depth is geo.depths[0]): texel (i, j) is centred at
// geo.origin + ((i + 1/2) lx / width, (j + 1/2) ly / height) on a horizontal plane; periodic bilinear
// lookup in the grid x grid slice with the propagator's walk removed, as WaveFieldTable::lookup() does,
// but without its coverage test (the field tiles), scaled to irradiance (a horizontal plane faces the
// refracted beam by the factor 1 that lookup() divides out).
void fill_periodic_texture(const WaveFieldTable& table, int n, const LookupGeometry& geo, Image& mono, Image* rgb);

}  // namespace caustics::wave_optics
