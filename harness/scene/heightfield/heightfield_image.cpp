// The `image` height-field generator: z = base_height + amplitude * value, value the first channel of
// a height map (8/16-bit images read as [0, 1]), bilinearly resampled onto the grid. The image covers
// the field's rectangle with its top row at +y (north up when seen from above). Gradients by central
// differences.
//
// Reading: a truncated or corrupt file is an error with one line naming it. libpng prints its own
// "libpng error: ..." lines to stderr before OpenImageIO returns the error, so stderr is redirected to
// /dev/null while the image library runs (scene loading and frame set-up are single-threaded; nothing
// else writes then).
#include <fcntl.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "detail/heightfield_generators.hpp"

namespace caustics {

namespace {

// Sends file descriptor 2 to /dev/null for its lifetime.
class StderrSilencer {
public:
    StderrSilencer() {
        std::fflush(stderr);
        saved_ = ::dup(2);
        const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
        if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
        if (null >= 0) ::close(null);
    }
    ~StderrSilencer() {
        std::fflush(stderr);
        if (saved_ >= 0) {
            ::dup2(saved_, 2);
            ::close(saved_);
        }
    }
    StderrSilencer(const StderrSilencer&) = delete;
    StderrSilencer& operator=(const StderrSilencer&) = delete;

private:
    int saved_ = -1;
};

// The first line of an image library's (possibly multi-line) message.
std::string first_line(const std::string& message) {
    std::string line = message.substr(0, message.find('\n'));
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    return line.empty() ? std::string("unknown error") : line;
}

std::unique_ptr<OIIO::ImageInput> open_height_map(const std::string& path, HeightMapInfo& info) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw std::runtime_error("cannot read the height map '" + path + "': " + first_line(OIIO::geterror()));
    const OIIO::ImageSpec& spec = in->spec();
    info.width = spec.width;
    info.height = spec.height;
    info.channels = spec.nchannels;
    info.bytes_per_channel = std::max<std::size_t>(1, spec.format.size());
    if (info.width <= 0 || info.height <= 0 || info.channels <= 0 || spec.depth > 1)
        throw std::runtime_error("the height map '" + path + "' has no pixels (a 2-D image is expected)");
    return in;
}

}  // namespace

HeightMapInfo read_height_map_info(const std::string& path) {
    const StderrSilencer quiet;
    HeightMapInfo info;
    auto in = open_height_map(path, info);
    in->close();
    (void)in->geterror();   // OpenImageIO prints errors never retrieved when the reader is destroyed
    return info;
}

std::vector<float> read_height_map(const std::string& path, HeightMapInfo& info) {
    const StderrSilencer quiet;
    auto in = open_height_map(path, info);
    std::vector<float> pixels(static_cast<std::size_t>(info.width) * static_cast<std::size_t>(info.height));
    const bool ok = in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, pixels.data());
    const std::string error = in->geterror();
    in->close();
    (void)in->geterror();
    if (!ok) throw std::runtime_error("the height map '" + path + "' is truncated or corrupt: " + first_line(error));
    for (const float v : pixels)
        if (!std::isfinite(v)) throw std::runtime_error("the height map '" + path + "' holds a value that is not finite");
    return pixels;
}

}  // namespace caustics

namespace caustics::detail {

void generate_image(const HeightFieldDesc& desc, HeightField& hf) {
    HeightMapInfo info;
    const std::vector<float> pixels = read_height_map(desc.image_path, info);
    const int w = info.width, h = info.height;

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
