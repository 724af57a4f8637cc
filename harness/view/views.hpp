#pragma once
// What the viewer's panes show, as RGBA8 images made from the session's float maps, and the hover
// readout. Method and reference panes of one space share one mapping (the same exposure and colour map,
// the scale taken from the truth when there is one), so that they can be compared by eye; the difference
// pane maps method - truth over a symmetric range [-s, s] with a diverging colour map (white = 0).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <caustics/util/image.hpp>
#include <caustics/view/colormap.hpp>
#include <caustics/view/session.hpp>

namespace caustics::view {

enum class ViewKind {
    Beauty,              // the camera view composited as the beauty image (run/beauty.hpp), sRGB
    MethodReceiver, ReferenceReceiver, DifferenceReceiver,
    MethodCamera, ReferenceCamera, DifferenceCamera,
    MethodVolume, ReferenceVolume, DifferenceVolume,
};
enum class Space { Receiver, Camera, Volume };

const char* to_string(ViewKind k);
Space space_of(ViewKind k);

struct DisplaySettings {
    Exposure exposure = Exposure::Linear;
    ColorMap colormap = ColorMap::Inferno;
    double exposure_gain = 1.0;     // multiplies the automatic scale's inverse: > 1 brightens
    double decades = 3.0;           // log exposure
};

struct Pane {
    ViewKind kind = ViewKind::MethodReceiver;
    std::string title;
    bool available = false;
    std::string missing;            // why not, when not available
    int width = 0, height = 0;
    // width x height x 4, row 0 first and drawn at the top, as the EXR files of `caustics render` store
    // and show them.
    std::vector<std::uint8_t> rgba;
    Mapping mapping;                // how the floats became colours (not for Beauty)
};

// The mapping of a space's method and reference panes (shared), and of its difference pane.
Mapping shared_mapping(const Session& s, Space space, const DisplaySettings& d);
Mapping difference_mapping(const Session& s, Space space, const DisplaySettings& d);

// The float map behind a pane (null when there is none yet): method output, truth, or nothing for the
// difference (computed), and the truth's standard error (null for a closed form or none).
const Image* method_map(const Session& s, Space space);
const Image* truth_map(const Session& s, Space space);
const Image* truth_stderr(const Session& s, Space space);
const std::vector<std::uint8_t>* space_mask(const Session& s, Space space);

// Both mappings of a space, computed once for all its panes (each takes a quantile of a map).
struct SpaceMappings {
    Mapping shared, difference;
};
SpaceMappings space_mappings(const Session& s, Space space, const DisplaySettings& d);

// Builds one pane. `beauty` is the composited beauty image (linear RGB) for ViewKind::Beauty; `mappings`
// (optional) those of the pane's space, else computed here.
Pane make_pane(const Session& s, ViewKind kind, const DisplaySettings& d, const Image* beauty = nullptr,
               const SpaceMappings* mappings = nullptr);

// The numbers under the mouse, at pixel (x, y) of the space's map (row 0 first, as stored).
struct Readout {
    bool valid = false;
    double method = 0.0;
    std::optional<double> truth, stderr_value, z;   // z = (method - truth) / stderr where stderr > 0
    bool covered = true;                            // camera: primary hit on a diffuse receiver
};
Readout readout(const Session& s, Space space, int x, int y);

}  // namespace caustics::view
