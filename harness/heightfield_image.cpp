// The `image` height-field generator: z = base_height + amplitude * value, value the first channel of
// a height map (8/16-bit images read as [0, 1]), bilinearly resampled onto the grid. The image covers
// the field's rectangle with its top row at +y (north up when seen from above). Gradients by central
// differences.
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "heightfield_generators.hpp"

namespace caustics::detail {

void generate_image(const HeightFieldDesc& desc, HeightField& hf) {
    auto in = OIIO::ImageInput::open(desc.image_path);
    if (!in) throw std::runtime_error("image height map '" + desc.image_path + "': " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    const int w = spec.width, h = spec.height, channels = spec.nchannels;
    if (w <= 0 || h <= 0 || channels <= 0) throw std::runtime_error("image height map '" + desc.image_path + "' is empty");
    std::vector<float> pixels(static_cast<std::size_t>(w) * h);
    if (!in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, pixels.data()))
        throw std::runtime_error("image height map '" + desc.image_path + "': " + in->geterror());
    in->close();

    auto value = [&](int x, int y) { return static_cast<double>(pixels[static_cast<std::size_t>(y) * w + x]); };
    for (int j = 0; j < hf.ny; ++j) {
        // Grid row j = 0 is the field's -y edge, i.e. the bottom row of the image.
        const double py = hf.ny > 1 ? (1.0 - static_cast<double>(j) / (hf.ny - 1)) * (h - 1) : 0.5 * (h - 1);
        const int y0 = std::clamp(static_cast<int>(std::floor(py)), 0, std::max(0, h - 2));
        const int y1 = std::min(y0 + 1, h - 1);
        const double fy = std::clamp(py - y0, 0.0, 1.0);
        for (int i = 0; i < hf.nx; ++i) {
            const double px = hf.nx > 1 ? static_cast<double>(i) / (hf.nx - 1) * (w - 1) : 0.5 * (w - 1);
            const int x0 = std::clamp(static_cast<int>(std::floor(px)), 0, std::max(0, w - 2));
            const int x1 = std::min(x0 + 1, w - 1);
            const double fx = std::clamp(px - x0, 0.0, 1.0);
            const double v = (1 - fy) * ((1 - fx) * value(x0, y0) + fx * value(x1, y0)) +
                             fy * ((1 - fx) * value(x0, y1) + fx * value(x1, y1));
            hf.height[static_cast<std::size_t>(j) * hf.nx + i] = static_cast<float>(desc.base_height + desc.amplitude * v);
        }
    }
    gradients_by_central_differences(hf);
}

}  // namespace caustics::detail
