#pragma once
// A plain float image: row-major, `channels` interleaved floats per pixel, row 0 first.
// Receiver maps use 1 channel (caustic irradiance E_c in W/m^2); RGB previews use 3.
#include <cstddef>
#include <vector>

namespace caustics {

struct Image {
    int width = 0;
    int height = 0;
    int channels = 1;
    std::vector<float> pixels;

    Image() = default;
    Image(int w, int h, int c = 1, float fill = 0.0f)
        : width(w), height(h), channels(c), pixels(static_cast<std::size_t>(w) * h * c, fill) {}

    bool empty() const { return pixels.empty(); }
    std::size_t index(int x, int y, int c = 0) const {
        return (static_cast<std::size_t>(y) * width + x) * channels + c;
    }
    float& at(int x, int y, int c = 0) { return pixels[index(x, y, c)]; }
    float at(int x, int y, int c = 0) const { return pixels[index(x, y, c)]; }
};

}  // namespace caustics
