#pragma once
// Where a receiver lookup (lookup.hpp) can return anything but 0: one bit per texel of each face of the
// receivers' positions texture, set where some texel within one texel of it (its 3 x 3 block, clamped at
// the borders) holds caustic flux or no receiver (id -1). A lookup reads the id of its own texel and
// the four caustic-map texels of its bilinear read, all within that block; where the bit is clear, that
// id is a receiver and the four reads are 0, so the lookup returns 0 and counts nothing -- it can skip
// both reads. Most lookups of the camera view and of the receiver map see no caustic: the mask (74 KB at
// map 768) replaces reads in two 2.4 MB arrays by one in a table that stays in cache.
//
// Built in every render from that render's caustic map (nothing is kept between renders, lookup.hpp).
#include <cstddef>
#include <cstdint>
#include <vector>

#include <caustics/util/image.hpp>
#include "positions_texture.hpp"

namespace caustics::caustic_mapping {

class LookupMask {
public:
    // Rebuilds the mask of every face from its G-buffer's ids and its caustic map (same sizes).
    void build(const PositionsTexture& receivers, const std::vector<Image>& caustic);

    // Face f's rows: `words()` 64-bit words a row, texel x of row y at bit x % 64 of word y * words() + x / 64.
    const std::uint64_t* face(std::size_t f) const { return bits_.data() + f * face_words_; }
    int words() const { return words_; }

    static bool test(const std::uint64_t* face, int words, int x, int y) {
        return (face[static_cast<std::size_t>(y) * static_cast<std::size_t>(words) + static_cast<std::size_t>(x >> 6)] >>
                (x & 63)) & 1u;
    }
    // True when any bit of texels [x0, x1] x [y0, y1] is set.
    static bool any(const std::uint64_t* face, int words, int x0, int y0, int x1, int y1);

private:
    int words_ = 0;
    std::size_t face_words_ = 0;
    std::vector<std::uint64_t> rows_;   // per row: the texels' own bits, dilated along the row
    std::vector<std::uint64_t> bits_;   // the mask: rows_ dilated across rows
};

}  // namespace caustics::caustic_mapping
