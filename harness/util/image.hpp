#pragma once
// A plain float image: row-major, `channels` interleaved floats per pixel, row 0 first.
// Receiver maps use 1 channel (caustic irradiance E_c in W/m^2); RGB previews use 3.
//
// The pixels live in zeroed memory (util/huge_pages.hpp: from 1 MiB on, fresh 2 MiB pages or a block
// freed earlier and cleared; cleared heap memory below): a new large image of zeros costs no pass over
// fresh memory and few page faults. A 1024 x 768 view is 3 MB, and a reference's result is 2 + R of them
// per view (10 with 8 replicas); from std::allocator, value-initialised, they faulted in 4 KiB pages and
// were written twice. Differences from std::vector<float>: a different type (PixelVector; copy into a
// std::vector<float> with assign); large buffers are rounded up to 2 MiB and, once freed, up to 256 MiB
// of them stay mapped for reuse; pixels.resize(n) grows with zeros only into new memory (after a shrink it
// keeps the old values), where resize(n, 0.0f) always writes.
#include <cmath>
#include <cstddef>
#include <vector>

#include <caustics/util/huge_pages.hpp>

namespace caustics {

using PixelVector = std::vector<float, HugePageAllocator<float>>;

struct Image {
    int width = 0;
    int height = 0;
    int channels = 1;
    PixelVector pixels;

    Image() = default;
    Image(int w, int h, int c = 1, float fill = 0.0f) : width(w), height(h), channels(c) {
        const std::size_t n = static_cast<std::size_t>(w) * h * c;
        if (fill == 0.0f && !std::signbit(fill)) pixels.resize(n);   // zeros from the allocation
        else pixels.assign(n, fill);
    }

    bool empty() const { return pixels.empty(); }
    std::size_t index(int x, int y, int c = 0) const {
        return (static_cast<std::size_t>(y) * width + x) * channels + c;
    }
    float& at(int x, int y, int c = 0) { return pixels[index(x, y, c)]; }
    float at(int x, int y, int c = 0) const { return pixels[index(x, y, c)]; }
};

}  // namespace caustics
